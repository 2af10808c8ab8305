//! glTF instancing end to end: shared meshes, shapes and nodes load as instances and render like
//! their unshared copies (Khronos samples included), `convert` keeps instancing, and wide, deep
//! and plane-holding graphs load.

use base64::Engine;
use quadray::{Film, NoProgress, Scene, render};
use quadray_tests::{display_difference, render_file, repo_root};
use std::path::Path;

/// Renders any scene file quadray reads, seen by the camera and lit by the lights `like` gets
/// (a glTF file gets a framing camera and a key light: the framing would differ, instance bounds
/// being boxes of transformed boxes).
fn render_any(path: &Path, like: &Path) -> (Film, quadray::AccelStats) {
    let mut loaded = quadray_loader::load_any(path).unwrap_or_else(|e| panic!("{e}"));
    let view = quadray_loader::load_any(like).unwrap().description;
    loaded.description.camera = view.camera;
    loaded.description.lights = view.lights;
    let mut settings = loaded.settings.render_settings();
    settings.width = 160;
    settings.height = 120;
    let scene = Scene::new(loaded.description).expect("scene is valid");
    let film = render(&scene, &settings, &NoProgress).unwrap().film;
    (film, scene.accel().stats(scene.geometry()))
}

/// A glTF document and its buffer, written to `dir` as `name.gltf` + `name.bin`.
fn write_gltf(
    dir: &Path,
    name: &str,
    mut doc: serde_json::Value,
    bin: &[u8],
) -> std::path::PathBuf {
    std::fs::write(dir.join(format!("{name}.bin")), bin).unwrap();
    doc["buffers"][0]["uri"] = serde_json::json!(format!("{name}.bin"));
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

/// Khronos' SimpleMeshes (one mesh used by two nodes) loads as one prototype placed twice and
/// renders exactly like the same file with the mesh duplicated (which loads flat, baked).
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn gltf_shared_meshes_render_like_their_copies() {
    let dir = repo_root().join("../shared/assets/gltf/khronos/SimpleMeshes/glTF");
    assert!(dir.is_dir(), "{} is absent", dir.display());
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("SimpleMeshes.gltf")).unwrap())
            .unwrap();
    let bin = std::fs::read(dir.join("triangle.bin")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let shared = write_gltf(tmp.path(), "shared", doc.clone(), &bin);
    let mut flat_doc = doc;
    let mesh = flat_doc["meshes"][0].clone();
    flat_doc["meshes"].as_array_mut().unwrap().push(mesh);
    flat_doc["nodes"][1]["mesh"] = serde_json::json!(1);
    let flat = write_gltf(tmp.path(), "flat", flat_doc, &bin);
    let (a, stats) = render_any(&shared, &flat);
    let (b, flat_stats) = render_any(&flat, &flat);
    assert_eq!((stats.prototypes, stats.placements), (1, 2));
    assert_eq!((flat_stats.prototypes, flat_stats.triangles_stored), (0, 2));
    assert_eq!((stats.triangles_stored, stats.triangles_instanced), (1, 2));
    let (share, largest) = display_difference(&a, &b);
    assert!(
        share <= 0.001,
        "{share} of pixels differ (largest {largest}/255)"
    );
    let pixels = a.to_srgb8();
    assert!(
        pixels.iter().any(|&v| v != pixels[0]),
        "the triangles are visible"
    );
}

