//! Unit tests of the glTF export: what goes out, and what comes back through the import.

use super::*;
use crate::import::ImportOptions;
use glam::{DVec3, Vec3};
use quadray::Light;
use quadray::Texture;

const SCENE: &str = r#"
version = 1
[camera]
from = [3, -6, 2]
to = [0, 0, 0.5]
vfov = 35
[render]
resolution = [320, 180]
[[material]]
name = "ramp"
texture = "ramp"
reflectivity = 0.3
specular = 0.5
shininess = 40
[[material]]
name = "floor"
texture = "checker"
checker_size = 0.5
color = [0.2, 0.3, 0.4]
[[material]]
name = "red"
color = [0.8, 0.1, 0.1]
specular_model = "blinn"
[[sphere]]
center = [1, 2, 0.5]
radius = 0.5
material = "red"
[[plane]]
point = [0, 0, -1]
normal = [0, 0.6, 0.8]
material = "floor"
[[quadric]]
kind = "hyperboloid1"
a = 0.4
b = 0.5
c = 0.6
clip = { min = [-1, -1, -0.5], max = [1, 1, 1] }
transform = { translate = [-1, 0.5, 0.2], rotate = [10, 20, 30], scale = [1, 2, 0.5] }
material = "ramp"
[[quadric]]
kind = "general"
coefficients = [1, 1, -1, 0.2, 0, 0, 0, 0, 0.1, -0.5]
clip = 1.5
material = "red"
[[mesh]]
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0.5]]
indices = [[0, 1, 2]]
normals = [[0, 0, 1], [0, 0, 1], [0, 0.1, 1]]
material = "red"
[[light]]
type = "point"
position = [2, -3, 4]
color = [1, 0.5, 0.25]
intensity = 20
[[light]]
type = "directional"
direction = [-1, 1, -2]
intensity = 0.8
"#;

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("quadray-export-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() <= 1e-12 * (1.0 + a.length())
}

