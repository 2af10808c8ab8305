//! One frame over many processes: `render --tile I/N` pieces merged by `quadray merge` are the
//! one-process render byte for byte, and every way pieces can fail to fit together is refused
//! with a message that says which.

use crate::common;
use common::{quadray, scene, tmp};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// Render settings shared by every run of this file: small, but several of the EXR writer's 64x64
/// blocks (whose order in the file must not depend on threads), with passes and several samples.
const SETTINGS: [&str; 6] = ["--res", "150x90", "--spp", "2", "--aov", "depth,normal"];

fn ok(o: Output) -> Output {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn render(scene_file: &str, out: &Path, extra: &[&str]) -> Output {
    let out = out.to_str().unwrap();
    quadray(
        &[
            &["render", scene_file, "-o", out, "-q"],
            &SETTINGS[..],
            extra,
        ]
        .concat(),
    )
}

fn piece(dir: &tempfile::TempDir, i: u32, n: u32) -> PathBuf {
    let path = tmp(dir, &format!("part-{i:02}-of-{n:02}.exr"));
    ok(render(
        &scene("defense.toml"),
        &path,
        &["--tile", &format!("{i}/{n}")],
    ));
    path
}

fn merge(pieces: &[PathBuf], extra: &[&str]) -> Output {
    let names: Vec<&str> = pieces.iter().map(|p| p.to_str().unwrap()).collect();
    quadray(&[&["merge"], &names[..], extra].concat())
}

#[test]
fn merged_pieces_are_the_one_process_render_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let (one_exr, one_png) = (tmp(&dir, "one.exr"), tmp(&dir, "one.png"));
    ok(render(&scene("defense.toml"), &one_exr, &[]));
    let png_settings = ["--res", "150x90", "--spp", "2"];
    let out = one_png.to_str().unwrap();
    ok(quadray(
        &[
            &["render", &scene("defense.toml"), "-o", out, "-q"],
            &png_settings[..],
        ]
        .concat(),
    ));
    for n in [1, 3, 7] {
        let pieces: Vec<PathBuf> = (0..n).map(|i| piece(&dir, i, n)).collect();
        let (exr, png) = (tmp(&dir, "merged.exr"), tmp(&dir, "merged.png"));
        ok(merge(&pieces, &["-o", exr.to_str().unwrap(), "-q"]));
        ok(merge(&pieces, &["-o", png.to_str().unwrap(), "-q"]));
        assert!(
            std::fs::read(&exr).unwrap() == std::fs::read(&one_exr).unwrap(),
            "{n} pieces: EXR"
        );
        assert!(
            std::fs::read(&png).unwrap() == std::fs::read(&one_png).unwrap(),
            "{n} pieces: PNG"
        );
    }
}