/// A node used by two parents (glTF asks for trees; files share nodes anyway) becomes one
/// prototype placed twice, and renders like the file with the node duplicated; a `QUADRAY_quadrics`
/// sphere on the shared node is instanced with it.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn gltf_shared_nodes_render_like_their_copies() {
    let dir = repo_root().join("../shared/assets/gltf/khronos/SimpleMeshes/glTF");
    assert!(dir.is_dir(), "{} is absent", dir.display());
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("SimpleMeshes.gltf")).unwrap())
            .unwrap();
    let bin = std::fs::read(dir.join("triangle.bin")).unwrap();
    let ext = serde_json::json!({"QUADRAY_quadrics": {"shapes": [
        {"type": "sphere", "sphere": {"radius": 0.2}}
    ]}});
    doc["extensionsUsed"] = serde_json::json!(["QUADRAY_quadrics"]);
    doc["extensions"] = ext;
    doc["nodes"] = serde_json::json!([
        {"children": [2], "translation": [-0.8, 0.0, 0.0]},
        {"children": [2], "translation": [0.8, 0.3, 0.0], "rotation": [0.0, 0.0, 0.3826834, 0.9238795]},
        {"children": [3, 4], "scale": [1.0, 0.5, 1.0]},
        {"mesh": 0},
        {"translation": [0.5, 0.5, 0.2], "extensions": {"QUADRAY_quadrics": {"shape": 0}}}
    ]);
    doc["scenes"] = serde_json::json!([{"nodes": [0, 1]}]);
    let tmp = tempfile::tempdir().unwrap();
    let shared = write_gltf(tmp.path(), "shared", doc.clone(), &bin);
    // The flat copy: node 2's subtree, its mesh and its shape duplicated for node 1 (so nothing
    // is used twice).
    let mesh = doc["meshes"][0].clone();
    doc["meshes"].as_array_mut().unwrap().push(mesh);
    doc["extensions"]["QUADRAY_quadrics"]["shapes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"type": "sphere", "sphere": {"radius": 0.2}}));
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.push(serde_json::json!({"children": [6, 7], "scale": [1.0, 0.5, 1.0]}));
    nodes.push(serde_json::json!({"mesh": 1}));
    nodes.push(serde_json::json!({"translation": [0.5, 0.5, 0.2], "extensions": {"QUADRAY_quadrics": {"shape": 1}}}));
    nodes[1]["children"] = serde_json::json!([5]);
    let flat = write_gltf(tmp.path(), "flat", doc, &bin);
    let (a, stats) = render_any(&shared, &flat);
    let (b, flat_stats) = render_any(&flat, &flat);
    assert_eq!(stats.prototypes, 1, "node 2 is one prototype");
    assert_eq!(stats.placements, 2);
    assert_eq!(
        stats.primitives_stored, 2,
        "one triangle and one sphere stored"
    );
    assert_eq!(
        (flat_stats.prototypes, flat_stats.primitives_stored),
        (0, 4)
    );
    let (share, largest) = display_difference(&a, &b);
    assert!(
        share <= 0.001,
        "{share} of pixels differ (largest {largest}/255)"
    );
}

/// A GLB file's JSON and binary chunks.
fn read_glb(path: &Path) -> (serde_json::Value, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let chunk = |at: usize| {
        let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        (&bytes[at + 8..at + 8 + len], at + 8 + len)
    };
    let (json, next) = chunk(12);
    let (bin, _) = chunk(next);
    (serde_json::from_slice(json).unwrap(), bin.to_vec())
}

/// Khronos samples whose meshes several nodes use load them once and render as before: like the
/// same file with every shared mesh duplicated per node, which loads flat (the path every file
/// took before instancing). The camera is the flat file's framing one.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn khronos_samples_with_shared_meshes_render_as_before() {
    let root = repo_root().join("../shared/assets/gltf/khronos");
    assert!(root.is_dir(), "{} is absent", root.display());
    let tmp = tempfile::tempdir().unwrap();
    for name in ["2CylinderEngine", "CesiumMilkTruck", "NegativeScaleTest"] {
        let (doc, bin) = read_glb(&root.join(format!("{name}/glTF-Binary/{name}.glb")));
        // The buffer holds images by bufferView, so the .bin serves both copies unchanged.
        let shared = write_gltf(tmp.path(), &format!("{name}-shared"), doc.clone(), &bin);
        let mut flat_doc = doc;
        let mut used = std::collections::HashSet::new();
        let node_count = flat_doc["nodes"].as_array().map_or(0, Vec::len);
        for i in 0..node_count {
            let Some(mesh) = flat_doc["nodes"][i]["mesh"].as_u64() else {
                continue;
            };
            if !used.insert(mesh) {
                let copy = flat_doc["meshes"][mesh as usize].clone();
                let meshes = flat_doc["meshes"].as_array_mut().unwrap();
                meshes.push(copy);
                flat_doc["nodes"][i]["mesh"] = serde_json::json!(meshes.len() - 1);
            }
        }
        let flat = write_gltf(tmp.path(), &format!("{name}-flat"), flat_doc, &bin);
        let (a, stats) = render_any(&shared, &flat);
        let (b, flat_stats) = render_any(&flat, &flat);
        assert!(stats.prototypes > 0, "{name} shares meshes");
        assert_eq!(flat_stats.prototypes, 0, "{name}");
        assert_eq!(
            stats.triangles_instanced, flat_stats.triangles_stored as u64,
            "{name}"
        );
        assert!(
            stats.triangles_stored < flat_stats.triangles_stored,
            "{name}"
        );
        let (share, largest) = display_difference(&a, &b);
        assert!(
            share <= 0.001,
            "{name}: {share} of pixels differ (largest {largest}/255)"
        );
        // The framing camera follows the same bounds: vertices placed through the instances.
        let camera = |p: &Path| quadray_loader::load_any(p).unwrap().description.camera;
        let (c, f) = (camera(&shared), camera(&flat));
        assert!(
            (c.from - f.from).length() <= 1e-6 * f.from.length().max(1.0),
            "{name}"
        );
    }
}

