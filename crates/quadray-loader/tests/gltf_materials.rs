//! glTF material features on a one-triangle file: emission, sides, metals, and the extensions
//! quadray warns about.

mod common;

use common::{load, triangle};
use glam::Vec3;
use quadray::Texture;
use serde_json::{Value, json};

/// The triangle drawn with `material`, loaded.
fn with_material(name: &str, material: Value) -> quadray_loader::LoadedScene {
    let (mut gltf, bin) = triangle();
    gltf["materials"] = json!([material]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    load(name, &gltf, Some(&bin)).unwrap()
}

#[test]
fn emission_is_factor_times_strength() {
    let s = with_material(
        "emissive",
        json!({"emissiveFactor": [1.0, 0.5, 0.0],
               "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}),
    );
    assert_eq!(
        s.description.materials[0].emission,
        Some(Texture::Constant(Vec3::new(4.0, 2.0, 0.0)))
    );
    let dark = with_material("dark", json!({"emissiveFactor": [0.0, 0.0, 0.0]}));
    assert_eq!(dark.description.materials[0].emission, None);
    // A file may require the extension: quadray honours it.
    let (mut gltf, bin) = triangle();
    gltf["extensionsRequired"] = json!(["KHR_materials_emissive_strength"]);
    gltf["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    if let Err(e) = load("required", &gltf, Some(&bin)) {
        panic!("{e}");
    }
    let (mut gltf, bin) = triangle();
    gltf["materials"] = json!([{"emissiveFactor": [1.0, 1.0, 1.0],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": -1.0}}}]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = load("negative", &gltf, Some(&bin)).unwrap_err();
    assert!(e.contains("emissiveStrength"), "{e}");
}

#[test]
fn refraction_extensions_are_named_in_a_warning() {
    let s = with_material(
        "glass",
        json!({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                              "KHR_materials_ior": {"ior": 1.5}}}),
    );
    for extension in ["KHR_materials_transmission", "KHR_materials_ior"] {
        assert!(
            s.notes
                .iter()
                .any(|n| n.starts_with("warning:") && n.contains(extension)),
            "{extension}: {:?}",
            s.notes
        );
    }
}

#[test]
fn materials_are_single_sided_unless_they_say_otherwise() {
    let one = with_material("one", json!({}));
    assert!(one.description.geometry.meshes[0].single_sided());
    let two = with_material("two", json!({"doubleSided": true}));
    assert!(!two.description.geometry.meshes[0].single_sided());
    // No material at all: glTF's default material, single-sided too.
    let (gltf, bin) = triangle();
    let default = load("default", &gltf, Some(&bin)).unwrap();
    assert!(default.description.geometry.meshes[0].single_sided());
}

/// BoxInterleaved's material: a red base colour with the default metallic 1 and roughness 1. A
/// rough metal: no diffuse term, and highlights and reflections in its own red.
#[test]
fn a_rough_red_metal_stays_red() {
    let s = with_material(
        "metal",
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.0, 0.0, 1.0]}}),
    );
    let m = &s.description.materials[0];
    assert_eq!(m.diffuse, 0.0);
    assert_eq!((m.specular_tint, m.reflection_tint), (1.0, 1.0));
    assert_eq!(
        m.highlight_color(Vec3::new(0.8, 0.0, 0.0)),
        Vec3::new(0.8, 0.0, 0.0) * m.specular
    );
}

/// A file with no lights of its own gets the default key light and the grey studio environment
/// for its reflections; one with lights keeps reflections on the background.
#[test]
fn default_lighting_brings_a_studio_environment() {
    let (gltf, bin) = triangle();
    let s = load("unlit", &gltf, Some(&bin)).unwrap();
    assert_eq!(s.description.lights.len(), 1);
    assert_eq!(
        s.description.environment,
        Some(quadray_loader::standalone::STUDIO_ENVIRONMENT)
    );
    let (mut gltf, bin) = triangle();
    gltf["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    gltf["extensions"] = json!({"KHR_lights_punctual": {"lights": [{"type": "directional"}]}});
    gltf["nodes"] = json!([{"mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": 0}}}]);
    gltf["scenes"] = json!([{"nodes": [0, 1]}]);
    let s = load("lit", &gltf, Some(&bin)).unwrap();
    assert_eq!(s.description.environment, None);
}
