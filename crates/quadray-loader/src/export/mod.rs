//! Writing a scene as glTF 2.0 (`.gltf` with a `.bin` beside it, or `.glb`), analytic shapes as
//! `QUADRAY_quadrics` shapes with tessellated fallback meshes, so quadray scenes open in other
//! tools and read back into quadray exactly.
//!
//! Layout of the file written:
//! - One root node, "quadray (z up)", whose matrix turns quadray's z-up world into glTF's y-up
//!   one (exactly: its entries are 0 and ±1); every other node is its child and keeps quadray's
//!   coordinates.
//! - A mesh node per quadray mesh (vertices in world space), a node per quadric (matrix = its
//!   placement, fallback mesh in its object frame), per sphere (translation) and per plane (its
//!   frame; the fallback is a square as large as the scene), a node for the camera and one per
//!   light (KHR_lights_punctual; intensities times 683·π, the inverse of the import).
//! - Materials carry a pbrMetallicRoughness approximation for other viewers and quadray's exact
//!   parameters in `extensions.QUADRAY_quadrics.whitted`; image textures are written as PNG from
//!   the original 8-bit codes, so nothing is lost.
//! - Both extensions are listed in `extensionsUsed` only, never `extensionsRequired`.
//!
//! The background colour and the render settings have no place in glTF; they are kept as
//! application data in the scene's `extras.quadray`, which quadray reads back and others ignore.

mod document;
mod lights;
mod shapes;

pub use shapes::MAX_EXPORT_NODES;

use crate::export::document::{Document, looking, set_matrix};
use crate::export::shapes::ShapeWriter;
use crate::framing::geometry_bounds;
use crate::gltf::quadrics_ext::{self, NodeExtension, RootExtension, ShapeDef};
use crate::native::LoadedScene;
use crate::tessellate;
use glam::{DAffine3, DMat3};
use quadray::Projection;
use quadray::math::orthonormal_basis;
use serde_json::json;
use std::path::{Path, PathBuf};

/// Why a scene could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The output file (or its .bin) could not be written.
    // The cause is the error's source, not repeated in its own message: a chain printed whole
    // (`{:#}`) would say it twice.
    #[error("cannot write `{}`", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The output name does not end in .gltf or .glb.
    #[error("`{}`: the output must end in .gltf or .glb", .0.display())]
    Extension(PathBuf),
    /// Something in the scene cannot be written.
    #[error("{0}")]
    Unsupported(String),
}

/// Writes `scene` to `out` (`.gltf` + `.bin` beside it, or `.glb`); returns notes on what other
/// viewers will see differently.
pub fn export_gltf(scene: &LoadedScene, out: &Path) -> Result<Vec<String>, ExportError> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let binary = match ext.as_deref() {
        Some("glb") => true,
        Some("gltf") => false,
        _ => return Err(ExportError::Extension(out.to_path_buf())),
    };
    let d = &scene.description;
    let mut doc = Document::default();
    let mut notes = Vec::new();
    let mut children = Vec::new();

    for (i, m) in d.materials.iter().enumerate() {
        let name = scene
            .material_names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("material {i}"));
        let v = doc.material(&name, m)?;
        doc.materials.push(v);
    }
    // glTF needs a material for fallback meshes whose shape names none; quadray shapes always have one.
    let g = &d.geometry;
    let extent = geometry_bounds(g)
        .map(|(lo, hi)| (hi - lo).length().max(lo.abs().max(hi.abs()).max_element()))
        .unwrap_or(10.0)
        .max(1.0);

    // Meshes, quadrics, spheres and instances (prototypes written once: shapes.rs).
    children.extend(ShapeWriter::new(g).level_nodes(&mut doc, 0, None)?);
    let normal_mapped = (0..g.level_count())
        .flat_map(|l| g.level(l).meshes)
        .filter(|m| m.normal_map().is_some())
        .count();
    if normal_mapped > 0 {
        notes.push(format!(
            "{normal_mapped} normal-mapped meshes are written without their normal maps (not exported yet)"
        ));
    }
    children.extend(plane_nodes(&mut doc, g, extent, &mut notes)?);

    let cam = &d.camera;
    children.push(camera_node(&mut doc, scene, extent));
    children.extend(lights::light_nodes(&mut doc, &d.lights, cam.to, &mut notes));

    // quadray (x, y, z) → glTF (x, z, −y): columns are the images of x, y and z.
    let root = doc.node(json!({
        "name": "quadray (z up)",
        "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        "children": children,
    }));
    // Not glTF content: quadray's own settings, as application data other tools ignore.
    let hints = quadrics_ext::RenderHints {
        background: Some(d.background.to_array()),
        environment: d.environment.map(|e| e.to_array()),
        resolution: Some([scene.settings.width, scene.settings.height]),
        spp: Some(scene.settings.spp),
        max_depth: Some(scene.settings.max_depth),
    };

    let gltf = document_json(&mut doc, root, hints, binary, out)?;
    write_files(&gltf, &doc.bin, binary, out)?;
    Ok(notes)
}

