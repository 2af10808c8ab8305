//! Renders checked against analytic facts: areas, silhouettes, and rays that must not re-hit.

use glam::{DVec3, Vec3};
use quadray::math::offset_origin;
use quadray::*;
use quadray_tests::render_with_threads;

fn white() -> Material {
    Material {
        texture: Texture::Constant(Vec3::ONE),
        ambient: 1.0,
        diffuse: 0.0,
        ..Material::default()
    }
}

fn scene(camera: Camera, geometry: Geometry) -> Scene {
    Scene::new(SceneDescription {
        camera,
        background: Vec3::ZERO,
        environment: None,
        materials: vec![white()],
        lights: vec![],
        geometry,
    })
    .unwrap()
}

fn settings(width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp: 1,
        ..RenderSettings::default()
    }
}

fn lit_pixels(film: &Film) -> usize {
    film.pixels().iter().filter(|p| p.x > 0.0).count()
}

#[test]
fn orthographic_sphere_covers_pi_r_squared_pixels() {
    // Area of the disc over the area of a pixel: π·r² / (2.5 / 400)² = 80 424.8 pixels.
    let camera = Camera {
        from: DVec3::new(0.3, -0.2, 10.0),
        to: DVec3::new(0.3, -0.2, 0.0),
        up: DVec3::Y,
        projection: Projection::Orthographic { height: 2.5 },
    };
    let sphere = Sphere {
        center: DVec3::new(0.3, -0.2, 0.0),
        radius: 1.0,
        material: 0,
    };
    let s = scene(
        camera,
        Geometry {
            spheres: vec![sphere],
            ..Geometry::default()
        },
    );
    let film = render_with_threads(&s, &settings(400, 400), 2).film;
    let expected = std::f64::consts::PI / (2.5f64 / 400.0).powi(2);
    let got = lit_pixels(&film) as f64;
    assert!(
        (got - expected).abs() / expected < 0.01,
        "{got} pixels, expected {expected:.1}"
    );
}