#[test]
fn pieces_that_do_not_fit_together_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let pieces: Vec<PathBuf> = (0..3).map(|i| piece(&dir, i, 3)).collect();
    let out = tmp(&dir, "merged.exr");
    let out_arg = ["-o", out.to_str().unwrap()];
    let refused = |set: &[PathBuf], says: &[&str]| {
        let o = merge(set, &out_arg);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        for text in says {
            assert!(err.contains(text), "{text:?} missing from {err}");
        }
        assert!(!out.exists(), "nothing is written");
    };
    // A missing piece, and --missing listing it for a retry loop.
    refused(
        &[pieces[0].clone(), pieces[2].clone()],
        &["pieces missing: 1 (of 3"],
    );
    let listed = ok(merge(
        &[pieces[0].clone(), pieces[2].clone()],
        &["--missing"],
    ));
    assert_eq!(String::from_utf8_lossy(&listed.stdout), "1\n");
    let complete = ok(merge(&pieces, &["--missing"]));
    assert!(complete.stdout.is_empty());
    // The same piece twice.
    let again = tmp(&dir, "again.exr");
    std::fs::copy(&pieces[1], &again).unwrap();
    refused(
        &[&pieces[..], &[again]].concat(),
        &["piece 1/3 is given 2 times"],
    );
    // A piece of another scene.
    let other = tmp(&dir, "other.exr");
    ok(render(&scene("quadrics.toml"), &other, &["--tile", "1/3"]));
    refused(
        &[pieces[0].clone(), other, pieces[2].clone()],
        &["other.exr was rendered from another scene"],
    );
    // A piece rendered with other settings: another seed, or textures point sampled (the merged
    // frame would match neither render).
    for (name, option, says) in [
        ("seeded.exr", ["--seed", "9"], "seed 9"),
        (
            "point.exr",
            ["--texture-filter", "none"],
            "texture filter off",
        ),
    ] {
        let other = tmp(&dir, name);
        ok(render(
            &scene("defense.toml"),
            &other,
            &[&["--tile", "1/3"], &option[..]].concat(),
        ));
        refused(
            &[pieces[0].clone(), other, pieces[2].clone()],
            &[&format!("{name} was rendered with other settings"), says],
        );
    }
    // A piece rendered after a mesh the scene reads was changed: the scene file is the same.
    let meshed = tempfile::tempdir().unwrap();
    let scene_file = meshed.path().join("scene.toml");
    let mesh = meshed.path().join("tri.obj");
    std::fs::write(
        &scene_file,
        "version = 1\n[camera]\nfrom = [0, -4, 1]\nto = [0, 0, 0]\n[[material]]\nname = \"m\"\n\
         [[mesh]]\npath = \"tri.obj\"\nmaterial = \"m\"\n",
    )
    .unwrap();
    let triangle = |z: f32| format!("v -1 0 0\nv 1 0 0\nv 0 0 {z}\nf 1 2 3\n");
    std::fs::write(&mesh, triangle(1.0)).unwrap();
    let first = tmp(&dir, "mesh-0.exr");
    ok(render(
        scene_file.to_str().unwrap(),
        &first,
        &["--tile", "0/2"],
    ));
    std::fs::write(&mesh, triangle(1.5)).unwrap();
    let second = tmp(&dir, "mesh-1.exr");
    ok(render(
        scene_file.to_str().unwrap(),
        &second,
        &["--tile", "1/2"],
    ));
    refused(
        &[first, second.clone()],
        &["mesh-1.exr was rendered from another scene"],
    );
    // A piece of a frame cut another way.
    let quarter = tmp(&dir, "quarter.exr");
    ok(render(&scene("defense.toml"), &quarter, &["--tile", "1/4"]));
    refused(
        &[pieces[0].clone(), quarter, pieces[2].clone()],
        &["cut into 4 pieces"],
    );
    // An image that is not a piece.
    let plain = tmp(&dir, "plain.exr");
    ok(render(&scene("defense.toml"), &plain, &[]));
    refused(&[plain], &["plain.exr: not a piece of a quadray render"]);
    let junk = tmp(&dir, "junk.exr");
    std::fs::write(&junk, "not an image").unwrap();
    refused(&[junk], &["reading", "junk.exr"]);
}

/// A task killed while it renders leaves no piece behind (pieces are written atomically), so
/// `merge --missing` names it and a re-run completes the frame.
#[test]
fn a_killed_piece_is_simply_rendered_again() {
    let dir = tempfile::tempdir().unwrap();
    let pieces: Vec<PathBuf> = (0..3)
        .map(|i| tmp(&dir, &format!("part-{i}.exr")))
        .collect();
    for i in [0, 2] {
        ok(render(
            &scene("defense.toml"),
            &pieces[i],
            &["--tile", &format!("{i}/3")],
        ));
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args([
            "render",
            &scene("defense.toml"),
            "-o",
            pieces[1].to_str().unwrap(),
        ])
        .args([
            "--tile",
            "1/3",
            "--res",
            "1600x1200",
            "--spp",
            "16",
            "-t",
            "1",
            "-q",
        ])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(150));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!pieces[1].exists(), "a killed task leaves no piece");
    let present: Vec<PathBuf> = pieces.iter().filter(|p| p.exists()).cloned().collect();
    let listed = ok(merge(&present, &["--missing"]));
    assert_eq!(String::from_utf8_lossy(&listed.stdout), "1\n");
    ok(render(
        &scene("defense.toml"),
        &pieces[1],
        &["--tile", "1/3"],
    ));
    ok(merge(
        &pieces,
        &["-o", tmp(&dir, "frame.exr").to_str().unwrap(), "-q"],
    ));
}

