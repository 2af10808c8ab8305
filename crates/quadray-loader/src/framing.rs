//! What a scene without a camera or lights gets: the bounds of its geometry, a camera fitted to
//! them, and a key light over the camera's shoulder.

use glam::{DAffine3, DVec3, Vec3};
use quadray::{Camera, Geometry, Light};

/// Bounds of the bounded primitives of `g`, instances included, if any (for framing a camera).
///
/// Mesh vertices are placed through every instance path, so the box is the one the same scene
/// written flat would have, as long as the expansion stays small (at most [`EXACT_BOUNDS_WORK`]
/// vertex placements); beyond, each prototype's box is placed by its instances instead (a box of
/// boxes: never smaller, possibly larger). Spheres and quadrics under instances contribute their
/// boxes' placed corners.
pub fn geometry_bounds(g: &Geometry) -> Option<(DVec3, DVec3)> {
    let mut acc = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut budget = EXACT_BOUNDS_WORK;
    let mut grow = |p: DVec3| {
        acc.0 = acc.0.min(p);
        acc.1 = acc.1.max(p);
    };
    if place_points(g, 0, DAffine3::IDENTITY, &mut grow, &mut budget) {
        return (acc.0.cmple(acc.1).all()).then_some(acc);
    }
    boxed_bounds(g)
}

/// Most vertex and instance placements [`geometry_bounds`] computes before it settles for boxes
/// of boxes.
pub const EXACT_BOUNDS_WORK: u64 = 20_000_000;

/// Slices across the framing view that [`framing_points`] summarises the geometry in.
const FRAMING_SLICES: usize = 256;

/// The framing view's direction: azimuth and elevation of the camera about its target, degrees
/// (from the front-right and above), and its vertical field of view.
const FRAMING_YAW: f64 = -65.0;
const FRAMING_PITCH: f64 = 25.0;
const FRAMING_VFOV: f64 = 40.0;

/// A few points that stand for the geometry of `g` when [`framing_camera`] fits its view, so
/// the view fits what is there rather than its bounding box (a thin model lying diagonally fills
/// a small part of its box's projection).
///
/// Every placed vertex and shape box corner is sorted by its depth along the framing view into
/// `FRAMING_SLICES` slices; each slice gives two points at its nearest depth, one at its least
/// sideways and vertical offsets, one at its greatest. A point nearer the camera projects
/// farther out, so a view that holds these points holds every vertex behind them. Within the
/// same work budget as [`geometry_bounds`]; beyond it, the eight corners of the bounds.
pub fn framing_points(g: &Geometry) -> Vec<DVec3> {
    let Some((lo, hi)) = geometry_bounds(g) else {
        return Vec::new();
    };
    let (forward, right, up) = framing_axes();
    let depths = corners((lo, hi)).map(|c| c.dot(forward));
    let (near, far) = depths.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
        (a.min(d), b.max(d))
    });
    let slice_depth = (far - near) / FRAMING_SLICES as f64;
    if !(slice_depth > 0.0 && slice_depth.is_finite()) {
        return corners((lo, hi)).collect();
    }
    // Per slice: nearest depth, least and greatest offsets right and up.
    let empty = (
        f64::INFINITY,
        DVec3::splat(f64::INFINITY),
        DVec3::splat(f64::NEG_INFINITY),
    );
    let mut slices = vec![empty; FRAMING_SLICES];
    let mut budget = EXACT_BOUNDS_WORK;
    let mut add = |p: DVec3| {
        let depth = p.dot(forward);
        let i = (((depth - near) / slice_depth) as usize).min(FRAMING_SLICES - 1);
        let offset = DVec3::new(0.0, p.dot(right), p.dot(up));
        let slice = &mut slices[i];
        *slice = (slice.0.min(depth), slice.1.min(offset), slice.2.max(offset));
    };
    if !place_points(g, 0, DAffine3::IDENTITY, &mut add, &mut budget) {
        return corners((lo, hi)).collect();
    }
    slices
        .iter()
        .filter(|(depth, _, _)| depth.is_finite())
        .flat_map(|&(depth, least, greatest)| {
            [least, greatest].map(|o| forward * depth + right * o.y + up * o.z)
        })
        .collect()
}

