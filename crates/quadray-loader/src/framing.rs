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
    if exact_bounds(g, 0, DAffine3::IDENTITY, &mut acc, &mut budget) {
        return (acc.0.cmple(acc.1).all()).then_some(acc);
    }
    boxed_bounds(g)
}

/// Most vertex and instance placements [`geometry_bounds`] computes before it settles for boxes
/// of boxes.
pub const EXACT_BOUNDS_WORK: u64 = 20_000_000;

/// Grows `acc` by level `level` placed by `m`; false when `budget` runs out.
fn exact_bounds(
    g: &Geometry,
    level: usize,
    m: DAffine3,
    acc: &mut (DVec3, DVec3),
    budget: &mut u64,
) -> bool {
    let l = g.level(level);
    let mut grow = |p: DVec3| {
        acc.0 = acc.0.min(p);
        acc.1 = acc.1.max(p);
    };
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
            grow(b.0);
            grow(b.1);
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
            && exact_bounds(
                g,
                inst.prototype as usize + 1,
                m * inst.transform.to_world,
                acc,
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
    let level_box = |level: quadray::Level<'_>, boxes: &[Option<(DVec3, DVec3)>]| {
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
            let Some(Some((a, b))) = boxes.get(inst.prototype as usize) else {
                continue;
            };
            for c in corners((*a, *b)) {
                let w = inst.transform.to_world.transform_point3(c);
                grow((w, w));
            }
        }
        (lo.cmple(hi).all()).then_some((lo, hi))
    };
    for i in 0..g.prototypes.len() {
        let b = level_box(g.level(i + 1), &boxes);
        boxes.push(b);
    }
    level_box(g.level(0), &boxes)
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

/// Share of the image's width and height the framed bounds may fill: a 5% margin on each side.
const FRAMING_FILL: f64 = 0.9;

/// A perspective camera framing bounds `(lo, hi)` in an image of `aspect` (width / height): from
/// the front-right and above (a three-quarter view; the front of a y-up file faces −y after
/// import), with a 40° vertical field of view. The camera keeps that direction and moves as close
/// as it can while the eight corners of the bounds stay inside the image with a 5% margin, its
/// target shifted sideways so the projected box is centred (as "frame all" does in a modeller).
pub fn framing_camera(bounds: Option<(DVec3, DVec3)>, aspect: f64) -> Camera {
    const VFOV: f64 = 40.0;
    const YAW: f64 = -65.0;
    const PITCH: f64 = 25.0;
    let Some((lo, hi)) = bounds.filter(|(lo, hi)| lo.is_finite() && hi.is_finite()) else {
        return Camera::orbit(DVec3::ZERO, YAW, PITCH, 3.0, VFOV);
    };
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let unit = Camera::orbit(centre, YAW, PITCH, 1.0, VFOV);
    let forward = (unit.to - unit.from).normalize();
    let up = unit.up.normalize();
    let right = forward.cross(up);
    let half_height = (VFOV * 0.5).to_radians().tan() * FRAMING_FILL;
    let half_width = half_height * aspect.clamp(1e-3, 1e3);
    // Each corner as (depth offset along the view, x, y) relative to the centre: at distance d
    // its depth is d + offset, and it is inside when |x − shift| ≤ half_width · depth (same in y).
    let seen: Vec<DVec3> = corners((lo, hi))
        .map(|corner| {
            let v = corner - centre;
            DVec3::new(v.dot(forward), v.dot(right), v.dot(up))
        })
        .collect();
    // The shifts that keep every corner inside, per axis, at distance d: an interval (maybe empty).
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
    // any direction and shift 0 satisfies) and zero.
    let mut far = radius / half_height.min(half_width).atan().sin() + radius;
    let mut near = 0.0;
    for _ in 0..64 {
        let mid = 0.5 * (near + far);
        if fits(mid) {
            far = mid;
        } else {
            near = mid;
        }
    }
    // Centre the projected box: the shift at which its projections reach equally far to both
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
    Camera::orbit(target, YAW, PITCH, far, VFOV)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_camera_fits_the_bounds_to_the_image() {
        let lo = DVec3::new(-1.0, -2.0, 0.0);
        let hi = DVec3::new(3.0, 2.0, 1.0);
        for aspect in [0.5, 4.0 / 3.0, 16.0 / 9.0, 3.0] {
            let cam = framing_camera(Some((lo, hi)), aspect);
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
}