#[test]
fn unit_sphere_ten_thousand_units_away_is_a_full_disc() {
    // The disc spans 100 pixels across. Every pixel whose ray passes the centre closer than the
    // radius (computed here independently, in f64 point-line distance) must hit, every other miss.
    let d: f64 = 1e4;
    let vfov = (4.0 / d).to_degrees();
    let camera = Camera {
        from: DVec3::ZERO,
        to: DVec3::new(0.0, d, 0.0),
        up: DVec3::Z,
        projection: Projection::Perspective { vfov_deg: vfov },
    };
    let centre = DVec3::new(0.0, d, 0.0);
    let s = scene(
        camera,
        Geometry {
            spheres: vec![Sphere {
                center: centre,
                radius: 1.0,
                material: 0,
            }],
            ..Geometry::default()
        },
    );
    let n = 200;
    let film = render_with_threads(&s, &settings(n, n), 2).film;
    let frame = camera.prepare(1.0).unwrap();
    let (mut holes, mut phantoms, mut inside) = (0, 0, 0);
    for y in 0..n {
        for x in 0..n {
            let ray = frame.ray((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64);
            let miss_distance = centre.cross(ray.dir).length() / ray.dir.length();
            let hit = film.get(x, y).x > 0.0;
            if miss_distance < 1.0 - 1e-9 {
                inside += 1;
                holes += usize::from(!hit);
            } else if miss_distance > 1.0 + 1e-9 {
                phantoms += usize::from(hit);
            }
        }
    }
    assert!(
        inside > 7000,
        "the disc covers about π·50² pixels, got {inside}"
    );
    assert_eq!((holes, phantoms), (0, 0));
}

#[test]
fn ray_exactly_along_a_paraboloid_axis_hits_and_the_cup_has_no_holes() {
    // Odd resolution: the centre pixel's ray is exactly the axis x = y = 0 (a = 0 in the quadratic).
    let camera = Camera {
        from: DVec3::new(0.0, 0.0, 5.0),
        to: DVec3::ZERO,
        up: DVec3::Y,
        projection: Projection::Orthographic { height: 2.4 },
    };
    let cup = Quadric::new(
        QuadricSurface::Canonical {
            kind: QuadricKind::EllipticParaboloid,
            a: 1.0,
            b: 1.0,
            c: 1.0,
        },
        ClipBox {
            min: DVec3::new(-1.5, -1.5, 0.0),
            max: DVec3::new(1.5, 1.5, 1.0),
        },
        Transform::IDENTITY,
        0,
    )
    .unwrap();
    let s = scene(
        camera,
        Geometry {
            quadrics: vec![cup],
            ..Geometry::default()
        },
    );
    let n = 101;
    let film = render_with_threads(&s, &settings(n, n), 2).film;
    assert!(film.get(50, 50).x > 0.0, "the axis ray hits the vertex");
    let pixel = 2.4 / n as f64;
    for y in 0..n {
        for x in 0..n {
            let r =
                ((x as f64 + 0.5 - 50.5).powi(2) + (y as f64 + 0.5 - 50.5).powi(2)).sqrt() * pixel;
            // Inside the rim z = 1 (radius 1) every pixel hits; outside it nothing does.
            if r < 0.98 {
                assert!(film.get(x, y).x > 0.0, "hole at pixel ({x}, {y})");
            } else if r > 1.02 {
                assert_eq!(film.get(x, y).x, 0.0, "phantom at ({x}, {y})");
            }
        }
    }
}

/// Deterministic pseudo-random unit vectors (SplitMix64), so the test is repeatable.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn unit(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * self.next();
        let phi = std::f64::consts::TAU * self.next();
        let s = (1.0 - z * z).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

#[test]
fn no_acne_on_any_primitive_kind() {
    // pbrt's re-intersection protocol: from each hit, rays leaving on the side the camera ray came
    // from must not hit the same primitive again at that point (t below 1e-6 of the object size).
    let rotate = Transform::from_srt(
        DVec3::new(1.0, 1.3, 0.8),
        DVec3::new(25.0, -40.0, 70.0),
        DVec3::new(1e3, -2e3, 5e2),
    )
    .unwrap();
    let mut quadrics: Vec<Quadric> = QuadricKind::ALL
        .iter()
        .map(|&kind| {
            Quadric::new(
                QuadricSurface::Canonical {
                    kind,
                    a: 0.7,
                    b: 0.9,
                    c: 0.6,
                },
                ClipBox::cube(1.0),
                rotate,
                0,
            )
            .unwrap()
        })
        .collect();
    let mut rng = Rng(7);
    let (mut hits, mut acne) = (0, 0);
    for q in quadrics.drain(..) {
        let kind = q.class();
        let centre = rotate.to_world.translation;
        let s = scene(
            Camera::orbit(centre, 0.0, 0.0, 5.0, 40.0),
            Geometry {
                quadrics: vec![q],
                spheres: vec![Sphere {
                    center: centre + DVec3::new(0.0, 0.0, -4.0),
                    radius: 1.5,
                    material: 0,
                }],
                ..Geometry::default()
            },
        );
        let integrator = Whitted::default();
        let mut kind_hits = 0;
        for _ in 0..300 {
            let from = centre + rng.unit() * 6.0;
            let ray = Ray::new(from, (centre + rng.unit() * 0.8 - from).normalize());
            let Some(hit) = integrator.intersect(&s, &ray, None) else {
                continue;
            };
            kind_hits += 1;
            let g = hit.geometry;
            let side = if g.geometric_normal.dot(ray.dir) < 0.0 {
                g.geometric_normal
            } else {
                -g.geometric_normal
            };
            for _ in 0..50 {
                let mut dir = rng.unit();
                if dir.dot(side) < 0.0 {
                    dir = -dir;
                }
                let spawned = Ray::new(offset_origin(g.point, side, g.error, dir), dir);
                let again =
                    s.accel()
                        .closest(s.geometry(), &spawned, f64::INFINITY, Some(hit.prim));
                if again.is_some_and(|(t, prim)| prim == hit.prim && t < 1e-6) {
                    acne += 1;
                }
            }
        }
        assert!(kind_hits > 30, "{kind}: {kind_hits} hits");
        hits += kind_hits;
    }
    assert!(hits > 1000);
    assert_eq!(acne, 0);
}

/// An emitter is seen at its emission exactly, directly and in a perfect mirror, and lights no
/// other surface (Whitted tracing follows light only from the scene's lights, of which there are
/// none here): a white diffuse sphere beside it stays black.
#[test]
fn emission_is_seen_directly_and_in_mirrors_and_lights_nothing() {
    let glow = Vec3::new(2.0, 1.0, 0.5);
    let black = Texture::Constant(Vec3::ZERO);
    let materials = vec![
        Material {
            texture: black.clone(),
            emission: Some(Texture::Constant(glow)),
            ..Material::default()
        },
        Material {
            texture: black,
            reflectivity: 1.0,
            ..Material::default()
        },
        Material {
            texture: Texture::Constant(Vec3::ONE),
            ambient: 0.0,
            diffuse: 1.0,
            ..Material::default()
        },
    ];
    let scene = Scene::new(SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 0.0, 30.0, 20.0, 40.0),
        background: Vec3::ZERO,
        environment: None,
        materials,
        lights: vec![],
        geometry: Geometry {
            spheres: vec![
                Sphere {
                    center: DVec3::new(0.0, 0.0, 5.0),
                    radius: 1.0,
                    material: 0,
                },
                Sphere {
                    center: DVec3::new(5.0, 0.0, 5.0),
                    radius: 1.0,
                    material: 2,
                },
            ],
            planes: vec![Plane {
                point: DVec3::ZERO,
                normal: DVec3::Z,
                material: 1,
            }],
            ..Geometry::default()
        },
    })
    .unwrap();
    let whitted = Whitted::default();
    let mut counts = RayCounts::default();
    let down = |x: f64, z: f64| Ray::new(DVec3::new(x, 0.0, z), -DVec3::Z);
    assert_eq!(
        whitted.camera_ray(
            &scene,
            &down(0.0, 10.0),
            RayCone::POINT,
            quadray::sampler::SampleKey::LONE,
            &mut counts
        ),
        glow
    );
    // Down to the mirror at z = 0, back up to the emitter's underside.
    assert_eq!(
        whitted.camera_ray(
            &scene,
            &down(0.0, 3.0),
            RayCone::POINT,
            quadray::sampler::SampleKey::LONE,
            &mut counts
        ),
        glow
    );
    assert_eq!(counts.reflection, 1);
    assert_eq!(
        whitted.camera_ray(
            &scene,
            &down(5.0, 10.0),
            RayCone::POINT,
            quadray::sampler::SampleKey::LONE,
            &mut counts
        ),
        Vec3::ZERO
    );
}