/// The framing view's forward, right and up directions.
fn framing_axes() -> (DVec3, DVec3, DVec3) {
    let unit = Camera::orbit(DVec3::ZERO, FRAMING_YAW, FRAMING_PITCH, 1.0, FRAMING_VFOV);
    let forward = (unit.to - unit.from).normalize();
    let up = unit.up.normalize();
    (forward, forward.cross(up), up)
}

/// Visits every vertex and shape box corner of level `level` placed by `m`, instances
/// included; false when `budget` runs out.
fn place_points(
    g: &Geometry,
    level: usize,
    m: DAffine3,
    grow: &mut impl FnMut(DVec3),
    budget: &mut u64,
) -> bool {
    let l = g.level(level);
    let identity = level == 0;
    // A shape's box costs its eight corners.
    let shapes = 8 * (l.spheres.len() + l.quadrics.len()) as u64;
    if *budget < shapes {
        return false;
    }
    *budget -= shapes;
    for b in l
        .spheres
        .iter()
        .map(|s| s.bounds())
        .chain(l.quadrics.iter().map(|q| q.bounds()))
    {
        if identity {
            corners(b).for_each(&mut *grow);
        } else {
            corners(b).for_each(|c| grow(m.transform_point3(c)));
        }
    }
    for mesh in l.meshes {
        let n = mesh.positions().len() as u64;
        if *budget < n {
            return false;
        }
        *budget -= n;
        for p in mesh.positions() {
            grow(m.transform_point3(p.as_dvec3()));
        }
    }
    l.instances.iter().all(|inst| {
        // Each placement costs one unit, so a deep DAG of shapes without vertices ends too.
        *budget = budget.saturating_sub(1);
        *budget > 0
            && place_points(
                g,
                inst.prototype as usize + 1,
                m * inst.transform.to_world,
                grow,
                budget,
            )
    })
}

/// The eight corners of a box.
fn corners((a, b): (DVec3, DVec3)) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |c| {
        DVec3::new(
            if c & 1 == 0 { a.x } else { b.x },
            if c & 2 == 0 { a.y } else { b.y },
            if c & 4 == 0 { a.z } else { b.z },
        )
    })
}

/// Bounds as boxes of boxes: each prototype's box once, children first, placed by its instances'
/// transforms.
fn boxed_bounds(g: &Geometry) -> Option<(DVec3, DVec3)> {
    let mut boxes: Vec<Option<(DVec3, DVec3)>> = Vec::with_capacity(g.level_count());
    for i in 0..g.prototypes.len() {
        let b = level_box(g.level(i + 1), &boxes);
        boxes.push(b);
    }
    level_box(g.level(0), &boxes)
}

/// The box of what `level` holds, its instances' prototypes placed as the boxes in
/// `prototype_boxes` (by prototype; `None`, or a prototype past the list, holds nothing); `None`
/// when it holds nothing.
pub(crate) fn level_box(
    level: quadray::Level<'_>,
    prototype_boxes: &[Option<(DVec3, DVec3)>],
) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut grow = |(a, b): (DVec3, DVec3)| {
        lo = lo.min(a);
        hi = hi.max(b);
    };
    level.spheres.iter().for_each(|s| grow(s.bounds()));
    level.quadrics.iter().for_each(|q| grow(q.bounds()));
    for m in level.meshes {
        for p in m.positions() {
            let p = p.as_dvec3();
            grow((p, p));
        }
    }
    for inst in level.instances {
        let Some(Some((a, b))) = prototype_boxes.get(inst.prototype as usize) else {
            continue;
        };
        for c in corners((*a, *b)) {
            let w = inst.transform.to_world.transform_point3(c);
            grow((w, w));
        }
    }
    (lo.cmple(hi).all()).then_some((lo, hi))
}

