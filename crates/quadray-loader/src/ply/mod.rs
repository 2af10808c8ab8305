//! Spheres from the vertices of a PLY file (`[[spheres]] path = "atoms.ply"` in a native scene):
//! particle and molecular data sets of millions of spheres, read at the speed of the disk.
//!
//! The file's `vertex` element gives one sphere a vertex: its centre from the `x`, `y`, `z`
//! properties (any numeric type), its radius from an optional `radius` property, its colour from
//! optional `red`, `green`, `blue` properties (`uchar`: 8-bit sRGB codes, decoded to linear;
//! `float` or `double`: linear values). Other elements and properties are skipped. ASCII, binary
//! little-endian and binary big-endian files are read, by the `ply-rs-bw` crate, one vertex at a
//! time into a small fixed struct (no map per vertex, no list of vertices: each vertex goes
//! straight to its caller).
//!
//! The file is read through [`crate::read_limited`] (regular files only, within
//! [`MAX_SPHERE_FILE_BYTES`], inside the confinement folder). Every problem is an error naming the
//! file and, for a vertex, its index (`vertex[17].radius`) and, in an ASCII file, its line.

use crate::error::{LoadError, LoadErrorKind, Location};
use glam::{DVec3, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};
use std::collections::HashSet;
use std::io::BufRead;
use std::path::{Path, PathBuf};

#[cfg(test)]
mod tests;

/// Largest PLY file of spheres read: 4 GiB (10^8 spheres of three floats).
pub const MAX_SPHERE_FILE_BYTES: u64 = 4 << 30;

/// Most spheres reserved for before the vertices are read, when their count is only a claim.
const MAX_GUESS: usize = 1 << 16;

/// The colour properties, in channel order.
const COLOUR_NAMES: [&str; 3] = ["red", "green", "blue"];

/// One vertex of the file, as a sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereVertex {
    /// Centre, in the file's coordinates.
    pub center: DVec3,
    /// Radius: the vertex's own, or the default the caller gave.
    pub radius: f64,
    /// Linear RGB colour, when the file has colour properties.
    pub colour: Option<Vec3>,
}

/// A PLY file whose header has been read and checked: ready to hand out its vertices.
#[derive(Debug)]
pub struct SphereFile {
    path: PathBuf,
    bytes: Vec<u8>,
    header: Header,
    /// Where the body starts in `bytes`, and the line it starts on (1-based).
    body: (usize, usize),
    /// Index of the `vertex` element among the header's elements.
    vertex_element: usize,
    radii: Radii,
    has_colour: bool,
}

/// Where the spheres' radii come from.
#[derive(Clone, Copy, Debug)]
enum Radii {
    /// The vertices' `radius` property.
    PerVertex,
    /// One radius for all (the file has no `radius` property).
    Default(f64),
}

