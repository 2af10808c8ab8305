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
