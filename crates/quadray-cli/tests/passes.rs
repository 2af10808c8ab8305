//! Render passes through the binary: EXR channels read back by an independent reader
//! (OpenImageIO's `oiiotool`), PNGs of one pass and their display mappings.

use std::process::Command;

use crate::common;
use common::{pass_scene, quadray, scene, tmp};

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

/// Runs oiiotool, or says why the test cannot use it; under CI, where `.ci/run` installs it, its
/// absence fails the test.
fn oiiotool(args: &[&str]) -> Option<String> {
    match Command::new("oiiotool").args(args).output() {
        Ok(o) => {
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            Some(String::from_utf8_lossy(&o.stdout).into_owned())
        }
        Err(e) if std::env::var_os("CI").is_some() => panic!("oiiotool is not available: {e}"),
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
        "ViewLayer.DiffCol.R",
        "ViewLayer.DiffCol.G",
        "ViewLayer.DiffCol.B",
        "ViewLayer.IndexOB.X",
    ] {
        assert!(info.contains(name), "{name} missing from {info}");
    }
    // oiiotool lists channels alphabetically, as the file stores them: Combined RGBA, Depth,
    // DiffCol RGB, IndexOB, Normal XYZ.
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
            &[0.2, 0.4, 0.6, 1.0, 9.0, 0.2, 0.4, 0.6, 1.0, 0.0, 0.0, 1.0]
        ),
        "{c:?}"
    );
    // Corner: the plane 12 units down, object 2 (spheres are numbered before planes).
    let k = pixel(0, 0);
    assert!(
        close(
            &k,
            &[0.7, 0.7, 0.7, 1.0, 12.0, 0.7, 0.7, 0.7, 2.0, 0.0, 0.0, 1.0]
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

/// The numbers of an attribute line of `oiiotool --info -v`, e.g. `worldToNDC: 0.25, 0, …`.
fn attribute_numbers(info: &str, name: &str) -> Option<Vec<f64>> {
    let line = info
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("{name}:")))?;
    let values = line.split_once(':')?.1;
    Some(
        values
            .split(',')
            .map(|v| v.trim().parse().expect("a number"))
            .collect(),
    )
}