/// The nodes of the scene's infinite planes: each a `plane` shape with a square fallback mesh of
/// side 4·`extent` for other viewers.
fn plane_nodes(
    doc: &mut Document,
    g: &quadray::Geometry,
    extent: f64,
    notes: &mut Vec<String>,
) -> Result<Vec<usize>, ExportError> {
    let mut children = Vec::new();
    if !g.planes.is_empty() {
        notes.push(format!(
            "infinite planes get a square of side {:.4} as their fallback mesh in other viewers",
            4.0 * extent
        ));
    }
    for (i, p) in g.planes.iter().enumerate() {
        let name = format!("plane {i}");
        let material = p.material as usize;
        let mesh = doc.fallback(&name, &tessellate::square(2.0 * extent), material);
        doc.shapes.push(ShapeDef {
            kind: "plane".into(),
            name: Some(name.clone()),
            material: Some(material),
            ..ShapeDef::default()
        });
        let (u, v) = orthonormal_basis(p.normal);
        let frame = DAffine3::from_mat3_translation(DMat3::from_cols(u, v, p.normal), p.point);
        let mut node = json!({
            "name": name,
            "extensions": {quadrics_ext::EXTENSION: NodeExtension { shape: doc.shapes.len() - 1, extensions: None, extras: None }},
        });
        set_matrix(&mut node, &frame);
        if let Some(mesh) = mesh {
            node["mesh"] = json!(mesh);
        }
        children.push(doc.node(node));
    }

    Ok(children)
}

/// The camera and its node (glTF cameras look down their −z with +y up).
fn camera_node(doc: &mut Document, scene: &LoadedScene, extent: f64) -> usize {
    let cam = &scene.description.camera;
    let aspect = scene.settings.width as f64 / scene.settings.height.max(1) as f64;
    let camera = match cam.projection {
        Projection::Perspective { vfov_deg } => json!({
            "name": "camera",
            "type": "perspective",
            "perspective": {"yfov": vfov_deg.to_radians(), "aspectRatio": aspect, "znear": 1e-3 * extent}
        }),
        Projection::Orthographic { height } => json!({
            "name": "camera",
            "type": "orthographic",
            "orthographic": {"xmag": height * 0.5 * aspect, "ymag": height * 0.5, "znear": 0.0, "zfar": 1e4 * extent}
        }),
    };
    doc.cameras.push(camera);
    let view = looking(cam.from, cam.to - cam.from, cam.up);
    let mut camera_node = json!({"name": "camera", "camera": 0});
    set_matrix(&mut camera_node, &view);
    doc.node(camera_node)
}

