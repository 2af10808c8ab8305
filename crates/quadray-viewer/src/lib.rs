//! quadray-view: the interactive viewer. A scene file (TOML, OBJ, glTF, GLB), or with no file the
//! quadric explorer (the original program's panel), shown progressively: a quick preview while
//! the view moves, then frames refined sample by sample, rendered on a worker thread.
//!
//! - [`app::Viewer`]: the window's state and panels (egui), usable in a test harness.
//! - [`worker`]: the render thread, with cancellation and progressive refinement.
//! - [`orbit`]: the orbit camera and its mouse controls; [`explorer`]: the quadric panel;
//!   [`source`]: loading and watching files; [`pick`]: the object under a pixel;
//!   [`final_render`]: the Render button; [`open_dialog`]: the Open window.

pub mod app;
pub mod explorer;
pub mod final_render;
pub mod open_dialog;
pub mod orbit;
pub mod pick;
pub mod source;
pub mod worker;

pub use app::Viewer;
