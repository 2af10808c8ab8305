//! "Did you mean": the closest known name to a misspelt one, for error messages.

/// ` (did you mean "NAME"?)` for the candidate closest to `word`, when one is close enough to be a
/// likely misspelling (Jaro–Winkler similarity of at least 0.8, the threshold at which typos of
/// one or two letters in words of four or more letters score), else an empty string.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    let lower = word.to_lowercase();
    candidates
        .into_iter()
        .filter(|c| *c != word)
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
}
