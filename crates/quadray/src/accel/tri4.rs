//! Four triangles in structure-of-arrays form, tested against one ray at once with the watertight
//! test of [`crate::triangle`] in glam's `Vec4` (SSE2 on x86-64, NEON on aarch64).
//!
//! Each lane performs exactly the scalar test's arithmetic in the same order (its sign test on
//! the edge functions is written with a minimum and a maximum, which decide the same), so a
//! triangle gives the same answer in a block as alone, and shared edges stay watertight across
//! blocks. Unused lanes hold NaN vertices, which no comparison accepts.

use crate::triangle::{self, ShearedRay, gamma32};
use glam::{BVec4A, DVec3, Vec4};

/// Marks an unused lane of a block.
pub(crate) const NO_TRIANGLE: u32 = u32::MAX;

/// Four triangles: `v[3·vertex + axis]` holds that coordinate of the four triangles.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct Tri4 {
    v: [[f32; 4]; 9],
    /// Each lane's triangle, numbered in the BVH's triangle order; [`NO_TRIANGLE`] when unused.
    pub(crate) tri: [u32; 4],
}

/// The nearest lane a ray hits in a block.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneHit {
    /// Which lane.
    pub(crate) lane: usize,
    /// Ray parameter.
    pub(crate) t: f32,
    /// Barycentric weights of the lane's vertices 0, 1, 2.
    pub(crate) barycentrics: [f32; 3],
}

/// A ray's per-lane candidate hits in a block: which lanes hit, and the arrays to finish them.
pub(crate) struct BlockHits {
    pub(crate) valid: u32,
    t: [f32; 4],
    u: [f32; 4],
    v: [f32; 4],
    w: [f32; 4],
}

impl BlockHits {
    /// No lane hit.
    const NONE: BlockHits = BlockHits {
        valid: 0,
        t: [0.0; 4],
        u: [0.0; 4],
        v: [0.0; 4],
        w: [0.0; 4],
    };

    /// The nearest of the lanes set in `mask` (a subset of `valid`).
    #[inline(always)]
    pub(crate) fn nearest(&self, mask: u32) -> Option<LaneHit> {
        let mut best: Option<usize> = None;
        for lane in 0..4 {
            if mask & (1 << lane) != 0 && best.is_none_or(|b| self.t[lane] < self.t[b]) {
                best = Some(lane);
            }
        }
        best.map(|lane| {
            let inv = 1.0 / (self.u[lane] + self.v[lane] + self.w[lane]);
            LaneHit {
                lane,
                t: self.t[lane],
                barycentrics: [self.u[lane] * inv, self.v[lane] * inv, self.w[lane] * inv],
            }
        })
    }
}

impl Tri4 {
    /// A block with every lane unused.
    pub(crate) const EMPTY: Tri4 = Tri4 {
        v: [[f32::NAN; 4]; 9],
        tri: [NO_TRIANGLE; 4],
    };

    /// A block of up to four triangles (`tri` numbers them); missing lanes stay unused.
    #[cfg(test)]
    pub(crate) fn new(triangles: &[([[f32; 3]; 3], u32)]) -> Tri4 {
        debug_assert!(triangles.len() <= 4);
        let mut block = Tri4::EMPTY;
        for (lane, &(vertices, tri)) in triangles.iter().enumerate() {
            block.set(lane, vertices, tri);
        }
        block
    }

    /// Puts triangle number `tri` with `vertices` in lane `lane` (below 4).
    pub(crate) fn set(&mut self, lane: usize, vertices: [[f32; 3]; 3], tri: u32) {
        for (vertex, p) in vertices.iter().enumerate() {
            for (axis, &coordinate) in p.iter().enumerate() {
                self.v[3 * vertex + axis][lane] = coordinate;
            }
        }
        self.tri[lane] = tri;
    }

    /// How many lanes are in use: lanes fill from the first.
    pub(crate) fn lanes_used(&self) -> usize {
        self.tri.iter().take_while(|&&t| t != NO_TRIANGLE).count()
    }

