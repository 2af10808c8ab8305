//! Loading the real third-party OBJ files in `../shared/assets` (listed with sources and licences
//! in `../shared/assets/SOURCES.md`), read in place. Each test is ignored, with the reason,
//! where `../shared` is absent (and fails there under CI). The facts asserted are the triangle counts of SOURCES.md and the
//! quirks of real files: libraries never shipped, undefined material names, Windows paths.

use crate::common;

use common::assets;
use quadray::{Scene, Texture};
use quadray_loader::{ImportOptions, obj::import_obj_bytes};
use std::path::Path;

/// OBJ files and their triangle counts after fan triangulation (SOURCES.md).
const OBJ: &[(&str, usize)] = &[
    ("meshes/bunny.obj", 3674),
    ("meshes/dragon_res2.obj.zst", 202520),
    ("meshes/dragon_res3.obj", 47794),
    ("meshes/dragon_res4.obj", 11102),
    ("meshes/teapot.obj", 992),
    ("meshes/cgal/anchor_dense.obj", 7598),
    ("meshes/cgal/armadillo.obj", 52000),
    ("meshes/cgal/blade.obj", 16222),
    ("meshes/cgal/camel.obj", 19536),
    ("meshes/cgal/elephant.obj", 5558),
    ("meshes/cgal/fandisk.obj", 12946),
    ("meshes/cgal/knot1.obj", 6400),
    ("meshes/cgal/mech-holes-shark.obj", 10192),
    ("meshes/neverball/pin.obj", 352),
    ("meshes/neverball/snowman.obj", 892),
    ("meshes/neverball/snowglobe/snowglobe-scene.obj", 808),
    ("meshes/obvhs_kitchen/kitchen.obj.zst", 56939),
    ("meshes/pymeshlab/airplane.obj", 10796),
    ("meshes/pymeshlab/bunny.obj", 56172),
    ("meshes/pymeshlab/cow.obj", 5804),
    (
        "meshes/pymeshlab/bunny10k_textured/bunny10k_textured.obj",
        9999,
    ),
    ("meshes/qt3d/ball.obj", 3968),
    ("meshes/qt3d/plane-10x10.obj", 200),
    ("meshes/qt3d/toyplane.obj", 7548),
    ("meshes/qt3d/trefoil.obj", 8000),
    ("meshes/stellarium_testscene/Stellarium-Testscene.obj", 3240),
    (
        "meshes/stellarium_testscene/Stellarium-Testscene_ground.obj",
        2,
    ),
    ("meshes/suzanne_kivy/monkey.obj", 3936),
];

/// Reads an OBJ asset, decompressing `.obj.zst` files in memory.
fn read_obj(root: &Path, file: &str) -> quadray_loader::Imported {
    let path = root.join(file);
    match file.strip_suffix(".zst") {
        Some(plain) => {
            let bytes = common::unzstd(&path);
            import_obj_bytes(&bytes, &root.join(plain), &ImportOptions::default())
        }
        None => quadray_loader::obj::import_obj(&path, &ImportOptions::default()),
    }
    .unwrap_or_else(|e| panic!("{file}: {e}"))
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn every_obj_asset_loads_with_the_counts_of_sources_md() {
    let root = assets();
    for &(file, triangles) in OBJ {
        let imported = read_obj(&root, file);
        assert_eq!(imported.triangle_count(), triangles, "{file}");
        let scene =
            quadray_loader::standalone::scene_from_import(imported, Path::new(file), None).unwrap();
        Scene::new(scene.description).unwrap_or_else(|e| panic!("{file}: {e}"));
    }
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn obj_quirks_are_handled_and_said() {
    let root = assets();
    // An mtllib that was never shipped: a warning naming the file, and a default material.
    let pin = read_obj(&root, "meshes/neverball/pin.obj");
    assert!(
        pin.notes
            .iter()
            .any(|n| n.contains("pin.mtl") && n.contains("not found"))
    );
    // usemtl names that the library does not define.
    let globe = read_obj(&root, "meshes/neverball/snowglobe/snowglobe-scene.obj");
    assert!(
        globe.notes.iter().any(|n| n.contains("name no material")),
        "{:?}",
        globe.notes
    );
    // Backslash texture paths (TX_Stellarium-Testscene\Stein_….jpg) resolve and decode.
    let stellarium = read_obj(
        &root,
        "meshes/stellarium_testscene/Stellarium-Testscene.obj",
    );
    assert_eq!(stellarium.materials.len(), 2);
    for (name, m) in &stellarium.materials {
        assert!(
            matches!(m.texture, Texture::Image(_)),
            "{name} has no image"
        );
    }
    assert!(stellarium.notes.is_empty(), "{:?}", stellarium.notes);
    // A textured OBJ: texture coordinates on the mesh, an image in the material.
    let bunny = read_obj(
        &root,
        "meshes/pymeshlab/bunny10k_textured/bunny10k_textured.obj",
    );
    assert!(bunny.geometry.meshes[0].texcoords(0).is_some());
    assert!(matches!(bunny.materials[0].1.texture, Texture::Image(_)));
    // Quads and 5- to 8-gons are fanned into triangles.
    assert_eq!(
        read_obj(&root, "meshes/qt3d/toyplane.obj").triangle_count(),
        7548
    );
}
