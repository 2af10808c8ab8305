//! Shared helpers for the end-to-end tests: locating the repository's scenes and rendering them.

use quadray::{NoProgress, RenderSettings, Rendered, Scene};
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
