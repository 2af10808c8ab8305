//! The hostile-input corpus's manifest, `tests/hostile/cases.toml`: each file and the outcome it
//! must give.

use serde::Deserialize;
use std::path::PathBuf;

/// The corpus folder, `tests/hostile/`.
pub fn corpus_dir() -> PathBuf {
    crate::repo_root().join("tests/hostile")
}

/// What a case must do.
#[derive(Debug, PartialEq)]
pub enum Expect {
    /// Loads and renders.
    Loads,
    /// Loads and renders, with a note that contains [`Case::says`].
    Warns,
    /// Fails with an error of this class (`syntax`, `invalid`, ..., or `scene`).
    Error(String),
}

/// One file of the corpus and the outcome it must give.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// The file, relative to `tests/hostile/`.
    pub file: String,
    expect: String,
    /// Text the error or warning must contain.
    #[serde(default)]
    pub says: String,
    /// "LINE:" or "LINE:COL" that must follow the file name in the error.
    pub at: Option<String>,
}

impl Case {
    /// The expected outcome.
    pub fn expect(&self) -> Expect {
        match self.expect.as_str() {
            "loads" => Expect::Loads,
            "warns" => Expect::Warns,
            class => Expect::Error(class.to_string()),
        }
    }
}

#[derive(Deserialize)]
struct Manifest {
    case: Vec<Case>,
    /// Command lines, run by the CLI's own test (crates/quadray-cli/tests/hostile.rs).
    #[allow(dead_code)]
    command: Vec<toml::Value>,
}

/// Every case of the manifest, in order.
pub fn cases() -> Vec<Case> {
    let path = corpus_dir().join("cases.toml");
    let text = std::fs::read_to_string(&path).expect("tests/hostile/cases.toml exists");
    let manifest: Manifest = toml::from_str(&text).expect("cases.toml parses");
    let classes = [
        "io",
        "syntax",
        "invalid",
        "unsupported",
        "referenced",
        "include",
        "scene",
    ];
    for case in &manifest.case {
        let known = matches!(case.expect(), Expect::Loads | Expect::Warns)
            || classes.contains(&case.expect.as_str());
        assert!(known, "{}: unknown expect {:?}", case.file, case.expect);
    }
    manifest.case
}

/// Scene files (.toml, .obj, .gltf, .glb) in the corpus that no case lists. Other files (.mtl,
/// .png, .bin) are what the cases refer to.
pub fn unlisted_files(cases: &[Case]) -> Vec<String> {
    let mut unlisted = Vec::new();
    for folder in ["toml", "obj", "gltf", "texture"] {
        let Ok(entries) = std::fs::read_dir(corpus_dir().join(folder)) else {
            continue;
        };
        for entry in entries {
            let name = entry.expect("readable folder").file_name();
            let rel = format!("{folder}/{}", name.to_string_lossy());
            let scene_like = [".toml", ".obj", ".gltf", ".glb"]
                .iter()
                .any(|e| rel.ends_with(e));
            if scene_like && !cases.iter().any(|c| c.file == rel) {
                unlisted.push(rel);
            }
        }
    }
    unlisted
}
