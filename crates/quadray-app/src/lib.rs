//! quadray's application layer: what the command line (`quadray`) and the viewer (`quadray-view`)
//! both do around the renderer, so that neither depends on the other.
//!
//! - [`scene_file`]: a scene loaded as the user named it (`--set` overrides, import options, a
//!   camera choice, `--res`), and where its render goes by default;
//! - [`output`] and [`exr_file`]: images and passes written atomically, PNG and EXR (with
//!   Blender's channel names and the pieces of a distributed render);
//! - [`passes`]: the render passes as 8-bit images;
//! - [`compare`]: image differences (RMSE, largest difference, FLIP);
//! - [`snippet`]: a located loader error shown with its line and a caret;
//! - [`showcase`]: the seed's textbook presentation of each quadric kind;
//! - [`logging`]: `-v`'s log of phases and files on stderr;
//! - [`memory`]: the memory free for a render, to refuse one too large before it starts.
//!
//! Dependencies point down: `quadray` (core) ← `quadray-loader` ← this crate ← the CLI and the
//! viewer.

pub mod compare;
pub mod exr_file;
pub mod logging;
pub mod memory;
pub mod output;
pub mod passes;
pub mod scene_file;
pub mod showcase;
pub mod snippet;
