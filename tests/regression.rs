//! The regression suite on scene files: every scene in `scenes/` (`*.toml` and `*.gltf`, found
//! automatically) must pass `quadray check`, and its render at most 320x240 must match
//! `scenes/refs/<name>.png` under the comparison rule of `quadray compare` (more than 2/255 in
//! any channel in at most 0.1% of pixels, nothing over 32/255).
//!
//! Each reference was checked another way before it was accepted (`scenes/README.md` says how:
//! POV-Ray renders of the same scenes, analytic facts). Renders are deterministic, so on one
//! machine they match bit for bit; the tolerance leaves room for other targets' floating point
//! (FMA contraction, SIMD widths in glam) flipping a few edge pixels.
//!
//! On failure the new image and the FLIP heat map are written to
//! `target/tmp/regression/<name>.{new,diff}.png`. `QUADRAY_UPDATE_REFS=1` writes the references
//! anew instead (check them another way before committing them).

use quadray::{RenderSettings, Scene, Whitted};
use quadray_app::compare::{LinearImage, Thresholds, compare, read_image};
use quadray_app::output::write_rgb8_png;
use quadray_tests::repo_root;
use std::path::{Path, PathBuf};

/// Largest reference size: references stay small so the suite stays fast.
const MAX_W: u32 = 320;
const MAX_H: u32 = 240;

/// The scene files the suite covers: every `*.toml` and `*.gltf` in `scenes/`, sorted.
fn scene_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo_root().join("scenes"))
        .expect("scenes/ exists")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| {
            p.is_file()
                && matches!(
                    p.extension().and_then(|e| e.to_str()),
                    Some("toml" | "gltf")
                )
        })
        .collect();
    files.sort();
    files
}

fn refs_dir() -> PathBuf {
    repo_root().join("scenes").join("refs")
}

/// The scene's own resolution, scaled down (keeping the aspect) to fit 320x240.
fn fitted(w: u32, h: u32) -> (u32, u32) {
    let k = (MAX_W as f64 / w as f64)
        .min(MAX_H as f64 / h as f64)
        .min(1.0);
    (
        ((w as f64 * k).round() as u32).max(1),
        ((h as f64 * k).round() as u32).max(1),
    )
}

/// Renders a scene file at its fitted resolution with its own samples and depth.
fn render(path: &Path) -> Result<LinearImage, String> {
    render_with(path, 1, |settings| settings)
}

/// Renders a scene file at its fitted resolution divided by `shrink`, with its own samples and
/// depth unless `adjust` changes them.
fn render_with(
    path: &Path,
    shrink: u32,
    adjust: impl FnOnce(RenderSettings) -> RenderSettings,
) -> Result<LinearImage, String> {
    let loaded = quadray_loader::load_any(path).map_err(|e| e.to_string())?;
    let s = loaded.settings;
    let (width, height) = fitted(s.width, s.height);
    let settings = adjust(RenderSettings {
        width: (width / shrink).max(1),
        height: (height / shrink).max(1),
        spp: s.spp,
        whitted: Whitted {
            max_depth: s.max_depth,
            ..Whitted::default()
        },
        ..RenderSettings::default()
    });
    let scene = Scene::new(loaded.description).map_err(|e| e.to_string())?;
    let rendered =
        quadray::render(&scene, &settings, &quadray::NoProgress).map_err(|e| e.to_string())?;
    Ok(LinearImage::from_film(&rendered.film))
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .expect("scene names are UTF-8")
        .to_owned()
}

