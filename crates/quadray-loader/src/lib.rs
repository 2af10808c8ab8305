//! Scene loading for quadray.
//!
//! # Brief overview
//! - [`native`]: the TOML scene format documented in `docs/scene-format.md`; [`load_scene`] reads a
//!   file into a validated [`quadray::SceneDescription`] plus [`SceneSettings`].
//! - [`obj`] (with its MTL materials) and [`gltf`] (with [`gltf::quadrics_ext`], the
//!   `QUADRAY_quadrics` extension) import other formats into an [`Imported`] scene part, which
//!   [`standalone`] completes into a scene of its own and [`native`] merges into a native scene.
//! - `ply`: the vertices of a PLY file as spheres, for a native scene's `[[spheres]]` table.
//! - [`export`] writes a scene as glTF 2.0 with the `QUADRAY_quadrics` extension.
//! - [`LoadError`]: every error names the file, the line and column where known, and the bad key.
//! - Around every format: [`read_limited`] (the sizes files are read within), [`image_file`]
//!   (texture decoding and its budget), [`atomic_file`] (outputs written whole or not at all),
//!   [`confine`] (reads and writes kept inside one folder), [`framing`] (a camera for a scene
//!   without one), [`suggest`] ("did you mean") and `plain_words` (serde's type errors in a scene
//!   author's terms).
//!
//! One folder a format: `native/`, `obj/`, `gltf/`, `ply/`, `export/`.

pub mod atomic_file;
pub mod confine;
mod error;
pub mod export;
pub mod framing;
pub mod gltf;
pub mod image_file;
mod import;
mod include;
pub mod native;
pub mod obj;
mod plain_words;
mod ply;
mod reach;
pub mod read_limited;
pub mod standalone;
pub mod suggest;
mod tangents;
mod tessellate;

pub use error::{LoadError, LoadErrorKind, Location};
pub use import::{FileFormat, ImportOptions, Imported, Selector, UpAxis};
pub use native::overrides::Override;
pub use native::{LoadedScene, SceneSettings, load_scene, load_scene_with, parse_scene};

use std::path::Path;

/// The note for `merged` coincident placements dropped at load, if any.
pub(crate) fn coincident_note(merged: usize) -> Option<String> {
    (merged > 0).then(|| {
        format!(
            "merged {merged} coincident placements (the same group, shape or mesh placed again at \
             the same transform with the same material draws the same surface)"
        )
    })
}

/// Loads any scene file quadray reads, chosen by its extension: `.toml` (the native format),
/// `.obj`, `.gltf` or `.glb` (rendered on their own: see [`standalone`]).
pub fn load_any(path: &Path) -> Result<LoadedScene, LoadError> {
    load_any_with(path, &ImportOptions::default(), None)
}

/// [`load_any`] with import options (scene choice, up axis) and a camera choice for OBJ and glTF
/// files; native scenes ignore both.
pub fn load_any_with(
    path: &Path,
    options: &ImportOptions,
    camera: Option<&Selector>,
) -> Result<LoadedScene, LoadError> {
    let mut imported = match FileFormat::of(path) {
        Some(FileFormat::Native) => return load_scene(path),
        Some(FileFormat::Obj) => obj::import_obj(path, options)?,
        Some(FileFormat::Gltf) => gltf::import_gltf(path, options)?,
        None => {
            return Err(LoadError::new(
                path,
                None,
                LoadErrorKind::Unsupported(
                    "unknown scene file type (expected .toml, .obj, .gltf or .glb)".into(),
                ),
            ));
        }
    };
    if let Some(resolution) = options.resolution {
        imported.hints.resolution = Some(resolution);
    }
    standalone::scene_from_import(imported, path, camera)
}
