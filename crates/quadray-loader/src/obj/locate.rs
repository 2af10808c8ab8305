//! Where in an OBJ file a problem is. tobj parses the file but reports errors without a line, so
//! when it fails (or when what it read cannot be used) these scans find the first statement at
//! fault. They are diagnostics only, run on error paths, except [`oversized_face`], which guards
//! the parse itself.

/// Most vertices one OBJ face may have. A polygon is triangulated as a fan of slivers that all
/// share its first vertex, on which the BVH builder's nearest-neighbour merging grows
/// quadratically (a 100 000-vertex face took 17 s); 16 384 build in well under a second.
pub const MAX_FACE_VERTICES: usize = 16_384;

/// The first face with more than [`MAX_FACE_VERTICES`] vertices: its 1-based line and size.
pub(crate) fn oversized_face(bytes: &[u8]) -> Option<(usize, usize)> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .find_map(|(i, line)| {
            let rest = line.strip_prefix(b"f")?;
            if !rest.first().is_some_and(|b| b.is_ascii_whitespace()) {
                return None;
            }
            let count = rest
                .split(|b| b.is_ascii_whitespace())
                .filter(|t| !t.is_empty())
                .count();
            (count > MAX_FACE_VERTICES).then_some((i + 1, count))
        })
}

/// A located problem: the 1-based line and what is wrong there.
pub(crate) type Located = (usize, String);

/// The statements of `text` as (1-based line, keyword, the words after it).
fn statements(text: &str) -> impl Iterator<Item = (usize, &str, Vec<&str>)> {
    text.lines().enumerate().filter_map(|(n, line)| {
        let mut words = line.split_whitespace();
        let keyword = words.next()?;
        Some((n + 1, keyword, words.collect()))
    })
}

/// The first statement that tobj's error `e` is about, with a message saying what is wrong.
pub(crate) fn locate_parse_error(bytes: &[u8], e: &tobj::LoadError) -> Option<Located> {
    use tobj::LoadError as T;
    match e {
        T::FaceVertexOutOfBounds
        | T::FaceTexCoordOutOfBounds
        | T::FaceNormalOutOfBounds
        | T::FaceColorOutOfBounds => locate_bad_index(bytes),
        T::PositionParseError | T::ScalingByZeroError | T::ColorParseError => locate_bad_numbers(
            bytes,
            "v",
            "a vertex (v) needs x y z, optionally w or r g b",
        ),
        T::NormalParseError => locate_bad_numbers(bytes, "vn", "a normal (vn) needs x y z"),
        T::TexcoordParseError => locate_bad_numbers(
            bytes,
            "vt",
            "a texture coordinate (vt) needs u v, optionally w",
        ),
        T::FaceParseError => locate_bad_face(bytes),
        // tobj's polygon of no corners: an `f` with nothing after it.
        T::InvalidPolygon => {
            statements(&String::from_utf8_lossy(bytes)).find_map(|(line, k, words)| {
                (k == "f" && words.is_empty())
                    .then(|| (line, "a face (f) with no corners".to_string()))
            })
        }
        _ => None,
    }
}

/// The first `keyword` statement whose numbers are not what `expected` describes.
fn locate_bad_numbers(bytes: &[u8], keyword: &str, expected: &str) -> Option<Located> {
    let text = String::from_utf8_lossy(bytes);
    let allowed: &[usize] = match keyword {
        "v" => &[3, 4, 6],
        "vt" => &[2, 3],
        _ => &[3],
    };
    statements(&text).find_map(|(line, k, words)| {
        if k != keyword {
            return None;
        }
        let parsed: Result<Vec<f32>, _> = words.iter().map(|w| w.parse::<f32>()).collect();
        let problem = match parsed {
            Err(_) => {
                let bad = words.iter().find(|w| w.parse::<f32>().is_err())?;
                format!("`{bad}` is not a number; {expected}")
            }
            Ok(values) if !allowed.contains(&values.len()) => {
                format!("{} numbers; {expected}", values.len())
            }
            Ok(values) if keyword == "v" && values.len() == 4 && values[3] == 0.0 => {
                "the vertex's w is 0 (it divides x, y and z)".to_string()
            }
            Ok(_) => return None,
        };
        Some((line, problem))
    })
}

