//! The scene graph in scene files end to end: groups and instances render exactly like the same
//! scene written flat, and a hostile graph (a cycle, a bad matrix, an unknown name, too deep, too
//! far) is a clear error. glTF instancing is in `instancing_gltf.rs`.

use quadray::Scene;
use quadray_tests::{display_difference, render_file, repo_root};
use std::path::Path;

/// scenes/columns.toml (a template column, a row of three instances of it, the row placed twice,
/// once by a quaternion and with a material override, and an orb placed by a matrix) renders to
/// the pixels of tests/scenes/columns-flat.toml, where every transform was composed by hand.
/// Tolerance: the regression suite's rule (0.1% of pixels over 2/255), for targets where the
/// instance's two-step transform of a ray rounds differently from the composed one; here they
/// agree exactly.
#[test]
fn instanced_columns_render_like_the_flat_scene() {
    let root = repo_root();
    let (instanced, stats) = render_file(&root.join("scenes/columns.toml"));
    let (flat, flat_stats) = render_file(&root.join("tests/scenes/columns-flat.toml"));
    let (share, largest) = display_difference(&instanced, &flat);
    assert!(
        share <= 0.001,
        "{share} of pixels differ (largest {largest}/255)"
    );
    // Stored once: the column's 3 shapes and the orb, against 21 flat.
    assert_eq!(stats.primitives_stored, 4);
    assert_eq!(flat_stats.primitives_stored, 21);
    assert_eq!(stats.prototypes, 3);
    // Placements: 2 rows + 6 columns + 3 orbs.
    assert_eq!(stats.placements, 11);
}

fn load_text(text: &str) -> Result<quadray_loader::LoadedScene, String> {
    quadray_loader::parse_scene(text, Path::new("graph.toml")).map_err(|e| e.to_string())
}

const HEADER: &str = r#"
version = 1
[camera]
from = [0, -5, 1]
to = [0, 0, 0]
[[material]]
name = "m"
"#;

fn error(body: &str) -> String {
    let e = load_text(&format!("{HEADER}{body}")).expect_err("an error");
    assert!(e.contains("graph.toml"), "names the file: {e}");
    e
}

#[test]
fn cycles_unknown_names_and_bad_matrices_are_located_errors() {
    // a -> b -> a.
    let e = error(
        r#"
[[group]]
name = "a"
  [[group.instance]]
  of = "b"
[[group]]
name = "b"
  [[group.instance]]
  of = "a"
"#,
    );
    assert!(
        e.contains("cycle") && e.contains("\"a\" -> \"b\" -> \"a\""),
        "{e}"
    );
    assert!(e.starts_with("graph.toml:16:"), "{e}");
    // A group placing itself.
    let e = error("[[group]]\nname = \"s\"\n  [[group.instance]]\n  of = \"s\"\n");
    assert!(e.contains("\"s\" -> \"s\""), "{e}");
    let e = error("[[instance]]\nof = \"nowhere\"\n");
    assert!(e.contains("no group or named shape \"nowhere\""), "{e}");
    assert!(e.contains("`instance[0].of`"), "{e}");
    assert!(e.starts_with("graph.toml:9:"), "{e}");
    let sphere = "[[sphere]]\nname = \"s\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n";
    for (matrix, expected) in [
        (
            "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]",
            "singular",
        ),
        (
            "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0.5, 1]]",
            "affine",
        ),
        (
            "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, nan], [0, 0, 0, 1]]",
            "finite",
        ),
    ] {
        let e = error(&format!(
            "{sphere}[[instance]]\nof = \"s\"\ntransform = {{ matrix = {matrix} }}\n"
        ));
        assert!(
            e.contains(expected) && e.contains("instance[0].transform.matrix"),
            "{e}"
        );
        assert!(e.starts_with("graph.toml:15:"), "{e}");
    }
    let e = error(&format!(
        "{sphere}[[instance]]\nof = \"s\"\ntransform = {{ rotation = [0, 0, 0, 0] }}\n"
    ));
    assert!(e.contains("quaternion"), "{e}");
    let e = error(
        "[[group]]\nname = \"g\"\n  [[group.plane]]\n  point = [0, 0, 0]\n  normal = [0, 0, 1]\n  material = \"m\"\n",
    );
    assert!(e.contains("unbounded"), "{e}");
    let e = error(&format!("{sphere}[[group]]\nname = \"s\"\n"));
    assert!(e.contains("already the name of sphere[0]"), "{e}");
}

