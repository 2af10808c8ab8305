//! OBJ (with its MTL handling) into a complete scene, then the scene build: any bytes, no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quadray_loader::{ImportOptions, obj, standalone};

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.obj");
    if let Ok(imported) = obj::import_obj_bytes(data, path, &ImportOptions::default())
        && let Ok(loaded) = standalone::scene_from_import(imported, path, None)
    {
        let _ = quadray::Scene::new(loaded.description);
    }
});
