//! Hole maps of the built-in hard scenes: the renderer's production path agrees with the exact
//! oracle on every unambiguous pixel, while the naive variants do not.

use glam::{DVec3, Vec3};
use quadray::{
    Camera, ClipBox, Geometry, Material, Projection, Quadric, QuadricKind, QuadricSurface, Scene,
    SceneDescription, Transform,
};
use quadray_bench::holes::{self, HoleCounts};
use quadray_bench::variants::Variant;

fn counts(s: &holes::HoleScene, oracle: &[holes::OraclePixel], v: Variant) -> HoleCounts {
    let got = holes::variant_pixels(&s.scene, s.width, s.height, v).unwrap();
    HoleCounts::of(oracle, &got)
}

/// 10⁷ units away, production (through the BVH) and production + Newton differ from the oracle in
/// no unambiguous pixel; naive f32 gets about half the image wrong, and naive and stable f64 leave
/// rings of wrong pixels at the silhouettes (their γ = f(o) at the far origin cancels).
#[test]
fn far_scene_production_has_no_holes_and_the_naive_variants_have_many() {
    let s = holes::far(180, 60);
    let oracle = holes::oracle_pixels(&s.scene, s.width, s.height).unwrap();
    let hits = oracle.iter().filter(|p| p.object.is_some()).count();
    assert!(hits > 1000, "the row fills part of the image: {hits}");
    for v in [Variant::Production, Variant::ProductionNewton] {
        let c = counts(&s, &oracle, v);
        assert_eq!(c.differing(), 0, "{}: {c:?}", v.name());
    }
    let f32_counts = counts(&s, &oracle, Variant::NaiveF32);
    assert!(f32_counts.differing() > hits / 2, "{f32_counts:?}");
    for v in [Variant::NaiveF64, Variant::StableF64] {
        let c = counts(&s, &oracle, v);
        assert!(c.differing() > 20, "{}: {c:?}", v.name());
    }
}

/// 10⁶ units from the world origin with the camera nearby, every f64 variant is exact at the pixel
/// centres while the f32 variant, which maps world coordinates in f32, shifts the edges.
#[test]
fn moved_scene_breaks_only_the_f32_variant() {
    let s = holes::moved(180, 60);
    let oracle = holes::oracle_pixels(&s.scene, s.width, s.height).unwrap();
    for v in [
        Variant::NaiveF64,
        Variant::StableF64,
        Variant::Production,
        Variant::ProductionNewton,
    ] {
        let c = counts(&s, &oracle, v);
        assert_eq!(c.differing(), 0, "{}: {c:?}", v.name());
    }
    let c = counts(&s, &oracle, Variant::NaiveF32);
    assert!(c.differing() > 50, "{c:?}");
}

/// The BVH (f32 boxes, padded) loses nothing: the renderer's path equals production's
/// intersector run on every quadric.
#[test]
fn the_bvh_path_equals_the_brute_force_production_loop() {
    for s in [holes::far(120, 40), holes::moved(120, 40)] {
        let bvh = holes::variant_pixels(&s.scene, s.width, s.height, Variant::Production).unwrap();
        let all = holes::production_without_bvh(&s.scene, s.width, s.height).unwrap();
        assert_eq!(bvh, all, "{}", s.name);
    }
}

/// The middle pixel of an odd-sized image of a double cone, looked at through its apex, is
/// within the oracle's margin (the apex decides nothing robustly), and is counted apart; every
/// other pixel is unambiguous and production gets all of them right.
#[test]
fn a_ray_through_the_cone_apex_is_ambiguous() {
    let cone = Quadric::new(
        QuadricSurface::Canonical {
            kind: QuadricKind::Cone,
            a: 0.5,
            b: 0.5,
            c: 1.0,
        },
        ClipBox::cube(1.0),
        Transform::IDENTITY,
        0,
    )
    .unwrap();
    let scene = Scene::new(SceneDescription {
        camera: Camera {
            from: DVec3::new(2.2, -2.2, 0.5),
            to: DVec3::ZERO,
            up: DVec3::Z,
            projection: Projection::Perspective { vfov_deg: 30.0 },
        },
        background: Vec3::ZERO,
        environment: None,
        materials: vec![Material::default()],
        lights: vec![],
        geometry: Geometry {
            quadrics: vec![cone],
            ..Geometry::default()
        },
    })
    .unwrap();
    let s = holes::HoleScene {
        name: "apex".into(),
        about: "a double cone seen through its apex".into(),
        scene,
        width: 41,
        height: 41,
    };
    let mapped = holes::scene_holes(&s).unwrap();
    let middle = mapped.oracle[20 * 41 + 20];
    assert!(middle.ambiguous, "{middle:?}");
    let ambiguous = mapped.oracle.iter().filter(|p| p.ambiguous).count();
    assert!(ambiguous < 5, "only pixels next to the apex: {ambiguous}");
    let c = mapped.counts(Variant::Production);
    assert_eq!((c.ambiguous, c.differing()), (ambiguous, 0), "{c:?}");
    let md = holes::markdown(&[mapped]);
    assert!(md.contains("| apex (41x41) | production | 1681 |"), "{md}");
}
