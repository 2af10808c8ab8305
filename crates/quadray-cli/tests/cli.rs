//! The real `quadray` binary, run as a user would: exit codes, messages and files.

use std::process::Command;

mod common;
use common::{quadray, scene, tmp};

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
    // The line itself, with a caret under the column.
    assert!(err.contains("7 | radius = -2\n  |          ^"), "{err}");
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
    assert_eq!(
        o.status.code(),
        Some(2),
        "values out of range are usage errors"
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("100000x100000 is outside the limits"));
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
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists());
}

/// A scene without lights, and a camera that looks away from everything, load and render but
/// are warned about, by `check` and `render` alike; a lit scene in view gets no warning.
#[test]
fn dark_and_empty_views_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let unlit = tmp(&dir, "unlit.toml");
    let base = "version = 1\n[camera]\nfrom = [0, -5, 1]\nto = [0, 0, 0]\n[[material]]\nname = \"m\"\n\
                [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n";
    std::fs::write(&unlit, base).unwrap();
    let away = tmp(&dir, "away.toml");
    let light = "[[light]]\ntype = \"point\"\nposition = [2, -3, 4]\nintensity = 20\n";
    std::fs::write(
        &away,
        base.replace("to = [0, 0, 0]", "to = [0, -10, 1]") + light,
    )
    .unwrap();
    let lit = tmp(&dir, "lit.toml");
    std::fs::write(&lit, base.to_string() + light).unwrap();
    for (file, expected) in [
        (&unlit, Some("has no lights")),
        (&away, Some("the camera sees none")),
        (&lit, None),
    ] {
        let path = file.to_str().unwrap();
        let out = tmp(&dir, "o.png");
        for o in [
            quadray(&["check", path]),
            quadray(&["render", path, "--res", "8x6", "-o", out.to_str().unwrap()]),
        ] {
            assert!(o.status.success());
            let err = String::from_utf8_lossy(&o.stderr);
            match expected {
                Some(text) => assert!(err.contains(text) && err.contains("warning:"), "{err}"),
                None => assert!(!err.contains("warning"), "{err}"),
            }
        }
    }
}

/// The depth PNG spans the finite content: the defense scene's floor runs to the horizon, which
/// used to squeeze every object into white. Now the nearest hit is white, the farthest object
/// point the darkest grey (0.15 of white, where far floor pixels clamp), and the objects spread
/// over many grey levels between.
#[test]
fn the_depth_png_spans_the_scene_not_the_horizon() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "depth.png");
    let o = quadray(&[
        "render",
        &scene("defense.toml"),
        "--pass",
        "depth",
        "--res",
        "160x90",
        "--spp",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("depth shown from") && err.contains("farther plane pixels clamp"),
        "{err}"
    );
    let img = image::open(&out).unwrap().to_luma8();
    let mut levels: Vec<u8> = img.pixels().map(|p| p.0[0]).filter(|&v| v > 0).collect();
    levels.sort_unstable();
    levels.dedup();
    assert_eq!(levels.first(), Some(&38), "far pixels at 0.15 of white");
    assert_eq!(levels.last(), Some(&255), "the nearest hit white");
    assert!(levels.len() > 100, "{} grey levels", levels.len());
}

