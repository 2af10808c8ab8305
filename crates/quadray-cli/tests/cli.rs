//! The real `quadray` binary, run as a user would: exit codes, messages and files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn quadray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(args)
        .output()
        .expect("the quadray binary runs")
}

fn scene(name: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    root.to_string_lossy().into_owned()
}

fn tmp(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

#[test]
fn renders_both_bundled_scenes_to_png_and_exr() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["defense.toml", "quadrics.toml"] {
        for ext in ["png", "exr"] {
            let out = tmp(&dir, &format!("{name}.{ext}"));
            let o = quadray(&[
                "render",
                &scene(name),
                "-o",
                out.to_str().unwrap(),
                "--res",
                "160x90",
                "--spp",
                "1",
            ]);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let stats = String::from_utf8_lossy(&o.stderr);
            assert!(stats.contains("160x90, 1 spp: 14400 camera"), "{stats}");
            let bytes = std::fs::read(&out).unwrap();
            let magic: &[u8] = if ext == "png" {
                b"\x89PNG"
            } else {
                &[0x76, 0x2f, 0x31, 0x01]
            };
            assert_eq!(&bytes[..4], magic);
        }
    }
}

#[test]
fn malformed_scene_exits_nonzero_with_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let bad = tmp(&dir, "bad.toml");
    std::fs::write(&bad, "version = 1\n[camera]\nfrom = [0, -5, 1]\nto = [0, 0, 0]\n[[sphere]]\ncenter = [0, 0, 0]\nradius = -2\nmaterial = \"x\"\n").unwrap();
    let out = tmp(&dir, "out.png");
    std::fs::write(&out, b"previous image").unwrap();
    let o = quadray(&["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml:7:10: `sphere[0].radius`: must be positive, got -2"),
        "{err}"
    );
    // The older output survives a failed render, and no temporary file is left.
    assert_eq!(std::fs::read(&out).unwrap(), b"previous image");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn bad_arguments_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "o.png");
    let o = quadray(&["render", "/no/such/scene.toml", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("/no/such/scene.toml: cannot read the file")
    );
    let o = quadray(&[
        "render",
        &scene("defense.toml"),
        "-o",
        out.to_str().unwrap(),
        "--res",
        "100000x100000",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&o.stderr)
            .contains("resolution 100000x100000 is outside the limits")
    );
    let o = quadray(&["render", &scene("defense.toml"), "-o", "x.jpg"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("must end in .png or .exr"));
    let o = quadray(&[
        "render",
        &scene("defense.toml"),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "0",
    ]);
    assert!(!o.status.success());
    let o = quadray(&["render", &scene("defense.toml")]);
    assert_eq!(o.status.code(), Some(2), "clap usage errors exit 2");
    assert!(!out.exists());
}

#[test]
fn check_validates_without_rendering() {
    let o = quadray(&["check", &scene("defense.toml")]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("ok: 2 spheres, 1 planes, 4 quadrics, 1 meshes (20 triangles), 2 lights"),
        "{text}"
    );
}