impl SphereFile {
    /// Reads the file at `path` and checks its header: a `vertex` element with numeric `x`, `y`,
    /// `z`; `radius` numeric if present, else `default_radius` must be given; `red`, `green`,
    /// `blue` all or none, each `uchar`, `float` or `double`; a binary body long enough for the
    /// vertices the header declares.
    pub fn read(path: &Path, default_radius: Option<f64>) -> Result<SphereFile, LoadError> {
        let bytes = crate::read_limited::read(path, MAX_SPHERE_FILE_BYTES)
            .map_err(|e| LoadError::new(path, None, LoadErrorKind::Io(e)))?;
        let mut rest: &[u8] = &bytes;
        let mut reader = Reader::new(&mut rest);
        let header = Parser::<SkippedElement>::new()
            .read_header(&mut reader)
            .map_err(|e| {
                let location = e.line().map(|line| Location { line, column: 1 });
                LoadError::new(
                    path,
                    location,
                    LoadErrorKind::Syntax(format!("not a PLY header: {}", first_line(&e))),
                )
            })?;
        let body_start = bytes.len() - rest.len();
        let body_line = bytes[..body_start].iter().filter(|&&b| b == b'\n').count() + 1;
        check_declarations(
            &bytes[..body_start],
            (header.version.major, header.version.minor),
        )
        .map_err(|(line, message)| {
            let location = Some(Location { line, column: 1 });
            LoadError::new(path, location, LoadErrorKind::Syntax(message))
        })?;
        let invalid = |key: &str, message: String| LoadError::invalid(path, None, key, message);
        let vertex_element = header
            .elements
            .get_index_of("vertex")
            .ok_or_else(|| invalid("vertex", "the file has no `vertex` element".into()))?;
        let def = &header.elements[vertex_element];
        let scalar = |name: &str| match def.properties.get(name).map(|p| &p.data_type) {
            None => Ok(None),
            Some(PropertyType::Scalar(t)) => Ok(Some(t.clone())),
            Some(PropertyType::List(..)) => Err(invalid(
                &format!("vertex.{name}"),
                "must be a number, not a list".into(),
            )),
        };
        for name in ["x", "y", "z"] {
            if scalar(name)?.is_none() {
                return Err(invalid(
                    &format!("vertex.{name}"),
                    format!("the vertex element has no `{name}` property"),
                ));
            }
        }
        let radii = match (scalar("radius")?, default_radius) {
            (Some(_), _) => Radii::PerVertex,
            (None, Some(r)) => Radii::Default(r),
            (None, None) => {
                return Err(invalid(
                    "vertex.radius",
                    "the vertex element has no `radius` property: give the scene's table a \
                     `radius` for every sphere"
                        .into(),
                ));
            }
        };
        let colour_types = COLOUR_NAMES.map(scalar);
        let mut given = Vec::new();
        for (name, t) in COLOUR_NAMES.iter().zip(colour_types) {
            match t? {
                None => {}
                Some(ScalarType::UChar | ScalarType::Float | ScalarType::Double) => {
                    given.push(*name)
                }
                Some(other) => {
                    return Err(invalid(
                        &format!("vertex.{name}"),
                        format!(
                            "a colour is uchar (8-bit sRGB) or float/double (linear), not {other:?}"
                        ),
                    ));
                }
            }
        }
        if !given.is_empty() && given.len() < 3 {
            let missing = COLOUR_NAMES
                .iter()
                .find(|n| !given.contains(n))
                .unwrap_or(&"");
            return Err(invalid(
                &format!("vertex.{missing}"),
                format!(
                    "the vertex element has {} but not `{missing}`: give all of red, green, blue or none",
                    given.join(", ")
                ),
            ));
        }
        let file = SphereFile {
            path: path.to_path_buf(),
            header,
            body: (body_start, body_line),
            vertex_element,
            radii,
            has_colour: given.len() == 3,
            bytes,
        };
        file.check_binary_length()?;
        Ok(file)
    }

    /// Whether the vertices carry their own radii (a `radius` property).
    pub fn has_radius(&self) -> bool {
        matches!(self.radii, Radii::PerVertex)
    }

    /// How many spheres to reserve room for: the vertex count of a binary file whose rows have a
    /// fixed size (its length was checked against the count), else at most [`MAX_GUESS`] (an
    /// ASCII file's count is only a claim until its lines are read, and a header claiming 10^12
    /// vertices must not reserve room for them).
    pub fn capacity(&self) -> usize {
        let def = &self.header.elements[self.vertex_element];
        let exact = self.header.encoding != Encoding::Ascii
            && self
                .header
                .elements
                .iter()
                .take(self.vertex_element + 1)
                .all(|(_, d)| row_bytes(d).is_some());
        if exact {
            def.count
        } else {
            def.count.min(MAX_GUESS)
        }
    }

    /// A binary body shorter than its elements up to the vertices need (when their rows have a
    /// fixed size) is an error before anything is read.
    fn check_binary_length(&self) -> Result<(), LoadError> {
        if self.header.encoding == Encoding::Ascii {
            return Ok(());
        }
        let mut needed: u128 = 0;
        for (_, def) in self.header.elements.iter().take(self.vertex_element + 1) {
            let Some(row) = row_bytes(def) else {
                return Ok(()); // Lists: only reading finds the end.
            };
            needed += row as u128 * def.count as u128;
        }
        let body = (self.bytes.len() - self.body.0) as u128;
        if needed > body {
            let def = &self.header.elements[self.vertex_element];
            return Err(LoadError::invalid(
                &self.path,
                None,
                "vertex",
                format!(
                    "the file is truncated: the header declares {} vertices, which need {needed} \
                     bytes after the header, and the file has {body}",
                    def.count
                ),
            ));
        }
        Ok(())
    }

