//! Unit tests of scenes: single-sided meshes, plain, instanced and mirrored.

use super::*;
use crate::geometry::Prototype;
use crate::geometry::instance::Instance;
use crate::math::Transform;
use crate::test_rng::{centred_stream as uniform, corner_rays, square_cone};
use crate::{Projection, Sphere};
use glam::{DAffine3, DVec3};

/// The unit square at z = 0, counter-clockwise seen from +z: its front faces +z.
fn square(single_sided: bool) -> Mesh {
    let p = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    Mesh::new(p, vec![[0, 1, 2], [0, 2, 3]], None, 0)
        .unwrap()
        .with_single_sided(single_sided)
}

/// A camera 10 units up the z axis looking down at the origin.
fn looking_down() -> Camera {
    Camera {
        from: DVec3::new(0.0, 0.0, 10.0),
        to: DVec3::ZERO,
        up: DVec3::Y,
        projection: Projection::Perspective { vfov_deg: 40.0 },
    }
}

/// A square at z = 0 (world, or placed by `placement` as an instance) and a sphere of radius
/// 0.5 at z = 2, above it.
fn scene(single_sided: bool, placement: Option<DAffine3>) -> Scene {
    let mut geometry = Geometry {
        spheres: vec![Sphere {
            center: DVec3::new(0.0, 0.0, 2.0),
            radius: 0.5,
            material: 0,
        }],
        ..Geometry::default()
    };
    match placement {
        None => geometry.meshes.push(square(single_sided)),
        Some(m) => {
            geometry
                .prototypes
                .push(Prototype::mesh(square(single_sided)));
            geometry
                .instances
                .push(Instance::new(0, Transform::new(m).unwrap()));
        }
    }
    unlit(geometry)
}

/// `geometry` seen by [`looking_down`], one default material, no lights, a black background.
fn unlit(geometry: Geometry) -> Scene {
    Scene::new(SceneDescription {
        camera: looking_down(),
        background: Vec3::ZERO,
        environment: None,
        materials: vec![Material::default()],
        lights: vec![],
        geometry,
    })
    .unwrap()
}

/// A single-sided square hides what lies behind its front and lets rays through its back,
/// shadow rays too. Through a mirroring instance the same faces stay in front, which the mirror
/// turns to face −z.
#[test]
fn single_sided_meshes_are_seen_from_the_front_only() {
    let up = Ray::new(DVec3::new(0.1, 0.2, -5.0), DVec3::Z);
    let down = Ray::new(DVec3::new(0.1, 0.2, 5.0), -DVec3::Z);
    let hit_t = |s: &Scene, ray: &Ray| s.intersect(ray).map(|h| h.t);

    let two_sided = scene(false, None);
    assert_eq!(hit_t(&two_sided, &up), Some(5.0));
    let one_sided = scene(true, None);
    // From below, the square's back: the ray goes on to the sphere's bottom, where
    // x² + y² + (z − 2)² = 0.25 with x² + y² = 0.05.
    let bottom = 2.0 - 0.2f64.sqrt();
    let t = hit_t(&one_sided, &up).unwrap();
    assert!((t - (5.0 + bottom)).abs() < 1e-9, "{t}");
    assert!(!one_sided.occluded(&up, 6.0), "the back casts no shadow");
    assert!(one_sided.occluded(&up, 7.0), "the sphere beyond it does");
    assert!(two_sided.occluded(&up, 6.0));
    // From above, its front: the sphere's top, then nothing behind it.
    assert!((hit_t(&one_sided, &down).unwrap() - (5.0 - (4.0 - bottom))).abs() < 1e-9);
    let beside = Ray::new(DVec3::new(0.9, 0.9, 5.0), -DVec3::Z);
    assert_eq!(hit_t(&one_sided, &beside), Some(5.0));
    assert!(one_sided.occluded(&beside, 5.5), "the front casts a shadow");
    assert!(!one_sided.occluded(&beside, 4.5));

    // Moved up by 1 as an instance: the same, with the mirror swapping the seen side.
    let lift = DAffine3::from_translation(DVec3::Z);
    let placed = scene(true, Some(lift));
    assert!((hit_t(&placed, &up).unwrap() - (5.0 + bottom)).abs() < 1e-9);
    assert_eq!(hit_t(&placed, &beside), Some(4.0));
    let mirrored = scene(
        true,
        Some(lift * DAffine3::from_scale(DVec3::new(1.0, 1.0, -1.0))),
    );
    // Its front now faces −z: rays from below stop at it, rays from above pass.
    assert_eq!(hit_t(&mirrored, &up), Some(6.0));
    assert!(mirrored.occluded(&up, 6.5));
    assert_eq!(hit_t(&mirrored, &beside), None);
    assert!(!mirrored.occluded(&beside, 100.0));
    assert!(
        !placed.occluded(&up, 6.0),
        "an instance's back face casts no shadow"
    );
}

