//! Scene loading for quadray.
//!
//! # Brief overview
//! - [`native`]: the TOML scene format documented in `docs/scene-format.md`; [`load_scene`] reads a
//!   file into a validated [`quadray::SceneDescription`] plus [`SceneSettings`].
//! - [`LoadError`]: every error names the file, the line and column where known, and the bad key.

pub mod error;
pub mod native;

pub use error::{LoadError, LoadErrorKind, Location};
pub use native::{LoadedScene, SceneSettings, load_scene, parse_scene};

use std::path::Path;

/// Loads any scene file quadray reads, chosen by its extension (`.toml`: the native format).
pub fn load_any(path: &Path) -> Result<LoadedScene, LoadError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("toml") => load_scene(path),
        _ => Err(LoadError::new(
            path,
            None,
            LoadErrorKind::Unsupported("unknown scene file type (expected .toml)".into()),
        )),
    }
}
