//! Unit tests of the native format: values, errors and their locations.

use super::*;

const MINIMAL: &str = r#"
version = 1
[camera]
from = [0, -5, 1]
to = [0, 0, 0]
[[material]]
name = "red"
color = [0.8, 0.1, 0.1]
"#;

fn parse(extra: &str) -> Result<LoadedScene, LoadError> {
    parse_scene(&format!("{MINIMAL}{extra}"), Path::new("t.toml"))
}

fn error(extra: &str) -> String {
    parse(extra).unwrap_err().to_string()
}

#[test]
fn loads_every_kind_of_item() {
    let s = parse(
        r#"
[render]
resolution = [320, 200]
spp = 4
background = [0.1, 0.2, 0.3]
[[material]]
name = "ramp"
texture = "ramp"
reflectivity = 0.5
[[sphere]]
center = [0, 0, 1]
radius = 1
material = "red"
[[plane]]
point = [0, 0, 0]
normal = [0, 0, 2]
material = "red"
[[quadric]]
kind = "cone"
clip = { min = [-1, -1, -1], max = [1, 1, 0.5] }
transform = { translate = [1, 2, 3], rotate = [0, 0, 45], scale = 2 }
material = "ramp"
[[quadric]]
kind = "general"
coefficients = [1, 1, -1, 0, 0, 0, 0, 0, 0, -1]
clip = 1.5
material = "ramp"
[[mesh]]
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
indices = [[0, 1, 2]]
material = "red"
[[light]]
type = "point"
position = [1, 2, 3]
intensity = 10
[[light]]
type = "directional"
direction = [0, 0, -1]
"#,
    )
    .unwrap();
    let g = &s.description.geometry;
    assert_eq!(
        (
            g.spheres.len(),
            g.planes.len(),
            g.quadrics.len(),
            g.meshes.len()
        ),
        (1, 1, 2, 1)
    );
    assert_eq!(
        s.settings,
        SceneSettings {
            width: 320,
            height: 200,
            spp: 4,
            max_depth: 8,
            adaptive: None,
            antialias: None,
            compact_meshes: false,
        }
    );
    assert_eq!(g.planes[0].normal, DVec3::Z);
    assert_eq!(s.description.lights.len(), 2);
    assert_eq!(s.material_names, ["red", "ramp"]);
    quadray::Scene::new(s.description).unwrap();
}

#[test]
fn errors_name_file_line_column_and_key() {
    let e = error("[[sphere]]\ncenter = [0, 0, 0]\nradius = -1\nmaterial = \"red\"\n");
    assert!(
        e.starts_with("t.toml:11:10: `sphere[0].radius`: must be positive"),
        "{e}"
    );
    let e = error("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"blue\"\n");
    assert!(
        e.contains(":12:12: `sphere[0].material`: unknown material \"blue\""),
        "{e}"
    );
    // A name of 100 000 bytes is cut in the message (the source line under it was already).
    let long = "x".repeat(100_000);
    let e = error(&format!(
        "[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"{long}\"\n"
    ));
    assert!(e.contains("xxx… (100000 bytes)\""), "{}", &e[..300]);
    assert!(e.len() < 2000, "{} bytes", e.len());
}