/// Irradiance of the default key light: a white matte surface facing it shows 0.1 + 0.9·0.8 =
/// 0.82 (0.92 on the display), short of clipping, as glTF viewers' neutral lighting keeps white
/// below full white; at 1 such surfaces clipped to flat white.
pub const KEY_LIGHT_IRRADIANCE: f32 = 0.8;

/// The default key light when a file brings none: a directional light over the camera's left
/// shoulder, so that the visible sides are lit and shadows fall away to the lower right.
pub fn default_key_light(camera: &Camera) -> Light {
    let forward = (camera.to - camera.from).normalize_or(DVec3::Y);
    let right = forward.cross(camera.up).normalize_or(DVec3::X);
    let up = right.cross(forward);
    let towards_light = (-forward + up * 1.2 - right * 0.6).normalize();
    Light::Directional {
        direction: -towards_light,
        irradiance: Vec3::splat(KEY_LIGHT_IRRADIANCE),
    }
}

/// `camera` (a file's, which has a view direction but no target) aimed at the depth of the
/// middle of `bounds`: its target moves along the view to the point nearest the bounds' centre,
/// so an orbit (the viewer's drag, `--orbit-frames`) turns about the scene instead of about a
/// point one unit in front of the lens. What the camera shows is unchanged. A scene wholly
/// behind the camera leaves the target where it was.
pub fn aimed_into(camera: Camera, bounds: Option<(DVec3, DVec3)>) -> Camera {
    let Some((lo, hi)) = bounds else {
        return camera;
    };
    let Some(forward) = (camera.to - camera.from).try_normalize() else {
        return camera;
    };
    let depth = ((lo + hi) * 0.5 - camera.from).dot(forward);
    let farthest = corners((lo, hi))
        .map(|c| (c - camera.from).dot(forward))
        .fold(f64::NEG_INFINITY, f64::max);
    let depth = if depth > 0.0 { depth } else { 0.5 * farthest };
    if !(depth > 0.0 && depth.is_finite()) {
        return camera;
    }
    Camera {
        to: camera.from + forward * depth,
        ..camera
    }
}

/// Share of the image's width and height the framed bounds may fill: a 5% margin on each side.
const FRAMING_FILL: f64 = 0.9;

