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
