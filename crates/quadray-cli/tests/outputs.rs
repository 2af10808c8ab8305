//! What commands write, and what they never overwrite: a closed stdout or stderr keeps the
//! command's exit status, an output never replaces one of the command's inputs, and a `.gltf` and
//! its `.bin` are replaced together.

use crate::common;
use std::path::Path;

/// A reader that closed the pipe ends the command quietly with success, as in ripgrep: no panic,
/// no error line.
#[test]
fn a_closed_pipe_ends_output_quietly() {
    use std::process::{Command, Stdio};
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/defense.toml");
    for args in [
        vec!["check".to_string(), scene.to_string_lossy().into_owned()],
        vec!["quadric".to_string(), "--list".to_string()],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader goes before anything is written
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("panicked") && !stderr.contains("error"),
            "{args:?}: {stderr}"
        );
    }
}

/// A closed stderr (its reader gone, as `quadray … 2>&1 | head -1` leaves it) loses the messages
/// but never turns into a panic (exit status 101): a render still writes its image and succeeds,
/// an invalid scene still exits 1.
#[test]
fn a_closed_stderr_keeps_the_exit_status() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let out = common::tmp(&dir, "out.png");
    let bad = common::tmp(&dir, "bad.toml");
    std::fs::write(&bad, "version = 1\n[[sphere]]\nradius = -1\n").unwrap();
    let good = common::scene("sphere-on-plane.toml");
    let cases: [(Vec<&str>, i32); 3] = [
        (vec!["render", &good, "--res", "16x9"], 0),
        (vec!["check", bad.to_str().unwrap()], 1),
        (vec!["convert", bad.to_str().unwrap(), "-o"], 2),
    ];
    for (mut args, status) in cases {
        if args[0] == "render" {
            args.extend(["-o", out.to_str().unwrap()]);
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args(&args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stderr.take()); // the reader goes before anything is written
        let done = child.wait().unwrap();
        assert_eq!(done.code(), Some(status), "{args:?}");
    }
    assert!(out.exists(), "the render wrote its image");
}

/// An output that is one of the command's own inputs is refused (exit 2) before anything is
/// written, whatever its spelling: the heat map of `compare` over an image it compares, a render
/// over the texture its scene reads, a conversion over its source, and a `.gltf` conversion
/// whose buffer would replace the source's. A `.glb`, which writes no buffer beside it, is not
/// refused for the source's buffer.
#[test]
fn outputs_never_replace_the_commands_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let copy = |name: &str, to: &str| {
        let to = common::tmp(&dir, to);
        std::fs::copy(common::scene(name), &to).unwrap();
        to
    };
    // The glTF scene under another name; its buffer keeps the name the file refers to.
    let source = copy("gltf-quadrics.gltf", "source.gltf");
    let bin = copy("gltf-quadrics.bin", "gltf-quadrics.bin");
    let image = common::tmp(&dir, "a.png");
    let made = common::quadray(&[
        "render",
        &path(&source),
        "--res",
        "16x9",
        "-o",
        &path(&image),
    ]);
    assert!(made.status.success(), "{made:?}");
    // The OBJ scene, whose MTL reads a texture, copied with its folder.
    let scene = copy("obj-mesh.toml", "obj-mesh.toml");
    std::fs::create_dir_all(common::tmp(&dir, "obj-mtl/textures")).unwrap();
    for name in [
        "obj-mtl/pedestal.obj",
        "obj-mtl/pedestal.mtl",
        "obj-mtl/textures/tiles.png",
    ] {
        copy(name, name);
    }
    let texture = common::tmp(&dir, "obj-mtl/textures/tiles.png");
    let respelled = dir.path().join("obj-mtl/../obj-mtl/textures/tiles.png");
    // A .gltf output not there yet, whose buffer beside it is the source's.
    let beside = common::tmp(&dir, "gltf-quadrics.gltf");
    let image_s = path(&image);
    let cases: [(Vec<String>, &Path); 4] = [
        (
            ["compare", &image_s, &image_s, "--diff", &image_s]
                .map(String::from)
                .into(),
            &image,
        ),
        (
            [
                "render",
                &path(&scene),
                "--res",
                "8x8",
                "-o",
                &path(&respelled),
            ]
            .map(String::from)
            .into(),
            &texture,
        ),
        (
            ["convert", &path(&source), "-o", &path(&source)]
                .map(String::from)
                .into(),
            &source,
        ),
        (
            ["convert", &path(&source), "-o", &path(&beside)]
                .map(String::from)
                .into(),
            &bin,
        ),
    ];
    for (args, kept) in cases {
        let before = std::fs::read(kept).unwrap();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = common::quadray(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("name another output"), "{args:?}: {stderr}");
        assert_eq!(
            std::fs::read(kept).unwrap(),
            before,
            "{args:?} changed {kept:?}"
        );
    }
    assert!(!beside.exists(), "the refused conversion wrote nothing");
    let glb = common::tmp(&dir, "gltf-quadrics.glb");
    let o = common::quadray(&["convert", &path(&source), "-o", &path(&glb)]);
    assert!(
        o.status.success(),
        "a .glb writes no buffer beside it: {o:?}"
    );
}

fn path(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// A .gltf and its .bin are replaced together: when the .gltf cannot be written (a folder in its
/// place), the old .bin stays as it was and no temporary file is left.
#[test]
fn a_gltf_and_its_buffer_are_replaced_together() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(common::tmp(&dir, "out.gltf")).unwrap();
    let bin = common::tmp(&dir, "out.bin");
    std::fs::write(&bin, b"old buffer").unwrap();
    let o = common::quadray(&[
        "convert",
        &common::scene("sphere-on-plane.toml"),
        "-o",
        &path(&common::tmp(&dir, "out.gltf")),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("out.gltf") && stderr.contains("folder"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&bin).unwrap(), b"old buffer");
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["out.bin", "out.gltf"]);
}

/// An output that is a symbolic link is written through, as `cp` and a shell's `>` write: the
/// file it names gets the image and the link stays a link. A loop of links is an error naming the
/// output, exit 1, and writes nothing.
#[cfg(unix)]
#[test]
fn a_linked_output_is_written_through() {
    use std::os::unix::fs::symlink;
    let dir = tempfile::tempdir().unwrap();
    let (real, link) = (common::tmp(&dir, "real.png"), common::tmp(&dir, "link.png"));
    std::fs::write(&real, b"old image").unwrap();
    symlink("real.png", &link).unwrap();
    let o = common::render_to("sphere-on-plane.toml", &link, "16x9");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(link.symlink_metadata().unwrap().file_type().is_symlink());
    assert_eq!(image::open(&real).unwrap().width(), 16);
    let looped = common::tmp(&dir, "loop.png");
    symlink("loop.png", &looped).unwrap();
    let o = common::render_to("sphere-on-plane.toml", &looped, "16x9");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("loop.png") && stderr.contains("loop of them"),
        "{stderr}"
    );
}
