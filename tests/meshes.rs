//! Triangle meshes through the two-level acceleration structure, checked against geometric facts:
//! a closed surface seen from inside has no holes (watertight), rays spawned outward from a convex
//! surface never hit it again (no acne), at scales 1e-6 to 1e29; an instance renders as the same
//! mesh baked into world space; the ray-casting API agrees with the geometry.

use glam::{DAffine3, DQuat, DVec3, Vec3};
use quadray::math::offset_origin;
use quadray::*;

/// A unit icosphere (subdivided `levels` times, shared vertices), scaled by `scale` about `centre`.
fn icosphere(levels: u32, scale: f64, centre: DVec3) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push(((p[a as usize] + p[b as usize]) * 0.5).normalize());
                p.len() as u32 - 1
            })
        };
        let mut next = Vec::new();
        for [a, b, c] in f {
            let (ab, bc, ca) = (
                midpoint(a, b, &mut p),
                midpoint(b, c, &mut p),
                midpoint(c, a, &mut p),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    let positions = p.iter().map(|v| (centre + *v * scale).as_vec3()).collect();
    Mesh::new(positions, f, None, 0).unwrap()
}

fn scene_of(geometry: Geometry) -> Scene {
    Scene::new(SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 30.0, 20.0, 6.0, 40.0),
        background: Vec3::ZERO,
        environment: None,
        materials: vec![Material::default(), Material::default()],
        lights: vec![],
        geometry,
    })
    .unwrap()
}

/// Directions on the sphere (a Fibonacci lattice), plus every vertex and edge midpoint of the
/// mesh as seen from `centre`: rays through shared vertices and edges are the ones a
/// non-watertight test loses.
fn directions(mesh: &Mesh, centre: DVec3, n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut d: Vec<DVec3> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    let p = |i: u32| mesh.positions()[i as usize].as_dvec3();
    for [a, b, c] in mesh.indices() {
        d.push(p(*a) - centre);
        d.push((p(*a) + p(*b)) * 0.5 - centre);
        d.push((p(*b) + p(*c)) * 0.5 - centre);
    }
    d
}

/// From inside a closed mesh every ray hits it (checked by the geometry: the mesh encloses the
/// centre), and a ray spawned outward from each hit, the way the integrator spawns reflection rays,
/// never meets the convex mesh again. At scales 1e-6, 1 and 1e6, placed off the origin, and at
/// 1e13 to 1e29, where the f32 test's products overflow and its lanes are finished in f64
/// (before that fallback, every one of the 20 000 rays from the centre missed at 1e15 and 1e20;
/// at 1e20 the BVH's plan panicked first). (With pbrt-v3's own bound on the triangle test's t
/// error this test counted 3840 holes at 1e-6: every ray aimed at a vertex or an edge midpoint.)
#[test]
fn closed_mesh_is_watertight_and_acne_free_at_any_scale() {
    for scale in [1e-6, 1.0, 1e6, 1e13, 1e15, 1e20, 1e29] {
        let centre = DVec3::new(0.3, -0.2, 0.1) * scale;
        let mesh = icosphere(3, scale, centre);
        let dirs = directions(&mesh, centre, 20_000);
        let scene = scene_of(Geometry {
            meshes: vec![mesh],
            ..Geometry::default()
        });
        let (mut holes, mut acne) = (0, 0);
        for d in &dirs {
            let ray = Ray::new(centre, *d);
            let Some(hit) = scene.intersect(&ray) else {
                holes += 1;
                continue;
            };
            let g = hit.geometry;
            // Leave outward along a direction tilted from the normal: a convex surface is behind it.
            let n = if g.geometric_normal.dot(*d) > 0.0 {
                g.geometric_normal
            } else {
                -g.geometric_normal
            };
            let out = (n + d.normalize() * 0.9).normalize();
            let spawned = Ray::new(offset_origin(g.point, n, g.error, out), out);
            if scene.intersect_from(&spawned, Some(hit.prim)).is_some()
                || scene
                    .accel()
                    .occluded(scene.geometry(), &spawned, f64::INFINITY, Some(hit.prim))
            {
                acne += 1;
            }
        }
        assert_eq!((holes, acne), (0, 0), "scale {scale}: {} rays", dirs.len());
        // The slice query finds the same hits.
        let rays: Vec<Ray> = dirs.iter().map(|d| Ray::new(centre, *d)).collect();
        let mut many = vec![None; rays.len()];
        scene.intersect_many(&rays, &mut many);
        for (ray, got) in rays.iter().zip(&many) {
            assert_eq!(
                got.map(|h| (h.t, h.prim)),
                scene.intersect(ray).map(|h| (h.t, h.prim))
            );
        }
    }
}