/// `--set` overrides a scene file's values with the file's own validation, and names itself in
/// errors about the values it set.
#[test]
fn set_overrides_scene_values() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "set.png");
    let o = quadray(&[
        "render",
        &scene("sphere-on-plane.toml"),
        "--set",
        "render.resolution=[12,10]",
        "--set",
        "camera.vfov=20",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (12, 10));
    let o = quadray(&["check", &scene("defense.toml"), "--set", "render.spp=0"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("`render.spp`: must be between 1 and 65536, got 0 (the value comes from --set render.spp=0)"),
        "{err}"
    );
    let o = quadray(&["check", &scene("defense.toml"), "--set", "render.spd=4"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("did you mean \"spp\""));
}

/// `--seed` gives independent renders: the same seed the same bytes, another seed other jitter.
#[test]
fn seeds_decorrelate_renders_and_repeat_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let render = |seed: &str, name: &str| {
        let out = tmp(&dir, name);
        let o = quadray(&[
            "render",
            &scene("sphere-on-plane.toml"),
            "--res",
            "48x36",
            "--spp",
            "4",
            "--seed",
            seed,
            "-q",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        image::open(&out).unwrap().to_rgb8().into_raw()
    };
    let (a, again, other) = (
        render("0", "a.png"),
        render("0", "b.png"),
        render("7", "c.png"),
    );
    assert_eq!(a, again);
    assert_ne!(a, other);
}

/// Without `-o`, `render` writes the scene's name with .png beside the scene.
#[test]
fn the_output_defaults_to_a_png_beside_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let copy = tmp(&dir, "ball.toml");
    std::fs::copy(scene("sphere-on-plane.toml"), &copy).unwrap();
    let o = quadray(&["render", copy.to_str().unwrap(), "--res", "8x6", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(tmp(&dir, "ball.png")).unwrap();
    assert_eq!((img.width(), img.height()), (8, 6));
}

/// `--version` names the program, and `--help` lists every subcommand and the exit statuses.
#[test]
fn version_and_help_say_what_a_user_needs() {
    let o = quadray(&["--version"]);
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        format!("quadray {}", env!("CARGO_PKG_VERSION"))
    );
    let help = String::from_utf8_lossy(&quadray(&["--help"]).stdout).into_owned();
    for command in [
        "render", "check", "convert", "bench", "quadric", "gallery", "compare",
    ] {
        assert!(
            help.lines().any(|l| l.trim_start().starts_with(command)),
            "--help lists {command}: {help}"
        );
    }
    assert!(
        help.contains("Exit status") && help.contains("usage error"),
        "{help}"
    );
}

/// Shell completions and the man page come from the parser's own definitions.
#[test]
fn completions_and_man_page_cover_the_subcommands() {
    for shell in ["bash", "zsh", "fish"] {
        let o = quadray(&["completions", shell]);
        assert!(o.status.success(), "{shell}");
        let script = String::from_utf8_lossy(&o.stdout);
        // fish writes long options as `-l spp`.
        for word in ["render", "compare", "spp", "max-depth"] {
            assert!(script.contains(word), "{shell} completes {word}");
        }
    }
    assert_eq!(quadray(&["completions", "tcsh"]).status.code(), Some(2));
    let o = quadray(&["man"]);
    assert!(o.status.success());
    let page = String::from_utf8_lossy(&o.stdout);
    assert!(page.contains(".TH quadray"), "{page}");
    assert!(
        page.contains("render") && page.contains("Exit status"),
        "{page}"
    );
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
    assert!(
        text.contains("structure: 0 prototypes, 0 instances (0 placements); 26 shapes stored (20 triangles), 20 triangles instanced"),
        "{text}"
    );
    // The colonnade: one column (3 shapes) and one orb stored; 6 columns and 3 orbs placed.
    let o = quadray(&["check", &scene("columns.toml")]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(
            "structure: 3 prototypes, 8 instances (11 placements); 4 shapes stored (0 triangles)"
        ),
        "{text}"
    );
}

/// A unit sphere (material colour 0.2, 0.4, 0.6) over a plane at z = -2, seen straight down by an
/// orthographic camera 10 units up: every pass value at the centre and corner follows by hand.
const PASS_SCENE: &str = r#"version = 1
[camera]
projection = "orthographic"
from = [0, 0, 10]
to = [0, 0, 0]
up = [0, 1, 0]
height = 4.0
[render]
resolution = [9, 9]
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

fn pass_scene(dir: &tempfile::TempDir) -> String {
    let path = tmp(dir, "passes.toml");
    std::fs::write(&path, PASS_SCENE).unwrap();
    path.to_string_lossy().into_owned()
}

/// Runs oiiotool, or says why the test cannot use it (it is installed by .ci/run).
fn oiiotool(args: &[&str]) -> Option<String> {
    match Command::new("oiiotool").args(args).output() {
        Ok(o) => {
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            Some(String::from_utf8_lossy(&o.stdout).into_owned())
        }
        Err(e) => {
            println!(
                "skipped: oiiotool is not available ({e}); `apt-get install openimageio-tools`"
            );
            None
        }
    }
}

#[test]
fn exr_passes_read_back_in_an_independent_reader() {
    let dir = tempfile::tempdir().unwrap();
    let scene = pass_scene(&dir);
    let out = tmp(&dir, "passes.exr");
    let o = quadray(&[
        "render",
        &scene,
        "-o",
        out.to_str().unwrap(),
        "--aov",
        "depth,normal,albedo,object-id",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let Some(info) = oiiotool(&["--info", "-v", out.to_str().unwrap()]) else {
        return;
    };
    assert!(
        info.contains("9 x    9, 12 channel, float openexr"),
        "{info}"
    );
    for name in [
        "ViewLayer.Combined.R",
        "ViewLayer.Combined.G",
        "ViewLayer.Combined.B",
        "ViewLayer.Combined.A",
        "ViewLayer.Depth.Z",
        "ViewLayer.Normal.X",
        "ViewLayer.Normal.Y",
        "ViewLayer.Normal.Z",
        "ViewLayer.Albedo.R",
        "ViewLayer.Albedo.G",
        "ViewLayer.Albedo.B",
        "ViewLayer.IndexOB.X",
    ] {
        assert!(info.contains(name), "{name} missing from {info}");
    }
    // oiiotool lists channels alphabetically, as the file stores them: Albedo RGB, Combined RGBA,
    // Depth, IndexOB, Normal XYZ.
    let dump = oiiotool(&["--dumpdata", out.to_str().unwrap()]).unwrap();
    let pixel = |x: u32, y: u32| -> Vec<f64> {
        let tag = format!("Pixel ({x}, {y}):");
        let line = dump
            .lines()
            .find(|l| l.contains(&tag))
            .expect("pixel listed");
        line.split(':')
            .nth(1)
            .unwrap()
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
    // Centre: the sphere's top, straight below the camera: depth 10 - 1, normal +z, object 1 (the
    // first sphere), lit head-on by the unit directional light: (0.1 + 0.9) · albedo.
    let c = pixel(4, 4);
    assert!(
        close(
            &c,
            &[0.2, 0.4, 0.6, 0.2, 0.4, 0.6, 1.0, 9.0, 1.0, 0.0, 0.0, 1.0]
        ),
        "{c:?}"
    );
    // Corner: the plane 12 units down, object 2 (spheres are numbered before planes).
    let k = pixel(0, 0);
    assert!(
        close(
            &k,
            &[0.7, 0.7, 0.7, 0.7, 0.7, 0.7, 1.0, 12.0, 2.0, 0.0, 0.0, 1.0]
        ),
        "{k:?}"
    );

    // --half: the beauty pass in half floats, the passes still f32.
    let half = tmp(&dir, "half.exr");
    let o = quadray(&[
        "render",
        &scene,
        "-o",
        half.to_str().unwrap(),
        "--aov",
        "depth",
        "--half",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info = oiiotool(&["--info", "-v", half.to_str().unwrap()]).unwrap();
    assert!(
        info.contains("ViewLayer.Combined.R (half)") && info.contains("ViewLayer.Depth.Z (float)"),
        "{info}"
    );
}

#[test]
fn png_shows_one_pass_and_bad_pass_options_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = pass_scene(&dir);
    let out = tmp(&dir, "normal.png");
    let o = quadray(&[
        "render",
        &scene,
        "-o",
        out.to_str().unwrap(),
        "--pass",
        "normal",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out).unwrap().to_rgb8();
    // +z as (n + 1)/2 colours: (128, 128, 255).
    assert_eq!(img.get_pixel(4, 4).0, [128, 128, 255]);
    let ids = tmp(&dir, "ids.png");
    let o = quadray(&[
        "render",
        &scene,
        "-o",
        ids.to_str().unwrap(),
        "--pass",
        "object-id",
        "-q",
    ]);
    assert!(o.status.success());
    let img = image::open(&ids).unwrap().to_rgb8();
    assert_ne!(img.get_pixel(4, 4), img.get_pixel(0, 0));

    for (args, message) in [
        (
            vec!["-o", "x.png", "--aov", "depth"],
            "--aov needs an .exr output",
        ),
        (
            vec!["-o", "x.exr", "--pass", "depth"],
            "--pass is for PNG output",
        ),
        (vec!["-o", "x.png", "--half"], "--half is for EXR output"),
        (
            vec!["-o", "x.exr", "--aov", "combined"],
            "the beauty image is always written",
        ),
    ] {
        let mut all = vec!["render", scene.as_str()];
        all.extend(args);
        let o = quadray(&all);
        assert_eq!(
            o.status.code(),
            Some(2),
            "options that conflict are usage errors"
        );
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(message),
            "{message}"
        );
    }
    let o = quadray(&["render", &scene, "-o", "x.exr", "--aov", "speed"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "unknown pass names are usage errors"
    );
}

#[test]
fn quadric_explorer_lists_renders_and_refuses_bad_input() {
    let o = quadray(&["quadric", "--list"]);
    assert!(o.status.success());
    let list = String::from_utf8_lossy(&o.stdout);
    assert_eq!(list.lines().count(), 10);
    assert!(
        list.contains("hyperboloid2           x²/a² + y²/b² − z²/c² = −1"),
        "{list}"
    );
    assert!(list.contains("general"));

    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "cone.png");
    let o = quadray(&[
        "quadric",
        "cone",
        "-a",
        "0.5",
        "-b",
        "0.8",
        "--clip",
        "1.5",
        "--texture",
        "checker",
        "--yaw",
        "-30",
        "--pitch",
        "10",
        "--res",
        "64x48",
        "--spp",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // The cone shows: pixels other than the background's.
    let bg = img.get_pixel(0, 0);
    assert!(img.pixels().filter(|p| *p != bg).count() > 200);

    // Without lighting the texture's flat colours show: the ramp's pure stops appear.
    let flat = tmp(&dir, "flat.png");
    let o = quadray(&[
        "quadric",
        "general",
        "--coeffs",
        "1,1,-1,0,0,0,0,0,0,-0.25",
        "--no-lighting",
        "--res",
        "48x48",
        "--spp",
        "1",
        "-o",
        flat.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    // Usage errors (2), then a quadric the options describe but that shows nothing (1).
    for (args, message, code) in [
        (
            vec!["quadric", "sphere", "-o", "x.png"],
            "unknown quadric kind \"sphere\"",
            2,
        ),
        (
            vec!["quadric", "general", "-o", "x.png"],
            "exactly 10 numbers",
            2,
        ),
        (
            vec!["quadric", "cone", "--coeffs", "1,2", "-o", "x.png"],
            "--coeffs is for `general`",
            2,
        ),
        (
            vec!["quadric", "ellipsoid", "-a", "-1", "-o", "x.png"],
            "-a must be",
            2,
        ),
        (
            vec!["quadric", "ellipsoid", "--clip", "0", "-o", "x.png"],
            "--clip must be a positive",
            2,
        ),
        (
            vec!["quadric", "ellipsoid", "--pitch", "100", "-o", "x.png"],
            "--pitch must be in",
            2,
        ),
        (
            vec!["quadric", "ellipsoid", "-o", "x.jpg"],
            "must end in .png or .exr",
            2,
        ),
        (
            vec![
                "quadric",
                "general",
                "--coeffs",
                "1,1,1,0,0,0,0,0,0,1",
                "-o",
                "x.png",
            ],
            "empty",
            1,
        ),
    ] {
        let o = quadray(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
}

#[test]
fn gallery_is_a_labelled_sheet_of_every_kind() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "gallery.png");
    let o = quadray(&[
        "gallery",
        "-o",
        out.to_str().unwrap(),
        "--tile",
        "120x110",
        "--spp",
        "1",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&out).unwrap().to_rgb8();
    // Five tiles a row, two rows, a 22-pixel title band at text scale 1.
    assert_eq!(img.dimensions(), (600, 22 + 2 * 110));
    // The labels' warm white appears in every tile's caption band.
    for i in 0..10u32 {
        let (x0, y0) = ((i % 5) * 120, 22 + (i / 5) * 110 + 80);
        let has_label =
            (x0..x0 + 120).any(|x| (y0..y0 + 30).any(|y| img.get_pixel(x, y).0 == [240, 236, 226]));
        assert!(has_label, "tile {i} has its name drawn in");
    }
    let o = quadray(&["gallery", "-o", out.to_str().unwrap(), "--tile", "10x10"]);
    assert_eq!(o.status.code(), Some(2));
    let o = quadray(&["gallery", "-o", tmp(&dir, "g.exr").to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("must end in .png"));
}

#[test]
fn compare_measures_and_fails_over_the_thresholds() {
    let dir = tempfile::tempdir().unwrap();
    let a = tmp(&dir, "a.png");
    let b = tmp(&dir, "b.png");
    let e = tmp(&dir, "a.exr");
    let scene = pass_scene(&dir);
    for (out, extra) in [(&a, "1"), (&e, "1"), (&b, "2")] {
        // b differs: a second sample per pixel moves the sphere's edge pixels.
        let o = quadray(&[
            "render",
            &scene,
            "-o",
            out.to_str().unwrap(),
            "--spp",
            extra,
            "--res",
            "40x40",
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let same = quadray(&["compare", a.to_str().unwrap(), e.to_str().unwrap()]);
    assert!(
        same.status.success(),
        "{}",
        String::from_utf8_lossy(&same.stderr)
    );
    let text = String::from_utf8_lossy(&same.stdout);
    assert!(text.contains("0 pixels (0.000%) over 2/255"), "{text}");

    let diff = tmp(&dir, "diff.png");
    let o = quadray(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--diff",
        diff.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("differ:"));
    assert_eq!(image::open(&diff).unwrap().to_rgb8().dimensions(), (40, 40));
    // Loose enough thresholds accept the same pair.
    let o = quadray(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--max-percent",
        "100",
        "--max-diff",
        "255",
    ]);
    assert!(o.status.success());

    let small = tmp(&dir, "small.png");
    quadray(&[
        "render",
        &scene,
        "-o",
        small.to_str().unwrap(),
        "--res",
        "8x8",
        "-q",
    ]);
    let o = quadray(&["compare", a.to_str().unwrap(), small.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("differ in size"));
    let o = quadray(&["compare", a.to_str().unwrap(), "/no/such.png"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "compare: trouble is 2, a difference 1"
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("/no/such.png"));
}

/// The AVX2+FMA traversal (chosen at run time where the CPU has it, for scenes that are mostly
/// triangles, as scenes/obj-mesh.toml is) and the baseline traversal render bit-identical images:
/// the same arithmetic, only the instruction encoding differs. On a CPU without AVX2 both runs take
/// the baseline path and the test still checks determinism.
#[test]
fn simd_paths_render_identical_images() {
    let dir = tempfile::tempdir().unwrap();
    let mut outputs = Vec::new();
    for (path, name) in [("baseline", "base.png"), ("auto", "auto.png")] {
        let out = tmp(&dir, name);
        let status = Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args(["render", &scene("obj-mesh.toml"), "-o"])
            .arg(&out)
            .args(["--res", "160x90", "--spp", "2", "--stats"])
            .env("QUADRAY_SIMD", path)
            .output()
            .unwrap();
        assert!(status.status.success());
        let stats = String::from_utf8_lossy(&status.stderr);
        #[cfg(target_arch = "x86_64")]
        let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
        #[cfg(not(target_arch = "x86_64"))]
        let avx2 = false;
        let expected = if path == "auto" && avx2 {
            "traversal AVX2+FMA"
        } else {
            "traversal "
        };
        assert!(stats.contains(expected), "{stats}");
        if path == "baseline" {
            assert!(!stats.contains("AVX2"), "{stats}");
        }
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert!(
        outputs[0] == outputs[1],
        "the two traversal paths rendered different images"
    );
}