/// A shadow ray through the centre of a glass ball of index 1.5 keeps (1 − 0.04)² of the light
/// (two crossings at normal incidence), times the attenuation colour to the power of the path
/// length over the attenuation distance; an opaque ball keeps nothing; beside the ball, all.
#[test]
fn shadow_rays_pass_glass_attenuated_and_stop_at_opaque_surfaces() {
    use crate::dielectric::{Attenuation, Transmission};
    let ball = |transmission: Option<Transmission>| {
        Scene::new(SceneDescription {
            camera: looking_down(),
            background: Vec3::ZERO,
            environment: None,
            materials: vec![Material {
                texture: crate::Texture::Constant(Vec3::ONE),
                transmission,
                ..Material::default()
            }],
            lights: vec![],
            geometry: Geometry {
                spheres: vec![Sphere {
                    center: DVec3::ZERO,
                    radius: 1.0,
                    material: 0,
                }],
                ..Geometry::default()
            },
        })
        .unwrap()
    };
    let through_centre = Ray::new(DVec3::new(0.0, 0.0, -5.0), DVec3::Z);
    let beside = Ray::new(DVec3::new(0.0, 1.5, -5.0), DVec3::Z);
    let clear = ball(Some(Transmission::default()));
    assert!(clear.transmits());
    let t = clear.transmittance(&through_centre, 10.0, None);
    assert!(
        (t - Vec3::splat(0.96 * 0.96)).abs().max_element() < 1e-6,
        "{t}"
    );
    assert_eq!(clear.transmittance(&beside, 10.0, None), Vec3::ONE);
    let tinted = ball(Some(Transmission {
        attenuation: Some(Attenuation {
            color: Vec3::new(0.5, 0.8, 1.0),
            distance: 1.0,
        }),
        ..Transmission::default()
    }));
    // Two units inside: the colour squared.
    let t = tinted.transmittance(&through_centre, 10.0, None);
    let want = Vec3::new(0.25, 0.64, 1.0) * (0.96 * 0.96);
    assert!((t - want).abs().max_element() < 1e-5, "{t}");
    // A light inside the ball: one crossing, one unit of glass.
    let t = tinted.transmittance(&through_centre, 5.0, None);
    let want = Vec3::new(0.5, 0.8, 1.0) * 0.96;
    assert!((t - want).abs().max_element() < 1e-5, "{t}");
    let opaque = ball(None);
    assert!(!opaque.transmits());
    assert_eq!(
        opaque.transmittance(&through_centre, 10.0, None),
        Vec3::ZERO
    );
}

/// A world of spheres, every kind of clipped quadric, a mesh, an instanced mesh and a plane, lit
/// by lights around and among the shapes (one inside a sphere, whose box then fills every cell),
/// seen by a pinhole camera from `eye`.
fn buffered_world(eye: DVec3) -> Scene {
    buffered_world_with(eye, true)
}