#[test]
fn tile_options_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let exr = tmp(&dir, "p.exr");
    let png = tmp(&dir, "p.png");
    let s = scene("defense.toml");
    for (args, says) in [
        (vec!["--tile", "3/3"], "--tile"),
        (vec!["--tile", "0/91"], "cannot be cut into 91 pieces"),
        (vec!["--tile", "0/2", "--crop", "0,1,0,0.5"], "--crop"),
    ] {
        let o = render(&s, &exr, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(says),
            "{args:?}"
        );
    }
    let o = quadray(&["render", &s, "-o", png.to_str().unwrap(), "--tile", "0/2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("writes a piece as an .exr"));
}

/// A turntable from one scene file, one task per frame: frame I of N turns the camera 360·I/N
/// degrees about the vertical through its target and writes its own numbered file.
#[test]
fn orbit_frames_turn_the_camera_and_number_the_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene("defense.toml");
    let pattern = tmp(&dir, "turn-###.png");
    let small = ["--res", "64x36", "-q"];
    for frame in ["0", "30"] {
        let args = [
            "render",
            &s,
            "-o",
            pattern.to_str().unwrap(),
            "--orbit-frames",
            "120",
        ];
        ok(quadray(
            &[&args[..], &["--frame", frame], &small[..]].concat(),
        ));
    }
    // Frame 0 is the scene's own view; frame 30 of 120 the camera a quarter turn round, which
    // --set writes by hand (cos 90° rounds, so compared within compare's tolerance).
    let plain = tmp(&dir, "plain.png");
    ok(quadray(
        &[&["render", &s, "-o", plain.to_str().unwrap()], &small[..]].concat(),
    ));
    assert_eq!(
        std::fs::read(tmp(&dir, "turn-000.png")).unwrap(),
        std::fs::read(&plain).unwrap()
    );
    let quarter = tmp(&dir, "quarter.png");
    let set = ["--set", "camera.from=[9.5, 0.0, 3.6]"];
    ok(quadray(
        &[
            &["render", &s, "-o", quarter.to_str().unwrap()],
            &set[..],
            &small[..],
        ]
        .concat(),
    ));
    let turned = tmp(&dir, "turn-030.png");
    ok(quadray(&[
        "compare",
        quarter.to_str().unwrap(),
        turned.to_str().unwrap(),
    ]));
    // Without a # the frames would overwrite each other: refused.
    let o = quadray(&[
        "render",
        &s,
        "-o",
        plain.to_str().unwrap(),
        "--orbit-frames",
        "4",
        "--frame",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("needs a run of #"));
    let o = quadray(&[
        "render",
        &s,
        "-o",
        pattern.to_str().unwrap(),
        "--orbit-frames",
        "4",
        "--frame",
        "4",
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// A piece rendered twice is the same file byte for byte (its text attributes are written in a
/// fixed order, not a hash map's), and `merge -o` naming one of its own pieces, under any
/// spelling of the path, is refused before anything is written.
#[test]
fn pieces_are_reproducible_and_never_merged_over() {
    let dir = tempfile::tempdir().unwrap();
    let first = piece(&dir, 1, 3);
    let bytes = std::fs::read(&first).unwrap();
    for _ in 0..3 {
        let again = piece(&dir, 1, 3);
        assert_eq!(
            std::fs::read(&again).unwrap(),
            bytes,
            "the same piece twice"
        );
    }
    let pieces: Vec<PathBuf> = (0..3).map(|i| piece(&dir, i, 3)).collect();
    let round_about = dir.path().join(".").join(pieces[2].file_name().unwrap());
    for output in [&pieces[0], &round_about] {
        let before = std::fs::read(output).unwrap();
        let o = merge(&pieces, &["-o", output.to_str().unwrap()]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(String::from_utf8_lossy(&o.stderr).contains("is one of the pieces to merge"));
        assert_eq!(
            std::fs::read(output).unwrap(),
            before,
            "the piece is untouched"
        );
    }
}

/// A glTF camera has a direction but no target: the turntable turns about the scene, so every
/// frame shows it (each turned about a point one unit in front of the lens, frames 1 to 3 of 4
/// showed only background).
#[test]
fn orbit_frames_of_a_gltf_camera_keep_the_scene_in_view() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene("gltf-quadrics.gltf");
    let pattern = tmp(&dir, "turn-#.png");
    for frame in 0..4 {
        ok(quadray(&[
            "render",
            &s,
            "-o",
            pattern.to_str().unwrap(),
            "--orbit-frames",
            "4",
            "--frame",
            &frame.to_string(),
            "--res",
            "64x36",
            "--spp",
            "1",
            "-q",
        ]));
        let img = image::open(tmp(&dir, &format!("turn-{frame}.png")))
            .unwrap()
            .to_rgb8();
        let background = *img.get_pixel(0, 0);
        let shown = img.pixels().filter(|p| **p != background).count();
        assert!(
            shown > 64 * 36 / 10,
            "frame {frame}: {shown} pixels show the scene"
        );
    }
}
