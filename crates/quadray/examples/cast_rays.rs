//! Casting rays through quadray's public API, without the renderer, as users of pbrt's and
//! Embree's ray queries expect: a scene built in code (a clipped hyperboloid, a sphere, a floor),
//! a fan of rays shot at it with [`Scene::intersect`], and a shadow query with
//! [`Scene::occluded_from`] (the any-hit query, [`Scene::occluded`] for a ray leaving a surface)
//! from each hit towards a light.
//!
//! `cargo run --release -p quadray --example cast_rays`

use glam::{DVec3, Vec3};
use quadray::math::offset_origin;
use quadray::{
    Camera, ClipBox, Geometry, Material, Plane, Quadric, QuadricKind, QuadricSurface, Ray, Scene,
    SceneDescription, Sphere, Transform,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A hyperboloid of one sheet in the seed's clip cube [-1, 1]³, a sphere beside it, a floor.
    let hyperboloid = Quadric::new(
        QuadricSurface::Canonical {
            kind: QuadricKind::Hyperboloid1,
            a: 0.5,
            b: 0.5,
            c: 0.7,
        },
        ClipBox::cube(1.0),
        Transform::IDENTITY,
        0,
    )?;
    let scene = Scene::new(SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 30.0, 20.0, 6.0, 40.0),
        background: Vec3::ZERO,
        environment: None,
        materials: vec![Material::default()],
        lights: Vec::new(),
        geometry: Geometry {
            quadrics: vec![hyperboloid],
            spheres: vec![Sphere {
                center: DVec3::new(2.5, 0.0, 0.0),
                radius: 0.75,
                material: 0,
            }],
            planes: vec![Plane {
                point: DVec3::new(0.0, 0.0, -1.0),
                normal: DVec3::Z,
                material: 0,
            }],
            ..Geometry::default()
        },
    })?;
    let light = DVec3::new(-4.0, -6.0, 8.0);
    // Rays from y = -6 towards the scene, fanning over x at the height z = 0.2.
    for k in 0..7 {
        let x = -1.5 + 0.75 * k as f64;
        let origin = DVec3::new(x, -6.0, 0.2);
        let ray = Ray::new(origin, DVec3::new(0.0, 1.0, -0.02));
        match scene.intersect(&ray) {
            Some(hit) => {
                let p = hit.geometry.point;
                let to_light = light - p;
                // A shadow ray leaving the surface: its origin offset by the hit's own error bound
                // (no fixed epsilon), and the primitive it leaves named so it cannot shadow itself.
                let dir = to_light.normalize();
                let g = &hit.geometry;
                let shadow = Ray::new(offset_origin(p, g.geometric_normal, g.error, dir), dir);
                let lit = !scene.occluded_from(&shadow, to_light.length(), Some(hit.prim));
                println!(
                    "x = {x:5.2}: hit t = {:.6} at ({:.3}, {:.3}, {:.3}), {}",
                    hit.t,
                    p.x,
                    p.y,
                    p.z,
                    if lit { "lit" } else { "in shadow" }
                );
            }
            None => println!("x = {x:5.2}: no hit"),
        }
    }
    Ok(())
}
