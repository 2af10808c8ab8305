//! The native scene parser and validator, then the scene build: any bytes, no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new("fuzz.toml");
    if let Ok(loaded) = quadray_loader::parse_scene(text, path) {
        let _ = quadray::Scene::new(loaded.description);
    }
});