/// The first face whose corners are not `v`, `v/vt`, `v//vn` or `v/vt/vn` integers.
fn locate_bad_face(bytes: &[u8]) -> Option<Located> {
    let text = String::from_utf8_lossy(bytes);
    statements(&text).find_map(|(line, k, words)| {
        if k != "f" {
            return None;
        }
        let bad = words.iter().find(|corner| {
            let fields: Vec<&str> = corner.split('/').collect();
            fields.len() > 3
                || fields[0].is_empty()
                || fields
                    .iter()
                    .any(|f| !f.is_empty() && f.parse::<i64>().is_err())
        })?;
        Some((
            line,
            format!("face corner `{bad}` is not v, v/vt, v//vn or v/vt/vn (whole numbers)"),
        ))
    })
}

/// The first face-index statement whose index refers to an element not defined before it.
fn locate_bad_index(bytes: &[u8]) -> Option<Located> {
    let text = String::from_utf8_lossy(bytes);
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    for (line, keyword, words) in statements(&text) {
        match keyword {
            "v" => v += 1,
            "vt" => vt += 1,
            "vn" => vn += 1,
            "f" => {
                for corner in words {
                    for (slot, field) in corner.split('/').enumerate() {
                        let (count, what) = match slot {
                            0 => (v, "vertices (v)"),
                            1 => (vt, "texture coordinates (vt)"),
                            _ => (vn, "normals (vn)"),
                        };
                        let Ok(i) = field.parse::<i64>() else {
                            continue;
                        };
                        let resolved = if i < 0 { count + 1 + i } else { i };
                        if !(1..=count).contains(&resolved) {
                            return Some((
                                line,
                                format!(
                                    "face index {i} is out of range: {count} {what} are defined before this line"
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// The first vertex position or colour (`v`), normal (`vn`) or texture coordinate (`vt`) that is
/// not a finite 32-bit number (NaN, infinity, or a value beyond ±3.4e38 that rounds to
/// infinity), which tobj reads without complaint; with the statement's keyword.
pub(crate) fn locate_non_finite(bytes: &[u8]) -> Option<(&'static str, Located)> {
    let text = String::from_utf8_lossy(bytes);
    statements(&text).find_map(|(line, k, words)| {
        let (keyword, what) = match k {
            "v" => ("v", "vertex coordinate or colour"),
            "vn" => ("vn", "normal component"),
            "vt" => ("vt", "texture coordinate"),
            _ => return None,
        };
        let bad = words
            .iter()
            .find(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite()))?;
        let message = format!(
            "{what} `{bad}` is not a finite 32-bit number (meshes store f32; |x| must stay below \
             3.4e38)"
        );
        Some((keyword, (line, message)))
    })
}

/// The first vertex (`v`) with a coordinate (one of its first three numbers) beyond `limit` in
/// magnitude.
pub(crate) fn locate_far_vertex(bytes: &[u8], limit: f32) -> Option<Located> {
    let text = String::from_utf8_lossy(bytes);
    statements(&text).find_map(|(line, k, words)| {
        if k != "v" {
            return None;
        }
        let bad = (words.iter().take(3)).find(|w| w.parse::<f32>().is_ok_and(|x| x.abs() > limit))?;
        let message = format!(
            "vertex coordinate `{bad}` lies past quadray's limit of ±{limit:e} for coordinates (its \
             BVHs use f32 boxes)"
        );
        Some((line, message))
    })
}

/// The first face corner with an index of 0, which OBJ does not have (indices count from 1, or
/// back from -1); tobj reads a texture or normal index 0 without complaint.
pub(crate) fn locate_zero_index(bytes: &[u8]) -> Option<Located> {
    // Most files have no `/0` at all: scan the bytes before splitting lines.
    if !bytes.windows(2).any(|w| w == b"/0") {
        return None;
    }
    let text = String::from_utf8_lossy(bytes);
    statements(&text).find_map(|(line, k, words)| {
        if k != "f" {
            return None;
        }
        let bad = words
            .iter()
            .find(|corner| corner.split('/').any(|f| f.parse::<i64>() == Ok(0)))?;
        Some((
            line,
            format!(
                "face corner `{bad}` has an index 0; OBJ indices count from 1 (or back from -1)"
            ),
        ))
    })
}

/// The material names `usemtl` statements give that are not in `defined`, each once, in order of
/// first use (for the warning about faces that fall back to a default material).
pub(crate) fn undefined_materials(bytes: &[u8], defined: &[&str]) -> Vec<String> {
    let text = String::from_utf8_lossy(bytes);
    let mut undefined: Vec<String> = Vec::new();
    for (_, keyword, words) in statements(&text) {
        if keyword == "usemtl"
            && let Some(name) = words.first()
            && !defined.contains(name)
            && !undefined.iter().any(|u| u == name)
        {
            undefined.push(name.to_string());
        }
    }
    undefined
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_are_located_on_their_line() {
        let t = tobj::LoadError::PositionParseError;
        let (line, m) = locate_parse_error(b"v 0 0 0\nv 1 zero 0\n", &t).unwrap();
        assert_eq!(line, 2);
        assert!(m.contains("`zero` is not a number"), "{m}");
        let (line, m) = locate_parse_error(b"v 0 0\n", &t).unwrap();
        assert_eq!(line, 1);
        assert!(m.contains("2 numbers"), "{m}");
        let f = tobj::LoadError::FaceParseError;
        let (line, m) = locate_parse_error(b"v 0 0 0\n\nf 1 a/2 3\n", &f).unwrap();
        assert_eq!(line, 3);
        assert!(m.contains("`a/2`"), "{m}");
        let vt = tobj::LoadError::TexcoordParseError;
        assert_eq!(locate_parse_error(b"vt 0\n", &vt).unwrap().0, 1);
    }

    #[test]
    fn undefined_materials_are_named_once() {
        let text = b"usemtl red\nusemtl blue\nusemtl blue\nusemtl green\n";
        assert_eq!(undefined_materials(text, &["red"]), ["blue", "green"]);
    }

    #[test]
    fn far_vertices_are_located() {
        let text = b"v 0 0 0\nvn 2e31 0 1\nv 1 -2e31 0 0.5 0.5 0.5\n";
        let (line, message) = locate_far_vertex(text, 1e30).unwrap();
        assert_eq!(line, 3);
        assert!(message.contains("`-2e31`"), "{message}");
        // A colour past the limit is not a coordinate; within it, nothing is found.
        assert!(locate_far_vertex(b"v 0 0 0 2e31 0 0\n", 1e30).is_none());
        assert!(locate_far_vertex(b"v 1e30 0 0\n", 1e30).is_none());
    }

    #[test]
    fn non_finite_numbers_are_located() {
        let (keyword, (line, m)) = locate_non_finite(b"v 0 0 0\nv 1e300 0 0\n").unwrap();
        assert_eq!((keyword, line), ("v", 2));
        assert!(m.contains("`1e300`"), "{m}");
        assert!(locate_non_finite(b"v 0 0 0\nv 1e30 0 0\n").is_none());
        let (keyword, (line, _)) = locate_non_finite(b"v 0 0 0\nvt 0 0\nvn 0 inf 1\n").unwrap();
        assert_eq!((keyword, line), ("vn", 3));
        let (keyword, _) = locate_non_finite(b"vt nan 0\n").unwrap();
        assert_eq!(keyword, "vt");
    }

    #[test]
    fn zero_indices_are_located() {
        let (line, m) = locate_zero_index(b"v 0 0 0\nf 1/1 2/1 3/1\nf 1//0 2//1 3//1\n").unwrap();
        assert_eq!(line, 3);
        assert!(m.contains("`1//0`"), "{m}");
        assert!(locate_zero_index(b"f 1/10 2/20 3/30\n").is_none());
    }
}
