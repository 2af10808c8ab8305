//! Loading the real third-party glTF files in `../shared/assets` (listed with sources and licences
//! in `../shared/assets/SOURCES.md`), read in place; the OBJ files are in `real_obj.rs`. Each test
//! is ignored, with the reason, where `../shared` is absent (and fails there under CI). The facts asserted are ones a reader can check:
//! the triangle and node counts of SOURCES.md, camera parameters written in Cameras.gltf, positions
//! that Blender's default scene is known to have, and geometric consequences of the transforms of
//! OrientationTest and NegativeScaleTest.

use crate::common;

use common::assets;
use glam::{DVec3, Vec3};
use quadray::{Light, Projection, Scene, Texture, Wrap};
use quadray_loader::{
    ImportOptions, LoadErrorKind, Selector, gltf::import_gltf, load_any, load_any_with,
};

/// glTF files: path, triangles instanced by the default scene (SOURCES.md), node count where
/// SOURCES.md gives one.
const GLTF: &[(&str, usize, Option<usize>)] = &[
    (
        "gltf/blender_default_scene/blender_default_scene.gltf",
        12,
        Some(3),
    ),
    ("gltf/qt3d/RiggedFigure/RiggedFigure.gltf", 256, Some(22)),
    ("gltf/qt3d/RiggedSimple/RiggedSimple.gltf", 188, Some(5)),
    ("gltf/webxr/generic-hand_left.glb", 2314, Some(30)),
    (
        "gltf/webxr/generic-trigger-squeeze-touchpad-thumbstick_left.glb",
        5829,
        Some(50),
    ),
    ("gltf/webxr/meta-quest-touch-plus_left.glb", 4470, Some(31)),
    ("gltf/webxr/pico-4u_left.glb", 4731, Some(37)),
    ("gltf/khronos/Box/glTF/Box.gltf", 12, None),
    ("gltf/khronos/Box/glTF-Embedded/Box.gltf", 12, None),
    ("gltf/khronos/Box/glTF-Binary/Box.glb", 12, None),
    ("gltf/khronos/BoxTextured/glTF/BoxTextured.gltf", 12, None),
    (
        "gltf/khronos/BoxTextured/glTF-Embedded/BoxTextured.gltf",
        12,
        None,
    ),
    (
        "gltf/khronos/BoxTextured/glTF-Binary/BoxTextured.glb",
        12,
        None,
    ),
    (
        "gltf/khronos/BoxInterleaved/glTF-Embedded/BoxInterleaved.gltf",
        12,
        None,
    ),
    (
        "gltf/khronos/BoxInterleaved/glTF-Binary/BoxInterleaved.glb",
        12,
        None,
    ),
    ("gltf/khronos/Duck/glTF/Duck.gltf", 4212, None),
    ("gltf/khronos/Duck/glTF-Embedded/Duck.gltf", 4212, None),
    ("gltf/khronos/Duck/glTF-Binary/Duck.glb", 4212, None),
    ("gltf/khronos/Cameras/glTF/Cameras.gltf", 2, None),
    ("gltf/khronos/Cameras/glTF-Embedded/Cameras.gltf", 2, None),
    ("gltf/khronos/SimpleMeshes/glTF/SimpleMeshes.gltf", 2, None),
    (
        "gltf/khronos/SimpleMeshes/glTF-Embedded/SimpleMeshes.gltf",
        2,
        None,
    ),
    (
        "gltf/khronos/OrientationTest/glTF/OrientationTest.gltf",
        524,
        Some(13),
    ),
    (
        "gltf/khronos/OrientationTest/glTF-Embedded/OrientationTest.gltf",
        524,
        Some(13),
    ),
    (
        "gltf/khronos/OrientationTest/glTF-Binary/OrientationTest.glb",
        524,
        Some(13),
    ),
    (
        "gltf/khronos/2CylinderEngine/glTF-Binary/2CylinderEngine.glb",
        121496,
        Some(82),
    ),
    (
        "gltf/khronos/MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb",
        1040409,
        Some(119),
    ),
    (
        "gltf/khronos/TextureCoordinateTest/glTF/TextureCoordinateTest.gltf",
        10,
        None,
    ),
    (
        "gltf/khronos/TextureCoordinateTest/glTF-Embedded/TextureCoordinateTest.gltf",
        10,
        None,
    ),
    (
        "gltf/khronos/TextureCoordinateTest/glTF-Binary/TextureCoordinateTest.glb",
        10,
        None,
    ),
    ("gltf/khronos/Suzanne/glTF/Suzanne.gltf", 3936, None),
    (
        "gltf/khronos/MeshPrimitiveModes/glTF/MeshPrimitiveModes.gltf",
        16,
        None,
    ),
    (
        "gltf/khronos/MeshPrimitiveModes/glTF-Embedded/MeshPrimitiveModes.gltf",
        16,
        None,
    ),
    (
        "gltf/khronos/NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb",
        7724,
        None,
    ),
    (
        "gltf/khronos/SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf",
        12,
        None,
    ),
    (
        "gltf/khronos/SimpleSparseAccessor/glTF-Embedded/SimpleSparseAccessor.gltf",
        12,
        None,
    ),
    (
        "gltf/khronos/TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf",
        1,
        None,
    ),
    (
        "gltf/khronos/TriangleWithoutIndices/glTF-Embedded/TriangleWithoutIndices.gltf",
        1,
        None,
    ),
    (
        "gltf/khronos/MultipleScenes/glTF-Embedded/MultipleScenes.gltf",
        2,
        None,
    ),
    (
        "gltf/khronos/TextureSettingsTest/glTF-Binary/TextureSettingsTest.glb",
        72,
        None,
    ),
    (
        "gltf/khronos/VertexColorTest/glTF-Binary/VertexColorTest.glb",
        36,
        None,
    ),
    (
        "gltf/khronos/MultiUVTest/glTF-Binary/MultiUVTest.glb",
        12,
        None,
    ),
    (
        "gltf/khronos/CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb",
        3624,
        None,
    ),
];

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn every_gltf_asset_loads_with_the_counts_of_sources_md() {
    let root = assets();
    for &(file, triangles, nodes) in GLTF {
        let path = root.join(file);
        let imported =
            import_gltf(&path, &ImportOptions::default()).unwrap_or_else(|e| panic!("{file}: {e}"));
        // Triangles with a repeated index are dropped (and counted), having no area.
        assert_eq!(
            imported.triangle_count() + imported.degenerate,
            triangles,
            "{file}"
        );
        if let Some(n) = nodes {
            assert_eq!(imported.nodes, n, "{file}: nodes");
        }
        let scene = load_any(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        Scene::new(scene.description).unwrap_or_else(|e| panic!("{file}: {e}"));
    }
    // The one file with degenerate triangles says how many it dropped.
    let engine = import_gltf(
        &root.join("gltf/khronos/2CylinderEngine/glTF-Binary/2CylinderEngine.glb"),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(engine.degenerate, 11154);
    assert!(engine.notes.iter().any(|n| n.contains("11154 degenerate")));
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn draco_and_gltf_1_files_are_refused_by_name() {
    let root = assets();
    for file in [
        "gltf/draco/gsimone_suzanne.glb",
        "gltf/draco/pmndrs_bunny.glb",
        "gltf/draco/pmndrs_suzi.glb",
    ] {
        let e = load_any(&root.join(file)).unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::Unsupported(_)));
        let text = e.to_string();
        assert!(text.contains("KHR_draco_mesh_compression"), "{text}");
        assert!(text.contains(file.rsplit('/').next().unwrap()), "{text}");
    }
    let e = load_any(&root.join("gltf/qt3d/wine_gltf1/wine.gltf"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("wine.gltf") && e.contains("glTF 0.8") && e.contains("2.0 only"),
        "{e}"
    );
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn cameras_gltf_gives_both_cameras_with_their_parameters() {
    let root = assets();
    let path = root.join("gltf/khronos/Cameras/glTF/Cameras.gltf");
    let imported = import_gltf(&path, &ImportOptions::default()).unwrap();
    assert_eq!(imported.cameras.len(), 2);
    // Both at glTF (0.5, 0.5, 3.0), looking down −z with +y up: quadray (0.5, −3, 0.5), +y, +z.
    for c in &imported.cameras {
        assert!((c.camera.from - DVec3::new(0.5, -3.0, 0.5)).length() < 1e-6);
        assert!(((c.camera.to - c.camera.from).normalize() - DVec3::Y).length() < 1e-12);
        assert!((c.camera.up - DVec3::Z).length() < 1e-12);
        assert_eq!(c.aspect, Some(1.0));
    }
    let Projection::Perspective { vfov_deg } = imported.cameras[0].camera.projection else {
        panic!("camera 0 is perspective")
    };
    assert!((vfov_deg - 0.7f64.to_degrees()).abs() < 1e-5, "{vfov_deg}");
    // Orthographic ymag 1: two units of height.
    assert_eq!(
        imported.cameras[1].camera.projection,
        Projection::Orthographic { height: 2.0 }
    );
    // Rendering the file: the first camera, the square image its aspect asks for, and a note.
    let scene = load_any(&path).unwrap();
    assert_eq!((scene.settings.width, scene.settings.height), (640, 640));
    assert!(scene.notes.iter().any(|n| n.contains("2 cameras")));
    let ortho = load_any_with(&path, &ImportOptions::default(), Some(&Selector::Index(1))).unwrap();
    assert_eq!(
        ortho.description.camera.projection,
        Projection::Orthographic { height: 2.0 }
    );
    let e = load_any_with(
        &path,
        &ImportOptions::default(),
        Some(&Selector::Name("x".into())),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("no camera \"x\" (the file has 2: #0, #1)"),
        "{e}"
    );
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn box_comes_back_to_its_z_up_coordinates() {
    let root = assets();
    let path = root.join("gltf/khronos/Box/glTF/Box.gltf");
    // Box's node matrix turns its z-up data to glTF's y-up; quadray turns y-up to z-up, so the
    // world positions are the raw POSITION values (read here with the gltf crate directly).
    let (doc, buffers) = {
        let gltf = gltf::Gltf::open(&path).unwrap();
        let bin = std::fs::read(path.with_file_name("Box0.bin")).unwrap();
        (gltf.document, vec![bin])
    };
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let raw: Vec<Vec3> = prim
        .reader(|b| Some(&buffers[b.index()]))
        .read_positions()
        .unwrap()
        .map(Vec3::from)
        .collect();
    let imported = import_gltf(&path, &ImportOptions::default()).unwrap();
    let mesh = &imported.geometry.meshes[0];
    assert_eq!(mesh.positions(), raw.as_slice());
    let (lo, hi) = imported.bounds().unwrap();
    assert_eq!((lo, hi), (DVec3::splat(-0.5), DVec3::splat(0.5)));
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn orientation_test_arrows_touch_their_targets() {
    let root = assets();
    for variant in [
        "glTF/OrientationTest.gltf",
        "glTF-Binary/OrientationTest.glb",
    ] {
        let path = root.join("gltf/khronos/OrientationTest").join(variant);
        let scene = load_any(&path).unwrap();
        let g = &scene.description.geometry;
        // Each coloured material is shared by one arrow (rotated by a TRS or a matrix node) and
        // its target (unrotated); placed right, the arrow's tip touches the target.
        let mut pairs = 0;
        for (id, name) in scene.material_names.iter().enumerate() {
            let meshes: Vec<_> = g
                .meshes
                .iter()
                .filter(|m| m.material() == id as u32)
                .collect();
            if name == "BaseMaterial" {
                let (lo, hi) = quadray_loader::framing::geometry_bounds(&quadray::Geometry {
                    meshes: meshes.into_iter().cloned().collect(),
                    ..Default::default()
                })
                .unwrap();
                assert!(
                    (lo + DVec3::splat(5.0)).length() < 1e-5
                        && (hi - DVec3::splat(5.0)).length() < 1e-5
                );
                continue;
            }
            assert_eq!(meshes.len(), 2, "{name}");
            // Arrows have more vertices than targets (74–78 against 50–54).
            let (arrow, target) = if meshes[0].positions().len() > meshes[1].positions().len() {
                (meshes[0], meshes[1])
            } else {
                (meshes[1], meshes[0])
            };
            let (lo, hi) = target
                .positions()
                .iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
                    (l.min(*p), h.max(*p))
                });
            // Distance from the arrow's nearest vertex to the target's box. The model itself leaves
            // 0.0028 (computed independently from the raw file with the spec's TRS formula, in
            // Python); the arrows are about 4 units long, so pointing 1° off would leave about 0.07.
            let gap = arrow
                .positions()
                .iter()
                .map(|p| (p.clamp(lo, hi) - *p).length())
                .fold(f32::INFINITY, f32::min);
            assert!(
                gap < 0.004,
                "{name}: the arrow stops {gap} short of its target"
            );
            pairs += 1;
        }
        assert_eq!(pairs, 6);
    }
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn negative_scale_test_keeps_triangles_facing_their_normals() {
    let root = assets();
    let path = root.join("gltf/khronos/NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb");
    let imported = import_gltf(&path, &ImportOptions::default()).unwrap();
    assert_eq!(imported.triangle_count(), 7724);
    // The file mirrors several instances (scale −1 on all axes). Every triangle's winding must
    // still agree with its vertices' normals, which the file authored to point outwards.
    let (mut agree, mut total) = (0, 0);
    for m in &imported.geometry.meshes {
        let (p, n) = (m.positions(), m.normals().expect("the file has normals"));
        for t in m.indices() {
            let [a, b, c] = t.map(|i| i as usize);
            let face = (p[b] - p[a]).cross(p[c] - p[a]);
            if face.length() > 1e-9 {
                total += 1;
                agree += usize::from(face.dot(n[a] + n[b] + n[c]) > 0.0);
            }
        }
    }
    assert_eq!(
        agree,
        total,
        "{} of {total} triangles face away from their normals",
        total - agree
    );
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn multiple_scenes_default_and_choice() {
    let root = assets();
    let path = root.join("gltf/khronos/MultipleScenes/glTF-Embedded/MultipleScenes.gltf");
    let default = import_gltf(&path, &ImportOptions::default()).unwrap();
    assert_eq!(default.triangle_count(), 2);
    assert!(
        default
            .notes
            .iter()
            .any(|n| n.contains("2 scenes; using scene #1"))
    );
    let first = ImportOptions {
        scene: Some(Selector::Index(0)),
        ..ImportOptions::default()
    };
    assert_eq!(import_gltf(&path, &first).unwrap().triangle_count(), 1);
    let missing = ImportOptions {
        scene: Some(Selector::Index(5)),
        ..ImportOptions::default()
    };
    let e = import_gltf(&path, &missing).unwrap_err().to_string();
    assert!(
        e.contains("scene #5 does not exist (the file has 2)"),
        "{e}"
    );
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn primitive_modes_sparse_accessors_and_unindexed_triangles() {
    let root = assets();
    let k = root.join("gltf/khronos");
    let modes = import_gltf(
        &k.join("MeshPrimitiveModes/glTF/MeshPrimitiveModes.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    // TRIANGLES (18 indices: 6), TRIANGLE_STRIP (6: 4), TRIANGLE_FAN (8: 6).
    let mut counts: Vec<usize> = modes
        .geometry
        .meshes
        .iter()
        .map(|m| m.triangle_count())
        .collect();
    counts.sort_unstable();
    assert_eq!(counts, [4, 6, 6]);
    let note = modes.notes.join(" ");
    for m in ["POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"] {
        assert!(note.contains(m), "{note}");
    }
    // SimpleSparseAccessor: vertices 8, 10 and 12 are replaced by (1,2,0), (3,3,0), (5,4,0),
    // which become (1,0,2), (3,0,3), (5,0,4) in quadray's z-up world.
    let sparse = import_gltf(
        &k.join("SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    let p = sparse.geometry.meshes[0].positions();
    for v in [
        Vec3::new(1.0, 0.0, 2.0),
        Vec3::new(3.0, 0.0, 3.0),
        Vec3::new(5.0, 0.0, 4.0),
    ] {
        assert!(p.iter().any(|q| (*q - v).length() < 1e-6), "{v} missing");
    }
    assert_eq!(sparse.bounds().unwrap().1.z, 4.0);
    let unindexed = import_gltf(
        &k.join("TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf"),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(unindexed.geometry.meshes[0].indices(), &[[0, 1, 2]]);
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn textures_samplers_vertex_colours_and_uv_sets() {
    let root = assets();
    let k = root.join("gltf/khronos");
    // The same PNG through an external file, a data URI and a GLB buffer view.
    for file in [
        "BoxTextured/glTF/BoxTextured.gltf",
        "BoxTextured/glTF-Embedded/BoxTextured.gltf",
        "BoxTextured/glTF-Binary/BoxTextured.glb",
    ] {
        let s = load_any(&k.join(file)).unwrap();
        let Texture::Image(t) = &s.description.materials[0].texture else {
            panic!("{file}: no image texture")
        };
        assert_eq!(
            (t.map.image.width(), t.map.image.height()),
            (256, 256),
            "{file}"
        );
        assert!(s.description.geometry.meshes[0].texcoords(0).is_some());
    }
    // TextureSettingsTest: each material's sampler wrap modes, by material name.
    let s = load_any(&k.join("TextureSettingsTest/glTF-Binary/TextureSettingsTest.glb")).unwrap();
    let wrap_of = |name: &str| {
        let i = s.material_names.iter().position(|n| n == name).unwrap();
        match &s.description.materials[i].texture {
            Texture::Image(t) => t.map.wrap,
            other => panic!("{name}: {other:?}"),
        }
    };
    assert_eq!(
        wrap_of("TextureMirrorMaterialT"),
        [Wrap::Repeat, Wrap::MirroredRepeat]
    );
    assert_eq!(
        wrap_of("TextureMirrorMaterialS"),
        [Wrap::MirroredRepeat, Wrap::Repeat]
    );
    assert_eq!(
        wrap_of("TextureClampMaterialT"),
        [Wrap::Repeat, Wrap::ClampToEdge]
    );
    assert_eq!(
        wrap_of("TextureClampMaterialS"),
        [Wrap::ClampToEdge, Wrap::Repeat]
    );
    // COLOR_0 and two texture coordinate sets.
    let vc = import_gltf(
        &k.join("VertexColorTest/glTF-Binary/VertexColorTest.glb"),
        &ImportOptions::default(),
    )
    .unwrap();
    assert!(vc.geometry.meshes.iter().any(|m| m.colors().is_some()));
    let multi = import_gltf(
        &k.join("MultiUVTest/glTF-Binary/MultiUVTest.glb"),
        &ImportOptions::default(),
    )
    .unwrap();
    let m = &multi.geometry.meshes[0];
    assert!(m.texcoords(0).is_some() && m.texcoords(1).is_some());
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn blender_default_scene_has_blenders_light_and_camera() {
    let root = assets();
    let scene =
        load_any(&root.join("gltf/blender_default_scene/blender_default_scene.gltf")).unwrap();
    let d = &scene.description;
    // Blender's default light and camera locations (z-up, as Blender shows them).
    let Light::Point {
        position,
        intensity,
    } = d.lights[0]
    else {
        panic!("the light is a point light")
    };
    assert!(
        (position - DVec3::new(4.0762, 1.0055, 5.9039)).length() < 1e-3,
        "{position}"
    );
    // 1000 W exported as 54 351 cd; quadray divides by 683·π.
    assert!((intensity.x - 54351.41 / (683.0 * std::f32::consts::PI)).abs() < 1e-2);
    assert!(
        (d.camera.from - DVec3::new(7.3589, -6.9258, 4.9583)).length() < 1e-3,
        "{}",
        d.camera.from
    );
    // 16:9 from the camera's aspect ratio.
    assert_eq!((scene.settings.width, scene.settings.height), (640, 360));
    assert!(scene.notes.is_empty(), "{:?}", scene.notes);
}