/// [`buffered_world`], with its plane or without.
fn buffered_world_with(eye: DVec3, plane: bool) -> Scene {
    use crate::plane::Plane;
    use crate::quadric::{ClipBox, Quadric, QuadricKind, QuadricSurface};
    let mut next = uniform(0x1234_5678_9abc_def1);
    let mut geometry = Geometry::default();
    for _ in 0..12 {
        geometry.spheres.push(Sphere {
            center: DVec3::new(next(), next(), next() + 0.5) * 8.0,
            radius: 0.3 + next().abs(),
            material: 0,
        });
    }
    for (n, &kind) in QuadricKind::ALL.iter().enumerate() {
        let at = DVec3::new(n as f64 - 4.0, 2.0 * next(), 2.0 + next());
        let t = Transform::from_srt(DVec3::splat(0.6), DVec3::new(next(), next(), 0.0), at);
        let surface = QuadricSurface::Canonical {
            kind,
            a: 1.0,
            b: 1.0,
            c: 1.0,
        };
        let q = Quadric::new(surface, ClipBox::cube(1.0), t.unwrap(), 0).unwrap();
        geometry.quadrics.push(q);
    }
    geometry.meshes.push(square(false));
    geometry.prototypes.push(Prototype::mesh(square(false)));
    let placed = DAffine3::from_translation(DVec3::new(3.0, -2.0, 4.0));
    (geometry.instances).push(Instance::new(0, Transform::new(placed).unwrap()));
    if plane {
        geometry.planes.push(Plane {
            point: DVec3::new(0.0, 0.0, -4.5),
            normal: DVec3::Z,
            material: 0,
        });
    }
    let inside = geometry.spheres[0].center;
    let lights: Vec<Light> = [
        DVec3::new(5.0, -6.0, 12.0),
        DVec3::new(-9.0, 2.0, 3.0),
        DVec3::new(0.5, 0.2, 1.0),
        inside,
    ]
    .into_iter()
    .map(|position| Light::PointNoFalloff {
        position,
        irradiance: Vec3::ONE,
    })
    .collect();
    Scene::new(SceneDescription {
        camera: Camera {
            from: eye,
            ..looking_down()
        },
        background: Vec3::ZERO,
        environment: None,
        materials: vec![Material::default()],
        lights,
        geometry,
    })
    .unwrap()
}

/// Whether `scene` says the rays from `eye` through `cone` ([`square_cone`]) meet nothing; if
/// it does, 16 rays through random points of the cone are checked to meet nothing in the BVH and
/// the planes.
fn said_empty_and_empty(
    scene: &Scene,
    eye: DVec3,
    cone: &impl Fn(f64, f64) -> DVec3,
    next: &mut impl FnMut() -> f64,
) -> bool {
    if !scene.camera_rays_meet_nothing(&corner_rays(eye, cone)) {
        return false;
    }
    for _ in 0..16 {
        let ray = Ray::new(eye, cone(next() * 2.0, next() * 2.0));
        let hit = (scene.accel).closest(&scene.geometry, &ray, f64::INFINITY, None);
        assert_eq!(hit, None, "eye {eye}, ray {ray:?}");
    }
    true
}

/// Cones of camera rays that the eye buffer says meet nothing meet nothing in the BVH and the
/// planes either: rays through random points of small random quadrilaterals of directions from
/// the eye, in [`buffered_world`] with its plane and without; the plane hides some cones.
#[test]
fn cones_said_to_meet_nothing_meet_nothing() {
    let mut next = uniform(0x5eed_c0de_0ff1_ce00);
    for eye in [DVec3::new(0.0, 0.0, 10.0), DVec3::new(-14.0, 9.0, 3.0)] {
        let scenes = [
            buffered_world_with(eye, false),
            buffered_world_with(eye, true),
        ];
        let (mut empty, mut cones) = ([0, 0], 0);
        for _ in 0..4000 {
            let size = 0.2 * next().abs();
            let cone = square_cone(&mut next, size);
            cones += 1;
            for (scene, empty) in scenes.iter().zip(&mut empty) {
                *empty += usize::from(said_empty_and_empty(scene, eye, &cone, &mut next));
            }
        }
        // Without the plane, many cones see nothing; the plane, below the shapes, hides some.
        let [open, under_plane] = empty;
        assert!(
            open * 10 > cones && open * 10 < cones * 9,
            "{open} of {cones}"
        );
        assert!(
            under_plane * 20 > cones && under_plane < open,
            "{under_plane}, {open}"
        );
    }
}