    /// The vertices of lane `lane` (below 4)'s triangle, in f64.
    #[inline(always)]
    pub(crate) fn vertices(&self, lane: usize) -> [DVec3; 3] {
        // Masked to a lane, so the nine reads need no bounds checks: as nested closures with
        // them, this was a call a vertex and 60 instructions a hit (3% of a camera-rays-only
        // kitchen frame's instructions).
        let lane = lane & 3;
        let v = &self.v;
        let at = |row: usize| v[row][lane] as f64;
        [
            DVec3::new(at(0), at(1), at(2)),
            DVec3::new(at(3), at(4), at(5)),
            DVec3::new(at(6), at(7), at(8)),
        ]
    }

    /// Vertex `vertex`'s permuted, sheared coordinates for all lanes: (x', y', z before sz).
    #[inline(always)]
    fn shear(&self, ray: &ShearedRay, vertex: usize) -> (Vec4, Vec4, Vec4) {
        let [kx, ky, kz] = ray.axes();
        let [ox, oy, oz] = ray.permuted_origin();
        let (sx, sy, _) = ray.shear_constants();
        let z = Vec4::from(self.v[3 * vertex + kz]) - Vec4::splat(oz);
        let x = (Vec4::from(self.v[3 * vertex + kx]) - Vec4::splat(ox)) - Vec4::splat(sx) * z;
        let y = (Vec4::from(self.v[3 * vertex + ky]) - Vec4::splat(oy)) - Vec4::splat(sy) * z;
        (x, y, z)
    }

    /// The lanes among `lanes` (bit l for lane l) whose triangle the ray meets in (δt, `t_max`),
    /// with what is needed to finish them. The other lanes are computed alike but decide nothing:
    /// neither the early exits nor the fallbacks to f64 wait on them.
    #[inline(always)]
    pub(crate) fn intersect(&self, ray: &ShearedRay, t_max: f32, lanes: u32) -> BlockHits {
        let (ax, ay, az) = self.shear(ray, 0);
        let (bx, by, bz) = self.shear(ray, 1);
        let (cx, cy, cz) = self.shear(ray, 2);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let degenerate = u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero);
        if degenerate.bitmask() & lanes != 0 {
            // An edge function rounded to zero: recompute that lane in f64, where the products
            // are exact (only that lane, as the scalar test does).
            let f = |a: Vec4, b: Vec4, c: Vec4, d: Vec4| {
                let (a, b, c, d) = (a.to_array(), b.to_array(), c.to_array(), d.to_array());
                Vec4::from_array(std::array::from_fn(|i| {
                    (a[i] as f64 * b[i] as f64 - c[i] as f64 * d[i] as f64) as f32
                }))
            };
            u = Vec4::select(degenerate, f(cx, by, cy, bx), u);
            v = Vec4::select(degenerate, f(ax, cy, ay, cx), v);
            w = Vec4::select(degenerate, f(bx, ay, by, ax), w);
        }
        // Signs mixed (some edge function below zero and some above): the least below zero and
        // the greatest above, four comparisons fewer than testing each function. A lane with a
        // NaN function (and so a NaN determinant and t) may pass here; the t test rejects it.
        let mixed = u.min(v).min(w).cmplt(zero) & u.max(v).max(w).cmpgt(zero);
        let inside = !mixed;
        // A block none of whose triangles holds the ray stops here, and one whose crossings all
        // lie at or beyond `t_max` stops below, before the bound on t's error. The lanes that go
        // on compute everything as before, so their answers are unchanged.
        if inside.bitmask() & lanes == 0 {
            return BlockHits::NONE;
        }
        let det = u + v + w;
        let (_, _, sz) = ray.shear_constants();
        let sz = Vec4::splat(sz);
        let max_z_unscaled = az.abs().max(bz.abs()).max(cz.abs());
        let (az, bz, cz) = (sz * az, sz * bz, sz * cz);
        let t_scaled = u * az + v * bz + w * cz;
        let inv_det = Vec4::ONE / det;
        let t = t_scaled * inv_det;
        let candidate: BVec4A = inside & det.cmpne(zero) & t.cmplt(Vec4::splat(t_max));
        // `triangle::overflowed`, lane by lane: those lanes are finished in f64 below. Unused
        // lanes, whose NaN vertices make everything NaN, are not overflowed: a used lane's
        // sheared coordinates are finite.
        let in_range = (det.abs() + t_scaled.abs()).cmplt(Vec4::splat(f32::INFINITY));
        let overflowed = ax.cmpeq(ax) & !in_range;
        if (candidate | overflowed).bitmask() & lanes == 0 {
            return BlockHits::NONE;
        }
        // In front of the origin, as in the scalar test: where all three sheared depths clearly
        // are (by more than twice their rounding error), else by the bound on t's error. The
        // first is the common case and cheaper, so the bound is computed only for the lanes it
        // leaves: the same lanes as the scalar test's `t > δt || (…)` in either order.
        let max_z = az.abs().max(bz.abs()).max(cz.abs());
        let g3 = Vec4::splat(gamma32(3));
        let delta_z = g3 * max_z;
        let min_z = az.min(bz).min(cz);
        let mut valid = candidate & min_z.cmpgt(Vec4::splat(2.0) * delta_z) & t.cmpgt(zero);
        if (candidate & !valid).bitmask() & lanes != 0 {
            let max_x = ax.abs().max(bx.abs()).max(cx.abs());
            let max_y = ay.abs().max(by.abs()).max(cy.abs());
            let g2 = Vec4::splat(gamma32(2));
            let g5 = Vec4::splat(gamma32(5));
            let delta_x = g5 * (max_x + max_z_unscaled);
            let delta_y = g5 * (max_y + max_z_unscaled);
            let delta_e =
                Vec4::splat(2.0) * (g2 * max_x * max_y + delta_y * max_x + delta_x * max_y);
            let max_e = u.abs().max(v.abs()).max(w.abs());
            let delta_t = Vec4::splat(3.0)
                * (g3 * max_e * max_z + delta_e * max_z + delta_z * max_e)
                * inv_det.abs();
            valid |= candidate & t.cmpgt(delta_t);
        }
        if overflowed.bitmask() & lanes != 0 {
            let [t, u, v, w] = [t, u, v, w].map(|x| x.to_array());
            let hits = BlockHits {
                valid: valid.bitmask() & lanes,
                t,
                u,
                v,
                w,
            };
            return self.finish_overflowed(hits, overflowed.bitmask() & lanes, ray, t_max);
        }
        BlockHits {
            valid: valid.bitmask() & lanes,
            t: t.to_array(),
            u: u.to_array(),
            v: v.to_array(),
            w: w.to_array(),
        }
    }
}