/// The glTF JSON of `doc` under the node `root`, with quadray's render `hints` and, for a `.gltf`,
/// the `.bin` beside `out` named as its buffer's URI. Takes the document's lists.
fn document_json(
    doc: &mut Document,
    root: usize,
    hints: quadrics_ext::RenderHints,
    binary: bool,
    out: &Path,
) -> Result<serde_json::Value, ExportError> {
    let mut used = vec![quadrics_ext::EXTENSION];
    if !doc.lights.is_empty() {
        used.push("KHR_lights_punctual");
    }
    if doc.emissive_strength {
        used.push(crate::gltf::material::EMISSIVE_STRENGTH);
    }
    if doc.transmission {
        used.extend([
            crate::gltf::transmission::TRANSMISSION,
            crate::gltf::transmission::IOR,
        ]);
    }
    if doc.volume {
        used.push(crate::gltf::transmission::VOLUME);
    }
    let root_ext = RootExtension {
        shapes: std::mem::take(&mut doc.shapes),
        extensions: None,
        extras: None,
    };
    let mut extensions = json!({quadrics_ext::EXTENSION: root_ext});
    if !doc.lights.is_empty() {
        extensions["KHR_lights_punctual"] = json!({"lights": std::mem::take(&mut doc.lights)});
    }
    let bin_path = out.with_extension("bin");
    let mut buffer = json!({"byteLength": doc.bin.len()});
    if !binary {
        let name = bin_path
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| ExportError::Unsupported("the output name is not valid UTF-8".into()))?;
        buffer["uri"] = json!(percent_encoding::utf8_percent_encode(name, URI_UNSAFE).to_string());
    }
    let mut gltf = json!({
        "asset": {"version": "2.0", "generator": concat!("quadray ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": used,
        "extensions": extensions,
        "scene": 0,
        "scenes": [{"name": "quadray scene", "nodes": [root], "extras": {"quadray": hints}}],
        "nodes": std::mem::take(&mut doc.nodes),
        "meshes": std::mem::take(&mut doc.meshes),
        "materials": std::mem::take(&mut doc.materials),
        "cameras": std::mem::take(&mut doc.cameras),
        "buffers": [buffer],
        "bufferViews": std::mem::take(&mut doc.buffer_views),
        "accessors": std::mem::take(&mut doc.accessors),
    });
    for (key, list) in [
        ("images", std::mem::take(&mut doc.images)),
        ("samplers", std::mem::take(&mut doc.samplers)),
        ("textures", std::mem::take(&mut doc.textures)),
    ] {
        if !list.is_empty() {
            gltf[key] = json!(list);
        }
    }
    Ok(gltf)
}

/// Writes `gltf` and its binary buffer `bin` to `out`: one `.glb`, or a `.gltf` with a `.bin`
/// beside it, each atomically.
fn write_files(
    gltf: &serde_json::Value,
    bin: &[u8],
    binary: bool,
    out: &Path,
) -> Result<(), ExportError> {
    let bin_path = out.with_extension("bin");
    let text =
        serde_json::to_vec_pretty(gltf).map_err(|e| ExportError::Unsupported(e.to_string()))?;
    if binary {
        write_atomically(out, &glb(&text, bin))
    } else {
        // The pair is replaced together: a .gltf that cannot be written leaves the old .bin.
        let files: [(&Path, &[u8]); 2] = [(&bin_path, bin), (out, &text)];
        crate::atomic_file::replace_all(&files)
            .map_err(|(path, source)| ExportError::Io { path, source })
    }
}

/// Characters escaped in the .bin file name written as a URI.
const URI_UNSAFE: &percent_encoding::AsciiSet = &percent_encoding::CONTROLS
    .add(b' ')
    .add(b'"')
    .add(b'#')
    .add(b'%')
    .add(b'<')
    .add(b'>')
    .add(b'?')
    .add(b'\\')
    .add(b'`')
    .add(b'{')
    .add(b'}');

pub(crate) fn describe(q: &quadray::Quadric) -> String {
    match q.surface_description() {
        quadray::QuadricSurface::Canonical { kind, .. } => kind.name().to_string(),
        quadray::QuadricSurface::General(_) => "general".to_string(),
    }
}

/// A GLB container: header, JSON chunk padded with spaces, BIN chunk padded with zeros.
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let json_len = json.len().next_multiple_of(4);
    let bin_len = bin.len().next_multiple_of(4);
    let total = 12 + 8 + json_len + if bin.is_empty() { 0 } else { 8 + bin_len };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.resize(12 + 8 + json_len, b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    out
}

/// Writes `bytes` to a temporary name beside `path`, then renames it into place, so a failed
/// write never leaves a truncated file under the real name.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), ExportError> {
    crate::atomic_file::replace(path, bytes).map_err(|source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests;
