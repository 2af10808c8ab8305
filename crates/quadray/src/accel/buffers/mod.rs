//! Direction buffers for rays through one point (Haines and Greenberg's light buffer, 1986, and
//! its camera-side twin): which of the world's shapes each direction from the point can meet, so a
//! ray through the point tests those alone instead of traversing the BVH.
//!
//! A cube around the point is divided into cells ([`Cube`]). Every shape of the world (a sphere
//! or a quadric; a mesh or an instance as the top item holding it) is listed in each cell its
//! padded box, grown by `reach`, can be seen through from the point. A ray looks up the cell of its
//! direction and tests the listed shapes with the exact tests, so its answer is the BVH's: a hit
//! at `p` lies in its shape's padded box (what makes the BVH agree with a test of every shape),
//! and the direction looked up is that of a point within `reach` of `p` on every axis ([`light`]
//! and [`eye`] say why for their rays). The projection widens each cell range by [`SLACK`], which
//! covers the rounding of the divisions on both sides; the box's coordinates relative to the point
//! round by far less than `reach`. Rays the argument does not cover go to the BVH.
//!
//! - [`LightBuffer`]: shadow rays ending at a point light, blocked or not.
//! - [`EyeBuffer`]: rays from a pinhole camera's eye, where at most four spheres and quadrics, or
//!   one mesh or instance, can be met.
//!
//! Both are built only for worlds of a few shapes ([`Accel::buffered_shapes`]), where the BVH's
//! per-ray set-up and node tests cost more than the shapes themselves; light buffers on the
//! baseline path only, and the eye buffer on both, where the AVX2 path asks it which tiles of
//! pixels see nothing but traces its camera rays through the BVH ([`Accel::eye_answers_rays`]).

mod eye;
mod four;
mod light;

pub use eye::EyeBuffer;
pub use light::LightBuffer;

use super::build::padded_aabb;
use super::{Accel, TopItem};
use crate::geometry::Geometry;
use crate::shape::LocalPrim;
use glam::DVec3;
use obvhs::aabb::Aabb;

/// Most analytic shapes in the world for which buffers are built, so the lists stay short (the
/// bundled scenes have at most 10; worlds of thousands keep the BVH alone; sizes between were not
/// measured).
const MAX_SHAPES: usize = 64;
/// Widening of every projected range, in face coordinates (which run from −1 to 1): many times
/// the rounding of a quotient of f64 coordinates.
const SLACK: f64 = 1e-9;
/// `reach` as a share of the larger of the world's coordinate extent and the point's: far more
/// than a shadow ray's offset from its surface, far less than a cell.
const REACH: f64 = 1.0 / (1u64 << 24) as f64;

/// What a listed shape is: a world sphere or quadric, or a top item of the world (meshes,
/// instances).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Shape {
    Analytic(LocalPrim),
    Item(TopItem),
}

/// A shape to list, with its padded box (what decides the cells it is listed in).
#[derive(Clone, Copy, Debug)]
struct Candidate {
    bounds: Aabb,
    shape: Shape,
}

/// A cube of `n`² cells a face around a point, indexing directions from it: a direction's face
/// is that of its largest component, and its cell along each other axis that component divided by
/// the largest, from −1 to 1 in `n` equal steps.
#[derive(Clone, Copy, Debug)]
struct Cube {
    n: usize,
}

impl Cube {
    /// Number of cells.
    fn len(self) -> usize {
        6 * self.n * self.n
    }

