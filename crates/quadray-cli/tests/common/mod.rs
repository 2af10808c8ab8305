//! Helpers shared by the CLI's end-to-end tests: running the real binary on bundled scenes.
// Each test file compiles this module on its own and uses only some of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `quadray` binary with `args`.
pub fn quadray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(args)
        .output()
        .expect("the quadray binary runs")
}

/// Renders the bundled scene `name` to `out` at `res` (`WxH`), waiting for the binary.
pub fn render_to(name: &str, out: &Path, res: &str) -> Output {
    quadray(&[
        "render",
        &scene(name),
        "-o",
        out.to_str().unwrap(),
        "--res",
        res,
    ])
}

/// Renders the bundled scene `name` to `out` with each of `cases`' extra arguments, and checks
/// that each is refused as a usage error (exit status 2) whose message holds the case's text.
pub fn assert_usage_errors(name: &str, out: &Path, cases: &[(Vec<&str>, &str)]) {
    let scene_path = scene(name);
    for (args, says) in cases {
        let mut full = vec!["render", &scene_path, "-o", out.to_str().unwrap()];
        full.extend(args.iter().copied());
        let o = quadray(&full);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}

/// Path of a bundled scene in `scenes/`.
pub fn scene(name: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    root.to_string_lossy().into_owned()
}

/// A file named `name` in the temporary folder `dir`.
pub fn tmp(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

/// A unit sphere (material colour 0.2, 0.4, 0.6) over a plane at z = -2, seen straight down by an
/// orthographic camera 10 units up, one sample at each pixel's centre: every pass value at the
/// centre and corner follows by hand.
const PASS_SCENE: &str = r#"version = 1
[camera]
projection = "orthographic"
from = [0, 0, 10]
to = [0, 0, 0]
up = [0, 1, 0]
height = 4.0
[render]
resolution = [9, 9]
spp = 1
background = [0.5, 0.5, 0.5]
[[material]]
name = "ball"
color = [0.2, 0.4, 0.6]
[[material]]
name = "ground"
color = [0.7, 0.7, 0.7]
[[sphere]]
center = [0, 0, 0]
radius = 1
material = "ball"
[[plane]]
point = [0, 0, -2]
normal = [0, 0, 1]
material = "ground"
[[light]]
type = "directional"
direction = [0, 0, -1]
"#;

pub fn pass_scene(dir: &tempfile::TempDir) -> String {
    let path = tmp(dir, "passes.toml");
    std::fs::write(&path, PASS_SCENE).unwrap();
    path.to_string_lossy().into_owned()
}
