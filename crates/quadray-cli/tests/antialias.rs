//! Anti-aliasing by contrast through the binary: the stats line, thread-count determinism, the
//! pixels it leaves alone, and bad values.

use crate::common;
use common::{quadray, scene, tmp};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The defense scene at 96x54 from one sample a pixel: edges and textures take 16, the rest keep
/// theirs (so the image differs from the 1-spp render only where the contrast was); 1 and 2
/// threads write the same bytes; a crop is the same pixels.
#[test]
fn antialiased_renders_report_their_samples_and_are_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let render = |extra: &[&str], out: &str| {
        let out = tmp(&dir, out);
        let scene = scene("defense.toml");
        let mut args = vec!["render", &scene, "--res", "96x54", "--spp", "1"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", out.to_str().unwrap()]);
        let o = quadray(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        (std::fs::read(&out).unwrap(), stderr(&o))
    };
    let (one, line) = render(&["--aa-threshold", "0.1", "-t", "1"], "one.png");
    let (two, _) = render(&["--aa-threshold", "0.1", "-t", "2"], "two.png");
    assert_eq!(one, two);
    assert!(
        line.contains("96x54, ") && line.contains("spp mean (1..16)"),
        "{line}"
    );
    let (plain, _) = render(&[], "plain.png");
    let decode = |png: &[u8]| image::load_from_memory(png).unwrap().to_rgb8();
    let (aa, plain) = (decode(&one), decode(&plain));
    let changed = aa
        .pixels()
        .zip(plain.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        (1..96 * 54 / 2).contains(&changed),
        "{changed} of {} pixels anti-aliased",
        96 * 54
    );
    // --aa-spp sets the count; a scene's window renders the same pixels.
    let (_, line) = render(&["--aa-threshold", "0.1", "--aa-spp", "8"], "eight.png");
    assert!(line.contains("spp mean (1..8)"), "{line}");
    // The scene file's keys (here through --set, validated as the file's own) say the same.
    let (from_scene, line) = render(
        &[
            "--set",
            "render.antialias_threshold=0.1",
            "--set",
            "render.antialias_spp=16",
        ],
        "scene.png",
    );
    assert!(line.contains("spp mean (1..16)"), "{line}");
    assert_eq!(decode(&from_scene), aa);
    // A scene's count left to its default follows --spp: four times 16 from 16 samples on.
    let sixteen = tmp(&dir, "sixteen.png");
    let o = quadray(&[
        "render",
        &scene("defense.toml"),
        "--res",
        "48x27",
        "--set",
        "render.antialias_threshold=0.1",
        "--spp",
        "16",
        "-o",
        sixteen.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("spp mean (16..64)"), "{}", stderr(&o));
    let (crop, _) = render(
        &["--aa-threshold", "0.1", "--crop", "0.25,0.75,0.5,1"],
        "crop.png",
    );
    let crop = decode(&crop);
    for (x, y, p) in crop.enumerate_pixels() {
        assert_eq!(p, aa.get_pixel(x + 24, y + 27), "({x}, {y})");
    }
}

#[test]
fn bad_antialiasing_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "x.png");
    let cases = [
        (vec!["--aa-threshold", "1.5"], "from 0 to 1"),
        (vec!["--aa-threshold", "nan"], "from 0 to 1"),
        (vec!["--aa-threshold=-0.1"], "from 0 to 1"),
        (vec!["--aa-spp", "8"], "--aa-threshold"),
        (
            vec!["--aa-threshold", "0.1", "--target-error", "0.01"],
            "cannot be used with",
        ),
        (
            vec!["--aa-threshold", "0.1", "--spp", "16", "--aa-spp", "8"],
            "more samples than the render's 16",
        ),
        (vec!["--aa-threshold", "0.1", "--aa-spp", "1"], "aa-spp"),
        (
            vec![
                "--set",
                "render.antialias_threshold=0.1",
                "--target-error",
                "0.01",
                "--aa-spp",
                "32",
            ],
            "adaptive sampling replaces here",
        ),
    ];
    common::assert_usage_errors("defense.toml", &out, &cases);
    assert!(!out.exists());
}
