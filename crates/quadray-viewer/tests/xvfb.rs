//! End to end under a virtual X display: `quadray-view scenes/defense.toml` is started in Xvfb,
//! its refined frame is taken from a screenshot of the screen (ImageMagick's `import`), and the
//! image area is compared with `quadray render` of the same view at the same size and samples.
//!
//! The viewer refines with the adaptive sampler's progressive sequence and the CLI with its
//! correlated multi-jittered one, so the two differ by sampling noise along edges. The bound is
//! measured in the same run: the screenshot may differ from the CLI's image by at most 1.5× the
//! mean FLIP between two CLI renders with independent sample sets (`--seed`), and by 0.05 at most.
//! Skips with a printed reason where xvfb-run or import is missing (`.ci/run` installs them).

use quadray_app::compare::{LinearImage, Thresholds, compare, read_image};
use std::path::{Path, PathBuf};
use std::process::Command;

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The numbers after `key` in the log line, e.g. `refined 684x384 at 4 spp` → [684, 384, 4].
fn numbers_after(line: &str, key: &str) -> Vec<u32> {
    let rest = &line[line.find(key).expect(key) + key.len()..];
    rest.split(|c: char| !c.is_ascii_digit() && c != '.')
        .filter(|s| !s.is_empty())
        .take(4)
        .map(|s| s.parse::<f64>().expect(s) as u32)
        .collect()
}

fn render_with_cli(res: (u32, u32), spp: u32, seed: u32, out: &Path) -> LinearImage {
    let scene = workspace().join("scenes/defense.toml");
    quadray_cli::run_args([
        "render".to_string(),
        scene.display().to_string(),
        "--res".into(),
        format!("{}x{}", res.0, res.1),
        "--spp".into(),
        spp.to_string(),
        "--seed".into(),
        seed.to_string(),
        "-q".into(),
        "-o".into(),
        out.display().to_string(),
    ])
    .unwrap();
    read_image(out).unwrap()
}

#[cfg_attr(
    not(quadray_xvfb),
    ignore = "needs xvfb-run and ImageMagick's import (Debian: xvfb, imagemagick)"
)]
#[test]
fn the_window_shows_what_the_renderer_renders() {
    for tool in ["xvfb-run", "import"] {
        assert!(
            have(tool),
            "{tool} is not installed (Debian: xvfb, imagemagick)"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let (log, shot) = (dir.path().join("view.log"), dir.path().join("shot.png"));
    // Start the viewer, wait for its refined frame (at most 120 s), photograph the screen.
    let script = format!(
        "{viewer} -v scenes/defense.toml > {log} 2>&1 & pid=$!; \
         for i in $(seq 1200); do grep -q refined {log} && break; sleep 0.1; done; \
         sleep 0.5; import -window root {shot}; kill $pid; wait $pid; true",
        viewer = env!("CARGO_BIN_EXE_quadray-view"),
        log = log.display(),
        shot = shot.display()
    );
    let status = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24", "sh", "-c", &script])
        .current_dir(workspace())
        .env("XDG_RUNTIME_DIR", dir.path())
        .status()
        .unwrap();
    assert!(status.success());
    let log_text = std::fs::read_to_string(&log).unwrap();
    let Some(line) = log_text.lines().find(|l| l.contains("refined")) else {
        panic!("the viewer never refined its frame:\n{log_text}");
    };
    let [width, height, spp] = numbers_after(line, "refined")[..3] else {
        panic!("{line}")
    };
    let image_at = numbers_after(line, "image at");
    let window_at = numbers_after(line, "window at");
    let (x0, y0) = (image_at[0] + window_at[0], image_at[1] + window_at[1]);

    let screen = image::open(&shot).unwrap().to_rgb8();
    let crop = image::imageops::crop_imm(&screen, x0, y0, width, height).to_image();
    crop.save(dir.path().join("window.png")).unwrap();
    let shown = LinearImage::from_srgb8(width, height, crop.as_raw());
    let reference = render_with_cli((width, height), spp, 0, &dir.path().join("cli.png"));
    let other_seed = render_with_cli((width, height), spp, 1, &dir.path().join("seed1.png"));
    let judge = Thresholds {
        max_flip: Some(1.0),
        ..Thresholds::default()
    };
    let noise = compare(&reference, &other_seed, &judge).unwrap().flip_mean;
    let difference = compare(&reference, &shown, &judge).unwrap().flip_mean;
    eprintln!(
        "{width}x{height} at {spp} spp: FLIP window vs quadray render {difference:.4}, \
         two sample sets {noise:.4}"
    );
    assert!(
        difference <= 1.5 * noise && difference <= 0.05,
        "the window differs from quadray render by FLIP {difference}, more than sampling noise ({noise})"
    );
}
