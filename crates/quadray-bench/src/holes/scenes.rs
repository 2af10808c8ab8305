//! The built-in hole-map scenes: a row of quadrics far from the origin, and the same row moved
//! so that their coefficients grow large.

use super::HoleScene;
use glam::DVec3;
use quadray::{
    Camera, ClipBox, Geometry, Light, Material, Projection, Quadric, QuadricKind, QuadricSurface,
    Scene, SceneDescription, Transform,
};

/// The built-in scenes' row of quadrics in their own frame: an ellipsoid (a unit sphere), a
/// hyperboloid of one sheet open at both ends, a double cone with its apex in view, and an
/// elliptic paraboloid cup, 2.6 units apart along x and tilted 30° towards a camera on −y.
fn row(offset: DVec3) -> Vec<Quadric> {
    let tilt = DVec3::new(30.0, 0.0, 0.0);
    let items = [
        (
            QuadricKind::Ellipsoid,
            [1.0, 1.0, 1.0],
            ClipBox::cube(1.0),
            0.0,
        ),
        (
            QuadricKind::Hyperboloid1,
            [0.5, 0.5, 0.7],
            ClipBox::cube(1.0),
            0.0,
        ),
        (QuadricKind::Cone, [0.6, 0.6, 1.0], ClipBox::cube(1.0), 0.0),
        // z = (x² + y²)/0.64 from its vertex up to z = 1.2, lowered to centre it.
        (
            QuadricKind::EllipticParaboloid,
            [0.8, 0.8, 1.0],
            ClipBox {
                min: DVec3::new(-1.0, -1.0, 0.0),
                max: DVec3::new(1.0, 1.0, 1.2),
            },
            -0.6,
        ),
    ];
    items
        .iter()
        .enumerate()
        .map(|(i, &(kind, [a, b, c], clip, lift))| {
            let at = offset + DVec3::new(-3.9 + 2.6 * i as f64, 0.0, lift);
            let transform = Transform::from_srt(DVec3::ONE, tilt, at)
                .expect("the row's placements are invertible");
            Quadric::new(
                QuadricSurface::Canonical { kind, a, b, c },
                clip,
                transform,
                i as u32,
            )
            .expect("the row's quadrics are valid")
        })
        .collect()
}

fn row_scene(quadrics: Vec<Quadric>, camera: Camera) -> Scene {
    let materials = (0..quadrics.len()).map(|_| Material::default()).collect();
    Scene::new(SceneDescription {
        camera,
        background: glam::Vec3::splat(0.05),
        environment: None,
        materials,
        lights: vec![Light::Directional {
            direction: DVec3::new(-0.4, 1.0, -0.6).normalize(),
            irradiance: glam::Vec3::ONE,
        }],
        geometry: Geometry {
            quadrics,
            ..Geometry::default()
        },
    })
    .expect("the built-in hole-map scenes are valid")
}

/// The row seen from 10⁷ units away through a 1.9·10⁻⁵ degree field of view (§4.1 of the
/// catalogue): every variant that evaluates f at the far ray origin loses the discriminant to
/// cancellation (β² and aγ are ~10¹⁴ times the object's own scale).
pub fn far(width: u32, height: u32) -> HoleScene {
    let distance = 1e7;
    let target = DVec3::new(0.0, distance, 0.0);
    let vfov = 2.0 * (1.7f64 / distance).atan().to_degrees();
    let camera = Camera {
        from: DVec3::ZERO,
        to: target,
        up: DVec3::Z,
        projection: Projection::Perspective { vfov_deg: vfov },
    };
    HoleScene {
        name: "far-1e7".into(),
        about: "ellipsoid, hyperboloid, cone apex and paraboloid cup 10⁷ units from the camera"
            .into(),
        scene: row_scene(row(target), camera),
        width,
        height,
    }
}

/// The row and its camera (12 units in front of it) moved 10⁶ units from the world origin along
/// every axis (§4.17): nothing is far from the camera, but world coordinates carry only about
/// 10⁻¹⁰ of their size in f64 and 6·10⁻⁸ in f32, so an intersector that maps the ray to the object
/// in world coordinates (the f32 variant) shifts every edge.
pub fn moved(width: u32, height: u32) -> HoleScene {
    let shift = DVec3::splat(1e6);
    let camera = Camera {
        from: shift + DVec3::new(0.0, -12.0, 0.0),
        to: shift,
        up: DVec3::Z,
        projection: Projection::Perspective { vfov_deg: 16.0 },
    };
    HoleScene {
        name: "moved-1e6".into(),
        about: "the same row and a camera 12 units away, all moved 10⁶ units along each axis"
            .into(),
        scene: row_scene(row(shift), camera),
        width,
        height,
    }
}
