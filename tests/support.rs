//! Shared helpers for the end-to-end tests: locating the repository's scenes and rendering them.

#[path = "hostile_cases.rs"]
pub mod hostile;

use quadray::{AccelStats, Film, NoProgress, RenderSettings, Rendered, Scene};
use std::path::{Path, PathBuf};

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits in the repository")
        .to_path_buf()
}

/// Path of a bundled scene file in `scenes/`.
pub fn scene_path(name: &str) -> PathBuf {
    repo_root().join("scenes").join(name)
}

/// Loads a bundled scene and its settings.
pub fn load(name: &str) -> (Scene, RenderSettings) {
    let loaded = quadray_loader::load_scene(&scene_path(name)).expect("bundled scene loads");
    let settings = loaded.settings.render_settings();
    (
        Scene::new(loaded.description).expect("bundled scene is valid"),
        settings,
    )
}

/// Renders on a dedicated pool of `threads` threads.
pub fn render_with_threads(scene: &Scene, settings: &RenderSettings, threads: usize) -> Rendered {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| quadray::render(scene, settings, &NoProgress))
        .expect("render succeeds")
}

/// Renders a native scene file at its own settings; returns the film and the stats of its
/// acceleration structure.
pub fn render_file(path: &Path) -> (Film, AccelStats) {
    let loaded = quadray_loader::load_scene(path).expect("scene loads");
    let settings = loaded.settings.render_settings();
    let scene = Scene::new(loaded.description).expect("scene is valid");
    let film = quadray::render(&scene, &settings, &NoProgress)
        .unwrap()
        .film;
    (film, scene.accel().stats(scene.geometry()))
}

/// Share of pixels whose display values (8-bit sRGB) differ by more than 2/255 in some channel,
/// and the largest difference in 8-bit steps: the measure of `quadray compare`, on both films
/// quantised as their PNGs would be.
pub fn display_difference(a: &Film, b: &Film) -> (f64, f32) {
    use quadray_app::compare::{LinearImage, Thresholds, compare};
    let image = |f: &Film| LinearImage::from_srgb8(f.width(), f.height(), &f.to_srgb8());
    let c = compare(&image(a), &image(b), &Thresholds::default()).expect("same size");
    (c.over_share, c.max_display)
}
