//! What the loader's tests share: the real assets' folder, and glTF files written by the tests (a
//! valid one-triangle file to edit, loaded from a fresh folder).

#![allow(dead_code)]

use quadray_loader::load_any;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// A fresh temporary folder for test `name`.
pub fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadray-bad-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A valid one-triangle glTF whose buffer lives in `tri.bin`: 3 positions, 3 u16 indices.
pub fn triangle() -> (Value, Vec<u8>) {
    let mut bin = Vec::new();
    for v in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bin.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        bin.extend(i.to_le_bytes());
    }
    bin.extend([0, 0]);
    let gltf = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "buffers": [{"uri": "tri.bin", "byteLength": 44}]
    });
    (gltf, bin)
}

/// Writes the glTF (and its bin) into a fresh folder; loads it; returns the error text.
pub fn load(
    name: &str,
    gltf: &Value,
    bin: Option<&[u8]>,
) -> Result<quadray_loader::LoadedScene, String> {
    let d = dir(name);
    if let Some(bin) = bin {
        std::fs::write(d.join("tri.bin"), bin).unwrap();
    }
    let path = d.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec(gltf).unwrap()).unwrap();
    let r = load_any(&path).map_err(|e| e.to_string());
    std::fs::remove_dir_all(&d).unwrap();
    r
}

/// `<workspace>/../shared/assets`. Tests that call it are ignored where it is absent (see
/// `build.rs`); where they run, its absence is a failure.
pub fn assets() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets");
    assert!(
        dir.join("SOURCES.md").is_file(),
        "the shared test assets are not at {} (../shared is absent)",
        dir.display()
    );
    dir
}

/// The bytes of the zstd-compressed file at `path` (the large meshes of `../shared/assets`).
pub fn unzstd(path: &std::path::Path) -> Vec<u8> {
    use std::io::Read;
    let file = std::fs::File::open(path).expect("the compressed asset opens");
    let mut decoder = ruzstd::decoding::StreamingDecoder::new(file).expect("a zstd frame");
    let mut bytes = Vec::new();
    decoder.read_to_end(&mut bytes).expect("zstd decodes");
    bytes
}