/// A perspective camera framing `points` (from [`framing_points`]) in an image of `aspect`
/// (width / height): from the front-right and above (a three-quarter view; the front of a y-up
/// file faces −y after import), with a 40° vertical field of view. The camera keeps that
/// direction and moves as close as it can while every point stays inside the image with a 5%
/// margin, its target shifted sideways so the points' projection is centred (as "frame all" does
/// in a modeller).
pub fn framing_camera(points: &[DVec3], aspect: f64) -> Camera {
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return Camera::orbit(DVec3::ZERO, FRAMING_YAW, FRAMING_PITCH, 3.0, FRAMING_VFOV);
    }
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let (forward, right, up) = framing_axes();
    let half_height = (FRAMING_VFOV * 0.5).to_radians().tan() * FRAMING_FILL;
    let half_width = half_height * aspect.clamp(1e-3, 1e3);
    // Each point as (depth offset along the view, x, y) relative to the centre: at distance d
    // its depth is d + offset, and it is inside when |x − shift| ≤ half_width · depth (same in y).
    let seen: Vec<DVec3> = points
        .iter()
        .map(|point| {
            let v = point - centre;
            DVec3::new(v.dot(forward), v.dot(right), v.dot(up))
        })
        .collect();
    // The shifts that keep every point inside, per axis, at distance d: an interval (maybe empty).
    let shifts = |d: f64, axis: usize, half: f64| {
        seen.iter()
            .fold((f64::NEG_INFINITY, f64::INFINITY), |(low, high), c| {
                let depth = d + c.x;
                (
                    low.max(c[axis] - half * depth),
                    high.min(c[axis] + half * depth),
                )
            })
    };
    let fits = |d: f64| {
        let (x, y) = (shifts(d, 1, half_width), shifts(d, 2, half_height));
        seen.iter().all(|c| d + c.x > 0.0) && x.0 <= x.1 && y.0 <= y.1
    };
    // Fitting is monotone in d: bisect between a distance that fits (the bounding sphere's, which
    // any direction and shift 0 satisfies) and the sphere's radius. The camera stays outside the
    // sphere: nearer, a model with a thin part pointing at the lens would be framed by that part
    // alone, seen from inside the model's extent.
    let mut far = radius / half_height.min(half_width).atan().sin() + radius;
    let mut near = radius;
    for _ in 0..64 {
        let mid = 0.5 * (near + far);
        if fits(mid) {
            far = mid;
        } else {
            near = mid;
        }
    }
    // Centre the projected points: the shift at which they reach equally far to both
    // sides, (max + min) of (c − s) / depth = 0, decreasing in s; it lies in the shifts that fit.
    let centred = |axis: usize, half: f64| {
        let (mut low, mut high) = shifts(far, axis, half);
        for _ in 0..64 {
            let s = 0.5 * (low + high);
            let (lowest, highest) =
                seen.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                        let p = (c[axis] - s) / (far + c.x);
                        (a.min(p), b.max(p))
                    });
            if lowest + highest > 0.0 {
                low = s;
            } else {
                high = s;
            }
        }
        0.5 * (low + high)
    };
    let target = centre + right * centred(1, half_width) + up * centred(2, half_height);
    Camera::orbit(target, FRAMING_YAW, FRAMING_PITCH, far, FRAMING_VFOV)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_camera_fits_the_bounds_to_the_image() {
        let lo = DVec3::new(-1.0, -2.0, 0.0);
        let hi = DVec3::new(3.0, 2.0, 1.0);
        for aspect in [0.5, 4.0 / 3.0, 16.0 / 9.0, 3.0] {
            let cam = framing_camera(&corners((lo, hi)).collect::<Vec<_>>(), aspect);
            let frame = cam.prepare(aspect).unwrap();
            // Project the corners through the camera itself: every one inside the 5% margin, and
            // the box touching the margin on at least one side (the closest such camera).
            let (mut min, mut max) = (glam::DVec2::splat(1.0), glam::DVec2::splat(0.0));
            for p in corners((lo, hi)) {
                let uv = frame.project(p).expect("in front of the camera");
                min = min.min(uv);
                max = max.max(uv);
            }
            assert!(min.min_element() > 0.05 - 1e-9 && max.max_element() < 0.95 + 1e-9);
            let touches = [min.x, min.y, 1.0 - max.x, 1.0 - max.y]
                .iter()
                .any(|m| (m - 0.05).abs() < 1e-6);
            assert!(touches, "aspect {aspect}: {min} .. {max}");
            // Centred: equal margins on opposite sides.
            assert!(
                (min.x - (1.0 - max.x)).abs() < 1e-6,
                "aspect {aspect}: {min} .. {max}"
            );
            assert!(
                (min.y - (1.0 - max.y)).abs() < 1e-6,
                "aspect {aspect}: {min} .. {max}"
            );
            default_key_light(&cam).validate().unwrap();
        }
    }

    /// A thin rod lying diagonally in its box: framed by its box, its projection spans a small
    /// part of the image; framed by its vertices, it reaches the margin.
    #[test]
    fn framing_fits_what_is_there_not_its_box() {
        use glam::Vec3;
        // A diagonal of its box 30° off the default view (yaw −65°, pitch 25°): its projection
        // is short, its box's wide.
        let (a, b) = (Vec3::new(-4.0, 3.0, 0.0), Vec3::new(4.0, -3.0, 2.0));
        let w = Vec3::new(0.02, -0.02, 0.0);
        let rod = quadray::Mesh::new(
            vec![a, b, b + w, a + w],
            vec![[0, 1, 2], [0, 2, 3]],
            None,
            0,
        )
        .unwrap();
        let g = Geometry {
            meshes: vec![rod],
            ..Geometry::default()
        };
        let points = framing_points(&g);
        let box_points: Vec<DVec3> = corners(geometry_bounds(&g).unwrap()).collect();
        // The rod's extent on the image: the larger side of its projection, and its centre.
        let extent = |cam: Camera| {
            let frame = cam.prepare(16.0 / 9.0).unwrap();
            let (mut min, mut max) = (
                glam::DVec2::splat(f64::INFINITY),
                glam::DVec2::splat(f64::NEG_INFINITY),
            );
            for p in g.meshes[0].positions() {
                let uv = frame.project(p.as_dvec3()).expect("in front");
                assert!(
                    uv.min_element() > 0.05 - 1e-3 && uv.max_element() < 0.95 + 1e-3,
                    "{uv}"
                );
                min = min.min(uv);
                max = max.max(uv);
            }
            (min, max)
        };
        let ((box_min, box_max), (min, max)) = (
            extent(framing_camera(&box_points, 16.0 / 9.0)),
            extent(framing_camera(&points, 16.0 / 9.0)),
        );
        // Measured: by its box, the rod spans 0.56 of the width, off to the right (margins 0.39
        // and 0.05); by its vertices, 0.71, centred.
        let (boxed, fitted) = ((box_max - box_min).max_element(), (max - min).max_element());
        assert!(fitted > boxed + 0.1, "box {boxed}, vertices {fitted}");
        let off_centre = |min: glam::DVec2, max: glam::DVec2| {
            (min - (glam::DVec2::ONE - max)).abs().max_element()
        };
        assert!(off_centre(min, max) < 1e-3, "{min} .. {max}");
        assert!(off_centre(box_min, box_max) > 0.2, "{box_min} .. {box_max}");
    }

    /// The framing points bound the geometry as seen from the framing view: each shape's box
    /// corner has points no farther from the camera that reach at least as far to each side.
    #[test]
    fn framing_points_hold_the_geometry() {
        let sphere = quadray::Sphere {
            center: DVec3::new(1.0, 2.0, 3.0),
            radius: 0.5,
            material: 0,
        };
        let g = Geometry {
            spheres: vec![
                sphere.clone(),
                quadray::Sphere {
                    center: DVec3::new(-3.0, 0.0, 0.0),
                    ..sphere
                },
            ],
            ..Geometry::default()
        };
        let points = framing_points(&g);
        let (lo, hi) = geometry_bounds(&g).unwrap();
        // The empty gap between the spheres holds no point.
        let (forward, right, up) = framing_axes();
        let slice = (hi - lo).length() / FRAMING_SLICES as f64;
        for s in &g.spheres {
            for corner in corners(s.bounds()) {
                // Along each image axis, on each side, some point no farther and within a slice's
                // depth is offset at least as far.
                let d = corner.dot(forward);
                for axis in [right, up, -right, -up] {
                    assert!(
                        points.iter().any(|p| {
                            (d - slice - 1e-9..=d + 1e-9).contains(&p.dot(forward))
                                && p.dot(axis) >= corner.dot(axis) - 1e-12
                        }),
                        "{corner} along {axis}"
                    );
                }
            }
        }
        let gap = DVec3::new(-1.0, 1.0, 1.5);
        assert!(points.iter().all(|p| (*p - gap).length() > 1.0));
        assert!(framing_points(&Geometry::default()).is_empty());
    }

    /// A file's camera keeps its view and gets a target at the depth of the scene's middle.
    #[test]
    fn a_files_camera_is_aimed_into_the_scene() {
        let cam = Camera {
            from: DVec3::new(0.0, -10.0, 1.0),
            to: DVec3::new(0.0, -9.0, 1.0),
            up: DVec3::Z,
            projection: quadray::Projection::Perspective { vfov_deg: 40.0 },
        };
        let bounds = Some((DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, 3.0, 2.0)));
        let aimed = aimed_into(cam, bounds);
        assert_eq!(aimed.from, cam.from);
        assert!(
            (aimed.to - DVec3::new(0.0, 1.0, 1.0)).length() < 1e-12,
            "{}",
            aimed.to
        );
        // Wholly behind the camera: unchanged.
        let behind = Some((DVec3::new(-1.0, -30.0, 0.0), DVec3::new(1.0, -20.0, 2.0)));
        assert_eq!(aimed_into(cam, behind), cam);
        assert_eq!(aimed_into(cam, None), cam);
    }
}