/// A chain of groups deeper than the documented maximum is an error, not a stack overflow; a
/// binary DAG of 2^20 placements loads from a file of a few dozen lines, in its own size, where
/// its copies lie apart; where they overlap at every level, a ray would enter every copy, and the
/// scene is refused.
#[test]
fn nesting_is_bounded_and_dags_load_at_the_cost_of_the_file() {
    let mut deep = String::from(
        "[[sphere]]\nname = \"g0\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n",
    );
    for i in 1..=40 {
        deep += &format!(
            "[[group]]\nname = \"g{i}\"\ntemplate = true\n  [[group.instance]]\n  of = \"g{}\"\n",
            i - 1
        );
    }
    deep += "[[instance]]\nof = \"g40\"\n";
    let e = error(&deep);
    assert!(e.contains("nest more than 32"), "{e}");

    // Each level places two copies of the one before, the second shifted by the first's size
    // along x, y and z in turn: 2^20 spheres on a 128 × 128 × 64 lattice of unit spacing.
    let dag = |shift: &dyn Fn(i32) -> [f64; 3]| {
        let mut dag = String::from(
            "[[sphere]]\nname = \"d0\"\ncenter = [0, 0, 0]\nradius = 0.25\nmaterial = \"m\"\n",
        );
        for i in 1..=20 {
            let [x, y, z] = shift(i);
            dag += &format!(
                "[[group]]\nname = \"d{i}\"\ntemplate = true\n  [[group.instance]]\n  of = \"d{p}\"\n  [[group.instance]]\n  of = \"d{p}\"\n  transform = {{ translate = [{x}, {y}, {z}] }}\n",
                p = i - 1
            );
        }
        dag + "[[instance]]\nof = \"d20\"\n"
    };
    let apart = |i: i32| {
        let mut t = [0.0; 3];
        t[(i as usize - 1) % 3] = 2f64.powi((i - 1) / 3);
        t
    };
    let loaded = load_text(&format!("{HEADER}{}", dag(&apart))).expect("the DAG loads");
    let scene = Scene::new(loaded.description).unwrap();
    let stats = scene.accel().stats(scene.geometry());
    // The d0 sphere is placed 2^20 times by the DAG (below 2^20 - 1 group placements) and once
    // where it is defined.
    assert_eq!(stats.placements, 1 << 21);
    assert_eq!(stats.primitives_stored, 1);
    // A ray down the z axis through a column of the lattice meets its top copy, at z = 63.
    let ray = quadray::Ray::new(glam::DVec3::new(5.0, 7.0, 100.0), -glam::DVec3::Z);
    let hit = scene.intersect(&ray).expect("a copy at x = 5, y = 7");
    assert!(
        (hit.geometry.point.z - 63.25).abs() < 1e-9,
        "{:?}",
        hit.geometry.point
    );

    // The same DAG with each level's copies a small step apart along x (2^-i: the copies of
    // every level overlap): a ray through x = 0.5 would enter each of the 2^21 placements there
    // (about 50 ms a ray), so the scene is refused, naming the overlap.
    let overlapping = |i: i32| [2f64.powi(-i), 0.0, 0.0];
    let loaded = load_text(&format!("{HEADER}{}", dag(&overlapping))).expect("it loads");
    let e = match Scene::new(loaded.description) {
        Ok(_) => panic!("an overlap of 2^21 placements is refused"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("placements overlap at one point"), "{e}");
}

/// Coordinates beyond the documented limit (shapes as placed, in any level) are a clear error,
/// not a panic inside the BVH build; a sphere prototype shrunk by 10⁻⁴⁰ (object-space ray origins
/// beyond f32) builds, and rays meet the world's shapes without panicking.
#[test]
fn coordinates_beyond_the_limit_are_errors_and_tiny_instances_build() {
    use quadray::*;
    let scene = |geometry: Geometry| {
        Scene::new(SceneDescription {
            camera: Camera::orbit(glam::DVec3::ZERO, 30.0, 20.0, 6.0, 40.0),
            background: glam::Vec3::ZERO,
            environment: None,
            materials: vec![Material::default()],
            lights: vec![],
            geometry,
        })
    };
    let sphere = |center: glam::DVec3, radius: f64| Sphere {
        center,
        radius,
        material: 0,
    };
    let far: Vec<Sphere> = (0..300)
        .map(|i| sphere(glam::DVec3::new(i as f64 * 1e298, 0.0, 0.0), 1e290))
        .collect();
    let e = scene(Geometry {
        spheres: far,
        ..Geometry::default()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("supports magnitudes up to 1e30"), "{e}");
    let placed_far = scene(Geometry {
        prototypes: vec![Prototype {
            spheres: vec![sphere(glam::DVec3::ZERO, 1.0)],
            ..Prototype::default()
        }],
        instances: vec![Instance::new(
            0,
            Transform::new(glam::DAffine3::from_translation(glam::DVec3::splat(1e35))).unwrap(),
        )],
        ..Geometry::default()
    });
    assert!(
        placed_far.is_err(),
        "an instance placing a shape at 1e35 is refused"
    );
    let tiny = scene(Geometry {
        spheres: vec![sphere(glam::DVec3::new(0.0, 0.0, -2.0), 1.0)],
        prototypes: vec![Prototype {
            spheres: vec![sphere(glam::DVec3::ZERO, 1.0)],
            ..Prototype::default()
        }],
        instances: vec![Instance::new(
            0,
            Transform::new(glam::DAffine3::from_scale(glam::DVec3::splat(1e-40))).unwrap(),
        )],
        ..Geometry::default()
    })
    .expect("a tiny instance is valid");
    let hit = tiny.intersect(&Ray::new(glam::DVec3::new(0.0, 0.0, 5.0), -glam::DVec3::Z));
    // The copy's object space puts the ray's origin at 5·10⁴⁰, beyond f32, where rays meet nothing
    // (documented): the world sphere behind it is hit.
    assert_eq!(hit.map(|h| h.prim.placement), Some(0));
}

/// A prototype scaled up by 10¹⁵ (its object-space rays have directions of length 10⁻¹⁵) is hit
/// by rays running along one of its boxes' faces, from the analytic BVH's node test and from its
/// level's top (a sphere and a mesh: two items tested box by box). The ray reciprocals are
/// clamped relative to the direction's length: an absolute clamp left such a ray's exit from the
/// slab it runs along before its entry on the other axes, and the copy was missed.
#[test]
fn hugely_scaled_instances_are_hit_along_their_faces() {
    use quadray::*;
    let triangle = Mesh::new(
        vec![
            glam::Vec3::new(5.0, 5.0, 0.0),
            glam::Vec3::new(6.0, 5.0, 0.0),
            glam::Vec3::new(5.0, 6.0, 0.0),
        ],
        vec![[0, 1, 2]],
        None,
        0,
    )
    .unwrap();
    let unit_sphere = Sphere {
        center: glam::DVec3::ZERO,
        radius: 1.0,
        material: 0,
    };
    for with_mesh in [false, true] {
        let scale = glam::DAffine3::from_scale(glam::DVec3::splat(1e15));
        let scene = Scene::new(SceneDescription {
            camera: Camera::orbit(glam::DVec3::ZERO, 30.0, 20.0, 6e15, 40.0),
            background: glam::Vec3::ZERO,
            environment: None,
            materials: vec![Material::default()],
            lights: vec![],
            geometry: Geometry {
                prototypes: vec![Prototype {
                    spheres: vec![unit_sphere.clone()],
                    meshes: if with_mesh {
                        vec![triangle.clone()]
                    } else {
                        vec![]
                    },
                    ..Prototype::default()
                }],
                instances: vec![Instance::new(0, Transform::new(scale).unwrap())],
                ..Geometry::default()
            },
        })
        .unwrap();
        // Along z, just inside the sphere's box face x = 1 (the sphere's rim at x = 0.999999).
        for x in [0.999_999, -0.999_999, 0.5] {
            let ray = Ray::new(glam::DVec3::new(x * 1e15, 0.0, -2e15), glam::DVec3::Z);
            let hit = scene.intersect(&ray);
            let z = -(1.0f64 - x * x).sqrt() * 1e15;
            let hit = hit.unwrap_or_else(|| panic!("missed at x = {x} (mesh {with_mesh})"));
            assert!(
                (hit.geometry.point.z - z).abs() < 1e-6 * 1e15,
                "{:?}",
                hit.geometry.point
            );
        }
    }
}
