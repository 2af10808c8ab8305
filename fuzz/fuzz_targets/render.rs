//! Whatever native scene parses and validates is rendered, at 8x6 with a short reflection chain:
//! no panic and no hang in traversal, intersection or shading.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new("fuzz.toml");
    let Ok(loaded) = quadray_loader::parse_scene(text, path) else { return };
    let Ok(scene) = quadray::Scene::new(loaded.description) else { return };
    let settings = quadray::RenderSettings {
        width: 8,
        height: 6,
        spp: 1,
        whitted: quadray::Whitted {
            max_depth: 3,
            ..quadray::Whitted::default()
        },
        ..quadray::RenderSettings::default()
    };
    let _ = quadray::render(&scene, &settings, &quadray::NoProgress);
});
