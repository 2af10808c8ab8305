//! Whether the viewer's window test can run here: it needs Xvfb and ImageMagick's `import` on the
//! PATH, and gets the cfg `quadray_xvfb` (see `tests/cfgs.rs`).

include!("../../tests/cfgs.rs");

fn main() {
    enable("quadray_xvfb", on_path("xvfb-run") && on_path("import"));
}