/// A prototype placed by an instance (rotated, non-uniformly scaled, translated) renders to the
/// same image as the mesh with the transform baked into its vertices, and its hits report the
/// instance's material and object index.
#[test]
fn instance_renders_like_the_baked_mesh() {
    let proto = icosphere(2, 1.0, DVec3::ZERO);
    let affine = DAffine3::from_scale_rotation_translation(
        DVec3::new(1.5, 0.7, 1.1),
        DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.5, 0.9),
        DVec3::new(0.4, -0.3, 0.2),
    );
    let baked_positions = proto
        .positions()
        .iter()
        .map(|p| affine.transform_point3(p.as_dvec3()).as_vec3())
        .collect();
    let baked = Mesh::new(baked_positions, proto.indices().to_vec(), None, 1).unwrap();
    let transform = Transform::new(affine).unwrap();
    let description = |geometry: Geometry| SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 30.0, 20.0, 6.0, 40.0),
        background: Vec3::splat(0.05),
        environment: None,
        materials: vec![
            Material::default(),
            // A constant colour: procedural textures are evaluated in object space, so they move
            // with an instance and would differ from the baked mesh's.
            Material {
                texture: Texture::Constant(Vec3::new(0.2, 0.6, 0.9)),
                reflectivity: 0.3,
                ..Material::default()
            },
        ],
        lights: vec![Light::Directional {
            direction: DVec3::new(-1.0, -0.5, -1.0).normalize(),
            irradiance: Vec3::ONE,
        }],
        geometry: Geometry {
            spheres: vec![Sphere {
                center: DVec3::new(0.0, 2.5, 0.0),
                radius: 0.8,
                material: 0,
            }],
            planes: vec![Plane {
                point: DVec3::new(0.0, 0.0, -1.5),
                normal: DVec3::Z,
                material: 0,
            }],
            ..geometry
        },
    };
    let flat = Scene::new(description(Geometry {
        meshes: vec![baked],
        ..Geometry::default()
    }))
    .unwrap();
    let instanced = Scene::new(description(Geometry {
        prototypes: vec![Prototype::mesh(proto)],
        instances: vec![Instance {
            prototype: 0,
            transform,
            material: Some(1),
        }],
        ..Geometry::default()
    }))
    .unwrap();
    let settings = RenderSettings {
        width: 96,
        height: 72,
        ..RenderSettings::default()
    };
    let a = render(&flat, &settings, &NoProgress).unwrap().film;
    let b = render(&instanced, &settings, &NoProgress).unwrap().film;
    // The two differ only by the rounding of the baked f32 vertices (the instance maps rays in
    // f64): a few pixels on silhouettes may change, the rest agree to f32 shading noise.
    let differing = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .filter(|(p, q)| (**p - **q).abs().max_element() > 1.0 / 255.0)
        .count();
    assert!(
        differing <= a.pixels().len() / 200,
        "{differing} pixels differ"
    );
    let centre_ray = Ray::new(DVec3::new(0.4, -0.3, 10.0), -DVec3::Z);
    let hit = instanced.intersect(&centre_ray).expect("the instance");
    assert_eq!(hit.material, 1);
    assert_eq!(hit.prim.placement, 1);
    assert!(matches!(
        hit.prim.local,
        LocalPrim::Triangle { mesh: 0, .. }
    ));
    let flat_hit = flat.intersect(&centre_ray).unwrap();
    assert!(
        (hit.t - flat_hit.t).abs() < 1e-5,
        "{} {}",
        hit.t,
        flat_hit.t
    );
    // Spheres, then planes, then quadrics, meshes, instances: the instance is object 3.
    assert_eq!(instanced.geometry().object_index(hit.prim), 3);
}