    /// The cell of direction `d`, or `None` for a zero, subnormal or non-finite direction.
    #[inline]
    fn cell(self, d: DVec3) -> Option<usize> {
        let a = d.abs();
        let (axis, u, v) = if a.x >= a.y && a.x >= a.z {
            (0, d.y, d.z)
        } else if a.y >= a.z {
            (1, d.x, d.z)
        } else {
            (2, d.x, d.y)
        };
        let n = self.n;
        // The largest component and its magnitude, indexed as arrays: `DVec3`'s own indexing is
        // a match on the axis, a branch apiece.
        let (largest, magnitude) = (d.to_array()[axis], a.to_array()[axis]);
        // (c / m + 1)·n/2, m the largest component's magnitude, with one division for both
        // coordinates: a few ulps off the quotient, far inside the projection's slack. An
        // infinite scale (m zero, or so small that n/2m overflows) is refused: c·∞ would not be
        // the quotient.
        let scale = 0.5 * n as f64 / magnitude;
        if !(scale.is_finite() && d.is_finite()) {
            return None;
        }
        let face = 2 * axis + usize::from(largest < 0.0);
        // Clamped in f64 (a quotient rounded below −1 or above 1 stays at the edge), so the
        // conversion needs none of a saturating cast's checks.
        let top = (n - 1) as f64;
        let cell = |c: f64| {
            let x = (c * scale + 0.5 * n as f64).max(0.0).min(top);
            // SAFETY: `x` is finite (d is, and m > 0) and within [0, n − 1].
            unsafe { x.to_int_unchecked::<u32>() as usize }
        };
        Some((face * n + cell(u)) * n + cell(v))
    }

    /// The face and the two cell coordinates of direction `d` (as [`Cube::cell`] finds them), or
    /// `None` for a zero, subnormal or non-finite direction.
    fn face_cell(self, d: DVec3) -> Option<(usize, usize, usize)> {
        let cell = self.cell(d)?;
        let n = self.n;
        Some((cell / (n * n), cell / n % n, cell % n))
    }

    /// Calls `f` with every cell through which a point of the box [`lo`, `hi`] (relative to the
    /// cube's centre) can be seen from the centre.
    fn for_cells_seeing(self, lo: DVec3, hi: DVec3, mut f: impl FnMut(usize)) {
        for face in 0..6 {
            let Some((us, vs)) = self.face_cells(face, lo, hi) else {
                continue;
            };
            for u in us.0..=us.1 {
                for v in vs.0..=vs.1 {
                    f((face * self.n + u) * self.n + v);
                }
            }
        }
    }

    /// The cell ranges (first, last) along `face`'s two coordinates that the box [`lo`, `hi`] can
    /// be seen through, or `None` when none.
    fn face_cells(
        self,
        face: usize,
        lo: DVec3,
        hi: DVec3,
    ) -> Option<((usize, usize), (usize, usize))> {
        let axis = face / 2;
        // Distances along the face's axis, on its side.
        let (m0, m1) = if face.is_multiple_of(2) {
            (lo[axis], hi[axis])
        } else {
            (-hi[axis], -lo[axis])
        };
        if m1 <= 0.0 {
            return None;
        }
        let (b, c) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let u = self.range(lo[b], hi[b], m0, m1)?;
        let v = self.range(lo[c], hi[c], m0, m1)?;
        Some((u, v))
    }

    /// The cells spanned by y / m for y in [`y0`, `y1`] and m in (max(`m0`, 0), `m1`]: the
    /// quotient is smallest at y0 over the largest m when y0 ≥ 0, else over the smallest, which
    /// near 0 is −∞ (and the largest likewise).
    fn range(self, y0: f64, y1: f64, m0: f64, m1: f64) -> Option<(usize, usize)> {
        let low = if y0 >= 0.0 {
            y0 / m1
        } else if m0 > 0.0 {
            y0 / m0
        } else {
            f64::NEG_INFINITY
        };
        let high = if y1 <= 0.0 {
            y1 / m1
        } else if m0 > 0.0 {
            y1 / m0
        } else {
            f64::INFINITY
        };
        let (low, high) = (low - SLACK, high + SLACK);
        if low > 1.0 || high < -1.0 {
            return None;
        }
        let n = self.n;
        let cell = |c: f64| (((c.clamp(-1.0, 1.0) + 1.0) * (0.5 * n as f64)) as usize).min(n - 1);
        Some((cell(low), cell(high)))
    }
}

/// Whether `ray` is finite once rounded to f32, as the BVH traverses it: the BVH's answer for a
/// ray beyond f32's range is "nothing", so the buffers leave such rays to it.
#[inline(always)]
fn finite_in_f32(ray: &crate::math::Ray) -> bool {
    crate::math::all_finite(ray.origin.as_vec3a(), ray.dir.as_vec3a())
}

