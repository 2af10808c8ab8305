//! Names in error messages: "did you mean" (the closest known name to a misspelt one), and a
//! name cut short where it is too long to show.

use std::borrow::Cow;

/// Longest name (in bytes) a message shows whole: a longer one is cut, so a scene naming a
/// material with 10 MB of text does not echo it.
pub const MAX_SHOWN_NAME: usize = 80;

/// The most known names a message lists; the rest are counted.
pub const MAX_LISTED_NAMES: usize = 16;

/// `name` as a message shows it: whole up to [`MAX_SHOWN_NAME`] bytes, else its start (cut at a
/// character boundary), an ellipsis and its length.
pub fn shown(name: &str) -> Cow<'_, str> {
    if name.len() <= MAX_SHOWN_NAME {
        return Cow::Borrowed(name);
    }
    let mut end = MAX_SHOWN_NAME;
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    Cow::Owned(format!("{}… ({} bytes)", &name[..end], name.len()))
}

/// `names` listed for a message, each [`shown`], at most [`MAX_LISTED_NAMES`] of them and a count
/// of the others.
pub fn listed<'a>(names: impl ExactSizeIterator<Item = &'a str>) -> String {
    let total = names.len();
    let mut list: Vec<Cow<'_, str>> = names.take(MAX_LISTED_NAMES).map(shown).collect();
    if total > MAX_LISTED_NAMES {
        list.push(Cow::Owned(format!("and {} more", total - MAX_LISTED_NAMES)));
    }
    list.join(", ")
}

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
        .map(|(_, c)| format!(" (did you mean \"{}\"?)", shown(c)))
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

    #[test]
    fn long_names_and_long_lists_are_cut() {
        assert_eq!(shown("glass"), "glass");
        let long = "é".repeat(1000);
        let cut = shown(&long);
        assert!(cut.ends_with("… (2000 bytes)"), "{cut}");
        assert_eq!(
            cut.chars().filter(|&c| c == 'é').count(),
            MAX_SHOWN_NAME / 2
        );
        let names: Vec<String> = (0..20).map(|i| format!("m{i}")).collect();
        let list = listed(names.iter().map(String::as_str));
        assert!(
            list.starts_with("m0, m1, ") && list.ends_with("m15, and 4 more"),
            "{list}"
        );
        assert_eq!(listed(["a", "b"].into_iter()), "a, b");
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