/// Many instances of one prototype share its BVH: the accelerator counts its triangles once, and
/// each instance is hit where its transform puts it.
#[test]
fn instances_share_one_prototype() {
    let proto = icosphere(1, 0.4, DVec3::ZERO);
    let triangles = proto.triangle_count();
    let instances: Vec<Instance> = (0..50)
        .map(|i| {
            let at = DVec3::new((i % 10) as f64, (i / 10) as f64, 0.0);
            Instance::new(0, Transform::new(DAffine3::from_translation(at)).unwrap())
        })
        .collect();
    let scene = scene_of(Geometry {
        prototypes: vec![Prototype::mesh(proto)],
        instances,
        ..Geometry::default()
    });
    assert_eq!(scene.accel().bounded_count(), triangles);
    for i in 0..50u32 {
        let at = DVec3::new((i % 10) as f64, (i / 10) as f64, 0.0);
        let ray = Ray::new(at + DVec3::new(0.01, 0.02, 5.0), -DVec3::Z);
        let hit = scene.intersect(&ray).expect("instance hit");
        assert_eq!(hit.prim.placement, 1 + i as u64);
        assert!(
            (hit.geometry.point.z - 0.4).abs() < 0.02,
            "{:?}",
            hit.geometry.point
        );
        assert!(scene.occluded(&ray, 5.0));
        assert!(!scene.occluded(&ray, 4.5));
    }
    // The slice queries agree with the single-ray ones.
    let rays: Vec<Ray> = (0..20)
        .map(|i| Ray::new(DVec3::new(i as f64 * 0.5, 0.0, 3.0), -DVec3::Z))
        .collect();
    let mut many = vec![None; rays.len()];
    scene.intersect_many(&rays, &mut many);
    for (ray, got) in rays.iter().zip(&many) {
        assert_eq!(
            got.map(|h| (h.t, h.prim)),
            scene.intersect(ray).map(|h| (h.t, h.prim))
        );
    }
    let shadow: Vec<(Ray, f64)> = rays.iter().map(|r| (*r, 3.0)).collect();
    let mut blocked = vec![false; rays.len()];
    scene.occluded_many(&shadow, &mut blocked);
    for ((ray, t_max), got) in shadow.iter().zip(&blocked) {
        assert_eq!(*got, scene.occluded(ray, *t_max));
    }
    assert!(blocked.iter().any(|&b| b) && many.iter().any(Option::is_none));
}

/// A bad instance is an error, not a panic: an unknown prototype.
#[test]
fn instance_of_a_missing_prototype_is_an_error() {
    let err = Scene::new(SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 30.0, 20.0, 6.0, 40.0),
        background: Vec3::ZERO,
        environment: None,
        materials: vec![Material::default()],
        lights: vec![],
        geometry: Geometry {
            instances: vec![Instance::new(3, Transform::IDENTITY)],
            ..Geometry::default()
        },
    })
    .unwrap_err();
    assert!(err.to_string().contains("prototype 3"), "{err}");
}

/// Rays from far away (10³ to 10⁶ times the mesh's size), aimed radially at every vertex and
/// edge midpoint of a closed convex mesh, cross its surface there and must hit it. (With
/// pbrt-v3's bound on t alone, 3584 of these 3840 rays missed at 10⁵: the bound grows with the
/// shear's absolute error; the triangle test now also accepts hits whose three vertices lie
/// clearly in front of the origin.)
#[test]
fn distant_rays_through_shared_edges_hit() {
    let mesh = icosphere(3, 1.0, DVec3::ZERO);
    let targets = directions(&mesh, DVec3::ZERO, 0);
    let scene = scene_of(Geometry {
        meshes: vec![mesh],
        ..Geometry::default()
    });
    for distance in [1e3, 1e4, 1e5, 1e6] {
        let holes = targets
            .iter()
            .filter(|&&p| {
                let origin = p.normalize() * distance;
                scene.intersect(&Ray::new(origin, p - origin)).is_none()
            })
            .count();
        assert_eq!(holes, 0, "distance {distance}: {} rays", targets.len());
    }
}

