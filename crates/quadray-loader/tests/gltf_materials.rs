//! glTF material features on a one-triangle file: emission, sides, metals, glass.

use crate::common;

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

/// KHR_materials_transmission, _ior and _volume become quadray's glass: thin-walled without a
/// volume (as glTF defines), a solid with Beer–Lambert absorption with one; out-of-range values
/// are errors naming the material.
#[test]
fn transmission_ior_and_volume_make_glass() {
    let thin = with_material(
        "thin",
        json!({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9},
                              "KHR_materials_ior": {"ior": 1.33}}}),
    );
    let t = thin.description.materials[0].transmission.unwrap();
    assert_eq!(
        (t.factor, t.ior, t.thin_walled, t.attenuation),
        (0.9, 1.33, true, None)
    );
    let solid = with_material(
        "solid",
        json!({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                              "KHR_materials_volume": {"thicknessFactor": 0.5,
                                  "attenuationDistance": 2.0,
                                  "attenuationColor": [0.5, 0.8, 1.0]}}}),
    );
    let t = solid.description.materials[0].transmission.unwrap();
    assert!(!t.thin_walled);
    // A solid's back faces are where rays leave it: never culled, whatever doubleSided says.
    assert!(!solid.description.geometry.meshes[0].single_sided());
    assert!(
        thin.description.geometry.meshes[0].single_sided(),
        "a sheet culls as glTF says"
    );
    assert_eq!(t.ior, 1.5, "KHR_materials_ior's default");
    let a = t.attenuation.unwrap();
    assert_eq!((a.color, a.distance), (Vec3::new(0.5, 0.8, 1.0), 2.0));
    let opaque = with_material(
        "opaque",
        json!({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.0}}}),
    );
    assert_eq!(opaque.description.materials[0].transmission, None);
    let (mut gltf, bin) = triangle();
    gltf["materials"] = json!([{"name": "diamond-ish",
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                       "KHR_materials_ior": {"ior": 0.5}}}]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = load("bad-ior", &gltf, Some(&bin)).unwrap_err();
    assert!(e.contains("diamond-ish") && e.contains("ior"), "{e}");
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

/// The triangle with normals +z and texture coordinates (u along +x, the top of the image along
/// +y), drawn with a material whose normal map is one texel `rgb`, given as a data URI.
fn normal_mapped(rgb: [u8; 3], with_normals: bool) -> (Value, Vec<u8>) {
    use base64::Engine;
    let (mut gltf, mut bin) = triangle();
    let offset = bin.len();
    for v in [[0f32, 0.0, 1.0]; 3] {
        for c in v {
            bin.extend(c.to_le_bytes());
        }
    }
    for uv in [[0f32, 1.0], [1.0, 1.0], [0.0, 0.0]] {
        for c in uv {
            bin.extend(c.to_le_bytes());
        }
    }
    gltf["buffers"][0]["byteLength"] = json!(bin.len());
    gltf["bufferViews"].as_array_mut().unwrap().extend([
        json!({"buffer": 0, "byteOffset": offset, "byteLength": 36}),
        json!({"buffer": 0, "byteOffset": offset + 36, "byteLength": 24}),
    ]);
    gltf["accessors"].as_array_mut().unwrap().extend([
        json!({"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}),
        json!({"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC2"}),
    ]);
    let attributes = &mut gltf["meshes"][0]["primitives"][0]["attributes"];
    if with_normals {
        attributes["NORMAL"] = json!(2);
    }
    attributes["TEXCOORD_0"] = json!(3);
    let mut png = Vec::new();
    image::RgbImage::from_pixel(1, 1, image::Rgb(rgb))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let uri = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&png)
    );
    gltf["images"] = json!([{"uri": uri}]);
    gltf["textures"] = json!([{"source": 0}]);
    gltf["materials"] = json!([{"normalTexture": {"index": 0, "scale": 0.5}}]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    (gltf, bin)
}

/// A normal map is read linearly, gets MikkTSpace tangents when the file has none (u along +x,
/// the bitangent towards the top of the image: in quadray's z-up axes +x and +z), and bends the
/// shading normal by the texel: (200, 90, 230) at scale 0.5 is (0.5·(2·200/255 − 1),
/// 0.5·(2·90/255 − 1), 2·230/255 − 1) in (tangent, bitangent, normal) = (+x, +z, −y).
#[test]
fn normal_maps_get_tangents_and_bend_normals() {
    let (gltf, bin) = normal_mapped([200, 90, 230], true);
    let s = load("normal-map", &gltf, Some(&bin)).unwrap();
    let mesh = &s.description.geometry.meshes[0];
    let map = mesh.normal_map().expect("a normal map");
    assert_eq!(map.scale, 0.5);
    assert_eq!(map.map.image.encoding(), quadray::ColorEncoding::Linear);
    for t in mesh.tangents().unwrap() {
        assert!(
            (*t - glam::Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-5,
            "{t}"
        );
    }
    // A ray down the file's −z, which is quadray's +y, onto the triangle's middle.
    let ray = quadray::math::Ray::new(glam::DVec3::new(0.25, -3.0, 0.25), glam::DVec3::Y);
    let g = mesh.surface(0, &ray, 3.0);
    let code = |c: u8| 2.0 * c as f64 / 255.0 - 1.0;
    let expected = (glam::DVec3::X * 0.5 * code(200)
        + glam::DVec3::Z * 0.5 * code(90)
        + glam::DVec3::NEG_Y * code(230))
    .normalize();
    assert!(
        (g.shading_normal - expected).length() < 1e-5,
        "{}",
        g.shading_normal
    );

    let (gltf, bin) = normal_mapped([200, 90, 230], false);
    let s = load("normal-map-without-normals", &gltf, Some(&bin)).unwrap();
    assert!(s.description.geometry.meshes[0].normal_map().is_none());
    assert!(
        s.notes.iter().any(|n| n.contains("normal map left off")),
        "{:?}",
        s.notes
    );
}
