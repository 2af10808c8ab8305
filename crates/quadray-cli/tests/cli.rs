//! The real `quadray` binary, run as a user would: rendering scenes, exit codes, messages,
//! warnings, outputs and the conventions of the command line (`--set`, `--seed`, `--version`,
//! completions).

use std::process::Command;

use crate::common;
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
    // An ellipsoid 1.1 wide, 10^6 + 1/3 from its coefficients' origin (printed to 17 digits): see
    // quadray::quadric::conditioning, whose test measures the surface moving.
    let far = tmp(&dir, "far.toml");
    let quadric = |coefficients: &str, clip: &str| {
        format!(
            "[[quadric]]\nkind = \"general\"\ncoefficients = [{coefficients}]\nclip = {clip}\n\
             material = \"m\"\n"
        )
    };
    let far_ellipsoid = quadric(
        "1, 1, 1e6, 0, 0, 0, -2000000.6666666667, 0, 0, 1000000666665.5677",
        "{ min = [999999.1, -1.2, -0.0012], max = [1000001.5, 1.2, 0.0012] }",
    );
    std::fs::write(
        &far,
        base.replace(
            "from = [0, -5, 1]\nto = [0, 0, 0]",
            "from = [1000000.3, -5, 1]\nto = [1000000.3, 0, 0]",
        ) + light
            + &far_ellipsoid,
    )
    .unwrap();
    // The same ellipsoid about its own centre, placed by a transform: nothing to say.
    let placed = tmp(&dir, "placed.toml");
    std::fs::write(
        &placed,
        std::fs::read_to_string(&far).unwrap().replace(
            &far_ellipsoid,
            &(quadric(
                "1, 1, 1e6, 0, 0, 0, 0, 0, 0, -1.21",
                "{ min = [-1.2, -1.2, -0.0012], max = [1.2, 1.2, 0.0012] }",
            ) + "transform = { translate = [1000000.3333333333, 0, 0] }\n"),
        ),
    )
    .unwrap();
    let outside = tmp(&dir, "outside.toml");
    std::fs::write(
        &outside,
        base.to_string()
            + light
            + &quadric(
                "1, 1, 1, 0, 0, 0, 0, 0, 0, -1",
                "{ min = [2, 2, 2], max = [3, 3, 3] }",
            ),
    )
    .unwrap();
    // An OBJ whose material has an image texture but whose faces have no texture coordinates.
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 30, 30]))
        .save(tmp(&dir, "red.png"))
        .unwrap();
    std::fs::write(
        tmp(&dir, "red.mtl"),
        "newmtl red\nKd 1 1 1\nmap_Kd red.png\n",
    )
    .unwrap();
    let no_uv = tmp(&dir, "no-uv.obj");
    std::fs::write(
        &no_uv,
        "mtllib red.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    )
    .unwrap();
    for (file, expected) in [
        (&unlit, Some("has no lights")),
        (&away, Some("the camera sees none")),
        (&lit, None),
        (&far, Some("cannot hold the surface")),
        (&far, Some("translate = [1000000.3333")),
        (&placed, None),
        (
            &outside,
            Some("quadric[0] (ellipsoid) does not reach into its clip box"),
        ),
        (
            &no_uv,
            Some(
                "material \"red\" has an image texture read through texture coordinates (set 0), which 1 mesh using it lacks",
            ),
        ),
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
    // A value of the wrong type names its override, not the file's line of the key, which holds
    // a valid value.
    let o = quadray(&[
        "check",
        &scene("defense.toml"),
        "--set",
        "camera.from=\"abc\"",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("(the value comes from --set camera.from=\"abc\")") && !err.contains("-->"),
        "{err}"
    );
    // Beside another override (here --res's own), only the one at fault is named.
    let o = quadray(&[
        "check",
        &scene("defense.toml"),
        "--set",
        "camera.vfov=abc",
        "--set",
        "render.spp=2",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("(the value comes from --set camera.vfov=abc)") && !err.contains("spp"),
        "{err}"
    );
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

/// Without `-o`, `render` writes the scene's `[output]`, else its name with .png beside it.
#[test]
fn the_output_defaults_to_a_png_beside_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let copy = tmp(&dir, "ball.toml");
    std::fs::copy(scene("sphere-on-plane.toml"), &copy).unwrap();
    let o = quadray(&["render", copy.to_str().unwrap(), "--res", "8x6", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(tmp(&dir, "ball.png")).unwrap();
    assert_eq!((img.width(), img.height()), (8, 6));

    // The scene's [output] (relative to the scene's folder) replaces that default; -o wins over it.
    let text = std::fs::read_to_string(&copy).unwrap() + "\n[output]\nfile = \"out/ball.exr\"\n";
    std::fs::write(&copy, text).unwrap();
    std::fs::create_dir(tmp(&dir, "out")).unwrap();
    let o = quadray(&["render", copy.to_str().unwrap(), "--res", "8x6", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(tmp(&dir, "out/ball.exr").is_file());
    let chosen = tmp(&dir, "chosen.png");
    let o = quadray(&[
        "render",
        copy.to_str().unwrap(),
        "--res",
        "8x6",
        "-q",
        "-o",
        chosen.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(chosen.is_file());
    // An [output] in a folder that does not exist is an error that says the scene named it.
    std::fs::remove_dir_all(tmp(&dir, "out")).unwrap();
    let o = quadray(&["render", copy.to_str().unwrap(), "--res", "8x6", "-q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("ball.toml's [output] file names") && err.contains("does not exist"),
        "{err}"
    );
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
    let bench = cfg!(feature = "bench").then_some("bench");
    for command in [
        "render", "check", "convert", "quadric", "gallery", "compare",
    ]
    .into_iter()
    .chain(bench)
    {
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
        text.contains("ok: 2 spheres, 1 plane, 4 quadrics, 1 mesh (20 triangles), 2 lights")
            && text.contains("640x360, 4 spp, max depth 8"),
        "{text}"
    );
    // How the scene samples, as its [render] table says.
    for (set, says) in [
        (
            vec!["--set", "render.antialias_threshold=0.1"],
            "4 spp, 16 where a pixel differs from a neighbour by more than 0.1, max depth 8",
        ),
        (
            vec![
                "--set",
                "render.spp=2",
                "--set",
                "render.antialias_threshold=0.05",
                "--set",
                "render.antialias_spp=32",
            ],
            "2 spp, 32 where a pixel differs from a neighbour by more than 0.05",
        ),
    ] {
        let scene_path = scene("defense.toml");
        let mut args = vec!["check", &scene_path];
        args.extend(set);
        let o = quadray(&args);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success() && text.contains(says), "{text}");
    }
    let dir = tempfile::tempdir().unwrap();
    let adaptive = dir.path().join("adaptive.toml");
    let defense = std::fs::read_to_string(scene("defense.toml")).unwrap();
    let without_spp: String = (defense.lines())
        .filter(|l| !l.trim_start().starts_with("spp"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(
        &adaptive,
        without_spp.replace("[render]\n", "[render]\ntarget_error = 0.01\n"),
    )
    .unwrap();
    let o = quadray(&["check", adaptive.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("adaptive to image error 0.01, 8..1024 spp, max depth 8"),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
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
    // A path quadray does not know is refused rather than ignored.
    let o = Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(["check", &scene("obj-mesh.toml")])
        .env("QUADRAY_SIMD", "avx512")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("QUADRAY_SIMD=avx512: its values are `baseline`"),
        "{stderr}"
    );
    assert!(
        outputs[0] == outputs[1],
        "the two traversal paths rendered different images"
    );
}

#[test]
fn verbose_logs_each_phase_and_every_file_read() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "v.png");
    let scene = scene("defense.toml");
    let out = out.to_str().unwrap();
    let run = |verbosity: &[&str]| {
        let o = quadray(&[&["render", &scene, "--res", "32x18", "-o", out], verbosity].concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let quiet = run(&[]);
    assert!(!quiet.contains("info:"), "{quiet}");
    let v = run(&["-v"]);
    for phase in [
        "info: loaded ",
        "info: built the scene and its BVH in ",
        "info: rendered 18 rows of ",
        "info: wrote ",
    ] {
        assert!(v.contains(phase), "{phase} missing from {v}");
    }
    assert!(!v.contains("debug:"), "{v}");
    // -vv adds every file read, and -v works before the subcommand too.
    let o = quadray(&["-vv", "render", &scene, "--res", "32x18", "-o", out]);
    let vv = String::from_utf8_lossy(&o.stderr);
    assert!(
        vv.contains("debug: read ") && vv.contains("defense.toml"),
        "{vv}"
    );
}

#[test]
fn texture_filter_none_point_samples_and_bad_values_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let out = tmp(&dir, name);
        let mut args = vec![
            "render",
            &scene("defense.toml")[..],
            "--res",
            "160x90",
            "-q",
        ]
        .into_iter()
        .map(str::to_owned)
        .collect::<Vec<_>>();
        args.extend(["-o".to_owned(), out.to_str().unwrap().to_owned()]);
        args.extend(extra.iter().map(|s| s.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        (quadray(&args), out)
    };
    let (filtered, filtered_png) = render("filtered.png", &[]);
    let (point, point_png) = render("point.png", &["--texture-filter", "none"]);
    assert!(filtered.status.success() && point.status.success());
    // The checkered floor and saddle differ; everything else is the same image.
    assert_ne!(
        std::fs::read(&filtered_png).unwrap(),
        std::fs::read(&point_png).unwrap()
    );
    let (bad, bad_png) = render("bad.png", &["--texture-filter", "mipmap"]);
    assert_eq!(bad.status.code(), Some(2));
    let message = String::from_utf8_lossy(&bad.stderr);
    assert!(
        message.contains("--texture-filter") && message.contains("box"),
        "{message}"
    );
    assert!(!bad_png.exists());
}
