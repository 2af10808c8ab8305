//! Tests of uniform rendering: tiles and batches against samples traced one by one.

use crate::aov::AovSelection;
use crate::camera::{Camera, Projection};
use crate::geometry::Geometry;
use crate::material::Material;
use crate::plane::Plane;
use crate::quadric::{ClipBox, Quadric, QuadricKind, QuadricSurface};
use crate::render::adaptive::tests::{white_on_black, white_shapes};
use crate::render::context::SampleContext;
use crate::render::{
    NoProgress, PixelWindow, Progress, RenderError, RenderSettings, render_with_aovs,
};
use crate::sampler::{SampleKey, pixel_pattern, sample_2d};
use crate::scene::{Scene, SceneDescription};
use crate::texture::Texture;
use crate::{RayCounts, Sphere, Transform};
use glam::{DVec3, Vec3};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A progress that asks to cancel from its `after`-th question on, and counts the rows
/// reported done.
struct CancelAtQuestion {
    after: usize,
    asked: AtomicUsize,
    rows: AtomicUsize,
}

impl Progress for CancelAtQuestion {
    fn row_done(&self) {
        self.rows.fetch_add(1, Ordering::Relaxed);
    }

    fn cancelled(&self) -> bool {
        self.asked.fetch_add(1, Ordering::Relaxed) + 1 >= self.after
    }
}

