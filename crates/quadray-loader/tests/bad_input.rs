//! Malformed glTF and OBJ files written by the test: each must give a clear error naming the file
//! and the problem (or, for a missing texture, a warning and the base colour), never a panic.

use crate::common;

use common::{dir, load, triangle};
use quadray_loader::{LoadErrorKind, load_any};
use serde_json::{Value, json};
use std::path::Path;

fn error(name: &str, edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> String {
    let (mut gltf, mut bin) = triangle();
    edit(&mut gltf, &mut bin);
    match load(name, &gltf, Some(&bin)) {
        Ok(_) => panic!("{name}: accepted"),
        Err(e) => {
            assert!(
                e.contains(&format!("{name}.gltf")),
                "the error does not name the file: {e}"
            );
            e
        }
    }
}

#[test]
fn the_valid_triangle_loads() {
    let (gltf, bin) = triangle();
    let s = load("valid", &gltf, Some(&bin)).unwrap();
    assert_eq!(s.description.geometry.meshes[0].triangle_count(), 1);
}

#[test]
fn missing_or_short_buffers() {
    let (gltf, _) = triangle();
    let e = load("nobin", &gltf, None).unwrap_err();
    assert!(
        e.contains("nobin.gltf") && e.contains("cannot read buffer 0") && e.contains("tri.bin"),
        "{e}"
    );
    let e = error("shortbin", |_, bin| bin.truncate(20));
    assert!(e.contains("byteLength is 44 but only 20 bytes"), "{e}");
}

#[test]
fn accessors_out_of_range_mistyped_or_absurd() {
    let e = error("count", |g, _| g["accessors"][0]["count"] = json!(4));
    assert!(
        e.contains("meshes[0].primitives[0]") && e.contains("run past the end of buffer view 0"),
        "{e}"
    );
    let e = error("absurd", |g, _| {
        g["accessors"][0]["count"] = json!(4_000_000_000u64)
    });
    assert!(e.contains("4000000000 elements"), "{e}");
    let e = error("zero", |g, _| g["accessors"][0]["count"] = json!(0));
    assert!(e.contains("0 elements"), "{e}");
    let e = error("offset", |g, _| {
        g["bufferViews"][1]["byteOffset"] = json!(40)
    });
    assert!(e.contains("past the end of buffer 0"), "{e}");
    let e = error("type", |g, _| g["accessors"][0]["type"] = json!("VEC2"));
    assert!(
        e.contains("is VEC2 of FLOAT, expected VEC3 of FLOAT"),
        "{e}"
    );
    let e = error("stride", |g, _| {
        g["bufferViews"][0]["byteStride"] = json!(8)
    });
    assert!(
        e.contains("byteStride 8 is smaller than one element (12 bytes)"),
        "{e}"
    );
    let e = error("index", |g, bin| {
        bin[38] = 9;
        let _ = g;
    });
    assert!(
        e.contains("vertex index 9, but the primitive has 3 vertices"),
        "{e}"
    );
    let e = error("position", |g, _| {
        g["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7)
    });
    assert!(
        e.contains("accessor 7 is out of range (the file has 2 accessors)"),
        "{e}"
    );
    let e = error("sparse", |g, bin| {
        // One sparse substitute whose index (the first u16 of view 1, set to 5) is past the end.
        g["accessors"][0]["sparse"] = json!({"count": 1,
            "indices": {"bufferView": 1, "componentType": 5123},
            "values": {"bufferView": 0}});
        bin[36] = 5;
    });
    assert!(e.contains("sparse index 5 is out of range"), "{e}");
}

#[test]
fn graph_and_transform_problems() {
    let e = error("cycle", |g, _| {
        g["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    });
    assert!(
        e.contains("node 0 contains itself") && e.contains("cycle"),
        "{e}"
    );
    let e = error("matrix", |g, _| {
        g["nodes"][0]["matrix"] = json!([1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    });
    assert!(e.contains("nodes[0]") && e.contains("not affine"), "{e}");
    let e = error("quat", |g, _| {
        g["nodes"][0]["rotation"] = json!([0, 0, 0, 0])
    });
    assert!(e.contains("not a unit quaternion"), "{e}");
    let e = error("mode", |g, _| {
        g["meshes"][0]["primitives"][0]["mode"] = json!(9)
    });
    assert!(e.contains("mode"), "{e}");
}

#[test]
fn unsupported_and_old_files() {
    let e = error("draco", |g, _| {
        g["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
        g["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    });
    assert!(
        e.contains("requires the glTF extension KHR_draco_mesh_compression"),
        "{e}"
    );
    let e = error("v1", |g, _| g["asset"]["version"] = json!("1.0"));
    assert!(e.contains("glTF 1.0") && e.contains("2.0 only"), "{e}");
    let e = error("json", |g, _| *g = json!("not an object"));
    assert!(e.contains("asset.version"), "{e}");
}

#[test]
fn a_missing_texture_warns_and_keeps_the_base_colour() {
    let (mut gltf, bin) = triangle();
    gltf["materials"] = json!([{"pbrMetallicRoughness": {
        "baseColorFactor": [0.2, 0.4, 0.6, 1.0], "baseColorTexture": {"index": 0}}}]);
    gltf["textures"] = json!([{"source": 0}]);
    gltf["images"] = json!([{"uri": "missing.png"}]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = load("texture", &gltf, Some(&bin)).unwrap();
    assert!(
        s.notes
            .iter()
            .any(|n| n.contains("missing.png") && n.contains("using the base colour")),
        "{:?}",
        s.notes
    );
    assert_eq!(
        s.description.materials[0].texture,
        quadray::Texture::Constant(glam::Vec3::new(0.2, 0.4, 0.6))
    );
}

#[test]
fn garbage_never_panics() {
    let d = dir("garbage");
    // Truncations of a valid GLB at every length, and single-byte corruptions of its header.
    let (gltf, bin) = triangle();
    let mut json_bytes = serde_json::to_vec(&{
        let mut g = gltf.clone();
        g["buffers"][0] = json!({"byteLength": 44});
        g
    })
    .unwrap();
    json_bytes.resize(json_bytes.len().next_multiple_of(4), b' ');
    let mut glb = b"glTF".to_vec();
    let total = 12 + 8 + json_bytes.len() + 8 + bin.len();
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((json_bytes.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json_bytes);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    let path = d.join("t.glb");
    std::fs::write(&path, &glb).unwrap();
    load_any(&path).expect("the valid GLB loads");
    for len in 0..glb.len() {
        std::fs::write(&path, &glb[..len]).unwrap();
        if let Err(e) = load_any(&path) {
            assert_eq!(e.path, path);
        }
    }
    for at in 0..24 {
        let mut bad = glb.clone();
        bad[at] ^= 0xff;
        std::fs::write(&path, &bad).unwrap();
        let _ = load_any(&path);
    }
    // OBJ oddities.
    let obj = d.join("t.obj");
    for text in [
        "v 1 2\n",
        "f 1 2 3\n",
        "v 0 0 0\nf 1 1 1 1\n",
        "vt 0\n",
        "mtllib\n",
        "usemtl\n",
        "f\n",
    ] {
        std::fs::write(&obj, text).unwrap();
        if let Err(e) = load_any(&obj) {
            assert_eq!(e.path, obj, "{text:?}: {e}");
        }
    }
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    let e = load_any(&obj).unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Syntax(_)));
    assert!(
        e.to_string()
            .contains("t.obj:4:1: face index 4 is out of range"),
        "{e}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn unknown_file_types_are_refused() {
    let e = load_any(Path::new("model.ply")).unwrap_err().to_string();
    assert!(
        e.contains("model.ply") && e.contains(".toml, .obj, .gltf or .glb"),
        "{e}"
    );
}

/// Files that never end (`/dev/zero`) or are not files are refused by kind and size before they
/// are read, wherever a scene names them: as the scene, a mesh, a glTF buffer or a texture.
#[test]
fn devices_are_never_read() {
    if !Path::new("/dev/zero").exists() {
        eprintln!("skipped: no /dev/zero on this system");
        return;
    }
    let d = dir("devices");
    for name in ["zero.toml", "zero.obj", "zero.glb"] {
        std::os::unix::fs::symlink("/dev/zero", d.join(name)).unwrap();
        let e = load_any(&d.join(name)).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{name}: {e}");
    }
    let scene = d.join("s.toml");
    std::fs::write(
        &scene,
        "version = 1\n[camera]\nfrom = [0, -5, 1]\nto = [0, 0, 0]\n[[material]]\nname = \"m\"\n\
         [[mesh]]\npath = \"/dev/zero\"\nmaterial = \"m\"\n",
    )
    .unwrap();
    let e = load_any(&scene).unwrap_err().to_string();
    assert!(
        e.contains("not a regular file") || e.contains("only .obj"),
        "{e}"
    );
    let obj = d.join("m.obj");
    std::fs::write(&obj, "v 0 0 0\n").unwrap();
    std::fs::write(
        &scene,
        std::fs::read_to_string(&scene)
            .unwrap()
            .replace("/dev/zero", "zero.obj"),
    )
    .unwrap();
    let e = load_any(&scene).unwrap_err().to_string();
    assert!(e.contains("not a regular file"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();

    let (mut gltf, _) = triangle();
    gltf["buffers"][0]["uri"] = json!("file:///dev/zero");
    let e = load("devbuffer", &gltf, None).unwrap_err();
    assert!(e.contains("not a regular file"), "{e}");
    let (mut gltf, bin) = triangle();
    gltf["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    gltf["textures"] = json!([{"source": 0}]);
    gltf["images"] = json!([{"uri": "file:///dev/zero"}]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = load("devtexture", &gltf, Some(&bin)).unwrap();
    assert!(
        s.notes.iter().any(|n| n.contains("not a regular file")),
        "{:?}",
        s.notes
    );
}

/// Images the gltf crate would unwrap on (a bufferView without mimeType, no source at all) are
/// a warning with the base colour kept, never a panic.
#[test]
fn images_without_a_source_or_type_do_not_panic() {
    for (name, image) in [
        ("nomime", json!({"bufferView": 0})),
        ("nosource", json!({"name": "nothing"})),
    ] {
        let (mut gltf, bin) = triangle();
        gltf["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
        gltf["textures"] = json!([{"source": 0}]);
        gltf["images"] = json!([image]);
        gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
        match load(name, &gltf, Some(&bin)) {
            Ok(s) => assert!(
                s.notes
                    .iter()
                    .any(|n| n.contains("mimeType") || n.contains("neither")),
                "{name}: {:?}",
                s.notes
            ),
            Err(e) => assert!(e.contains("image"), "{name}: {e}"),
        }
    }
}

/// A face with more vertices than the documented limit is a located error (its fan of slivers
/// made the BVH build quadratic: 17 s for 100 000 vertices), read in time linear in the file.
#[test]
fn enormous_polygons_are_refused_by_line() {
    let d = dir("polygon");
    let n = quadray_loader::obj::MAX_FACE_VERTICES + 1;
    let mut text = String::from("# one huge face\n");
    for i in 0..n {
        let a = i as f64 / n as f64 * std::f64::consts::TAU;
        text += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    text += "f";
    for i in 1..=n {
        text += &format!(" {i}");
    }
    text += "\n";
    let path = d.join("poly.obj");
    std::fs::write(&path, text).unwrap();
    let e = load_any(&path).unwrap_err().to_string();
    assert!(e.contains(&format!("poly.obj:{}:1", n + 2)), "{e}");
    assert!(e.contains(&format!("a face with {n} vertices")), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

/// Files that load but hold nothing to render are errors that say so: OBJ files of comments,
/// binary junk or two-vertex faces, and a glTF mesh without primitives.
#[test]
fn files_with_nothing_to_render_say_so() {
    let d = dir("empty");
    for (name, bytes) in [
        ("comments.obj", b"# nothing\n# at all\n".to_vec()),
        ("junk.obj", (0..=255u8).cycle().take(4096).collect()),
        ("lines.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\nl 1 2\n".to_vec()),
        ("vertices.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n".to_vec()),
    ] {
        let path = d.join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = load_any(&path).unwrap_err().to_string();
        let said = e.contains("no faces") || e.contains("not text");
        assert!(e.contains(name) && said, "{name}: {e}");
    }
    std::fs::remove_dir_all(&d).unwrap();
    let (mut gltf, bin) = triangle();
    gltf["meshes"][0]["primitives"] = json!([]);
    let e = load("noprims", &gltf, Some(&bin)).unwrap_err();
    assert!(e.contains("primitive"), "{e}");
}

/// A camera whose aspect ratio no image can have (quadray renders 1/64 to 64) is an error naming
/// the camera, rather than a 640x1 image.
#[test]
fn camera_aspect_ratios_beyond_the_render_limits_are_refused() {
    for aspect in [1e9, 1e-9] {
        let (mut gltf, bin) = triangle();
        gltf["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": aspect}}]);
        gltf["nodes"] = json!([{"mesh": 0}, {"camera": 0, "translation": [0, 0, 5]}]);
        gltf["scenes"] = json!([{"nodes": [0, 1]}]);
        let e = load("aspect", &gltf, Some(&bin)).unwrap_err();
        assert!(
            e.contains("cameras[0]") && e.contains("aspect ratio"),
            "{e}"
        );
    }
}