/// `convert` keeps instancing: the colonnade written as glTF stores each mesh and shape once per
/// material (the gold row's override makes its own shapes), places them by a node per placement
/// under instance nodes that keep the hierarchy, and reads back into the same image.
#[test]
fn converted_instances_stay_instances_and_render_the_same() {
    let root = repo_root();
    let native = root.join("scenes/columns.toml");
    let loaded = quadray_loader::load_scene(&native).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("columns.gltf");
    quadray_loader::export::export_gltf(&loaded, &out).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let shapes = json["extensions"]["QUADRAY_quadrics"]["shapes"]
        .as_array()
        .unwrap();
    // Marble column (3), gold column (3), orb (1); the floor plane (1).
    assert_eq!(shapes.len(), 8, "{shapes:#?}");
    let nodes = json["nodes"].as_array().unwrap();
    let instance_nodes = nodes
        .iter()
        .filter(|n| n["name"].as_str().is_some_and(|s| s.contains("instance")))
        .count();
    assert_eq!(instance_nodes, 11, "one node per placement, hierarchy kept");
    let (a, _) = render_file(&native);
    let mut reread = quadray_loader::load_any(&out).unwrap();
    // The scene's light has no falloff, which glTF cannot say (convert notes it): compare the
    // geometry and materials under the scene's own light.
    reread.description.lights = loaded.description.lights.clone();
    let settings = reread.settings.render_settings();
    let scene = Scene::new(reread.description).unwrap();
    let stats = scene.accel().stats(scene.geometry());
    assert!(
        stats.prototypes > 0,
        "shared shapes are instanced again on import"
    );
    let b = render(&scene, &settings, &NoProgress).unwrap().film;
    let (share, largest) = display_difference(&a, &b);
    assert!(
        share <= 0.001,
        "{share} of pixels differ (largest {largest}/255)"
    );
}

/// A minimal glTF (one triangle in an embedded buffer) with the given nodes and scene roots.
fn triangle_gltf(nodes: serde_json::Value, roots: serde_json::Value) -> serde_json::Value {
    let mut bin = Vec::new();
    for v in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": bin.len(), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "extensionsUsed": ["QUADRAY_quadrics"],
        "extensions": {"QUADRAY_quadrics": {"shapes": [{"type": "plane"}]}}
    })
}

fn load_gltf_json(doc: &serde_json::Value) -> Result<quadray_loader::LoadedScene, String> {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("graph.gltf");
    std::fs::write(&path, serde_json::to_string(doc).unwrap()).unwrap();
    quadray_loader::load_any(&path).map_err(|e| e.to_string())
}