#[test]
fn syntax_and_unknown_keys_are_located() {
    let e = error("[[sphere]]\ncentre = [0, 0, 0]\n");
    assert!(
        e.starts_with("t.toml:10:1:") && e.contains("unknown field `centre`"),
        "{e}"
    );
    let e = parse_scene("version = 1\n[camera\n", Path::new("bad.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("bad.toml:2:"), "{e}");
}

#[test]
fn rejects_nan_degenerate_and_absurd_values() {
    assert!(
        error("[[sphere]]\ncenter = [nan, 0, 0]\nradius = 1\nmaterial = \"red\"\n")
            .contains("finite")
    );
    let e = error(
        "[[quadric]]\nkind = \"general\"\ncoefficients = [0,0,0,0,0,0,0,0,0,0]\nclip = 1\nmaterial = \"red\"\n",
    );
    assert!(
        e.contains("degenerate quadric: all coefficients are zero"),
        "{e}"
    );
    let e = error(
        "[[quadric]]\nkind = \"general\"\ncoefficients = [1,1,1,0,0,0,0,0,0,1]\nclip = 1\nmaterial = \"red\"\n",
    );
    assert!(e.contains("empty"), "{e}");
    let e = error(
        "[[quadric]]\nkind = \"ellipsoid\"\nclip = { min = [0, 0, 0], max = [1, 1, 0] }\nmaterial = \"red\"\n",
    );
    assert!(
        e.contains(":11:8:") && e.contains("clip box is empty"),
        "{e}"
    );
    assert!(error("[render]\nresolution = [100000, 10]\n").contains("render.resolution"));
    assert!(error("[render]\nspp = 0\n").contains("render.spp"));
    let e = error(
        "[[mesh]]\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\nindices = [[0,1,3]]\nmaterial = \"red\"\n",
    );
    assert!(
        e.contains("mesh[0].indices[0]") && e.contains("out of range"),
        "{e}"
    );
    assert!(
        error("[[quadric]]\nkind = \"torus\"\nclip = 1\nmaterial = \"red\"\n")
            .contains("unknown kind \"torus\"")
    );
}

#[test]
fn point_lights_can_drop_their_falloff() {
    let s = parse(
        "[[light]]\ntype = \"point\"\nposition = [0, 0, 5]\nfalloff = false\nintensity = 0.5\n",
    )
    .unwrap();
    assert_eq!(
        s.description.lights[0],
        Light::PointNoFalloff {
            position: DVec3::new(0.0, 0.0, 5.0),
            irradiance: Vec3::splat(0.5),
        }
    );
    let s = parse("[[light]]\ntype = \"point\"\nposition = [0, 0, 5]\nfalloff = true\n").unwrap();
    assert!(matches!(s.description.lights[0], Light::Point { .. }));
    let e = error("[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\nfalloff = false\n");
    assert!(e.contains("a directional light has no falloff"), "{e}");
}

#[test]
fn camera_variants() {
    let orbit = "version = 1\n[camera]\norbit = { yaw = 30, pitch = 20, distance = 8 }\n";
    let s = parse_scene(orbit, Path::new("o.toml")).unwrap();
    assert!(((s.description.camera.from).length() - 8.0).abs() < 1e-12);
    let ortho = "version = 1\n[camera]\nprojection = \"orthographic\"\nfrom = [0,0,5]\nto = [0,0,0]\nup = [0,1,0]\nheight = 3\n";
    let s = parse_scene(ortho, Path::new("o.toml")).unwrap();
    assert_eq!(
        s.description.camera.projection,
        Projection::Orthographic { height: 3.0 }
    );
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    // A key the projection does not use is noted, not silently dropped.
    let noted = |text: &str| parse_scene(text, Path::new("o.toml")).unwrap().notes;
    let ortho_vfov = ortho.replace("height = 3\n", "height = 3\nvfov = 30\n");
    assert!(
        noted(&ortho_vfov)
            .iter()
            .any(|n| n.contains("camera.vfov is not used"))
    );
    let perspective_height = "version = 1\n[camera]\nfrom = [0,-5,1]\nto = [0,0,0]\nheight = 3\n";
    assert!(
        noted(perspective_height)
            .iter()
            .any(|n| n.contains("camera.height is not used"))
    );
    assert!(
        noted(&format!("{orbit}height = 2\n"))
            .iter()
            .any(|n| n.contains("height"))
    );
    let e = parse_scene(
        "version = 2\n[camera]\nfrom=[0,0,1]\nto=[0,0,0]\n",
        Path::new("v.toml"),
    )
    .unwrap_err();
    assert!(e.to_string().contains("version"));
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("quadray-native-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const TRIANGLE_OBJ: &str = "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl blue\nf 1 2 3\n";

#[test]
fn mesh_files_resolve_against_the_scene_and_take_transforms_and_overrides() {
    let dir = temp_dir("meshfile");
    std::fs::create_dir_all(dir.join("models")).unwrap();
    std::fs::write(dir.join("models/tri.obj"), TRIANGLE_OBJ).unwrap();
    std::fs::write(dir.join("models/tri.mtl"), "newmtl blue\nKd 0 0 1\n").unwrap();
    let text = format!(
        "{MINIMAL}[[mesh]]\npath = \"models\\\\tri.obj\"\ntransform = {{ translate = [0, 0, 5] }}\n\
             [[mesh]]\npath = \"models/tri.obj\"\nup = \"z\"\nmaterial = \"red\"\n"
    );
    let s = parse_scene(&text, &dir.join("scene.toml")).unwrap();
    let g = &s.description.geometry;
    assert_eq!(g.meshes.len(), 2);
    // y-up file rotated to z-up, then moved up by 5: (0, 1, 0) lands at (0, 0, 6).
    assert!(g.meshes[0].positions().contains(&Vec3::new(0.0, 0.0, 6.0)));
    assert_eq!(s.material_names, ["red", "tri.obj:blue"]);
    assert_eq!(g.meshes[0].material(), 1);
    assert_eq!(
        s.description.materials[1].texture,
        Texture::Constant(Vec3::Z)
    );
    // The override takes the scene's material, and `up = "z"` keeps coordinates.
    assert_eq!(g.meshes[1].material(), 0);
    assert!(g.meshes[1].positions().contains(&Vec3::new(0.0, 1.0, 0.0)));
    quadray::Scene::new(s.description).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn includes_bring_lights_and_camera_and_errors_name_both_files() {
    let dir = temp_dir("include");
    let inner = parse_scene(
            "version = 1\n[camera]\nfrom = [0, -4, 1]\nto = [0, 0, 0]\n[render]\nresolution = [400, 200]\n\
             [[material]]\nname = \"m\"\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n\
             [[light]]\ntype = \"point\"\nposition = [0, 0, 3]\n",
            Path::new("inner.toml"),
        )
        .unwrap();
    crate::export::export_gltf(&inner, &dir.join("part.gltf")).unwrap();
    let text = "version = 1\n[[material]]\nname = \"red\"\n\
                    [[include]]\npath = \"part.gltf\"\ntransform = { translate = [10, 0, 0] }\n\
                    [[sphere]]\ncenter = [0, 0, 0]\nradius = 0.5\nmaterial = \"red\"\n";
    let s = parse_scene(text, &dir.join("scene.toml")).unwrap();
    let g = &s.description.geometry;
    assert_eq!(g.spheres.len(), 2);
    assert!((g.spheres[1].center - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
    assert_eq!(s.description.lights.len(), 1);
    // No [camera]: the included one, moved with the include, and its aspect.
    assert!((s.description.camera.from - DVec3::new(10.0, -4.0, 1.0)).length() < 1e-9);
    assert_eq!((s.settings.width, s.settings.height), (640, 320));
    assert!(
        s.notes.iter().any(|n| n.contains("included file's camera")),
        "{:?}",
        s.notes
    );
    let no_lights = text.replace("[[sphere]]", "lights = false\n[[sphere]]");
    let s = parse_scene(&no_lights, &dir.join("scene.toml")).unwrap();
    assert!(s.description.lights.is_empty());
    // A missing file: the scene, the line of `path`, and the file that is missing.
    let e = parse_scene(
        &text.replace("part.gltf", "gone.glb"),
        &dir.join("scene.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("scene.toml:5:8: `include[0].path`") && e.contains("gone.glb"),
        "{e}"
    );
    let e = parse_scene(
        "version = 1\n[[include]]\npath = \"part.gltf\"\ncamera = \"nope\"\n",
        &dir.join("scene.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("include[0].camera") && e.contains("no camera \"nope\""),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn spot_lights_and_mesh_form_errors() {
    let s = parse(
            "[[light]]\ntype = \"spot\"\nposition = [0, 0, 5]\ndirection = [0, 0, -1]\ninner_angle = 10\nouter_angle = 20\n",
        )
        .unwrap();
    let Light::Spot {
        cos_inner,
        cos_outer,
        ..
    } = s.description.lights[0]
    else {
        panic!("not a spot light")
    };
    assert!((cos_inner - 10f64.to_radians().cos()).abs() < 1e-15);
    assert!((cos_outer - 20f64.to_radians().cos()).abs() < 1e-15);
    assert!(
        error("[[light]]\ntype = \"spot\"\nposition = [0, 0, 5]\n").contains("needs `direction`")
    );
    assert!(error("[[light]]\ntype = \"spot\"\nposition = [0,0,5]\ndirection = [0,0,-1]\ninner_angle = 30\nouter_angle = 20\n").contains("must not exceed"));
    assert!(
        error("[[light]]\ntype = \"point\"\nposition = [0,0,5]\nouter_angle = 20\n")
            .contains("only spot lights")
    );
    let e = error("[[mesh]]\npath = \"a.obj\"\nvertices = [[0,0,0]]\n");
    assert!(e.contains("either read from `path` or given inline"), "{e}");
    assert!(
        error("[[mesh]]\nvertices = [[0,0,0]]\nindices = [[0,0,0]]\n").contains("needs `material`")
    );
    let e = error("[[mesh]]\npath = \"model.ply\"\n");
    assert!(
        e.contains("`mesh[0].path`") && e.contains("only .obj, .gltf and .glb"),
        "{e}"
    );
}

#[test]
fn orbit_pitch_beyond_the_poles_is_refused() {
    let text = "version = 1\n[camera]\norbit = { yaw = 10, pitch = 120, distance = 5 }\n";
    let e = parse_scene(text, Path::new("o.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("o.toml:3:") && e.contains("within [-90, 90]"),
        "{e}"
    );
    let ok = "version = 1\n[camera]\norbit = { yaw = 10, pitch = -90, distance = 5 }\n";
    assert!(parse_scene(ok, Path::new("o.toml")).is_ok());
}

/// Lists of the wrong length are errors with their location: serde alone read `[f64; 3]` from a
/// longer array and dropped the rest.
#[test]
fn vectors_and_matrices_of_the_wrong_length_are_refused() {
    for (body, line) in [
        (
            "version = 1\n[camera]\nfrom = [0, -5, 1]\nto = [0, 0, 0, 4]\n",
            4,
        ),
        ("version = 1\n[camera]\nfrom = [0, -5]\nto = [0, 0, 0]\n", 3),
        ("version = 1\n[render]\nresolution = [64, 48, 3]\n", 3),
    ] {
        let e = parse_scene(body, Path::new("v.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&format!("v.toml:{line}:")), "{e}");
        assert!(e.contains("exactly"), "{e}");
    }
    let e = error(
        "[[sphere]]\nname = \"s\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"red\"\n\
         [[instance]]\nof = \"s\"\ntransform = { matrix = [[1, 0, 0, 0, 9], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }\n",
    );
    assert!(e.contains("exactly 4 values, got 5"), "{e}");
}

#[test]
fn output_is_resolved_beside_the_scene_and_must_be_an_image() {
    let text = format!("{MINIMAL}[output]\nfile = \"renders/a.exr\"\n");
    let s = parse_scene(&text, Path::new("scenes/t.toml")).unwrap();
    assert_eq!(s.output, Some(PathBuf::from("scenes/renders/a.exr")));
    assert_eq!(parse("").unwrap().output, None);
    let e = error("[output]\nfile = \"a.jpg\"\n");
    assert!(e.contains("t.toml:10:") && e.contains("output.file"), "{e}");
    assert!(error("[output]\nfile = \"a.png\"\nformat = 1\n").contains("format"));
}

#[test]
fn render_tables_choose_adaptive_sampling() {
    let s = parse("[render]\ntarget_error = 0.02\nmax_spp = 256\ntime_limit = 2.5\n").unwrap();
    let a = s.settings.adaptive.expect("adaptive");
    assert_eq!(a.target_error, 0.02);
    assert_eq!(
        (a.min_spp, a.max_spp),
        (quadray::adaptive::DEFAULT_MIN_SPP, 256)
    );
    assert_eq!(a.time_limit, Some(std::time::Duration::from_millis(2500)));
    assert_eq!(s.settings.render_settings().adaptive, Some(a));
    // A time limit alone refines every pixel until it runs out.
    let s = parse("[render]\ntime_limit = 1\nmax_spp = 8\n").unwrap();
    let a = s.settings.adaptive.unwrap();
    assert_eq!((a.target_error, a.min_spp, a.max_spp), (0.0, 8, 8));
    // A maximum that is not a power of two: the first round is the largest power of two within it.
    let s = parse("[render]\ntarget_error = 0.01\nmax_spp = 6\n").unwrap();
    let a = s.settings.adaptive.unwrap();
    assert_eq!((a.min_spp, a.max_spp), (4, 6));
    assert_eq!(
        parse("[render]\nspp = 4\n").unwrap().settings.adaptive,
        None
    );

    for (extra, key, says) in [
        (
            "spp = 4\ntarget_error = 0.01",
            "render.spp",
            "excludes adaptive",
        ),
        ("max_spp = 64", "render.max_spp", "adaptive sampling only"),
        ("target_error = -0.1", "render.target_error", "positive"),
        ("target_error = nan", "render.target_error", "finite"),
        (
            "target_error = 0.1\nmax_spp = 0",
            "render.max_spp",
            "between 1 and",
        ),
        (
            "target_error = 0.1\nmin_spp = 1",
            "render.min_spp",
            "power of two",
        ),
        (
            "target_error = 0.1\nmin_spp = 0",
            "render.min_spp",
            "power of two from 2 to the maximum (1024), got 0",
        ),
        (
            "target_error = 0.1\nmin_spp = -4",
            "render.min_spp",
            "power of two from 2",
        ),
        (
            "target_error = 0.1\nmin_spp = 24",
            "render.min_spp",
            "power of two",
        ),
        (
            "target_error = 0.1\nmin_spp = 64\nmax_spp = 32",
            "render.min_spp",
            "power of two",
        ),
        ("time_limit = 0", "render.time_limit", "positive"),
    ] {
        let e = error(&format!("[render]\n{extra}\n"));
        assert!(e.contains(key) && e.contains(says), "{extra}: {e}");
    }
}

#[test]
fn render_tables_choose_antialiasing_by_contrast() {
    let s = parse("[render]\nspp = 1\nantialias_threshold = 0.1\nantialias_spp = 32\n").unwrap();
    let aa = s.settings.antialias.expect("anti-aliased");
    assert_eq!((aa.threshold, aa.spp, s.settings.spp), (0.1, Some(32), 1));
    assert_eq!(s.settings.render_settings().antialias, Some(aa));
    // The count's default: 16, or four times spp from 16 on (left to the render's final spp).
    let default_of = |spp: u32| {
        let s = parse(&format!("[render]\nspp = {spp}\nantialias_threshold = 0\n")).unwrap();
        let aa = s.settings.antialias.unwrap();
        assert_eq!(aa.spp, None);
        aa.samples(s.settings.spp)
    };
    assert_eq!((default_of(1), default_of(4), default_of(16)), (16, 16, 64));
    assert_eq!(
        parse("[render]\nspp = 4\n").unwrap().settings.antialias,
        None
    );

    for (extra, key, says) in [
        (
            "antialias_spp = 16",
            "render.antialias_spp",
            "anti-aliasing by contrast only",
        ),
        (
            "antialias_threshold = 0.1\ntarget_error = 0.01",
            "render.antialias_threshold",
            "excludes adaptive",
        ),
        (
            "antialias_threshold = 1.5",
            "render.antialias_threshold",
            "in [0, 1]",
        ),
        (
            "antialias_threshold = -0.1",
            "render.antialias_threshold",
            "in [0, 1]",
        ),
        (
            "antialias_threshold = nan",
            "render.antialias_threshold",
            "finite",
        ),
        (
            "spp = 8\nantialias_threshold = 0.1\nantialias_spp = 8",
            "render.antialias_spp",
            "more samples than the render's 8",
        ),
        (
            "antialias_threshold = 0.1\nantialias_spp = -3",
            "render.antialias_spp",
            "between 1 and 65536, got -3",
        ),
    ] {
        let e = error(&format!("[render]\n{extra}\n"));
        assert!(e.contains(key) && e.contains(says), "{extra}: {e}");
    }
}

#[test]
fn materials_take_tints_and_emission() {
    let s = parse(
        "[[material]]\nname = \"gold\"\ncolor = [1, 0.8, 0.3]\nspecular = 1\nspecular_tint = 1\n\
         reflection_tint = 0.5\nemission = [2, 1, 0]\n",
    )
    .unwrap();
    let gold = &s.description.materials[1];
    assert_eq!((gold.specular_tint, gold.reflection_tint), (1.0, 0.5));
    assert_eq!(
        gold.emission,
        Some(quadray::Texture::Constant(glam::Vec3::new(2.0, 1.0, 0.0)))
    );
    assert_eq!(s.description.materials[0].emission, None);
    let e = error("[[material]]\nname = \"x\"\nspecular_tint = 2\n");
    assert!(e.contains("specular_tint") && e.contains("[0, 1]"), "{e}");
    let e = error("[[material]]\nname = \"x\"\nemission = [1, -1, 0]\n");
    assert!(e.contains("emission") && e.contains("non-negative"), "{e}");
}

#[test]
fn render_sets_an_environment_for_reflections() {
    let s =
        parse("[render]\nbackground = [0.1, 0.1, 0.1]\nenvironment = [0.5, 0.4, 0.3]\n").unwrap();
    assert_eq!(
        s.description.environment,
        Some(glam::Vec3::new(0.5, 0.4, 0.3))
    );
    assert_eq!(parse("").unwrap().description.environment, None);
    let e = error("[render]\nenvironment = [0.5, -1, 0]\n");
    assert!(e.contains("render.environment"), "{e}");
}