impl Tri4 {
    /// The lanes of `lanes` decided by [`triangle::intersect_overflowed`], as the one-triangle
    /// test decides them (their vertices sheared again by its arithmetic, the lanes' own: kept
    /// from the block test, they cost every block their registers), into `hits`: a hit keeps
    /// its barycentrics in place of u, v, w.
    #[cold]
    #[inline(never)]
    fn finish_overflowed(
        &self,
        mut hits: BlockHits,
        lanes: u32,
        ray: &ShearedRay,
        t_max: f32,
    ) -> BlockHits {
        let (_, _, sz) = ray.shear_constants();
        for lane in (0..4).filter(|lane| lanes & (1 << lane) != 0) {
            let vertex = |k: usize| std::array::from_fn(|axis| self.v[3 * k + axis][lane]);
            let sheared = ray.sheared([vertex(0), vertex(1), vertex(2)]);
            let bit = 1 << lane;
            match triangle::intersect_overflowed(sheared, sz, t_max) {
                Some((t, [u, v, w])) => {
                    hits.valid |= bit;
                    (hits.t[lane], hits.u[lane], hits.v[lane], hits.w[lane]) = (t, u, v, w);
                }
                None => hits.valid &= !bit,
            }
        }
        hits
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Every lane agrees with the scalar test bit for bit: t, barycentrics, and hit or miss.
    #[test]
    fn lanes_match_the_scalar_test() {
        let tris: Vec<[[f32; 3]; 3]> = (0..4)
            .map(|i| {
                let f = i as f32;
                [
                    [-1.0 + 0.1 * f, -1.0, 0.2 * f],
                    [1.0, -1.0 + 0.05 * f, 0.0],
                    [0.0, 1.0, -0.3 * f],
                ]
            })
            .collect();
        let block = Tri4::new(&tris.iter().copied().zip(0..4).collect::<Vec<_>>());
        let mut checked = 0;
        for k in 0..500 {
            let o = Vec3::new(
                (k as f32 * 0.37).sin() * 1.3,
                (k as f32 * 0.71).cos() * 1.3,
                3.0,
            );
            let d = Vec3::new(0.1 * (k as f32).sin(), 0.2 * (k as f32).cos(), -1.0);
            let ray = ShearedRay::new(o, d);
            let hits = block.intersect(&ray, f32::INFINITY, 0xF);
            for (lane, t) in tris.iter().enumerate() {
                let scalar = ray.intersect(&t[0], &t[1], &t[2], f32::INFINITY);
                assert_eq!(
                    scalar.is_some(),
                    hits.valid & (1 << lane) != 0,
                    "ray {k} lane {lane}"
                );
                if let Some(s) = scalar {
                    let h = hits.nearest(1 << lane).unwrap();
                    assert_eq!((h.t, h.barycentrics), (s.t, s.barycentrics));
                    checked += 1;
                }
            }
        }
        assert!(checked > 200, "{checked}");
        // A lane whose edge function is exactly zero (a vertex on the ray) is recomputed in f64
        // alone: its neighbour keeps its f32 result, as when tested by itself.
        let pair = [
            [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [
                [-0.973_664_05, 0.674_938_14, 0.0],
                [-0.481_291_98, -0.531_338_1, 0.0],
                [0.991_289_7, -0.059_472_986, 0.0],
            ],
        ];
        let block = Tri4::new(&[(pair[0], 0), (pair[1], 1)]);
        let ray = ShearedRay::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let hits = block.intersect(&ray, f32::INFINITY, 0xF);
        for (lane, t) in pair.iter().enumerate() {
            let scalar = ray.intersect(&t[0], &t[1], &t[2], f32::INFINITY).unwrap();
            let h = hits.nearest(1 << lane).unwrap();
            assert_eq!(
                (h.t, h.barycentrics),
                (scalar.t, scalar.barycentrics),
                "lane {lane}"
            );
        }
        // At scales whose f32 products overflow (10¹³: t's numerator; 10²⁰ and 10²⁹: the edge
        // functions too), the lanes are finished in f64 and still agree bit for bit, beside a
        // lane too small to overflow.
        for scale in [1e13f32, 1e20, 1e29] {
            let mut scaled: Vec<[[f32; 3]; 3]> = tris[..3]
                .iter()
                .map(|t| t.map(|p| p.map(|x| x * scale)))
                .collect();
            scaled.push(tris[3]);
            let block = Tri4::new(&scaled.iter().copied().zip(0..4).collect::<Vec<_>>());
            let mut hit = 0;
            for k in 0..200 {
                let o = Vec3::new((k as f32 * 0.37).sin(), (k as f32 * 0.71).cos(), 3.0) * scale;
                let d = Vec3::new(0.1 * (k as f32).sin(), 0.2 * (k as f32).cos(), -1.0);
                let ray = ShearedRay::new(o, d);
                let hits = block.intersect(&ray, f32::INFINITY, 0xF);
                for (lane, t) in scaled.iter().enumerate() {
                    let scalar = ray.intersect(&t[0], &t[1], &t[2], f32::INFINITY);
                    assert_eq!(scalar.is_some(), hits.valid & (1 << lane) != 0);
                    if let Some(s) = scalar {
                        let h = hits.nearest(1 << lane).unwrap();
                        assert_eq!((h.t, h.barycentrics), (s.t, s.barycentrics));
                        hit += usize::from(lane < 3);
                    }
                }
            }
            assert!(hit > 100, "scale {scale}: {hit} hits");
        }
        // Unused lanes never hit.
        let single = Tri4::new(&[(tris[0], 7)]);
        let ray = ShearedRay::new(Vec3::new(0.0, -0.5, 3.0), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(single.intersect(&ray, f32::INFINITY, 0xF).valid, 1);
    }
}
