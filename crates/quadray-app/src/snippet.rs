//! The line an error points at, with a caret under the column, as compilers show it:
//!
//! ```text
//!  --> scenes/bad.toml:7:10
//!   |
//! 7 | radius = -2
//!   |          ^
//! ```

use quadray_loader::{LoadError, LoadErrorKind, Location};
use std::path::Path;

/// Characters of a long line shown around the column (JSON files are often one line).
const WINDOW: usize = 100;

/// The snippet for the innermost located loader error in `err`'s chain, if the file can be read
/// again (text files up to the scene-file limit).
pub fn for_error(err: &anyhow::Error) -> Option<String> {
    let load = err.chain().find_map(|e| e.downcast_ref::<LoadError>())?;
    let (path, location) = innermost(load)?;
    let bytes =
        quadray_loader::read_limited::read(path, quadray_loader::read_limited::MAX_SCENE_BYTES)
            .ok()?;
    let text = String::from_utf8_lossy(&bytes);
    let line = text.lines().nth(location.line.checked_sub(1)?)?;
    Some(render(path, location, line))
}

/// The deepest error with a location: an include's own problem rather than the include key.
fn innermost(e: &LoadError) -> Option<(&Path, Location)> {
    if let LoadErrorKind::Include { source, .. } = &e.kind
        && let Some(found) = innermost(source)
    {
        return Some(found);
    }
    e.location.map(|l| (e.path.as_path(), l))
}

/// Formats the snippet: a window of the line around the column, tabs shown as spaces.
fn render(path: &Path, location: Location, line: &str) -> String {
    let chars: Vec<char> = line
        .chars()
        .map(|c| if c == '\t' { ' ' } else { c })
        .collect();
    let column = location.column.saturating_sub(1).min(chars.len());
    let start = column.saturating_sub(WINDOW / 2);
    let end = (start + WINDOW).min(chars.len());
    let mut shown: String = chars[start..end].iter().collect();
    let mut caret = column - start;
    if start > 0 {
        shown.insert(0, '…');
        caret += 1;
    }
    if end < chars.len() {
        shown.push('…');
    }
    let number = location.line.to_string();
    let pad = " ".repeat(number.len());
    format!(
        "{pad}--> {}:{}:{}\n{pad} |\n{number} | {shown}\n{pad} | {}^",
        path.display(),
        location.line,
        location.column,
        " ".repeat(caret)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_caret_sits_under_the_column() {
        let s = render(
            Path::new("a.toml"),
            Location {
                line: 7,
                column: 10,
            },
            "radius = -2",
        );
        assert_eq!(s, " --> a.toml:7:10\n  |\n7 | radius = -2\n  |          ^");
    }

    #[test]
    fn long_lines_are_windowed_around_the_column() {
        let line = "x".repeat(1000) + "!" + &"y".repeat(1000);
        let s = render(
            Path::new("a.gltf"),
            Location {
                line: 1,
                column: 1001,
            },
            &line,
        );
        let lines: Vec<&str> = s.lines().collect();
        let caret = lines[3].find('^').unwrap();
        assert_eq!(lines[2].chars().nth(caret), Some('!'), "{s}");
        assert!(lines[2].chars().count() < 120);
    }
}
