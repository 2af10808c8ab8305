//! "Did you mean": the closest known name to a misspelt one, for error messages.

/// Names longer than this (in bytes) are neither given suggestions nor suggested: a misspelling is
/// a typo in a name a person wrote, and comparing two names costs the product of their lengths
/// (an 8 MB scene of 400 names of 20 KB each took 102 s).
pub const MAX_SUGGESTED_NAME: usize = 128;

/// The most candidates one suggestion looks at: a bound on the work for a scene with very many
/// names (the first ones in the file are compared).
pub const MAX_CANDIDATES: usize = 4096;

/// ` (did you mean "NAME"?)` for the candidate closest to `word`, when one is close enough to be a
/// likely misspelling (Jaro–Winkler similarity of at least 0.8, the threshold at which typos of
/// one or two letters in words of four or more letters score), else an empty string. The work is
/// bounded by [`MAX_SUGGESTED_NAME`] and [`MAX_CANDIDATES`].
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    if word.len() > MAX_SUGGESTED_NAME {
        return String::new();
    }
    let lower = word.to_lowercase();
    candidates
        .into_iter()
        .take(MAX_CANDIDATES)
        .filter(|c| *c != word && c.len() <= MAX_SUGGESTED_NAME)
        .map(|c| (strsim::jaro_winkler(&lower, &c.to_lowercase()), c))
        .filter(|(score, _)| *score >= 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| format!(" (did you mean \"{c}\"?)"))
        .unwrap_or_default()
}

/// The suggestion for serde's "unknown field `X`, expected one of `a`, `b`, ..." message, or an
/// empty string when the message is of another kind.
pub fn for_unknown_field(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else {
        return String::new();
    };
    let Some((field, expected)) = rest.split_once('`') else {
        return String::new();
    };
    let candidates = expected.split('`').skip(1).step_by(2);
    did_you_mean(field, candidates)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_names_are_suggested_and_far_ones_not() {
        let kinds = ["ellipsoid", "hyperboloid1", "cone", "elliptic-paraboloid"];
        assert_eq!(
            did_you_mean("elipsoid", kinds),
            " (did you mean \"ellipsoid\"?)"
        );
        assert_eq!(did_you_mean("Cone", kinds), " (did you mean \"cone\"?)");
        assert_eq!(did_you_mean("torus", kinds), "");
        assert_eq!(
            for_unknown_field("unknown field `centre`, expected one of `name`, `center`, `radius`"),
            " (did you mean \"center\"?)"
        );
        assert_eq!(for_unknown_field("invalid type: string"), "");
    }

    /// 400 names of 20 KB each (an 8 MB scene) are not compared letter by letter.
    #[test]
    fn long_names_cost_nothing() {
        let long: Vec<String> = (0..400)
            .map(|i| format!("{i}{}", "x".repeat(20_000)))
            .collect();
        let refs = long.iter().map(String::as_str);
        assert_eq!(
            did_you_mean(&format!("9{}", "x".repeat(20_000)), refs.clone()),
            ""
        );
        assert_eq!(did_you_mean("xxxx", refs), "");
        let many = (0..100_000).map(|i| format!("name{i}")).collect::<Vec<_>>();
        assert_eq!(
            did_you_mean("nmae1", many.iter().map(String::as_str)),
            " (did you mean \"name1\"?)"
        );
    }
}
