//! Opening a glTF file: the GLB container, the JSON checks quadray makes before the gltf crate
//! sees it (version, required extensions), validation, and the buffers it refers to (read as
//! [`super::resources`] reads URIs).
//!
//! The GLB container and the URIs are handled here rather than by the gltf crate's importer,
//! because that importer panics on malformed input (a GLB header shorter than itself, an invalid
//! percent-encoded URI) and fails a whole file over one missing texture, which quadray reports
//! as a warning instead.

use super::resources::{UriError, read_uri};
use crate::error::{LoadError, LoadErrorKind, Location};
use glam::{DAffine3, DMat4, DQuat, DVec3};
use gltf::json::Value;
use std::path::{Path, PathBuf};

/// Extensions quadray can honour when a file requires them.
pub const SUPPORTED_REQUIRED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    "KHR_texture_transform",
    crate::gltf::quadrics_ext::EXTENSION,
];

/// A glTF document with its binary buffers, ready to convert.
#[derive(Debug)]
pub struct GltfFile {
    /// The validated document.
    pub document: gltf::Document,
    /// Buffer contents, by buffer index.
    pub buffers: Vec<Vec<u8>>,
    /// The folder relative URIs resolve against.
    pub base: PathBuf,
    /// Each node's local transform, read from the JSON in f64 (the gltf crate keeps f32, which
    /// would blur quadric placements written by quadray); an error says what is wrong with it.
    pub node_transforms: Vec<Result<DAffine3, String>>,
    /// Each scene's `extras.quadray` object, if any (kept here: the gltf crate drops extras).
    pub scene_extras: Vec<Option<Value>>,
    /// Each camera's JSON, for its parameters in f64 (the gltf crate keeps f32, which would move a
    /// converted scene's silhouettes by a pixel here and there).
    pub cameras: Vec<Value>,
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Reads the glTF or GLB file at `path`, with its buffers.
pub fn open(path: &Path) -> Result<GltfFile, LoadError> {
    let bytes = crate::read_limited::read(path, crate::read_limited::MAX_MESH_BYTES)
        .map_err(|e| LoadError::new(path, None, LoadErrorKind::Io(e)))?;
    open_bytes(&bytes, path)
}

/// Parses glTF or GLB bytes; `path` names the file in errors and locates external buffers.
pub fn open_bytes(bytes: &[u8], path: &Path) -> Result<GltfFile, LoadError> {
    let (json, blob) = if bytes.starts_with(GLB_MAGIC) {
        split_glb(bytes).map_err(|m| LoadError::new(path, None, m))?
    } else {
        let is_glb = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        let looks_like_json = bytes.trim_ascii_start().starts_with(b"{");
        if is_glb && !looks_like_json {
            return Err(LoadError::new(
                path,
                None,
                LoadErrorKind::Syntax(
                    "not a binary glTF (GLB) file: it does not start with `glTF`".into(),
                ),
            ));
        }
        (bytes, None)
    };
    let mut value: Value = serde_json::from_slice(json).map_err(|e| {
        // serde_json counts columns from 0 at the end of the input; editors count from 1.
        let location = (e.line() > 0).then_some(Location {
            line: e.line(),
            column: e.column().max(1),
        });
        LoadError::new(path, location, LoadErrorKind::Syntax(format!("JSON: {e}")))
    })?;
    check_version(&value).map_err(|k| LoadError::new(path, None, k))?;
    check_required_extensions(&mut value).map_err(|k| LoadError::new(path, None, k))?;
    check_position_indices(&value).map_err(|k| LoadError::new(path, None, k))?;
    let node_transforms = value
        .get("nodes")
        .and_then(Value::as_array)
        .map(|nodes| nodes.iter().map(node_transform).collect())
        .unwrap_or_default();
    let scene_extras = value
        .get("scenes")
        .and_then(Value::as_array)
        .map(|scenes| {
            scenes
                .iter()
                .map(|s| s.get("extras").and_then(|e| e.get("quadray")).cloned())
                .collect()
        })
        .unwrap_or_default();
    let cameras = value
        .get("cameras")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let root: gltf::json::Root = serde_path_to_error::deserialize(value).map_err(|e| {
        LoadError::invalid(
            path,
            None,
            e.path().to_string(),
            format!(
                "not valid glTF 2.0: {}",
                crate::plain_words::in_plain_words(&e.inner().to_string())
            ),
        )
    })?;
    let document = gltf::Document::from_json(root).map_err(|e| validation_error(path, e))?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let buffers = read_buffers(&document, blob, &base, path)?;
    Ok(GltfFile {
        document,
        buffers,
        base,
        node_transforms,
        scene_extras,
        cameras,
    })
}

/// The bytes of every buffer of `document`: the GLB binary chunk `blob`, data URIs, or files
/// beside the document (within the size limits); each at least as long as its `byteLength`.
fn read_buffers(
    document: &gltf::Document,
    blob: Option<&[u8]>,
    base: &Path,
    path: &Path,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let mut blob = blob.map(<[u8]>::to_vec);
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                LoadError::invalid(
                    path,
                    None,
                    format!("buffers[{i}]"),
                    "refers to the GLB binary chunk, which the file does not have",
                )
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(base, uri).map_err(|e| match e {
                UriError::Io(file, source) => LoadError::new(
                    path,
                    None,
                    LoadErrorKind::Referenced {
                        what: format!("buffer {i}"),
                        path: file,
                        source,
                    },
                ),
                UriError::Invalid(m) => {
                    LoadError::invalid(path, None, format!("buffers[{i}].uri"), m)
                }
            })?,
        };
        if data.len() < buffer.length() {
            return Err(LoadError::invalid(
                path,
                None,
                format!("buffers[{i}]"),
                format!(
                    "byteLength is {} but only {} bytes are there",
                    buffer.length(),
                    data.len()
                ),
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// A node's local transform from its JSON: `matrix` (column-major, must be affine) or
/// translation · rotation · scale, with the rotation normalised (the spec requires a unit
/// quaternion; exporters round).
fn node_transform(node: &Value) -> Result<DAffine3, String> {
    let numbers = |key: &str, n: usize| -> Result<Option<Vec<f64>>, String> {
        match node.get(key) {
            None => Ok(None),
            Some(Value::Array(a)) if a.len() == n => a
                .iter()
                .map(|v| v.as_f64().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f64>>>()
                .map(Some)
                .ok_or_else(|| format!("`{key}` must hold {n} finite numbers")),
            Some(_) => Err(format!("`{key}` must be an array of {n} numbers")),
        }
    };
    if let Some(m) = numbers("matrix", 16)? {
        let m = DMat4::from_cols_slice(&m);
        let last_row = [m.x_axis.w, m.y_axis.w, m.z_axis.w];
        if last_row.iter().any(|x| x.abs() > 1e-6) || (m.w_axis.w - 1.0).abs() > 1e-6 {
            return Err("`matrix` is not affine (its last row must be 0 0 0 1)".into());
        }
        return Ok(DAffine3::from_mat4(m));
    }
    let t = numbers("translation", 3)?.map_or(DVec3::ZERO, |v| DVec3::from_slice(&v));
    let s = numbers("scale", 3)?.map_or(DVec3::ONE, |v| DVec3::from_slice(&v));
    let q = numbers("rotation", 4)?.map_or(DQuat::IDENTITY, |v| DQuat::from_slice(&v));
    let len = q.length();
    if len.is_nan() || len <= 0.0 {
        return Err("`rotation` is not a unit quaternion".into());
    }
    Ok(DAffine3::from_scale_rotation_translation(s, q / len, t))
}

/// The JSON and BIN chunks of a GLB file, every length checked against the data.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), LoadErrorKind> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let bad = |m: &str| LoadErrorKind::Syntax(format!("GLB container: {m}"));
    let version = word(4).ok_or_else(|| bad("truncated header"))?;
    if version != 2 {
        return Err(LoadErrorKind::Unsupported(format!(
            "binary glTF version {version}; quadray reads glTF 2.0 only"
        )));
    }
    let length = word(8).ok_or_else(|| bad("truncated header"))? as usize;
    if length < 12 || length > bytes.len() {
        return Err(bad(&format!(
            "header says {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..length];
    let chunk = |at: usize| -> Result<Option<(u32, &[u8])>, LoadErrorKind> {
        if at >= bytes.len() {
            return Ok(None);
        }
        let len = word(at).ok_or_else(|| bad("truncated chunk header"))? as usize;
        let kind = word(at + 4).ok_or_else(|| bad("truncated chunk header"))?;
        let data = bytes
            .get(at + 8..)
            .and_then(|rest| rest.get(..len))
            .ok_or_else(|| bad(&format!("a chunk of {len} bytes runs past the end")))?;
        Ok(Some((kind, data)))
    };
    let (kind, json) = chunk(12)?.ok_or_else(|| bad("no JSON chunk"))?;
    if kind != CHUNK_JSON {
        return Err(bad("the first chunk is not JSON"));
    }
    // Chunks are padded to 4 bytes; the JSON chunk's length already includes its padding.
    let next = 12 + 8 + json.len().div_ceil(4) * 4;
    let bin = match chunk(next)? {
        Some((CHUNK_BIN, data)) => Some(data),
        _ => None,
    };
    Ok((json, bin))
}

/// Refuses anything but glTF 2.x, naming the version found.
fn check_version(value: &Value) -> Result<(), LoadErrorKind> {
    let old = |v: &str| {
        LoadErrorKind::Unsupported(format!(
            "glTF {v}: an older, incompatible format (dictionary-style JSON); quadray reads glTF 2.0 only. Convert the file to glTF 2.0 first (e.g. by importing and re-exporting it in Blender)"
        ))
    };
    let version = value.get("asset").and_then(|a| a.get("version"));
    let text = match version {
        Some(Value::String(s)) => s.clone(),
        Some(Value::Number(n)) => n.to_string(),
        _ => {
            // glTF 1.0 files keep their arrays as dictionaries.
            if value.get("meshes").is_some_and(Value::is_object) {
                return Err(old("1.0"));
            }
            return Err(LoadErrorKind::Invalid {
                key: "asset.version".into(),
                message: "missing: every glTF 2.0 file says \"2.0\" here".into(),
            });
        }
    };
    match text.split('.').next() {
        Some("2") => Ok(()),
        Some("0" | "1") => Err(old(&text)),
        _ => Err(LoadErrorKind::Unsupported(format!(
            "glTF version \"{text}\"; quadray reads glTF 2.0 only"
        ))),
    }
}

/// Refuses a file that requires an extension quadray cannot honour, naming it. Extensions quadray
/// implements itself (QUADRAY_quadrics) are removed from the list before the gltf crate validates
/// it, because that crate rejects every required extension it does not know.
fn check_required_extensions(value: &mut Value) -> Result<(), LoadErrorKind> {
    let Some(Value::Array(required)) = value.get_mut("extensionsRequired") else {
        return Ok(());
    };
    let names: Vec<String> = required
        .iter()
        .map(|v| v.as_str().unwrap_or("?").to_string())
        .collect();
    let unsupported: Vec<&String> = names
        .iter()
        .filter(|n| !SUPPORTED_REQUIRED.contains(&n.as_str()))
        .collect();
    if !unsupported.is_empty() {
        let described: Vec<String> = unsupported
            .iter()
            .map(|n| match n.as_str() {
                "KHR_draco_mesh_compression" => format!("{n} (Draco-compressed geometry)"),
                "EXT_meshopt_compression" => format!("{n} (meshopt-compressed buffers)"),
                "KHR_mesh_quantization" => format!("{n} (quantized vertex attributes)"),
                "KHR_texture_basisu" => format!("{n} (KTX2/Basis textures)"),
                _ => n.to_string(),
            })
            .collect();
        return Err(LoadErrorKind::Unsupported(format!(
            "the file requires the glTF extension {}, which quadray does not support; re-export it without (e.g. `gltf-transform copy` decompresses Draco)",
            described.join(", ")
        )));
    }
    required.retain(|v| v.as_str() != Some(crate::gltf::quadrics_ext::EXTENSION));
    Ok(())
}

/// Checks that every primitive's POSITION names an existing accessor. gltf-json's validation
/// indexes the accessor list with it before checking the index, and panics when it is out of
/// range; every other index is checked by that validation itself.
fn check_position_indices(value: &Value) -> Result<(), LoadErrorKind> {
    let accessors = value
        .get("accessors")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let meshes = value.get("meshes").and_then(Value::as_array);
    for (m, mesh) in meshes.into_iter().flatten().enumerate() {
        let primitives = mesh.get("primitives").and_then(Value::as_array);
        for (p, primitive) in primitives.into_iter().flatten().enumerate() {
            let position = primitive.get("attributes").and_then(|a| a.get("POSITION"));
            if let Some(i) = position.and_then(Value::as_u64)
                && i as usize >= accessors
            {
                return Err(LoadErrorKind::Invalid {
                    key: format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"),
                    message: format!(
                        "accessor {i} is out of range (the file has {accessors} accessors)"
                    ),
                });
            }
        }
    }
    Ok(())
}

fn validation_error(path: &Path, e: gltf::Error) -> LoadError {
    match e {
        gltf::Error::Validation(errors) => {
            let (key, first) = errors
                .first()
                .map(|(p, e)| (extension_names(&p.to_string()), e.to_string()))
                .unwrap_or_default();
            let more = if errors.len() > 1 {
                format!(" (and {} more problems)", errors.len() - 1)
            } else {
                String::new()
            };
            LoadError::invalid(path, None, key, format!("{first}{more}"))
        }
        other => LoadError::new(path, None, LoadErrorKind::Syntax(other.to_string())),
    }
}

/// A validation error's path with the Khronos extensions spelt as the file spells them: the gltf
/// crate names them by its fields (`extensions.khrLightsPunctual`), a key no file has
/// (`extensions.KHR_lights_punctual`).
fn extension_names(path: &str) -> String {
    let spelt = |part: &str| {
        let Some(rest) = part
            .strip_prefix("khr")
            .filter(|r| r.starts_with(char::is_uppercase))
        else {
            return part.to_string();
        };
        let mut name = String::from("KHR");
        for c in rest.chars() {
            if c.is_uppercase() {
                name.push('_');
            }
            name.push(c.to_ascii_lowercase());
        }
        name
    };
    path.split('.').map(spelt).collect::<Vec<_>>().join(".")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Khronos extensions in validation paths are spelt as in the file.
    #[test]
    fn extension_names_are_the_files() {
        assert_eq!(
            extension_names("extensions.khrLightsPunctual.lights[0].spot"),
            "extensions.KHR_lights_punctual.lights[0].spot"
        );
        assert_eq!(
            extension_names("materials[2].extensions.khrMaterialsEmissiveStrength"),
            "materials[2].extensions.KHR_materials_emissive_strength"
        );
        assert_eq!(extension_names("nodes[3].scale"), "nodes[3].scale");
    }

    fn err(json: &str) -> String {
        match open_bytes(json.as_bytes(), Path::new("t.gltf")) {
            Ok(_) => panic!("accepted {json}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn refuses_old_versions_and_unsupported_required_extensions() {
        let e = err(r#"{"asset": {"version": 0.8}, "meshes": {}}"#);
        assert!(e.contains("glTF 0.8") && e.contains("glTF 2.0 only"), "{e}");
        let e = err(r#"{"meshes": {"m": {}}}"#);
        assert!(e.contains("glTF 1.0"), "{e}");
        let e = err(
            r#"{"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"]}"#,
        );
        assert!(e.contains("KHR_draco_mesh_compression (Draco"), "{e}");
        // Required but implemented by quadray itself: accepted.
        open_bytes(
            br#"{"asset": {"version": "2.0"}, "extensionsUsed": ["QUADRAY_quadrics"], "extensionsRequired": ["QUADRAY_quadrics"]}"#,
            Path::new("ok.gltf"),
        )
        .unwrap();
    }

    #[test]
    fn reports_json_errors_with_location_and_validation_paths() {
        let e = err("{\n  \"asset\": {\"version\": \"2.0\"},\n  oops\n}");
        assert!(e.starts_with("t.gltf:3:"), "{e}");
        let e = err(
            r#"{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 3}}]}]}"#,
        );
        assert!(
            e.contains("meshes[0].primitives[0].attributes[\"POSITION\"]"),
            "{e}"
        );
        assert!(e.contains("accessor 3 is out of range"), "{e}");
        // Other indices are gltf-json's to check; its message names the path.
        let e = err(r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": 5}]}"#);
        assert!(e.contains("nodes[0].mesh"), "{e}");
    }

    #[test]
    fn glb_headers_are_checked_not_trusted() {
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(5u32.to_le_bytes());
        let e = open_bytes(&glb, Path::new("t.glb"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("GLB container"), "{e}");
        let mut v1 = b"glTF".to_vec();
        v1.extend(1u32.to_le_bytes());
        v1.extend(12u32.to_le_bytes());
        let e = open_bytes(&v1, Path::new("t.glb")).unwrap_err().to_string();
        assert!(e.contains("binary glTF version 1"), "{e}");
        // A chunk claiming more bytes than there are.
        let mut long = b"glTF".to_vec();
        long.extend(2u32.to_le_bytes());
        long.extend(24u32.to_le_bytes());
        long.extend(1000u32.to_le_bytes());
        long.extend(CHUNK_JSON.to_le_bytes());
        long.extend(b"{}  ");
        let e = open_bytes(&long, Path::new("t.glb"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("runs past the end"), "{e}");
    }

    #[test]
    fn buffers_missing_short_or_malformed_are_errors() {
        let e = err(
            r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "nowhere.bin", "byteLength": 4}]}"#,
        );
        assert!(
            e.contains("cannot read buffer 0") && e.contains("nowhere.bin"),
            "{e}"
        );
        let e = err(
            r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "data:application/octet-stream;base64,AAAA", "byteLength": 8}]}"#,
        );
        assert!(e.contains("byteLength is 8 but only 3"), "{e}");
        let e = err(
            r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "%FF%FE.bin", "byteLength": 4}]}"#,
        );
        assert!(e.contains("percent-encoded"), "{e}");
        let e = err(
            r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "https://example.com/a.bin", "byteLength": 4}]}"#,
        );
        assert!(e.contains("not fetched"), "{e}");
    }
}