/// A single-sided mesh is written with a `doubleSided: false` copy of its material, and
/// read back single-sided; the material stays two-sided for the scene's other shapes.
#[test]
fn single_sided_meshes_round_trip() {
    let mut scene = crate::native::parse_scene(SCENE, Path::new("s.toml")).unwrap();
    let mesh = &mut scene.description.geometry.meshes[0];
    *mesh = mesh.clone().with_single_sided(true);
    let out = temp("single-sided.gltf");
    export_gltf(&scene, &out).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let sides: Vec<bool> = json["materials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["doubleSided"].as_bool().unwrap())
        .collect();
    assert_eq!(sides.iter().filter(|&&two| !two).count(), 1, "{sides:?}");
    let back = crate::gltf::import_gltf(&out, &ImportOptions::default()).unwrap();
    assert!(back.geometry.meshes[0].single_sided());
}

/// Emission goes out as glTF's emissiveFactor, scaled by KHR_materials_emissive_strength
/// beyond 1, and comes back the same.
#[test]
fn emission_round_trips() {
    let mut scene = crate::native::parse_scene(SCENE, Path::new("s.toml")).unwrap();
    let glow = Texture::Constant(Vec3::new(3.0, 1.5, 0.0));
    scene.description.materials[0].emission = Some(glow.clone());
    let out = temp("emission.gltf");
    export_gltf(&scene, &out).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert!(
        json["extensionsUsed"]
            .as_array()
            .unwrap()
            .contains(&serde_json::json!("KHR_materials_emissive_strength"))
    );
    let back = crate::gltf::import_gltf(&out, &ImportOptions::default()).unwrap();
    let emissions: Vec<_> = back
        .materials
        .iter()
        .filter_map(|(_, m)| m.emission.clone())
        .collect();
    assert_eq!(emissions, [glow]);
}

/// Glass goes out as KHR_materials_transmission, _ior and (for a solid) _volume, and comes
/// back the same: a thin sheet and an absorbing solid.
#[test]
fn glass_round_trips() {
    let mut scene = crate::native::parse_scene(SCENE, Path::new("s.toml")).unwrap();
    let solid = quadray::Transmission {
        factor: 0.9,
        ior: 1.7,
        thin_walled: false,
        attenuation: Some(quadray::Attenuation {
            color: Vec3::new(0.5, 0.75, 1.0),
            distance: 2.0,
        }),
    };
    let sheet = quadray::Transmission {
        thin_walled: true,
        attenuation: None,
        ..solid
    };
    scene.description.materials[0].transmission = Some(solid);
    if let Some(m) = scene.description.materials.get_mut(1) {
        m.transmission = Some(sheet);
    }
    let out = temp("glass.gltf");
    export_gltf(&scene, &out).unwrap();
    let back = crate::gltf::import_gltf(&out, &ImportOptions::default()).unwrap();
    let glass: Vec<_> = back
        .materials
        .iter()
        .filter_map(|(_, m)| m.transmission)
        .collect();
    assert!(glass.contains(&solid), "{glass:?}");
    if scene.description.materials.len() > 1 {
        assert!(glass.contains(&sheet), "{glass:?}");
    }
}

#[test]
fn native_scene_round_trips_through_gltf_and_glb() {
    let scene = crate::native::parse_scene(SCENE, Path::new("s.toml")).unwrap();
    for name in ["round trip.gltf", "round-trip.glb"] {
        let out = temp(name);
        let notes = export_gltf(&scene, &out).unwrap();
        assert!(!notes.is_empty());
        let back = crate::gltf::import_gltf(&out, &ImportOptions::default()).unwrap();
        // Render settings and background come back through the scene's extras.
        let hints = &back.hints;
        assert_eq!(hints.resolution, Some([320, 180]));
        assert_eq!(
            hints.background,
            Some(scene.description.background.to_array())
        );
        let (a, b) = (&scene.description.geometry, &back.geometry);
        assert_eq!(b.quadrics.len(), 2);
        for (qa, qb) in a.quadrics.iter().zip(&b.quadrics) {
            assert_eq!(qa.surface_description(), qb.surface_description());
            assert_eq!(qa.clip(), qb.clip());
            let (ta, tb) = (qa.transform().to_world, qb.transform().to_world);
            assert!(close(ta.translation, tb.translation));
            for c in 0..3 {
                assert!(
                    close(ta.matrix3.col(c), tb.matrix3.col(c)),
                    "{ta:?} vs {tb:?}"
                );
            }
            // Materials are appended in first-use order on import; compare by name.
            let name = |s: &[String], id: u32| s[id as usize].clone();
            let back_names: Vec<String> = back.materials.iter().map(|(n, _)| n.clone()).collect();
            assert_eq!(
                name(&scene.material_names, qa.material()),
                name(&back_names, qb.material())
            );
            assert_eq!(
                scene.description.materials[qa.material() as usize],
                back.materials[qb.material() as usize].1
            );
        }
        assert_eq!(b.spheres.len(), 1);
        assert!(close(a.spheres[0].center, b.spheres[0].center));
        assert!((a.spheres[0].radius - b.spheres[0].radius).abs() < 1e-12);
        assert_eq!(b.planes.len(), 1);
        assert!(close(a.planes[0].point, b.planes[0].point));
        assert!(close(a.planes[0].normal, b.planes[0].normal));
        // Fallback meshes are skipped; the one real mesh comes back vertex for vertex.
        assert_eq!(b.meshes.len(), 1);
        assert_eq!(a.meshes[0].positions(), b.meshes[0].positions());
        assert_eq!(a.meshes[0].indices(), b.meshes[0].indices());
        let (na, nb) = (
            a.meshes[0].normals().unwrap(),
            b.meshes[0].normals().unwrap(),
        );
        assert!(na.iter().zip(nb).all(|(x, y)| (*x - *y).length() < 1e-6));
        assert!(!b.meshes[0].single_sided(), "doubleSided: true");
        assert_eq!(back.lights.len(), 2);
        for (la, lb) in scene.description.lights.iter().zip(&back.lights) {
            match (la, lb) {
                (
                    Light::Point {
                        position: pa,
                        intensity: ia,
                    },
                    Light::Point {
                        position: pb,
                        intensity: ib,
                    },
                ) => {
                    assert!(close(*pa, *pb));
                    assert!((*ia - *ib).length() < 1e-5 * ia.length());
                }
                (
                    Light::Directional {
                        direction: da,
                        irradiance: ia,
                    },
                    Light::Directional {
                        direction: db,
                        irradiance: ib,
                    },
                ) => {
                    assert!(close(*da, *db), "{da} vs {db}");
                    assert!((*ia - *ib).length() < 1e-5 * ia.length());
                }
                other => panic!("light kinds differ: {other:?}"),
            }
        }
        let (ca, cb) = (&scene.description.camera, &back.cameras[0]);
        assert!(close(ca.from, cb.camera.from));
        assert!(close(
            (ca.to - ca.from).normalize(),
            (cb.camera.to - cb.camera.from).normalize()
        ));
        // Camera parameters are read in f64 from the JSON: they come back exactly.
        let Projection::Perspective { vfov_deg } = cb.camera.projection else {
            panic!()
        };
        assert!((vfov_deg - 35.0).abs() < 1e-12);
        assert!((cb.aspect.unwrap() - 320.0 / 180.0).abs() < 1e-15);
        // Listed as used, never required.
        let doc = crate::gltf::document::open(&out).unwrap().document;
        assert!(doc.extensions_used().any(|e| e == quadrics_ext::EXTENSION));
        assert_eq!(doc.extensions_required().count(), 0);
        // Other viewers get fallback meshes: one per shape, on the nodes carrying the shapes.
        assert_eq!(doc.meshes().len(), 1 + 2 + 1 + 1);
    }
}

#[test]
fn refuses_unknown_output_types() {
    let scene = crate::native::parse_scene(SCENE, Path::new("s.toml")).unwrap();
    assert!(matches!(
        export_gltf(&scene, &temp("x.obj")),
        Err(ExportError::Extension(_))
    ));
    let e = export_gltf(&scene, Path::new("/nonexistent-dir/x.gltf")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent-dir/x.bin"), "{e}");
}