/// Checks one scene; `Err` says why it fails.
fn check_scene(path: &Path, update: bool, out_dir: &Path) -> Result<String, String> {
    let name = stem(path);
    quadray_cli::run_args([std::ffi::OsStr::new("check"), path.as_os_str()])
        .map_err(|e| format!("quadray check failed: {e:#}"))?;
    let new = render(path)?;
    let reference = refs_dir().join(format!("{name}.png"));
    let bytes = new.to_srgb8();
    if update {
        write_rgb8_png(new.width, new.height, &bytes, &reference).map_err(|e| format!("{e:#}"))?;
        return Ok(format!("wrote {}", reference.display()));
    }
    if !reference.exists() {
        return Err(format!(
            "no reference {}: render it with QUADRAY_UPDATE_REFS=1, check it another way, and \
             say how in scenes/README.md",
            reference.display()
        ));
    }
    // The reference went through 8-bit sRGB; so must the new image before they are compared.
    let new = LinearImage::from_srgb8(new.width, new.height, &bytes);
    let old = read_image(&reference).map_err(|e| format!("{e:#}"))?;
    let thresholds = Thresholds::default();
    let c = compare(&old, &new, &thresholds).map_err(|e| format!("{e:#}"))?;
    let failures = c.failures(&thresholds);
    if failures.is_empty() {
        return Ok(c.summary(&thresholds));
    }
    std::fs::create_dir_all(out_dir).map_err(|e| e.to_string())?;
    let new_path = out_dir.join(format!("{name}.new.png"));
    let diff_path = out_dir.join(format!("{name}.diff.png"));
    write_rgb8_png(new.width, new.height, &bytes, &new_path).map_err(|e| format!("{e:#}"))?;
    write_rgb8_png(c.width, c.height, &c.heat_map(), &diff_path).map_err(|e| format!("{e:#}"))?;
    Err(format!(
        "{}; {} (new image {}, FLIP heat map {})",
        failures.join("; "),
        c.summary(&thresholds),
        new_path.display(),
        diff_path.display()
    ))
}

#[test]
fn every_scene_passes_check_and_matches_its_reference() {
    let update = std::env::var("QUADRAY_UPDATE_REFS").is_ok_and(|v| v == "1");
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("regression");
    let scenes = scene_files();
    assert!(
        scenes.len() >= 14,
        "the suite covers at least 14 scenes, found {}",
        scenes.len()
    );
    let mut failed = Vec::new();
    for path in &scenes {
        match check_scene(path, update, &out_dir) {
            Ok(line) => println!("{}: {line}", stem(path)),
            Err(why) => failed.push(format!("{}: {why}", stem(path))),
        }
    }
    assert!(
        failed.is_empty(),
        "{} of {} scenes fail:\n{}",
        failed.len(),
        scenes.len(),
        failed.join("\n")
    );
}

/// How the references with filtered textures were checked: the point-sampled renders are the
/// ones POV-Ray confirms (`pov/verify.sh` renders with `--texture-filter none`), and filtering
/// must bring every scene's render at its own sample count closer to the converged image
/// (256 point samples a pixel, another sample set) than point sampling gets; a scene without a
/// checker or bands must render the same either way. At half the reference size, to stay quick.
#[test]
fn filtered_textures_bring_every_scene_closer_to_its_converged_image() {
    let thresholds = Thresholds::default();
    let mut failed = Vec::new();
    for path in &scene_files() {
        let point = |settings: RenderSettings| RenderSettings {
            texture_filter: false,
            ..settings
        };
        let converged = render_with(path, 2, |s| RenderSettings {
            spp: 256,
            seed: 7,
            ..point(s)
        })
        .unwrap();
        let sampled = render_with(path, 2, point).unwrap();
        let filtered = render_with(path, 2, |s| s).unwrap();
        let error =
            |image: &LinearImage| compare(&converged, image, &thresholds).unwrap().rmse_linear;
        let (point_error, filtered_error) = (error(&sampled), error(&filtered));
        println!(
            "{}: RMSE against 256 spp: point sampled {point_error:.2e}, filtered {filtered_error:.2e}",
            stem(path)
        );
        let same = sampled.pixels == filtered.pixels;
        if !(filtered_error < point_error || same) {
            failed.push(stem(path));
        }
    }
    assert!(failed.is_empty(), "filtering did not help: {failed:?}");
}

#[test]
fn every_reference_belongs_to_a_scene_and_is_small() {
    let names: Vec<String> = scene_files().iter().map(|p| stem(p)).collect();
    for entry in std::fs::read_dir(refs_dir()).expect("scenes/refs exists") {
        let path = entry.unwrap().path();
        let name = stem(&path);
        assert!(
            names.contains(&name),
            "{} has no scene file",
            path.display()
        );
        let img = read_image(&path).unwrap();
        assert!(
            img.width <= MAX_W && img.height <= MAX_H,
            "{} is {}x{}, larger than {MAX_W}x{MAX_H}",
            path.display(),
            img.width,
            img.height
        );
    }
}

#[test]
fn fitting_keeps_the_aspect_and_never_enlarges() {
    assert_eq!(fitted(640, 360), (320, 180));
    assert_eq!(fitted(800, 450), (320, 180));
    assert_eq!(fitted(200, 200), (200, 200));
    assert_eq!(fitted(1000, 2000), (120, 240));
}