    /// Hands every vertex, in file order, to `each` with its index; an error of `each` (a message)
    /// becomes an error naming the vertex.
    pub fn for_each(
        &self,
        mut each: impl FnMut(usize, SphereVertex) -> Result<(), String>,
    ) -> Result<(), LoadError> {
        let mut rest: &[u8] = &self.bytes[self.body.0..];
        let mut line = self.body.1;
        let skip = Parser::<SkippedElement>::new();
        let read = Parser::<RawVertex>::new();
        let mut text = String::new();
        for (index, (_, def)) in self.header.elements.iter().enumerate() {
            let is_vertex = index == self.vertex_element;
            if !is_vertex && self.header.encoding != Encoding::Ascii && def.properties.is_empty() {
                continue; // Nothing to read, however many the header declares.
            }
            for i in 0..def.count {
                let at = (self.header.encoding == Encoding::Ascii).then_some(line);
                // The key is built only for an error: no allocation a vertex.
                let key = || format!("{}[{i}]", def.name);
                let unreadable = |e: ply_rs_bw::parser::ParseError| {
                    let message = if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        format!(
                            "the file ends inside this element (the header declares {} `{}` elements)",
                            def.count, def.name
                        )
                    } else if self.header.encoding == Encoding::Ascii {
                        format!(
                            "the line does not hold the numbers the header declares ({})",
                            first_line(&e)
                        )
                    } else {
                        format!("cannot read the element: {}", first_line(&e))
                    };
                    self.error(at, &key(), message)
                };
                if self.header.encoding == Encoding::Ascii {
                    text.clear();
                    let n = rest.read_line(&mut text).map_err(|e| {
                        self.error(at, &key(), format!("cannot read the line: {e}"))
                    })?;
                    if n == 0 {
                        return Err(self.error(
                            at,
                            &key(),
                            format!(
                                "the file ends before this element (the header declares {} `{}` elements)",
                                def.count, def.name
                            ),
                        ));
                    }
                    line += 1;
                }
                let encoding = self.header.encoding;
                if !is_vertex {
                    read_row(&skip, encoding, &mut rest, &text, def).map_err(unreadable)?;
                    continue;
                }
                let raw = read_row(&read, encoding, &mut rest, &text, def).map_err(unreadable)?;
                let vertex = self.vertex(raw, i, at)?;
                each(i, vertex).map_err(|m| self.error(at, &key(), m))?;
            }
            if is_vertex {
                break; // Elements after the vertices are not needed.
            }
        }
        Ok(())
    }

    /// The checked sphere of vertex `i`.
    fn vertex(
        &self,
        raw: RawVertex,
        i: usize,
        at: Option<usize>,
    ) -> Result<SphereVertex, LoadError> {
        let check = |value: f64, name: &str| -> Result<(), LoadError> {
            let message = if !value.is_finite() {
                format!("must be a finite number, got {value}")
            } else if value.abs() > crate::native::MAX_NUMBER {
                crate::native::beyond_limit(value)
            } else {
                return Ok(());
            };
            Err(self.error(at, &format!("vertex[{i}].{name}"), message))
        };
        for (value, name) in raw.position.iter().zip(["x", "y", "z"]) {
            check(*value, name)?;
        }
        let radius = match self.radii {
            Radii::Default(r) => r,
            Radii::PerVertex => {
                check(raw.radius, "radius")?;
                if raw.radius <= 0.0 {
                    return Err(self.error(
                        at,
                        &format!("vertex[{i}].radius"),
                        format!("must be positive, got {}", raw.radius),
                    ));
                }
                raw.radius
            }
        };
        let colour = if self.has_colour {
            for (value, name) in raw.colour.iter().zip(COLOUR_NAMES) {
                check(*value as f64, name)?;
                if *value < 0.0 {
                    return Err(self.error(
                        at,
                        &format!("vertex[{i}].{name}"),
                        format!("colour components must be non-negative, got {value}"),
                    ));
                }
            }
            // `+ 0.0` turns a -0 into 0, so that equal colours have equal bits.
            Some(Vec3::from_array(raw.colour) + 0.0)
        } else {
            None
        };
        Ok(SphereVertex {
            center: DVec3::from_array(raw.position),
            radius,
            colour,
        })
    }

    /// An error about `key` of this file, at line `line` of an ASCII file.
    fn error(&self, line: Option<usize>, key: &str, message: String) -> LoadError {
        let location = line.map(|line| Location { line, column: 1 });
        LoadError::invalid(&self.path, location, key, message)
    }
}

