//! glTF JSON or GLB (with the QUADRAY_quadrics extension) into a complete scene, then the scene
//! build: any bytes, no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quadray_loader::{ImportOptions, gltf, standalone};

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.glb");
    let Ok(file) = gltf::open_bytes(data, path) else { return };
    if let Ok(imported) = gltf::convert(&file, path, &ImportOptions::default())
        && let Ok(loaded) = standalone::scene_from_import(imported, path, None)
    {
        let _ = quadray::Scene::new(loaded.description);
    }
});