/// Rays that are not finite in f32 (a NaN origin, an origin beyond f32's range, as from a camera
/// 10³⁹ away or an instance scaled by 10⁻⁴⁰) meet nothing and never panic.
#[test]
fn rays_beyond_f32_meet_nothing_without_panicking() {
    let scene = scene_of(Geometry {
        meshes: vec![icosphere(1, 1.0, DVec3::ZERO)],
        prototypes: vec![Prototype::mesh(icosphere(1, 1.0, DVec3::ZERO))],
        instances: vec![Instance::new(
            0,
            Transform::new(DAffine3::from_scale(DVec3::splat(1e-40))).unwrap(),
        )],
        ..Geometry::default()
    });
    for ray in [
        Ray::new(DVec3::NAN, -DVec3::Z),
        Ray::new(DVec3::new(0.0, 0.0, 1e39), -DVec3::Z),
        Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::new(f64::NAN, 0.0, -1.0)),
    ] {
        assert!(scene.intersect(&ray).is_none());
        assert!(!scene.occluded(&ray, f64::INFINITY));
    }
    // The instance, scaled down by 10⁻⁴⁰, maps this ray beyond f32's range: it is skipped, and
    // the world mesh (placement 0), which the ray leaves from inside, is hit.
    let near = Ray::new(DVec3::new(0.0, 0.0, 1e-39), -DVec3::Z);
    let hit = scene.intersect(&near).map(|h| h.prim);
    assert!(
        matches!(
            hit,
            Some(PrimRef {
                placement: 0,
                local: LocalPrim::Triangle { mesh: 0, .. }
            })
        ),
        "{hit:?}"
    );
}

/// A compact mesh BVH (`BuildOptions::compact_meshes`: its leaves name their triangles instead of
/// copying their vertices) renders the same image as the default one, bit for bit, from the same
/// rays: two world meshes, an instanced prototype, a sphere and a mirror floor under a point light
/// and a sun; in fewer bytes.
#[test]
fn a_compact_mesh_bvh_renders_the_same_image() {
    let placed = DAffine3::from_translation(DVec3::new(0.5, -1.5, 0.3));
    let description = SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 30.0, 25.0, 7.0, 45.0),
        background: Vec3::splat(0.05),
        environment: None,
        materials: vec![
            Material::default(),
            Material {
                reflectivity: 0.4,
                specular: 0.5,
                ..Material::default()
            },
        ],
        lights: vec![
            Light::Point {
                position: DVec3::new(3.0, -2.0, 5.0),
                intensity: Vec3::splat(20.0),
            },
            Light::Directional {
                direction: DVec3::new(-1.0, -0.5, -1.0).normalize(),
                irradiance: Vec3::splat(0.5),
            },
        ],
        geometry: Geometry {
            meshes: vec![
                icosphere(2, 1.0, DVec3::new(-1.5, 0.0, 0.0)),
                icosphere(1, 0.6, DVec3::new(1.2, 0.8, 0.2)),
            ],
            prototypes: vec![Prototype::mesh(icosphere(2, 0.5, DVec3::ZERO))],
            instances: vec![Instance {
                prototype: 0,
                transform: Transform::new(placed).unwrap(),
                material: Some(1),
            }],
            spheres: vec![Sphere {
                center: DVec3::new(0.0, 2.0, 0.0),
                radius: 0.7,
                material: 1,
            }],
            planes: vec![Plane {
                point: DVec3::new(0.0, 0.0, -1.2),
                normal: DVec3::Z,
                material: 1,
            }],
            ..Geometry::default()
        },
    };
    let copied = Scene::new(description.clone()).unwrap();
    let compact = Scene::build(
        description,
        BuildOptions {
            compact_meshes: true,
        },
    )
    .unwrap();
    let bytes = |s: &Scene| s.accel().stats(s.geometry()).bottom_bytes;
    assert!(bytes(&compact) < bytes(&copied));
    let settings = RenderSettings {
        width: 96,
        height: 64,
        spp: 2,
        ..RenderSettings::default()
    };
    let a = render(&copied, &settings, &NoProgress).unwrap();
    let b = render(&compact, &settings, &NoProgress).unwrap();
    let bits = |f: &Film| -> Vec<[u32; 3]> {
        (f.pixels().iter())
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&a.film), bits(&b.film));
    assert_eq!(a.counts, b.counts);
    assert!(a.counts.shadow > 0 && a.counts.reflection > 0);
}
