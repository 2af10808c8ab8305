//! serde's type errors in the words of a scene file's author: `invalid type: string "four",
//! expected i64` becomes `expected a whole number, found the text "four"`.
//!
//! serde writes these messages from three templates (`invalid type: FOUND, expected WHAT`,
//! `invalid value: FOUND, expected WHAT`, `invalid length N, expected WHAT`), with Rust's names
//! for WHAT (`i64`, `f64`, `a sequence`, `struct RenderSpec`). Only those templates are rewritten;
//! any other message, and any part this module does not know, is kept as it was.

/// `message` with serde's type, value and length errors said in TOML's and JSON's terms, found
/// after expected; other messages unchanged.
pub fn in_plain_words(message: &str) -> String {
    let rewritten = if let Some(rest) = message
        .strip_prefix("invalid type: ")
        .or_else(|| message.strip_prefix("invalid value: "))
    {
        // The last ", expected ": the found text may itself contain one.
        rest.rsplit_once(", expected ")
            .map(|(found, expected)| (found_words(found), expected))
    } else if let Some(rest) = message.strip_prefix("invalid length ") {
        rest.rsplit_once(", expected ")
            .map(|(n, expected)| (length_words(n), expected))
    } else {
        None
    };
    match rewritten {
        Some((found, expected)) => {
            // serde_json appends " at line L column C" to a message read from text.
            let (expected, place) = match expected.find(" at line ") {
                Some(i) => expected.split_at(i),
                None => (expected, ""),
            };
            format!(
                "expected {}, found {found}{place}",
                expected_words(expected)
            )
        }
        None => message.to_string(),
    }
}

/// What a serde `Unexpected` value reads as (`string "x"`, ``integer `5` ``, `sequence`).
fn found_words(found: &str) -> String {
    let quoted = |prefix: &str| {
        found
            .strip_prefix(prefix)
            .and_then(|v| v.strip_prefix('`'))
            .and_then(|v| v.strip_suffix('`'))
            .map(str::to_string)
    };
    if let Some(text) = found.strip_prefix("string ") {
        format!("the text {text}")
    } else if let Some(n) = quoted("integer ") {
        format!("the whole number {n}")
    } else if let Some(x) = quoted("floating point ") {
        format!("the number {x}")
    } else if let Some(b) = quoted("boolean ") {
        b
    } else {
        match found {
            "sequence" => "a list".to_string(),
            "map" => "a table".to_string(),
            "unit value" | "null" => "nothing".to_string(),
            other => other.to_string(),
        }
    }
}

/// The count of an `invalid length N` message as values found.
fn length_words(n: &str) -> String {
    match n {
        "1" => "1 value".to_string(),
        n => format!("{n} values"),
    }
}

/// What serde's expectation (a Rust type or a visitor's phrase) asks for.
fn expected_words(expected: &str) -> String {
    if ["i8", "i16", "i32", "i64", "i128", "isize"].contains(&expected) {
        return "a whole number".to_string();
    }
    if ["u8", "u16", "u32", "u64", "u128", "usize"].contains(&expected) {
        return "a whole number ≥ 0".to_string();
    }
    let size = |prefix: &str| expected.strip_prefix(prefix).map(str::to_string);
    if let Some(n) = size("an array of length ").or_else(|| size("a tuple of size ")) {
        return format!("a list of {n} values");
    }
    if expected.starts_with("struct ") {
        return "a table".to_string();
    }
    match expected {
        "f32" | "f64" => "a number",
        "a boolean" | "bool" => "true or false",
        "a string" | "a borrowed string" | "string" => "text in quotes",
        "a sequence" => "a list",
        "a map" | "map" => "a table",
        "a character" | "char" => "a single character",
        other => other,
    }
    .to_string()
}

#[cfg(test)]
mod tests {
    use super::in_plain_words;

    #[test]
    fn type_errors_name_toml_terms_expected_first() {
        for (serde, plain) in [
            (
                r#"invalid type: string "four", expected i64"#,
                r#"expected a whole number, found the text "four""#,
            ),
            (
                "invalid type: floating point `1.5`, expected u32",
                "expected a whole number ≥ 0, found the number 1.5",
            ),
            (
                "invalid type: boolean `true`, expected f64",
                "expected a number, found true",
            ),
            (
                r#"invalid type: string "big", expected a sequence"#,
                r#"expected a list, found the text "big""#,
            ),
            (
                "invalid type: integer `5`, expected struct RenderSpec",
                "expected a table, found the whole number 5",
            ),
            (
                "invalid type: map, expected a string",
                "expected text in quotes, found a table",
            ),
            (
                "invalid value: integer `-1`, expected u32",
                "expected a whole number ≥ 0, found the whole number -1",
            ),
            (
                r#"invalid type: string "4, expected 5", expected i64"#,
                r#"expected a whole number, found the text "4, expected 5""#,
            ),
            (
                "invalid length 2, expected an array of length 3",
                "expected a list of 3 values, found 2 values",
            ),
            (
                "invalid type: sequence, expected f64 at line 1 column 12",
                "expected a number, found a list at line 1 column 12",
            ),
        ] {
            assert_eq!(in_plain_words(serde), plain);
        }
    }

    #[test]
    fn other_messages_are_kept() {
        for m in [
            "missing field `version`",
            "unknown field `centre`, expected one of `name`, `center`",
            "invalid type: something new",
        ] {
            assert_eq!(in_plain_words(m), m);
        }
    }

    /// The messages the TOML reader really writes, through serde's real templates.
    #[test]
    fn toml_messages_are_rewritten() {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct Render {
            spp: i64,
            size: [f64; 2],
        }
        let message = |text: &str| {
            let e = toml::from_str::<Render>(text).unwrap_err();
            in_plain_words(e.message())
        };
        assert_eq!(
            message("spp = \"four\"\nsize = [1, 2]"),
            r#"expected a whole number, found the text "four""#
        );
        assert_eq!(
            message("spp = 1\nsize = [1, true]"),
            "expected a number, found true"
        );
    }
}
