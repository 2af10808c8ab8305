//! Tests of `quadray bench images`: a tiny end-to-end report and the argument checks.

use super::*;

fn scene_path() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/defense.toml").to_string()
}

/// On a tiny render of the defense scene, error against the reference falls with every step
/// of 4x the samples (stratified sampling: RMSE at least halves per step here) and all files
/// are written; the reference check is far below the 64-spp error.
#[test]
fn error_falls_with_samples_and_the_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    crate::run_args([
        "bench",
        "images",
        "--scene",
        &scene_path(),
        "--out",
        out,
        "--res",
        "64x36",
        "--reference-spp",
        "256",
        "--spp",
        "1,4,16,64",
        "--time-limit",
        "0.05,0.1",
        "--runs",
        "1",
        "--quiet",
    ])
    .unwrap();
    let md = std::fs::read_to_string(dir.path().join("image-error.md")).unwrap();
    let table = |prefix: &str| -> Vec<Vec<String>> {
        md.lines()
            .filter(|l| l.starts_with(prefix))
            .map(|l| l.split('|').map(|c| c.trim().to_string()).collect())
            .collect()
    };
    let rows: Vec<Vec<String>> = table("| ")
        .into_iter()
        .filter(|r| r[1].ends_with(" spp"))
        .collect();
    let spp: Vec<&str> = rows.iter().map(|r| r[2].as_str()).collect();
    assert_eq!(spp, ["1", "4", "16", "64"], "{md}");
    let rmse: Vec<f64> = rows.iter().map(|r| r[6].parse().unwrap()).collect();
    for w in rmse.windows(2) {
        assert!(
            w[1] < 0.75 * w[0],
            "RMSE must fall with samples: {rmse:?}\n{md}"
        );
    }
    let flip: Vec<f64> = rows.iter().map(|r| r[8].parse().unwrap()).collect();
    assert!(
        flip[3] < flip[0],
        "FLIP must fall from 1 to 64 spp: {flip:?}"
    );
    assert!(md.contains("reference's own error"), "{md}");
    // The adaptive rows: more samples and less error as the target tightens.
    let adaptive = table("| target ");
    assert_eq!(adaptive.len(), 6, "{md}");
    let display_rmse: Vec<f64> = adaptive.iter().map(|r| r[7].parse().unwrap()).collect();
    assert!(display_rmse[5] < display_rmse[0], "{display_rmse:?}");
    // The per-pixel rows, and the previews: from 2 samples, fewer samples at the same target.
    let pixel = table("| pixel ");
    assert_eq!(pixel.len(), 5, "{md}");
    let preview = table("| preview ");
    assert_eq!(preview.len(), 3, "{md}");
    let mean_spp = |r: &Vec<String>| -> f64 { r[2].split(' ').next().unwrap().parse().unwrap() };
    assert_eq!(
        (pixel[2][1].as_str(), preview[1][1].as_str()),
        ("pixel 0.04", "preview 0.04")
    );
    assert!(mean_spp(&preview[1]) < mean_spp(&pixel[2]), "{md}");
    // The anti-aliased rows: from one sample a pixel, more error than the uniform render at
    // their own top count (some pixels keep one sample) but less than at one sample, for less.
    let aa = table("| aa ");
    assert_eq!(aa.len(), 5, "{md}");
    assert_eq!(aa[1][1], "aa 0.1 (16 spp)", "{md}");
    let aa_16: f64 = aa[1][7].parse().unwrap();
    assert!(
        rmse[0] > aa_16 && aa_16 > rmse[2],
        "{rmse:?} and {aa_16}\n{md}"
    );
    assert!(
        mean_spp(&aa[1]) < 16.0 && aa[1][2].ends_with("(1..16)"),
        "{md}"
    );
    assert!(md.contains("quadray anti-aliased: CPU s to reach it") || !md.contains("POV-Ray"));
    // The time-limited rows: a longer limit, more samples.
    let timed = table("| time ");
    assert_eq!(timed.len(), 2, "{md}");
    assert!(mean_spp(&timed[1]) > mean_spp(&timed[0]), "{md}");
    let svg = std::fs::read_to_string(dir.path().join("image-error.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("64 spp") && svg.contains("image target"));
    assert!(
        svg.contains("preview 0.04")
            && svg.contains("time 0.1 s")
            && svg.contains("aa 0.1 (16 spp)"),
        "{svg}"
    );
    let png = image::open(dir.path().join("image-error-reference.png")).unwrap();
    assert_eq!((png.width(), png.height()), (64, 36));
    // Nothing but the three outputs (no temporary files left behind).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
}

#[test]
fn bad_arguments_are_refused_before_rendering() {
    let scene = scene_path();
    for bad in [
        vec!["--reference-spp", "64"],
        vec!["--spp", "4,1"],
        vec!["--spp", "0,4"],
        vec!["--runs", "0"],
        vec!["--res", "0x10"],
        vec!["--antialias", "0.1"],
        vec!["--antialias", "1.5:16"],
        vec!["--antialias", "0.1:1"],
    ] {
        let mut args = vec!["bench", "images", "--scene", &scene, "--quiet"];
        args.extend(bad.iter().copied());
        let err = crate::run_args(args).unwrap_err();
        assert!(!format!("{err:#}").is_empty());
    }
    // A list given with no value is empty: the arguments parse, and only --runs 0 is refused.
    let mut args = vec![
        "bench", "images", "--scene", &scene, "--quiet", "--runs", "0",
    ];
    args.extend([
        "--adaptive",
        "--pixel",
        "--time-limit",
        "--preview",
        "--antialias",
    ]);
    let err = format!("{:#}", crate::run_args(args).unwrap_err());
    assert!(err.contains("--runs must be at least 1"), "{err}");
    let err = crate::run_args(["bench", "images", "--scene", "/no/such/scene.toml"]).unwrap_err();
    assert!(
        format!("{err:#}").contains("/no/such/scene.toml"),
        "{err:#}"
    );
    assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
}