/// Camera rays that hit nothing see the background; reflection rays that hit nothing see the
/// environment, when the scene sets one.
#[test]
fn reflections_that_miss_see_the_environment() {
    let mirror = Material {
        texture: Texture::Constant(Vec3::ZERO),
        reflectivity: 1.0,
        ..Material::default()
    };
    let scene = |environment| {
        Scene::new(SceneDescription {
            camera: Camera::orbit(DVec3::ZERO, 0.0, 30.0, 20.0, 40.0),
            background: Vec3::splat(0.1),
            environment,
            materials: vec![mirror.clone()],
            lights: vec![],
            geometry: Geometry {
                planes: vec![Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                    material: 0,
                }],
                ..Geometry::default()
            },
        })
        .unwrap()
    };
    let whitted = Whitted::default();
    let mut counts = RayCounts::default();
    let (down, up) = (
        Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::new(0.3, 0.0, -1.0)),
        Ray::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z),
    );
    let studio = scene(Some(Vec3::splat(0.5)));
    assert_eq!(
        whitted.camera_ray(
            &studio,
            &up,
            RayCone::POINT,
            quadray::sampler::SampleKey::LONE,
            &mut counts
        ),
        Vec3::splat(0.1)
    );
    assert_eq!(
        whitted.camera_ray(
            &studio,
            &down,
            RayCone::POINT,
            quadray::sampler::SampleKey::LONE,
            &mut counts
        ),
        Vec3::splat(0.5)
    );
    let plain = scene(None);
    assert_eq!(plain.environment(), Vec3::splat(0.1));
    assert_eq!(
        whitted.camera_ray(
            &plain,
            &down,
            RayCone::POINT,
            quadray::sampler::SampleKey::LONE,
            &mut counts
        ),
        Vec3::splat(0.1)
    );
    assert!(
        Scene::new(SceneDescription {
            environment: Some(Vec3::new(f32::NAN, 0.0, 0.0)),
            ..plain.into_description()
        })
        .is_err()
    );
}

/// The share of the square [x0, x0 + side] × [y0, y0 + side] that lies on odd cells of a
/// checker of cell edge `cell` (cells (i, j) with i + j odd), by summing the overlap with every
/// cell the square touches: an area count independent of the renderer's closed form.
fn odd_share(x0: f64, y0: f64, side: f64, cell: f64) -> f64 {
    let cells = |lo: f64| (lo / cell).floor() as i64..=((lo + side) / cell).floor() as i64;
    let overlap = |lo: f64, k: i64| {
        ((lo + side).min((k + 1) as f64 * cell) - lo.max(k as f64 * cell)).max(0.0)
    };
    let mut odd = 0.0;
    for i in cells(x0) {
        for j in cells(y0) {
            if (i + j).rem_euclid(2) == 1 {
                odd += overlap(x0, i) * overlap(y0, j);
            }
        }
    }
    odd / (side * side)
}

/// Pixels a side of the head-on checkerboard images.
const CHECKER_SIDE: u32 = 64;