/// A cancelled render stops between tiles and reports no row of a band it left unfinished:
/// on one thread, where each tile asks once, cancelled at the third question the first band of
/// a four-tile-wide image is left after two tiles; at the sixth, the first band is finished
/// and reported, the second left after one tile.
#[test]
fn a_cancelled_render_stops_between_tiles() {
    let scene = white_on_black(vec![Sphere {
        center: DVec3::ZERO,
        radius: 1.0,
        material: 0,
    }]);
    let settings = RenderSettings {
        width: 4 * 32,
        height: 16,
        spp: 2,
        ..RenderSettings::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for (after, rows) in [(3, 0), (6, 8)] {
        let progress = CancelAtQuestion {
            after,
            asked: AtomicUsize::new(0),
            rows: AtomicUsize::new(0),
        };
        let result =
            pool.install(|| render_with_aovs(&scene, &settings, AovSelection::NONE, &progress));
        assert!(
            matches!(result, Err(RenderError::Cancelled)),
            "after {after}"
        );
        assert_eq!(progress.rows.load(Ordering::Relaxed), rows, "after {after}");
    }
}

/// Every pixel of `window` holds the mean of its own samples traced one by one, and every
/// sample is counted once; returns how many pixels are neither of `flat`'s two colours.
fn assert_pixels_are_traced(
    scene: &Scene,
    settings: &RenderSettings,
    window: PixelWindow,
    flat: [Vec3; 2],
) -> u32 {
    let spp = settings.spp;
    let (rendered, _) = render_with_aovs(scene, settings, AovSelection::NONE, &NoProgress).unwrap();
    assert_eq!(
        rendered.counts.camera,
        (window.width() * window.height() * spp) as u64
    );
    let context = SampleContext::new(scene, settings, AovSelection::NONE).unwrap();
    let cone = context.sample_cone(spp);
    let mut counts = RayCounts::default();
    let mut varied = 0;
    for y in window.y0..window.y1 {
        for x in window.x0..window.x1 {
            let pattern = pixel_pattern(x, y, settings.seed);
            let sum: Vec3 = (0..spp)
                .map(|index| {
                    let key = SampleKey {
                        pattern,
                        index,
                        count: Some(spp),
                    };
                    let offset = sample_2d(index, spp, pattern);
                    context.trace((x, y), offset, cone, key, None, &mut counts)
                })
                .sum();
            let expected = sum * (1.0 / spp as f32);
            let got = rendered.film.get(x - window.x0, y - window.y0);
            assert_eq!(got, expected, "pixel ({x}, {y})");
            varied += !flat.contains(&got) as u32;
        }
    }
    varied
}

/// Every pixel of a window whose sides are not multiples of a tile or a band holds the mean
/// of its own samples traced one by one, and every sample is traced once: tiles and bands
/// cover the window exactly.
#[test]
fn tiles_cover_every_pixel_once() {
    let scene = white_on_black(vec![
        Sphere {
            center: DVec3::new(0.3, -0.2, 0.0),
            radius: 0.9,
            material: 0,
        },
        Sphere {
            center: DVec3::new(-1.2, 1.1, 0.0),
            radius: 0.4,
            material: 0,
        },
    ]);
    // 45 columns: a whole tile of 32 and a partial one; 19 rows: two whole bands and a third.
    let window = PixelWindow {
        x0: 5,
        y0: 3,
        x1: 5 + 45,
        y1: 3 + 19,
    };
    // 1 sample a pixel takes the centre without the sampler, 3 the scalar sampler, 8 the
    // eight-wide one where the CPU has AVX2.
    for spp in [1, 3, 8] {
        let settings = RenderSettings {
            width: 64,
            height: 48,
            spp,
            crop: Some(window),
            ..RenderSettings::default()
        };
        // The spheres' edges cross the window: pixels differ, so a misplaced one would show
        // (at one sample a pixel as white pixels among black ones).
        let flat = match spp {
            1 => [Vec3::ZERO; 2],
            _ => [Vec3::ZERO, Vec3::ONE],
        };
        let varied = assert_pixels_are_traced(&scene, &settings, window, flat);
        assert!(varied > 10, "{varied} edge pixels at {spp} spp");
    }
}

/// A rough mirror sphere (GGX roughness 0.4) among white spheres outside the view, on black:
/// its pixels show the spheres through reflection directions drawn from each sample's key.
fn rough_mirror_among_spheres() -> Scene {
    let mut spheres = vec![Sphere {
        center: DVec3::ZERO,
        radius: 1.6,
        material: 1,
    }];
    spheres.extend(
        [(3.5, 0.0), (-3.5, 0.5), (0.5, 3.0), (-0.5, -3.0)].map(|(x, y)| Sphere {
            center: DVec3::new(x, y, 1.0),
            radius: 1.0,
            material: 0,
        }),
    );
    let camera = Camera {
        from: DVec3::new(0.0, 0.0, 10.0),
        to: DVec3::ZERO,
        up: DVec3::Y,
        projection: Projection::Orthographic { height: 4.0 },
    };
    let white = Material {
        texture: Texture::Constant(Vec3::ONE),
        ambient: 1.0,
        ..Material::default()
    };
    let rough_mirror = Material {
        texture: Texture::Constant(Vec3::splat(0.9)),
        ambient: 0.0,
        diffuse: 0.0,
        specular: 0.0,
        reflectivity: 1.0,
        roughness: 0.4,
        ..Material::default()
    };
    Scene::new(SceneDescription {
        camera,
        background: Vec3::ZERO,
        environment: None,
        materials: vec![white, rough_mirror],
        lights: vec![],
        geometry: Geometry {
            spheres,
            ..Geometry::default()
        },
    })
    .unwrap()
}

/// A render whose shading draws from each sample's key (glossy reflection directions) holds
/// in every pixel the mean of its samples traced one by one with their own keys, at one
/// sample a pixel (whose key is hashed only where a hit asks for it) and at several (keys
/// kept from the batch); and the keys matter there: another seed gives another image.
#[test]
fn batched_camera_rays_draw_each_samples_own_key() {
    let scene = rough_mirror_among_spheres();
    let window = PixelWindow {
        x0: 0,
        y0: 0,
        x1: 40,
        y1: 30,
    };
    // 40 samples a pixel: a batch of more rays than `Whitted::camera_rays` traces at once.
    for spp in [1, 2, 3, 8, 40] {
        let settings = |seed| RenderSettings {
            width: 40,
            height: 30,
            spp,
            seed,
            ..RenderSettings::default()
        };
        let varied = assert_pixels_are_traced(&scene, &settings(0), window, [Vec3::ZERO; 2]);
        assert!(varied > 40, "{varied} pixels lit at {spp} spp");
        let image = |seed| {
            let (rendered, _) =
                render_with_aovs(&scene, &settings(seed), AovSelection::NONE, &NoProgress).unwrap();
            rendered.film
        };
        let (a, b) = (image(0), image(7));
        let differing = (0..30)
            .flat_map(|y| (0..40).map(move |x| (x, y)))
            .filter(|&(x, y)| a.get(x, y) != b.get(x, y))
            .count();
        assert!(
            differing > 20,
            "{differing} pixels differ between seeds at {spp} spp"
        );
    }
}

/// Two spheres and a hyperboloid above a floor, white on a blue-grey background, seen by a
/// pinhole camera: many of its tiles see nothing, and the floor hides those below its horizon.
/// With `hidden` more spheres behind the camera (no camera ray meets them, and the scene has
/// no lights or mirrors), the same image; from 62 of them on, too many shapes for an eye
/// buffer, and the one box covering the shapes holds the camera, so every sample is traced.
pub(crate) fn shapes_above_a_floor(hidden: usize) -> (Scene, Vec3) {
    let mut geometry = Geometry {
        spheres: vec![
            Sphere {
                center: DVec3::new(0.5, 0.2, 0.0),
                radius: 0.7,
                material: 0,
            },
            Sphere {
                center: DVec3::new(-1.6, -0.9, 0.5),
                radius: 0.3,
                material: 0,
            },
        ],
        ..Geometry::default()
    };
    geometry.spheres.extend((0..hidden).map(|i| Sphere {
        center: DVec3::new(i as f64 * 0.1, 0.0, 20.0),
        radius: 0.01,
        material: 0,
    }));
    let t = Transform::from_srt(DVec3::splat(0.5), DVec3::ZERO, DVec3::new(-1.0, 1.0, 0.0));
    let surface = QuadricSurface::Canonical {
        kind: QuadricKind::Hyperboloid1,
        a: 1.0,
        b: 1.0,
        c: 1.0,
    };
    geometry
        .quadrics
        .push(Quadric::new(surface, ClipBox::cube(1.0), t.unwrap(), 0).unwrap());
    geometry.planes.push(Plane {
        point: DVec3::new(0.0, -1.5, 0.0),
        normal: DVec3::Y,
        material: 0,
    });
    let camera = Camera {
        from: DVec3::new(0.3, -0.4, 8.0),
        to: DVec3::ZERO,
        up: DVec3::Y,
        projection: Projection::Perspective { vfov_deg: 40.0 },
    };
    let background = Vec3::new(0.2, 0.3, 0.4);
    (white_shapes(geometry, camera, background), background)
}

/// Tiles whose rays provably meet nothing ([`shapes_above_a_floor`]) are filled with the
/// background without tracing, and hold exactly what tracing each sample gives; the scene has
/// such tiles and others.
#[test]
fn empty_tiles_hold_what_tracing_gives() {
    let (scene, background) = shapes_above_a_floor(0);
    let window = PixelWindow {
        x0: 0,
        y0: 0,
        x1: 96,
        y1: 64,
    };
    let settings = RenderSettings {
        width: 96,
        height: 64,
        spp: 3,
        ..RenderSettings::default()
    };
    let varied = assert_pixels_are_traced(&scene, &settings, window, [background, Vec3::ONE]);
    assert!(varied > 10, "{varied} edge pixels");
    let context = SampleContext::new(&scene, &settings, AovSelection::NONE).unwrap();
    // The render's tiles: 3 × 8 of 32 × 8 pixels.
    let tiles: Vec<bool> = (0..8)
        .flat_map(|band| (0..3).map(move |k| (k * 32, band * 8)))
        .map(|(x, y)| context.meets_nothing((x, y), (32, 8)))
        .collect();
    let empty = tiles.iter().filter(|&&e| e).count();
    assert!((3..=21).contains(&empty), "{empty} of {}", tiles.len());
    // The stats count the empty tiles' rays as camera rays not traced.
    let (rendered, _) =
        render_with_aovs(&scene, &settings, AovSelection::NONE, &NoProgress).unwrap();
    assert_eq!(rendered.counts.untraced_camera, empty as u64 * 32 * 8 * 3);
}