/// Review findings kept fixed: a node with thousands of children is wide, not deep; the deepest
/// chain of nodes accepted loads on a thread of a small stack, and a deeper one is refused, as
/// is a ladder of shared nodes as deep; a `QUADRAY_quadrics` plane under a node placed twice is
/// placed on both paths (it cannot be instanced).
#[test]
fn gltf_graphs_wide_deep_and_with_planes_under_shared_nodes() {
    let children: Vec<serde_json::Value> = (1..=3000)
        .map(|i| serde_json::json!({"mesh": 0, "translation": [i as f64, 0.0, 0.0]}))
        .collect();
    let mut nodes = vec![serde_json::json!({"children": (1..=3000).collect::<Vec<_>>()})];
    nodes.extend(children);
    let wide = load_gltf_json(&triangle_gltf(
        serde_json::json!(nodes),
        serde_json::json!([0]),
    ))
    .expect("a wide node loads");
    assert_eq!(wide.description.geometry.prototypes.len(), 1);
    assert_eq!(wide.description.geometry.instances.len(), 3000);

    // The deepest chain the loader accepts loads, and one node deeper is refused, on a thread
    // of a quarter of the default stack: the walk keeps its own stack of nodes (the test build
    // compiles the loader unoptimised, where a recursion a node at a time needed 4 to 8 MiB).
    // The last node holds a light too, which the walk of cameras and lights must reach, placed
    // by the whole chain's translations.
    let chain = |depth: usize| {
        let nodes: Vec<serde_json::Value> = (0..depth)
            .map(|i| match i {
                _ if i == depth - 1 => serde_json::json!({
                    "mesh": 0,
                    "extensions": {"KHR_lights_punctual": {"light": 0}}
                }),
                _ => serde_json::json!({"children": [i + 1], "translation": [0.001, 0.0, 0.0]}),
            })
            .collect();
        let mut doc = triangle_gltf(serde_json::json!(nodes), serde_json::json!([0]));
        doc["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual"]);
        doc["extensions"]["KHR_lights_punctual"] =
            serde_json::json!({"lights": [{"type": "point", "intensity": 100.0}]});
        doc
    };
    // And a ladder as deep: both nodes of each rung are children of both nodes of the rung
    // above, so each is shared, and the prototypes nest a rung at a time.
    let ladder = |depth: usize| {
        let nodes: Vec<serde_json::Value> = (0..2 * depth)
            .map(|i| match i / 2 {
                rung if rung == depth - 1 => serde_json::json!({"mesh": 0}),
                rung => serde_json::json!({"children": [2 * rung + 2, 2 * rung + 3]}),
            })
            .collect();
        triangle_gltf(serde_json::json!(nodes), serde_json::json!([0, 1]))
    };
    let deepest = quadray_loader::gltf::MAX_DEPTH;
    let (deep, deeper, ladder) = (chain(deepest), chain(deepest + 1), ladder(deepest));
    let (deep, deeper, ladder) = std::thread::Builder::new()
        .stack_size(512 << 10)
        .spawn(move || {
            let counts = |doc| {
                load_gltf_json(doc).map(|l| {
                    let lights = l.description.lights;
                    let x = lights
                        .first()
                        .and_then(|light| light.position())
                        .map(|p| p.x);
                    (l.description.geometry.meshes.len(), lights.len(), x)
                })
            };
            (counts(&deep), counts(&deeper), counts(&ladder))
        })
        .unwrap()
        .join()
        .expect("no stack overflow");
    let error = ladder.expect_err("prototypes nested a thousand deep are refused");
    assert!(error.contains("instances nest"), "{error}");
    let (meshes, lights, x) = deep.expect("the deepest chain loads");
    assert_eq!((meshes, lights), (1, 1));
    // 1023 translations of 0.001 along x (glTF's x stays quadray's x).
    let x = x.expect("a light");
    assert!((x - 1.023).abs() < 1e-9, "{x}");
    let error = deeper.expect_err("a chain past the limit is refused");
    assert!(
        error.contains(&format!(
            "the node hierarchy is deeper than {deepest} levels"
        )),
        "{error}"
    );

    let nodes = serde_json::json!([
        {"children": [2], "translation": [0.0, 0.0, 0.0]},
        {"children": [2], "translation": [0.0, 0.0, 5.0]},
        {"children": [3, 4, 5], "translation": [1.0, 0.0, 0.0]},
        {"mesh": 0},
        {"extensions": {"QUADRAY_quadrics": {"shape": 0}}},
        {"translation": [0.0, 2.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    let mut doc = triangle_gltf(nodes, serde_json::json!([0, 1]));
    doc["extensionsUsed"] = serde_json::json!(["QUADRAY_quadrics", "KHR_lights_punctual"]);
    doc["extensions"]["KHR_lights_punctual"] =
        serde_json::json!({"lights": [{"type": "point", "intensity": 100.0}]});
    let planes = load_gltf_json(&doc).expect("planes under a shared node load");
    let g = &planes.description.geometry;
    assert_eq!(g.planes.len(), 2, "one plane per path");
    assert_eq!((g.prototypes.len(), g.instances.len()), (1, 2));
    // The light under the shared node is placed on both paths, its transforms composed: glTF
    // (x, y, z) = (1, 2, 0) and (1, 2, 5) become quadray's z-up (x, -z, y).
    let mut at: Vec<[f64; 3]> = planes
        .description
        .lights
        .iter()
        .map(|l| match l {
            quadray::Light::Point { position, .. } => position.to_array(),
            other => panic!("{other:?}"),
        })
        .collect();
    at.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(at, vec![[1.0, -5.0, 2.0], [1.0, 0.0, 2.0]]);
}
