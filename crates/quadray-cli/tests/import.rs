//! The real `quadray` binary on OBJ and glTF files: `render` straight from them, `convert` to glTF
//! and back, and clean refusals.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn quadray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(args)
        .output()
        .expect("the quadray binary runs")
}

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
        .to_string_lossy()
        .into_owned()
}

/// A file of `../shared/assets`. Tests that call it are ignored where the folder is absent (see
/// `build.rs`); where they run, a missing file is a failure.
fn shared_asset(path: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/assets")
        .join(path);
    assert!(
        p.is_file(),
        "{} not found (../shared is absent)",
        p.display()
    );
    p
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Decoded RGB bytes of a PNG.
fn png(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path).expect("a PNG was written").into_rgb8();
    (img.width(), img.height(), img.into_raw())
}

#[test]
fn renders_obj_gltf_and_glb_files_directly() {
    let dir = tempfile::tempdir().unwrap();
    // The project's own OBJ + MTL (no camera, no lights: both assumed, and said).
    let out = dir.path().join("pedestal.png");
    let o = quadray(&[
        "render",
        &repo("scenes/obj-mtl/pedestal.obj"),
        "-o",
        out.to_str().unwrap(),
        "--res",
        "64x48",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("note: no camera in the file"), "{e}");
    assert!(e.contains("note: no lights in the file"), "{e}");
    let (w, h, rgb) = png(&out);
    assert_eq!((w, h), (64, 48));
    // The framing camera puts the model in the middle of the frame: the centre pixel is not the
    // background (0.05 grey, sRGB code 63).
    let centre = ((h / 2 * w + w / 2) * 3) as usize;
    assert_ne!(&rgb[centre..centre + 3], &[63, 63, 63]);

    // The project's own glTF with the extension, and a GLB written by convert.
    let out = dir.path().join("quadrics.png");
    let o = quadray(&[
        "render",
        &repo("scenes/gltf-quadrics.gltf"),
        "-o",
        out.to_str().unwrap(),
        "--res",
        "64x40",
        "--spp",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("64x40, 1 spp: 2560 camera"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn convert_writes_gltf_and_glb_that_render_like_the_native_scene() {
    let dir = tempfile::tempdir().unwrap();
    let native = dir.path().join("native.png");
    let o = quadray(&[
        "render",
        &repo("scenes/defense.toml"),
        "-o",
        native.to_str().unwrap(),
        "--res",
        "96x54",
        "--spp",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Converts a bundled scene to `out`, successfully; its summary line.
    let convert = |scene: &str, out: &std::path::Path| {
        let o = quadray(&["convert", &repo(scene), "-o", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    for name in ["defense.gltf", "defense.glb"] {
        let converted = dir.path().join(name);
        let summary = convert("scenes/defense.toml", &converted);
        assert!(
            summary.contains("4 quadrics, 2 spheres, 1 plane"),
            "{summary}"
        );
        if name.ends_with(".gltf") {
            assert!(dir.path().join("defense.bin").is_file());
        }
        // Instanced shapes are counted as placed, not as the world's none.
        let columns = dir.path().join(name.replace("defense", "columns"));
        let summary = convert("scenes/columns.toml", &columns);
        assert!(summary.contains(" placed by "), "{summary}");
        let out = dir.path().join(format!("{name}.png"));
        let o = quadray(&[
            "render",
            converted.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--res",
            "96x54",
            "--spp",
            "1",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        // Same geometry, materials, lights and background: the images agree but for pixels where
        // glTF's f32 camera angle moves a silhouette by a hair.
        let (a, b) = (png(&native).2, png(&out).2);
        let differing = a
            .chunks(3)
            .zip(b.chunks(3))
            .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 2))
            .count();
        assert!(
            differing <= 96 * 54 / 200,
            "{name}: {differing} pixels differ"
        );
    }
    // A missing output folder is said plainly, before the load, as `render` says it (it was an
    // error naming the hidden temporary file).
    let missing = dir.path().join("nodir").join("a.gltf");
    let o = quadray(&[
        "convert",
        &repo("scenes/defense.toml"),
        "-o",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("output folder") && !stderr(&o).contains("quadray-tmp"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn refusals_exit_nonzero_and_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let o = quadray(&[
        "convert",
        &repo("scenes/defense.toml"),
        "-o",
        dir.path().join("x.obj").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("must end in .gltf or .glb"),
        "{}",
        stderr(&o)
    );
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let o = quadray(&[
        "render",
        bad.to_str().unwrap(),
        "-o",
        dir.path().join("o.png").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("bad.obj:3:1: face index 3 is out of range"),
        "{e}"
    );
    assert!(!e.contains("panicked"), "{e}");
    // Choosing a camera or a glTF scene that the file does not have.
    let gltf = repo("scenes/gltf-quadrics.gltf");
    let out = dir.path().join("c.png");
    let o = quadray(&[
        "render",
        &gltf,
        "-o",
        out.to_str().unwrap(),
        "--camera",
        "5",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("no camera #5 (the file has 1: #0 \"camera\")"),
        "{}",
        stderr(&o)
    );
    let o = quadray(&[
        "render",
        &gltf,
        "-o",
        out.to_str().unwrap(),
        "--gltf-scene",
        "3",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("scene #3 does not exist (the file has 1)"),
        "{}",
        stderr(&o)
    );
    let o = quadray(&[
        "render",
        &gltf,
        "-o",
        out.to_str().unwrap(),
        "--res",
        "32x20",
        "--camera",
        "camera",
        "--gltf-scene",
        "0",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Neither means anything to a native scene or an OBJ file: refused, not dropped.
    for (scene_file, flag) in [
        (repo("scenes/defense.toml"), "--camera"),
        (repo("scenes/obj-mtl/pedestal.obj"), "--gltf-scene"),
    ] {
        let o = quadray(&[
            "render",
            &scene_file,
            "-o",
            out.to_str().unwrap(),
            flag,
            "0",
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("{flag} chooses a glTF file's"))
                && stderr(&o).contains("is not a .gltf or .glb file"),
            "{}",
            stderr(&o)
        );
    }
}

/// A real GLB with its own camera renders through it; only the light is assumed.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn a_real_glb_renders_through_its_own_camera() {
    let dir = tempfile::tempdir().unwrap();
    let duck = shared_asset("gltf/khronos/Duck/glTF-Binary/Duck.glb");
    let out = dir.path().join("duck.png");
    let o = quadray(&[
        "render",
        duck.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--res",
        "48x48",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The duck has a camera: only the light is assumed.
    assert!(!stderr(&o).contains("no camera"), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no lights in the file"),
        "{}",
        stderr(&o)
    );
}

/// A real Draco-compressed file is refused by the extension's name, and writes nothing.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn a_real_draco_file_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let draco = shared_asset("gltf/draco/pmndrs_bunny.glb");
    let o = quadray(&[
        "render",
        draco.to_str().unwrap(),
        "-o",
        dir.path().join("d.png").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("KHR_draco_mesh_compression"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.path().join("d.png").exists());
}

/// A model without a camera is framed to fill the image up to a 5% margin: for a cube the bounds
/// are the model, so its silhouette reaches the margin on one axis and stays inside on the other.
#[test]
fn a_model_without_a_camera_fills_the_frame() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    let mut obj = String::new();
    for i in 0..8 {
        let bit = |b: u32| if i & b == 0 { -1.0 } else { 1.0 };
        obj += &format!("v {} {} {}\n", bit(1), bit(2) * 0.5, bit(4) * 2.0);
    }
    // Faces with outward winding, 1-based.
    for f in [
        "1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6",
    ] {
        obj += &format!("f {f}\n");
    }
    std::fs::write(&cube, obj).unwrap();
    for (w, h) in [(160u32, 120u32), (200, 80), (80, 160)] {
        let out = dir.path().join("cube.png");
        let res = format!("{w}x{h}");
        let cube = cube.to_str().unwrap();
        // --res is known while loading: the framing fits that image.
        let o = quadray(&[
            "render",
            cube,
            "-o",
            out.to_str().unwrap(),
            "--res",
            &res,
            "-q",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let (_, _, pixels) = png(&out);
        let background = [pixels[0], pixels[1], pixels[2]];
        let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
        for y in 0..h {
            for x in 0..w {
                let i = 3 * (y * w + x) as usize;
                if pixels[i..i + 3] != background {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
                }
            }
        }
        let margins = [
            x0 as f64 / w as f64,
            y0 as f64 / h as f64,
            1.0 - x1 as f64 / w as f64,
            1.0 - y1 as f64 / h as f64,
        ];
        println!("{res}: margins {margins:?}");
        assert!(margins.iter().all(|m| *m > 0.03), "{res}: {margins:?}");
        assert!(margins.iter().any(|m| *m < 0.08), "{res}: {margins:?}");
        // Centred: opposite margins equal to a pixel or two.
        assert!(
            (margins[0] - margins[2]).abs() <= 2.5 / w as f64,
            "{res}: {margins:?}"
        );
        assert!(
            (margins[1] - margins[3]).abs() <= 2.5 / h as f64,
            "{res}: {margins:?}"
        );
    }
}

/// A glTF file `name` in `dir` of one triangle mesh (mesh 0), with `nodes` and `scenes`.
fn triangle_gltf(
    dir: &Path,
    name: &str,
    nodes: serde_json::Value,
    scenes: serde_json::Value,
) -> PathBuf {
    use base64::Engine;
    let triangle: Vec<u8> = [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&triangle)
    );
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": scenes,
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": triangle.len(), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": triangle.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}]
    });
    let path = dir.join(name);
    std::fs::write(&path, doc.to_string()).unwrap();
    path
}

/// The deepest glTF node chain the loader accepts renders through the binary, and a chain one
/// node deeper is refused with the node at fault, writing nothing.
#[test]
fn the_deepest_gltf_chain_renders_and_a_deeper_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let chain = |depth: usize| {
        let nodes: Vec<serde_json::Value> = (0..depth)
            .map(|i| match i {
                _ if i == depth - 1 => serde_json::json!({"mesh": 0}),
                _ => serde_json::json!({"children": [i + 1], "translation": [0.001, 0.0, 0.0]}),
            })
            .collect();
        let name = format!("chain-{depth}.gltf");
        triangle_gltf(
            dir.path(),
            &name,
            serde_json::json!(nodes),
            serde_json::json!([{"nodes": [0]}]),
        )
    };
    let deepest = quadray_loader::gltf::MAX_DEPTH;
    let (deep, deeper) = (chain(deepest), chain(deepest + 1));
    let (out, refused) = (dir.path().join("deep.png"), dir.path().join("deeper.png"));
    let render = |scene: &Path, out: &Path| {
        quadray(&[
            "render",
            scene.to_str().unwrap(),
            "--res",
            "8x8",
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let o = render(&deep, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(png(&out).0, 8);
    let o = render(&deeper, &refused);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!(
            "`nodes[{deepest}]`: the node hierarchy is deeper than"
        )),
        "{}",
        stderr(&o)
    );
    assert!(!refused.exists());
}

/// `check` checks the glTF scene and camera `render` would use: a file whose second scene places
/// its triangle past the coordinate limit passes as it is (its default scene is the first) and
/// fails with `--gltf-scene 1`, naming the node; a camera that is not there is refused by name.
#[test]
fn check_takes_the_gltf_scene_and_camera_render_takes() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = serde_json::json!([
        {"mesh": 0},
        {"mesh": 0, "translation": [2e30, 0.0, 0.0]}
    ]);
    let scenes = serde_json::json!([{"nodes": [0]}, {"nodes": [1]}]);
    let file = triangle_gltf(dir.path(), "two.gltf", nodes, scenes);
    let file = file.to_str().unwrap();
    let o = quadray(&["check", file]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = quadray(&["check", file, "--gltf-scene", "1"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("`nodes[1]`"), "{}", stderr(&o));
    let o = quadray(&["check", file, "--camera", "5"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("camera"), "{}", stderr(&o));
}