/// The EXR carries the camera as OpenEXR's standard matrices, checked by OpenImageIO against the
/// camera's own geometry: for the pass scene's orthographic camera (at z = 10 looking down, +y up
/// in the image, 4 units tall) camera space is (x, y, 10 − z), and NDC is
/// (0.5 + x/4, 0.5 − y/4); for the defense scene's perspective camera the point it looks at
/// lands at the image centre and a point half its field of view above the axis on the top edge.
/// The colour space is in the standard `chromaticities` attribute.
#[test]
fn exr_files_carry_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    let orthographic = pass_scene(&dir);
    let out = tmp(&dir, "camera.exr");
    let o = quadray(&["render", &orthographic, "-o", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let Some(info) = oiiotool(&["--info", "-v", out.to_str().unwrap()]) else {
        return;
    };
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6)
    };
    // Imath's row-vector matrices, row by row: the translation is the last row.
    let to_camera = attribute_numbers(&info, "worldToCamera").expect("worldToCamera");
    let expected = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 10.0, 1.0,
    ];
    assert!(close(&to_camera, &expected), "{to_camera:?}");
    let to_ndc = attribute_numbers(&info, "worldToNDC").expect("worldToNDC");
    let expected = [
        0.25, 0.0, 0.0, 0.0, 0.0, -0.25, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.5, 0.5, 10.0, 1.0,
    ];
    assert!(close(&to_ndc, &expected), "{to_ndc:?}");
    let position = attribute_numbers(&info, "cameraPosition").expect("cameraPosition");
    assert!(close(&position, &[0.0, 0.0, 10.0]), "{position:?}");
    assert!(
        !info.contains("fieldOfView"),
        "an orthographic camera has no field of view"
    );

    let perspective = tmp(&dir, "defense.exr");
    let o = quadray(&[
        "render",
        &scene("defense.toml"),
        "--res",
        "32x18",
        "-o",
        perspective.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let info = oiiotool(&["--info", "-v", perspective.to_str().unwrap()]).unwrap();
    let m = attribute_numbers(&info, "worldToNDC").expect("worldToNDC");
    // The scene's `to`, as a row vector times the matrix, then divided by w.
    let p = [0.0, 0.0, 0.9, 1.0];
    let column = |c: usize| (0..4).map(|r| p[r] * m[r * 4 + c]).sum::<f64>();
    let w = column(3);
    assert!(w > 0.0, "in front of the camera");
    // oiiotool prints six significant digits.
    let (x, y) = (column(0) / w, column(1) / w);
    assert!(
        (x - 0.5).abs() < 1e-4 && (y - 0.5).abs() < 1e-4,
        "{x} {y} {m:?}"
    );
    // The field of view is in worldToNDC: a point 21° (half the scene's vfov 42°) above the view
    // axis lands on the top edge, y = 0. Camera space: +z along the view, +y up.
    let to_camera = attribute_numbers(&info, "worldToCamera").expect("worldToCamera");
    let to_world = glam::DMat4::from_cols_array(&to_camera.clone().try_into().unwrap()).inverse();
    let edge = to_world.transform_point3(glam::DVec3::new(0.0, 21f64.to_radians().tan(), 1.0));
    let p = [edge.x, edge.y, edge.z, 1.0];
    let column = |c: usize| (0..4).map(|r| p[r] * m[r * 4 + c]).sum::<f64>();
    assert!(
        (column(1) / column(3)).abs() < 1e-4,
        "{}",
        column(1) / column(3)
    );
    assert!(
        !info.contains("fieldOfView"),
        "no non-standard field of view attributes"
    );
    // Linear Rec. 709 primaries, D65 white, in OpenEXR's standard attribute.
    let chromaticities = attribute_numbers(&info, "chromaticities").expect("chromaticities");
    assert!(
        close(
            &chromaticities,
            &[0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329]
        ),
        "{chromaticities:?}"
    );
}

#[test]
fn a_crop_window_is_placed_in_the_full_frame() {
    let dir = tempfile::tempdir().unwrap();
    let scene = pass_scene(&dir);
    let whole = tmp(&dir, "whole.png");
    let o = quadray(&["render", &scene, "-o", whole.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Of 9 columns, [0.3, 0.7] covers 3..7 (ceil(2.7), ceil(6.3)); of 9 rows, [0.5, 1] covers 5..9.
    let crop = ["--crop", "0.3,0.7,0.5,1"];
    let png = tmp(&dir, "crop.png");
    let o = quadray(
        &[
            &["render", &scene, "-o", png.to_str().unwrap(), "-q"],
            &crop[..],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (whole, part) = (
        image::open(&whole).unwrap().to_rgb8(),
        image::open(&png).unwrap().to_rgb8(),
    );
    assert_eq!(part.dimensions(), (4, 4));
    for (x, y, p) in part.enumerate_pixels() {
        assert_eq!(p, whole.get_pixel(x + 3, y + 5), "pixel ({x}, {y})");
    }
    let exr = tmp(&dir, "crop.exr");
    let o = quadray(
        &[
            &[
                "render",
                &scene,
                "-o",
                exr.to_str().unwrap(),
                "--aov",
                "depth",
                "-q",
            ],
            &crop[..],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let Some(info) = oiiotool(&["--info", "-v", exr.to_str().unwrap()]) else {
        return;
    };
    for fact in [
        "4 x    4, 5 channel",
        "pixel data origin: x=3, y=5",
        "full/display size: 9 x 9",
    ] {
        assert!(info.contains(fact), "{fact} missing from {info}");
    }
    // A window without a pixel is a usage error.
    let o = quadray(&[
        "render",
        &scene,
        "-o",
        png.to_str().unwrap(),
        "--crop",
        "0.3,0.7,0.5,0.51",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--crop 0.3,0.7,0.5,0.51"));
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