/// A glowing checkerboard seen head-on through an orthographic camera, and every pixel's exact
/// value: the share of its square on odd cells.
fn head_on_checker() -> (Scene, Vec<f64>) {
    const HEIGHT: f64 = 8.0;
    const CELL: f64 = 0.3;
    let pixel = HEIGHT / CHECKER_SIDE as f64;
    let centre = DVec3::new(0.013, 0.021, 10.0);
    let glowing_checker = Material {
        texture: Texture::Constant(Vec3::ZERO),
        emission: Some(Texture::Checker {
            size: CELL,
            even: Vec3::ZERO,
            odd: Vec3::ONE,
        }),
        ..Material::default()
    };
    let scene = Scene::new(SceneDescription {
        camera: Camera {
            from: centre,
            to: centre - DVec3::Z,
            up: DVec3::Y,
            projection: Projection::Orthographic { height: HEIGHT },
        },
        background: Vec3::ZERO,
        environment: None,
        materials: vec![glowing_checker],
        lights: vec![],
        geometry: Geometry {
            planes: vec![Plane {
                point: DVec3::ZERO,
                normal: DVec3::Z,
                material: 0,
            }],
            ..Geometry::default()
        },
    })
    .unwrap();
    let exact = (0..CHECKER_SIDE * CHECKER_SIDE)
        .map(|k| {
            let (i, j) = ((k % CHECKER_SIDE) as f64, (k / CHECKER_SIDE) as f64);
            // +x to the right, +y up the image: row j's top edge is HEIGHT/2 − j·pixel.
            let x0 = centre.x - HEIGHT / 2.0 + i * pixel;
            let y0 = centre.y + HEIGHT / 2.0 - (j + 1.0) * pixel;
            odd_share(x0, y0, pixel, CELL)
        })
        .collect();
    (scene, exact)
}

/// The RMSE of a render of the head-on checker against its exact pixel values.
fn checker_rmse(film: &Film, exact: &[f64]) -> f64 {
    let squares: f64 = film
        .pixels()
        .iter()
        .zip(exact)
        .map(|(p, e)| (p.x as f64 - e).powi(2))
        .sum();
    (squares / exact.len() as f64).sqrt()
}

/// The head-on checker: one filtered sample a pixel averages the texture over exactly the
/// pixel's square, so it gives the pixel integral; point samples alias.
#[test]
fn one_filtered_sample_gives_a_checkered_pixel_its_exact_integral() {
    let (scene, exact) = head_on_checker();
    let rmse = |spp: u32, texture_filter: bool| {
        let settings = RenderSettings {
            spp,
            texture_filter,
            ..settings(CHECKER_SIDE, CHECKER_SIDE)
        };
        checker_rmse(
            &render(&scene, &settings, &NoProgress).unwrap().film,
            &exact,
        )
    };
    let filtered = rmse(1, true);
    assert!(filtered < 1e-5, "one filtered sample: RMSE {filtered:e}");
    let point = rmse(1, false);
    assert!(point > 0.1, "one point sample: RMSE {point:e}");
    // More samples, each a quarter of the pixel wide: jittered boxes no longer tile the pixel
    // exactly, but they stay closer than as many point samples (measured 0.016 against 0.031).
    let (filtered, point) = (rmse(16, true), rmse(16, false));
    assert!(
        filtered < point / 1.5,
        "16 spp: {filtered:e} against {point:e}"
    );
}

/// The head-on checker, adaptively: every round's samples stand for their share of the pixel
/// at the most samples a pixel may take, so the samples of all rounds estimate one filtered
/// image. Pixels brought to 64 samples over four rounds (8, 16, 32, 64) are then exactly those
/// given 64 in one round: the same points of the same sequence, filtered alike. (When each round
/// used the footprint of the count it reached, they differed, and the rounds' render was further
/// from the exact integrals: RMSE 5.5e-3 against 3.9e-3 now, measured.)
#[test]
fn adaptive_rounds_filter_textures_as_the_final_count_does() {
    let (scene, exact) = head_on_checker();
    let every_pixel_to_64 = |min_spp: u32| RenderSettings {
        // The pixel rule at target 0 takes every pixel to the maximum, round by round.
        adaptive: Some(Adaptive {
            rule: adaptive::ErrorRule::Pixel,
            target_error: 0.0,
            min_spp,
            max_spp: 64,
            time_limit: None,
            spp_budget: None,
        }),
        ..settings(CHECKER_SIDE, CHECKER_SIDE)
    };
    let in_rounds = render(&scene, &every_pixel_to_64(8), &NoProgress).unwrap();
    let at_once = render(&scene, &every_pixel_to_64(64), &NoProgress).unwrap();
    assert_eq!(in_rounds.sampling.error.map(|e| e.rounds), Some(4));
    assert_eq!(in_rounds.film, at_once.film);
    let rounds = checker_rmse(&in_rounds.film, &exact);
    assert!(rounds < 4.5e-3, "RMSE {rounds:e}");
}