/// The relative box of `candidate` as listed from `point`: its padded box grown by `reach`, minus
/// the point.
fn relative_box(candidate: &Candidate, point: DVec3, reach: f64) -> (DVec3, DVec3) {
    let b = candidate.bounds;
    (
        b.min.as_dvec3() - DVec3::splat(reach) - point,
        b.max.as_dvec3() + DVec3::splat(reach) - point,
    )
}

impl Accel {
    /// The world's shapes with their padded boxes (its spheres and quadrics one by one, its other
    /// top items whole), for a world of at most [`MAX_SHAPES`] analytic shapes and no top BVH;
    /// `None` for any other.
    fn buffered_shapes(&self, g: &Geometry) -> Option<Vec<Candidate>> {
        let world = &self.levels[0];
        let level = g.level(0);
        if world.top.is_some() || level.spheres.len() + level.quadrics.len() > MAX_SHAPES {
            return None;
        }
        let extent = self.world_extent;
        let analytic = |prim: LocalPrim, bounds| Candidate {
            bounds: padded_aabb(bounds, extent),
            shape: Shape::Analytic(prim),
        };
        let mut shapes = Vec::new();
        for (&item, &bounds) in world.items.iter().zip(&world.item_boxes) {
            match item {
                TopItem::Analytic => {
                    for (i, s) in level.spheres.iter().enumerate() {
                        shapes.push(analytic(LocalPrim::Sphere(i as u32), s.bounds()));
                    }
                    for (i, q) in level.quadrics.iter().enumerate() {
                        shapes.push(analytic(LocalPrim::Quadric(i as u32), q.bounds()));
                    }
                }
                _ => shapes.push(Candidate {
                    bounds,
                    shape: Shape::Item(item),
                }),
            }
        }
        Some(shapes)
    }

    /// `reach` for buffers around `point` ([`REACH`]).
    fn reach(&self, point: DVec3) -> f64 {
        (self.world_extent as f64).max(point.abs().max_element()) * REACH
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells a box is seen through hold the direction of every point of the box: its corners,
    /// and random points inside it and on its faces (boxes around the centre too), on cubes of
    /// several sizes.
    #[test]
    fn boxes_are_seen_through_the_cells_of_their_points() {
        let mut unit = crate::test_rng::unit_stream(0x9e37_79b9_7f4a_7c15);
        let mut next = || unit() - 0.5;
        for n in [1, 7, 32, 128] {
            let cube = Cube { n };
            for _ in 0..5_000 {
                let c = DVec3::new(next(), next(), next()) * 10.0;
                let h = DVec3::new(next().abs(), next().abs(), next().abs());
                let (lo, hi) = (c - h, c + h);
                let mut seen = vec![false; cube.len()];
                cube.for_cells_seeing(lo, hi, |cell| seen[cell] = true);
                for k in 0..24 {
                    let pick = |bit: u32, r: f64| match (k < 8, k & bit != 0) {
                        (true, false) => 0.0,
                        (true, true) => 1.0,
                        (false, _) => (r * 1.2 + 0.5).clamp(0.0, 1.0),
                    };
                    let t = DVec3::new(pick(1, next()), pick(2, next()), pick(4, next()));
                    let p = lo + (hi - lo) * t;
                    if p == DVec3::ZERO {
                        continue;
                    }
                    let cell = cube.cell(p).expect("a non-zero direction");
                    assert!(seen[cell], "{p} in [{lo}, {hi}], {n} cells a face");
                }
            }
        }
        let cube = Cube { n: 32 };
        assert_eq!(cube.cell(DVec3::ZERO), None);
        assert_eq!(cube.cell(DVec3::new(f64::NAN, 1.0, 0.0)), None);
        assert_eq!(cube.cell(DVec3::new(f64::INFINITY, 1.0, 0.0)), None);
        // A subnormal largest component: n/2m overflows.
        assert_eq!(cube.cell(DVec3::new(1e-320, 0.0, 1e-321)), None);
        assert_eq!(
            cube.cell(DVec3::new(0.0, -1e-300, 0.0)),
            Some(3 * 32 * 32 + 16 * 32 + 16)
        );
    }
}
