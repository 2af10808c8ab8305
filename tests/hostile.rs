//! Replays the hostile-input corpus in `tests/hostile/` on the stable toolchain: every file the
//! fuzzers (`fuzz/`, docs/reliability.md) or reports ever found a problem with, run through the
//! same code as its fuzz target. Each must load, or fail with an error that names the file, and
//! never panic; scenes that load are rendered at 8x6.

use quadray::{NoProgress, RenderSettings, Scene, Whitted, render};
use quadray_loader::{ImportOptions, gltf, gltf_document, obj, standalone};
use quadray_tests::repo_root;
use std::path::Path;

/// Files of one corpus folder, sorted (empty when it does not exist).
fn corpus(kind: &str) -> Vec<std::path::PathBuf> {
    let dir = repo_root().join("tests/hostile").join(kind);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    files.sort();
    files
}

/// Builds and renders a loaded scene at 8x6; an invalid scene is an error, never a panic.
fn build_and_render(description: quadray::SceneDescription) {
    let Ok(scene) = Scene::new(description) else {
        return;
    };
    let settings = RenderSettings {
        width: 8,
        height: 6,
        spp: 1,
        whitted: Whitted {
            max_depth: 3,
            ..Whitted::default()
        },
        ..RenderSettings::default()
    };
    let _ = render(&scene, &settings, &NoProgress);
}

fn check_error_names_file(path: &Path, e: &quadray_loader::LoadError) {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    assert!(e.to_string().contains(&name), "{}: {e}", path.display());
}

#[test]
fn toml_corpus_loads_or_fails_cleanly() {
    for path in corpus("toml") {
        let bytes = std::fs::read(&path).unwrap();
        let Ok(text) = std::str::from_utf8(&bytes) else {
            continue;
        };
        match quadray_loader::parse_scene(text, &path) {
            Ok(loaded) => build_and_render(loaded.description),
            Err(e) => check_error_names_file(&path, &e),
        }
    }
}

#[test]
fn obj_corpus_loads_or_fails_cleanly() {
    for path in corpus("obj") {
        let bytes = std::fs::read(&path).unwrap();
        let loaded = obj::import_obj_bytes(&bytes, &path, &ImportOptions::default())
            .and_then(|imported| standalone::scene_from_import(imported, &path, None));
        match loaded {
            Ok(loaded) => build_and_render(loaded.description),
            Err(e) => check_error_names_file(&path, &e),
        }
    }
}

#[test]
fn gltf_corpus_loads_or_fails_cleanly() {
    for path in corpus("gltf") {
        let bytes = std::fs::read(&path).unwrap();
        let loaded = gltf_document::open_bytes(&bytes, &path)
            .and_then(|file| gltf::convert(&file, &path, &ImportOptions::default()))
            .and_then(|imported| standalone::scene_from_import(imported, &path, None));
        match loaded {
            Ok(loaded) => build_and_render(loaded.description),
            Err(e) => check_error_names_file(&path, &e),
        }
    }
}