/// What the PLY parser lets pass in a header (`header`, its text): a version other than 1.0, the
/// only one there is, and an element or a property declared twice, which the parser keeps once
/// while the rows still hold both, so every value after it would be read from the wrong place.
/// The error gives the line and the problem.
fn check_declarations(header: &[u8], (major, minor): (u16, u8)) -> Result<(), (usize, String)> {
    let lines = header
        .split(|&b| b == b'\n')
        .map(|l| String::from_utf8_lossy(l));
    let mut elements = HashSet::new();
    let mut properties = HashSet::new();
    let mut element = String::new();
    for (number, text) in (1..).zip(lines) {
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.as_slice() {
            ["format", _, version] if (major, minor) != (1, 0) => {
                return Err((number, format!("PLY version {version}: only 1.0 exists")));
            }
            ["element", name, ..] => {
                if !elements.insert(name.to_string()) {
                    return Err((number, format!("element `{name}` is declared twice")));
                }
                element = name.to_string();
                properties.clear();
            }
            ["property", .., name] if !properties.insert(name.to_string()) => {
                return Err((
                    number,
                    format!("property `{element}.{name}` is declared twice"),
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// One row of `def` read by `parser`: from `rest` in a binary file, from the line `text` already
/// taken from `rest` in an ASCII one.
fn read_row<P: PropertyAccess>(
    parser: &Parser<P>,
    encoding: Encoding,
    rest: &mut &[u8],
    text: &str,
    def: &ElementDef,
) -> Result<P, ply_rs_bw::parser::ParseError> {
    match encoding {
        Encoding::Ascii => parser.read_ascii_element(text, def),
        Encoding::BinaryLittleEndian => parser.read_little_endian_element(rest, def),
        Encoding::BinaryBigEndian => parser.read_big_endian_element(rest, def),
    }
}

/// The bytes of one row of `def` in a binary file, if all its properties are scalars.
fn row_bytes(def: &ElementDef) -> Option<usize> {
    def.properties
        .values()
        .map(|p| match p.data_type {
            PropertyType::Scalar(ref t) => Some(scalar_bytes(t)),
            PropertyType::List(..) => None,
        })
        .sum()
}

fn scalar_bytes(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The first line of a parser error, at most 200 characters (the rest repeats the line read,
/// which in a damaged file may be anything).
fn first_line(e: &ply_rs_bw::parser::ParseError) -> String {
    let text = e.to_string();
    let first = text.lines().next().unwrap_or_default();
    match first.char_indices().nth(200) {
        Some((cut, _)) => format!("{}…", &first[..cut]),
        None => first.to_string(),
    }
}

/// The properties of one vertex the spheres need, set by the parser property by property.
#[derive(Clone, Copy, Debug, Default)]
struct RawVertex {
    position: [f64; 3],
    radius: f64,
    /// Linear RGB.
    colour: [f32; 3],
}

impl RawVertex {
    /// Stores a number read for property `name`; colours are linear values here.
    fn number(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        match name {
            "x" => self.position[0] = value,
            "y" => self.position[1] = value,
            "z" => self.position[2] = value,
            "radius" => self.radius = value,
            "red" => self.colour[0] = value as f32,
            "green" => self.colour[1] = value as f32,
            "blue" => self.colour[2] = value as f32,
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for RawVertex {
    fn new() -> Self {
        RawVertex::default()
    }
    fn set_char(&mut self, name: &str, value: i8) -> PropertyAccessResult {
        self.number(name, value.into())
    }
    /// An 8-bit colour is an sRGB code (as image files store them); anything else a number.
    fn set_uchar(&mut self, name: &str, value: u8) -> PropertyAccessResult {
        match COLOUR_NAMES.iter().position(|n| *n == name) {
            Some(c) => {
                self.colour[c] = quadray::colour::decode_srgb8(value);
                PropertyAccessResult::Set
            }
            None => self.number(name, value.into()),
        }
    }
    fn set_short(&mut self, name: &str, value: i16) -> PropertyAccessResult {
        self.number(name, value.into())
    }
    fn set_ushort(&mut self, name: &str, value: u16) -> PropertyAccessResult {
        self.number(name, value.into())
    }
    fn set_int(&mut self, name: &str, value: i32) -> PropertyAccessResult {
        self.number(name, value.into())
    }
    fn set_uint(&mut self, name: &str, value: u32) -> PropertyAccessResult {
        self.number(name, value.into())
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.number(name, value.into())
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.number(name, value)
    }
}

/// An element the spheres do not use (faces, edges, …): read past, nothing kept.
#[derive(Clone, Copy, Debug)]
struct SkippedElement;

impl PropertyAccess for SkippedElement {
    fn new() -> Self {
        SkippedElement
    }
}
