//! The viewer: its panel under egui_kittest and the real window under Xvfb (one test binary for the crate).

mod ui;
mod xvfb;