/// In a world too large for an eye buffer (twelve placed squares and spheres: a top-level BVH,
/// 70 spheres), cones of camera rays said to meet nothing, through the boxes covering the world,
/// meet nothing in the BVH and the plane, and some cones are said to, from eyes above and beside
/// the content.
#[test]
fn cones_beside_the_world_meet_nothing() {
    use crate::plane::Plane;
    let mut next = uniform(0x0b0c_5e1d_e0f7_0001);
    let mut geometry = Geometry {
        prototypes: vec![Prototype::mesh(square(false))],
        ..Geometry::default()
    };
    for i in 0..12 {
        let at = DVec3::new((i % 4) as f64 * 3.0 - 4.5, (i / 4) as f64 * 3.0 - 3.0, 0.0);
        let t = Transform::new(DAffine3::from_translation(at)).unwrap();
        geometry.instances.push(Instance::new(0, t));
    }
    for i in 0..70 {
        geometry.spheres.push(Sphere {
            center: DVec3::new((i % 10) as f64 - 4.5, (i / 10) as f64 - 3.0, 1.0),
            radius: 0.2,
            material: 0,
        });
    }
    geometry.planes.push(Plane {
        point: DVec3::new(0.0, 0.0, -3.0),
        normal: DVec3::Z,
        material: 0,
    });
    let scene = unlit(geometry);
    assert!(scene.eye_buffer.is_none());
    for eye in [DVec3::new(0.0, 0.0, 12.0), DVec3::new(-16.0, 9.0, 4.0)] {
        let (mut empty, mut cones) = (0, 0);
        for _ in 0..3000 {
            let size = 0.2 * next().abs() + 0.01;
            let cone = square_cone(&mut next, size);
            cones += 1;
            empty += usize::from(said_empty_and_empty(&scene, eye, &cone, &mut next));
        }
        assert!(
            empty * 10 > cones && empty * 10 < cones * 9,
            "{empty} of {cones}"
        );
    }
}

/// Shadow rays answered through the light buffers agree with the BVH's answers, ray for ray, in
/// [`buffered_world`], the shadow rays made as shading makes them from the first hits of random
/// rays.
#[test]
fn light_buffers_answer_as_the_bvh() {
    let scene = buffered_world(DVec3::new(0.0, 0.0, 10.0));
    assert!(scene.light_buffers.iter().all(Option::is_some));
    let mut next = uniform(0x2545_f491_4f6c_dd1d);
    let (mut answered, mut blocked, mut rays) = (0, 0, 0);
    for _ in 0..20_000 {
        let origin = DVec3::new(next(), next(), next()) * 30.0;
        let target = DVec3::new(next(), next(), next() + 0.2) * 8.0;
        let Some(hit) = scene.intersect(&Ray::new(origin, target - origin)) else {
            continue;
        };
        let g = &hit.geometry;
        for (i, light) in scene.lights().iter().enumerate() {
            let Some(inc) = light.incident(g.point) else {
                continue;
            };
            let from =
                crate::math::offset_origin(g.point, g.geometric_normal, g.error, inc.to_light);
            let shadow = Ray::new(from, inc.to_light);
            let want = scene.occluded_from(&shadow, inc.distance, Some(hit.prim));
            let got = scene.occluded_towards_light(i, &shadow, inc.distance, Some(hit.prim));
            assert_eq!(got, want, "light {i}, shadow ray {shadow:?}");
            let buffer = scene.light_buffers[i].as_ref().unwrap();
            answered += usize::from(buffer.answers(&shadow, inc.distance));
            blocked += usize::from(want);
            rays += 1;
        }
    }
    // The buffers answered nearly every ray, blocked and clear ones both.
    assert!(
        rays > 20_000 && answered * 100 > rays * 99,
        "{answered} of {rays}"
    );
    assert!(
        blocked * 10 > rays && blocked * 10 < rays * 9,
        "{blocked} of {rays}"
    );
}

