//! The hostile-input corpus in `tests/hostile/`: every file the fuzzers (`fuzz/`,
//! docs/reliability.md) or reports found a problem with, and one case for each kind of bad input
//! the loaders know. `tests/hostile/cases.toml` gives each file the outcome it must have: it loads
//! (and renders at 8x6), it loads with a warning, or it fails with an error of a stated class
//! whose message names the file, the place where there is one, and the problem. Nothing may panic.
//!
//! The same cases run through the `quadray` binary in `crates/quadray-cli/tests/hostile.rs`, which
//! checks exit codes and that the message is printed once.

use quadray::{NoProgress, RenderSettings, Scene, Whitted, render};
use quadray_loader::{LoadErrorKind, load_any};
use quadray_tests::hostile::{Case, Expect, cases, corpus_dir, unlisted_files};

/// The class of a loader error, as the manifest names it.
fn class(kind: &LoadErrorKind) -> &'static str {
    match kind {
        LoadErrorKind::Io(_) => "io",
        LoadErrorKind::Syntax(_) => "syntax",
        LoadErrorKind::Invalid { .. } => "invalid",
        LoadErrorKind::Unsupported(_) => "unsupported",
        LoadErrorKind::Referenced { .. } => "referenced",
        LoadErrorKind::Include { .. } => "include",
        _ => "a class this test does not know yet",
    }
}

/// What happened to one case: `Ok(notes)` when it rendered, else the class and message.
fn outcome(case: &Case) -> Result<Vec<String>, (&'static str, String)> {
    let path = corpus_dir().join(&case.file);
    let loaded = load_any(&path).map_err(|e| (class(&e.kind), e.to_string()))?;
    let scene = Scene::new(loaded.description)
        .map_err(|e| ("scene", format!("{}: {e}", path.display())))?;
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
    let image = render(&scene, &settings, &NoProgress).expect("8x6 is within every limit");
    assert!(
        image.film.pixels().iter().all(|p| p.is_finite()),
        "{}: rendered a pixel that is not a finite number",
        case.file
    );
    Ok(loaded.notes)
}

/// Why a case's outcome differs from the manifest's, if it does.
fn mismatch(case: &Case) -> Option<String> {
    let file_name = case.file.rsplit('/').next().unwrap_or(&case.file);
    match (outcome(case), case.expect()) {
        (Ok(_), Expect::Loads) => None,
        (Ok(notes), Expect::Warns) => (!notes.iter().any(|n| n.contains(&case.says)))
            .then(|| format!("no warning says {:?}: {notes:?}", case.says)),
        (Ok(_), Expect::Error(class)) => Some(format!("loaded, expected a {class} error")),
        (Err((got, message)), expected) => {
            let wanted_at = match &case.at {
                Some(at) => format!("{file_name}:{at}"),
                None => file_name.to_string(),
            };
            if expected != Expect::Error(got.to_string()) {
                Some(format!("{got} error, expected {expected:?}: {message}"))
            } else if !message.contains(&wanted_at) {
                Some(format!(
                    "the message does not give {wanted_at:?}: {message}"
                ))
            } else if !message.contains(&case.says) {
                Some(format!(
                    "the message does not say {:?}: {message}",
                    case.says
                ))
            } else {
                None
            }
        }
    }
}

#[test]
fn every_case_has_its_expected_outcome() {
    let cases = cases();
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|c| mismatch(c).map(|m| format!("{}: {m}", c.file)))
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// The issue asked for at least 100 cases across the formats; each folder must hold some, and no
/// scene file may sit in the corpus without an expected outcome.
#[test]
fn the_corpus_is_complete() {
    let cases = cases();
    assert!(cases.len() >= 100, "{} cases", cases.len());
    for folder in ["toml/", "obj/", "gltf/", "texture/"] {
        let n = cases.iter().filter(|c| c.file.starts_with(folder)).count();
        assert!(n >= 5, "{folder}: only {n} cases");
    }
    assert!(
        cases.iter().any(|c| c.file.ends_with(".glb")),
        "no GLB case"
    );
    let unlisted = unlisted_files(&cases);
    assert!(unlisted.is_empty(), "not in cases.toml: {unlisted:?}");
}
