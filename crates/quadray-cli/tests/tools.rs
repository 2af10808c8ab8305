//! The explorer (`quadray quadric`), the contact sheet (`quadray gallery`) and `quadray compare`
//! through the binary.

use crate::common;
use common::{pass_scene, quadray, tmp};

/// Without `-o`, `quadric KIND` writes `quadric-KIND.png` and `gallery` writes `gallery.png` in the
/// current folder, as `render` has a default output; `general` without `--coeffs` is the gallery's.
#[test]
fn explorer_and_gallery_have_default_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args(args)
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let said = run(&["quadric", "cone", "--res", "32x24", "--spp", "1"]);
    assert!(said.contains("-> quadric-cone.png"), "{said}");
    run(&["quadric", "general", "--res", "32x24", "--spp", "1"]);
    run(&["gallery", "--tile", "64x62", "--spp", "1", "-q"]);
    for (name, size) in [
        ("quadric-cone.png", (32, 24)),
        ("quadric-general.png", (32, 24)),
    ] {
        let img = image::open(dir.path().join(name)).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), size, "{name}");
        let bg = img.get_pixel(0, 0);
        assert!(img.pixels().any(|p| p != bg), "{name} shows its quadric");
    }
    assert!(dir.path().join("gallery.png").is_file());
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
            vec!["quadric", "general", "--coeffs", "1,2", "-o", "x.png"],
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