/// Rays from the eye answered through the eye buffer find the BVH's nearest hit, ray for ray, in
/// [`buffered_world`] seen from outside, from among the shapes and from inside a sphere's box:
/// rays in every direction, and rays aimed at the shapes, some of them through cells that list
/// several shapes.
/// Batches of camera rays through the eye buffer answer as the BVH ray by ray, bit for bit:
/// batches of 32 neighbouring directions (so runs of four share a cell's list of one quadric or
/// of several shapes, tested four rays at once) and of scattered ones, from eyes outside the
/// shapes and among them.
#[test]
fn eye_buffer_batches_answer_as_the_bvh() {
    let mut next = uniform(0xba7c_4e5e_0f0e_7e5a);
    let (mut alike, mut rays_seen) = (0, 0);
    for eye in [
        DVec3::new(0.0, 0.0, 10.0),
        DVec3::new(-14.0, 9.0, 3.0),
        DVec3::new(0.4, -0.3, 2.2),
    ] {
        let scene = buffered_world(eye);
        let buffer = scene.eye_buffer.as_ref().expect("an eye buffer");
        for batch in 0..400 {
            let aim = DVec3::new(next(), next(), next() + 0.5) * 8.0 - eye;
            let rays: Vec<Ray> = (0..32)
                .map(|k| {
                    let spread = if batch % 4 == 3 { 0.5 } else { 1e-3 };
                    let jitter = DVec3::new(next(), next(), next()) * spread * aim.length();
                    Ray::new(eye, aim + jitter + DVec3::X * (k as f64 * 1e-3))
                })
                .collect();
            let mut got = vec![None; rays.len()];
            (scene.accel).closest_each_from_eye(&scene.geometry, buffer, &rays, &mut got);
            for (ray, got) in rays.iter().zip(&got) {
                let want = (scene.accel).closest(&scene.geometry, ray, f64::INFINITY, None);
                let bits = |h: Option<(f64, PrimRef)>| h.map(|(t, p)| (t.to_bits(), p));
                assert_eq!(bits(*got), bits(want), "eye {eye}, ray {ray:?}");
            }
            for four in rays.chunks_exact(4) {
                alike += usize::from(buffer.lists_alike(four.try_into().unwrap()));
                rays_seen += 4;
            }
        }
    }
    // Many runs of four share a list: the four-ray tests answered them.
    assert!(
        alike * 16 > rays_seen,
        "{alike} runs of four alike in {rays_seen} rays"
    );
}

#[test]
fn the_eye_buffer_answers_as_the_bvh() {
    let mut next = uniform(0x0ddb_1a5e_55ee_d001);
    for eye in [
        DVec3::new(0.0, 0.0, 10.0),
        DVec3::new(-14.0, 9.0, 3.0),
        DVec3::new(0.4, -0.3, 2.2),
    ] {
        let scene = buffered_world(eye);
        let buffer = scene
            .eye_buffer
            .as_ref()
            .expect("a pinhole camera in a few shapes");
        let (mut answered, mut several, mut hits, mut rays) = (0, 0, 0, 0);
        for k in 0..40_000 {
            let dir = if k % 2 == 0 {
                DVec3::new(next(), next(), next())
            } else {
                DVec3::new(next(), next(), next() + 0.5) * 8.0 - eye
            };
            // Now and then from the eye with its zeros negative: equal, but not bit for bit.
            let origin = match k % 7 {
                3 => DVec3::from(eye.to_array().map(|c| if c == 0.0 { -0.0 } else { c })),
                _ => eye,
            };
            let ray = Ray::new(origin, dir);
            let want = scene
                .accel
                .closest(&scene.geometry, &ray, f64::INFINITY, None);
            let got = scene.accel.closest_from_eye(&scene.geometry, buffer, &ray);
            assert_eq!(got, want, "eye {eye}, ray {ray:?}");
            let listed = buffer.listed(&ray);
            answered += usize::from(listed.is_some());
            several += usize::from(listed.is_some_and(|n| n > 1));
            hits += usize::from(want.is_some());
            rays += 1;
        }
        // Most rays are answered by the buffer, some of them by testing several shapes, and many
        // hit something.
        assert!(
            answered * 2 > rays && several * 50 > rays && hits * 4 > rays,
            "{answered} ({several} by several shapes), {hits} of {rays}"
        );
    }
}
