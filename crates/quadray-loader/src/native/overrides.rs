//! `--set KEY=VALUE`: command-line overrides of a scene file's values (Mitsuba's `-D`), applied to
//! the text with toml_edit, which keeps every other line where it was, so errors still point at
//! the file's own lines and the overridden values get the file's validation.

use std::str::FromStr;
use toml_edit::{DocumentMut, Item, Value};

/// The longest key of an override, in bytes.
pub const MAX_KEY_BYTES: usize = 1024;
/// The most dotted parts a key may have: the deepest key of a scene is a shape inside groups
/// nested [`quadray::MAX_NESTING`] deep, plus its value's name.
pub const MAX_KEY_PARTS: usize = quadray::MAX_NESTING + 2;

/// One override: a dotted key (`render.spp`, `camera.orbit.yaw`, `material[1].color`) and a TOML
/// value (`64`, `[1, 0, 0]`, `"orthographic"`; a bare word is taken as a string).
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The dotted key, `[i]` selecting one of an array of tables (`sphere[0].radius`).
    pub key: String,
    /// The value as written after `=`.
    pub value: String,
}

impl FromStr for Override {
    type Err = String;

    fn from_str(s: &str) -> Result<Override, String> {
        let (key, value) = s
            .split_once('=')
            .ok_or_else(|| format!("expected KEY=VALUE (e.g. render.spp=64), got \"{s}\""))?;
        let (key, value) = (key.trim(), value.trim());
        if key.is_empty() || value.is_empty() {
            return Err(format!(
                "expected KEY=VALUE (e.g. render.spp=64), got \"{s}\""
            ));
        }
        if key.len() > MAX_KEY_BYTES || key.split('.').count() > MAX_KEY_PARTS {
            return Err(format!(
                "the key is {} bytes in {} parts; at most {MAX_KEY_BYTES} bytes in \
                 {MAX_KEY_PARTS} parts",
                key.len(),
                key.split('.').count()
            ));
        }
        Ok(Override {
            key: key.to_string(),
            value: value.to_string(),
        })
    }
}

impl std::fmt::Display for Override {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "--set {}={}", self.key, self.value)
    }
}

/// The scene text with `overrides` applied in order, or the first override that cannot be applied
/// and why. Text that is not valid TOML is returned unchanged, for the parser to report where it
/// breaks. A key the file does not have is added at the end of its table.
pub fn apply(text: &str, overrides: &[Override]) -> Result<String, (Override, String)> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let Ok(mut doc) = text.parse::<DocumentMut>() else {
        return Ok(text.to_string());
    };
    for o in overrides {
        set(&mut doc, o).map_err(|m| (o.clone(), m))?;
    }
    Ok(doc.to_string())
}

/// Sets one override's value, creating tables on the way (`[render]` in a file without one).
fn set(doc: &mut DocumentMut, o: &Override) -> Result<(), String> {
    let mut value = o
        .value
        .parse::<Value>()
        .unwrap_or_else(|_| Value::from(o.value.as_str()));
    let segments: Vec<&str> = o.key.split('.').collect();
    let (last, path) = segments
        .split_last()
        .expect("split yields one segment at least");
    let mut table = doc.as_table_mut() as &mut dyn toml_edit::TableLike;
    for segment in path {
        let (name, index) = split_index(segment)?;
        let item = table
            .entry(name)
            .or_insert(Item::Table(toml_edit::Table::new()));
        table = match index {
            Some(i) => {
                let array = item
                    .as_array_of_tables_mut()
                    .ok_or_else(|| format!("`{name}` is not a list of [[{name}]] tables"))?;
                let len = array.len();
                array
                    .get_mut(i)
                    .ok_or_else(|| format!("`{name}[{i}]`: the file has {len} [[{name}]]"))?
            }
            None => item
                .as_table_like_mut()
                .ok_or_else(|| format!("`{name}` is a value, not a table"))?,
        };
    }
    let (name, index) = split_index(last)?;
    if index.is_some() {
        return Err("the last part of the key names a value, not a list entry".into());
    }
    if let Some(old) = table.get(name).and_then(Item::as_value) {
        // Keep the spacing around the value, and with it the layout of the line.
        *value.decor_mut() = old.decor().clone();
    }
    table.insert(name, Item::Value(value));
    Ok(())
}

/// `name[3]` as ("name", Some(3)); `name` as ("name", None).
fn split_index(segment: &str) -> Result<(&str, Option<usize>), String> {
    match segment.split_once('[') {
        None if !segment.is_empty() => Ok((segment, None)),
        Some((name, rest)) if !name.is_empty() => {
            let i = rest
                .strip_suffix(']')
                .and_then(|i| i.parse::<usize>().ok())
                .ok_or_else(|| format!("`{segment}`: expected NAME[INDEX]"))?;
            Ok((name, Some(i)))
        }
        _ => Err(format!("`{segment}`: an empty part of the key")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn o(s: &str) -> Override {
        s.parse().unwrap()
    }

    #[test]
    fn values_are_replaced_in_place_and_tables_created() {
        let text = "version = 1\n\n[render]\nspp = 4  # few\n\n[[sphere]]\nradius = 1\n[[sphere]]\nradius = 2\n";
        let out = apply(
            text,
            &[
                o("render.spp=64"),
                o("sphere[1].radius=0.5"),
                o("camera.vfov=30"),
            ],
        )
        .unwrap();
        assert!(out.contains("spp = 64  # few"), "{out}");
        assert!(
            out.contains("radius = 1\n[[sphere]]\nradius = 0.5"),
            "{out}"
        );
        assert!(out.contains("vfov = 30"), "{out}");
        // Lines before the edits keep their numbers.
        assert_eq!(out.lines().nth(3), Some("spp = 64  # few"));
    }

    #[test]
    fn bare_words_are_strings_and_bad_keys_are_named() {
        let out = apply("version = 1\n", &[o("camera.projection=orthographic")]).unwrap();
        assert!(out.contains("projection = \"orthographic\""), "{out}");
        let (_, e) = apply("version = 1\n[[sphere]]\n", &[o("sphere[3].radius=1")]).unwrap_err();
        assert!(e.contains("sphere[3]") && e.contains("has 1"), "{e}");
        let (_, e) = apply("version = 1\n", &[o("version.x=1")]).unwrap_err();
        assert!(e.contains("is a value"), "{e}");
        assert!("render.spp".parse::<Override>().is_err());
    }
}
