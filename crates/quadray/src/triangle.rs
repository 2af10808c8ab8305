//! Watertight ray/triangle intersection in f32: Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection" (JCGT 2013), with the conservative bound on t of pbrt-v3 (§3.9.6) so that a ray
//! spawned from a surface never re-hits it through rounding. Two changes to pbrt's test: the error
//! of the shear x' = x − sx·z is bounded with the unscaled z, not z·sz, so the bound holds for
//! directions of any length (pbrt's rejects true hits of a ray whose direction has length 1e-6);
//! and a hit whose three sheared vertex depths all lie clearly in front of the origin is accepted
//! whatever the bound says (pbrt's rejects every hit of a ray from 10⁵ times a triangle's size away,
//! where the shear's absolute error rivals the triangle).
//!
//! The ray is permuted so that its largest direction component becomes z, and sheared so that it
//! points along +z from the origin; the triangle is then tested in 2-d with three edge functions.
//! Every vertex is transformed by the same arithmetic whichever triangle it belongs to, and an edge
//! function of a shared edge is computed with the same products in both triangles (with opposite
//! sign), so a ray crossing an edge hits at least one of the two triangles: no cracks. An edge
//! function that rounds to exactly zero is recomputed in f64, where the products of f32 values are
//! exact, so its sign is exact too; so is a whole test whose products overflow f32 (a triangle
//! about 10¹³ across seen from as far: `intersect_overflowed`).

use glam::{DVec3, Vec3};

/// Unit roundoff of f32.
const F32_UNIT_ROUNDOFF: f32 = f32::EPSILON * 0.5;

/// Higham's gamma(n) for f32: the relative error bound of n chained roundings.
#[inline(always)]
pub(crate) fn gamma32(n: u32) -> f32 {
    let nu = n as f32 * F32_UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// A ray prepared for the watertight test: origin and direction in f32 with the permutation and
/// shear that map the direction to +z. Prepared once per ray and reused for every triangle.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    /// The origin's components in permuted order (kx, ky, kz).
    origin: [f32; 3],
    /// Source axes of the permuted x, y and z (z is the largest direction component).
    axes: [usize; 3],
    /// Shear constants: x' = x − sx·z, y' = y − sy·z, z' = sz·z.
    sx: f32,
    sy: f32,
    sz: f32,
}

/// Where a ray meets a triangle: the parameter and the barycentric weights of the three vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter, in units of the ray's direction.
    pub t: f32,
    /// Barycentric weights of vertices 0, 1 and 2 (they sum to 1).
    pub barycentrics: [f32; 3],
}

impl ShearedRay {
    /// Prepares `origin + t·dir` (f32) for the test; `dir` need not be unit length but must be non-zero.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> ShearedRay {
        let a = dir.abs();
        // z the largest component, x and y the next two in cyclic order (written out rather than
        // as two `% 3`: five instructions a ray query fewer).
        let (kz, mut kx, mut ky) = if a.x > a.y {
            if a.x > a.z { (0, 1, 2) } else { (2, 0, 1) }
        } else if a.y > a.z {
            (1, 2, 0)
        } else {
            (2, 0, 1)
        };
        // Indexed as arrays: `Vec3`'s own indexing is a match on the index, a branch apiece.
        let (origin, dir) = (origin.to_array(), dir.to_array());
        // Keep the winding: swapping x and y when z points backwards preserves the triangle orientation.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        ShearedRay {
            origin: [origin[kx], origin[ky], origin[kz]],
            axes: [kx, ky, kz],
            sx: dir[kx] / dir[kz],
            sy: dir[ky] / dir[kz],
            sz: 1.0 / dir[kz],
        }
    }

    /// Source axes of the permuted x, y and z.
    #[inline(always)]
    pub fn axes(&self) -> [usize; 3] {
        self.axes
    }

    /// The origin's components in permuted order.
    #[inline(always)]
    pub fn permuted_origin(&self) -> [f32; 3] {
        self.origin
    }

    /// The shear constants (sx, sy, sz): x' = x − sx·z, y' = y − sy·z, z' = sz·z.
    #[inline(always)]
    pub fn shear_constants(&self) -> (f32, f32, f32) {
        (self.sx, self.sy, self.sz)
    }

    /// Prepares an f64 ray (rounded to f32).
    #[inline]
    pub fn from_f64(origin: DVec3, dir: DVec3) -> ShearedRay {
        ShearedRay::new(origin.as_vec3(), dir.as_vec3())
    }

    /// Vertex `p` relative to the origin, permuted and sheared: (x', y', z' before scaling by sz).
    #[inline(always)]
    fn shear(&self, p: &[f32; 3]) -> (f32, f32, f32) {
        let [kx, ky, kz] = self.axes;
        let z = p[kz] - self.origin[2];
        (
            (p[kx] - self.origin[0]) - self.sx * z,
            (p[ky] - self.origin[1]) - self.sy * z,
            z,
        )
    }

    /// The three vertices of a triangle sheared as [`ShearedRay::intersect`] shears them.
    #[inline(always)]
    pub(crate) fn sheared(&self, [p0, p1, p2]: [[f32; 3]; 3]) -> [[f32; 3]; 3] {
        [p0, p1, p2].map(|p| {
            let (x, y, z) = self.shear(&p);
            [x, y, z]
        })
    }

    /// The hit of this ray with triangle (`p0`, `p1`, `p2`) in (δt, `t_max`), where δt bounds the
    /// rounding error of the computed t (hits that close to the origin are not trusted).
    #[inline(always)]
    pub fn intersect(
        &self,
        p0: &[f32; 3],
        p1: &[f32; 3],
        p2: &[f32; 3],
        t_max: f32,
    ) -> Option<TriangleHit> {
        let (ax, ay, az) = self.shear(p0);
        let (bx, by, bz) = self.shear(p1);
        let (cx, cy, cz) = self.shear(p2);
        // Edge functions (scaled barycentrics of p0, p1, p2).
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let f =
                |a: f32, b: f32, c: f32, d: f32| (a as f64 * b as f64 - c as f64 * d as f64) as f32;
            u = f(cx, by, cy, bx);
            v = f(ax, cy, ay, cx);
            w = f(bx, ay, by, ax);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        let sheared = [[ax, ay, az], [bx, by, bz], [cx, cy, cz]];
        // The shear's error depends on the unscaled z (pbrt-v3 uses the scaled one, which is only
        // valid for directions of length about 1).
        let max_z_unscaled = az.abs().max(bz.abs()).max(cz.abs());
        let (az, bz, cz) = (self.sz * az, self.sz * bz, self.sz * cz);
        let t_scaled = u * az + v * bz + w * cz;
        // Before the test of a zero determinant, which f64 makes again (as the block test does).
        if overflowed(det, t_scaled) {
            let (t, b) = intersect_overflowed(sheared, self.sz, t_max)?;
            let inv = 1.0 / (b[0] + b[1] + b[2]);
            return Some(TriangleHit {
                t,
                barycentrics: [b[0] * inv, b[1] * inv, b[2] * inv],
            });
        }
        if det == 0.0 {
            return None;
        }
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // pbrt-v3's bound on the error of t (Pharr, Jakob and Humphreys, 3rd ed., §3.9.6).
        let max_z = az.abs().max(bz.abs()).max(cz.abs());
        let max_x = ax.abs().max(bx.abs()).max(cx.abs());
        let max_y = ay.abs().max(by.abs()).max(cy.abs());
        let delta_z = gamma32(3) * max_z;
        let delta_x = gamma32(5) * (max_x + max_z_unscaled);
        let delta_y = gamma32(5) * (max_y + max_z_unscaled);
        let delta_e = 2.0 * (gamma32(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = u.abs().max(v.abs()).max(w.abs());
        let delta_t =
            3.0 * (gamma32(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs();
        // t is a weighted mean of the three sheared depths: when all three lie in front of the
        // origin by more than twice their rounding error, so does the hit, however loose δt is
        // (δt grows with the shear's absolute error and rejects every hit of a ray from 10⁵ times
        // a triangle's size away). Rays spawned on a surface have a vertex at depth ~0 and are
        // judged by δt alone.
        let min_z = az.min(bz).min(cz);
        let in_front = t > delta_t || (min_z > 2.0 * delta_z && t > 0.0);
        if !(in_front && t < t_max) {
            return None;
        }
        Some(TriangleHit {
            t,
            barycentrics: [u * inv_det, v * inv_det, w * inv_det],
        })
    }
}

/// Whether the f32 test's determinant or t's numerator left f32's range: the edge functions grow
/// as the square of a triangle's sheared extent and the numerator as their products with the
/// sheared depths, so a triangle about 10¹³ across seen from as far overflows. One sum and one
/// comparison, NaN and infinity alike failing it (the sum overflows only where both terms are
/// within a factor two of f32's largest value, and the lane is then taken in f64 too).
#[inline(always)]
pub(crate) fn overflowed(det: f32, t_scaled: f32) -> bool {
    !(det.abs() + t_scaled.abs()).is_finite()
}

/// [`ShearedRay::intersect`] in f64 for a triangle whose f32 products overflowed
/// ([`overflowed`]), from the same sheared vertices (x', y', z before sz; f32 and finite within
/// the coordinate limit). Products of f32 values are exact in f64, so the edge functions' signs
/// are exact, and they are the signs every non-zero f32 edge function has (rounding is
/// monotonic, and an overflow to infinity keeps the sign): a shared edge decides the same in a
/// neighbour tested in f32, and meshes stay watertight. The bound on t is the f32 test's
/// (its inputs carry f32's rounding), evaluated in f64. Returns t and the barycentrics u/det,
/// v/det and w/det, which both the block test and the one-triangle test normalise once more as
/// the block test does.
#[cold]
pub(crate) fn intersect_overflowed(
    sheared: [[f32; 3]; 3],
    sz: f32,
    t_max: f32,
) -> Option<(f32, [f32; 3])> {
    let [[ax, ay, az], [bx, by, bz], [cx, cy, cz]] = sheared.map(|p| p.map(f64::from));
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let max_z_unscaled = az.abs().max(bz.abs()).max(cz.abs());
    let sz = f64::from(sz);
    let (az, bz, cz) = (sz * az, sz * bz, sz * cz);
    let t = (u * az + v * bz + w * cz) / det;
    let gamma = |n| f64::from(gamma32(n));
    let max_z = az.abs().max(bz.abs()).max(cz.abs());
    let max_x = ax.abs().max(bx.abs()).max(cx.abs());
    let max_y = ay.abs().max(by.abs()).max(cy.abs());
    let delta_z = gamma(3) * max_z;
    let delta_x = gamma(5) * (max_x + max_z_unscaled);
    let delta_y = gamma(5) * (max_y + max_z_unscaled);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let max_e = u.abs().max(v.abs()).max(w.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) / det.abs();
    let min_z = az.min(bz).min(cz);
    let in_front = t > delta_t || (min_z > 2.0 * delta_z && t > 0.0);
    let t32 = t as f32;
    if !(in_front && t32 > 0.0 && t32 < t_max) {
        return None;
    }
    Some((t32, [(u / det) as f32, (v / det) as f32, (w / det) as f32]))
}

/// The parameter where the f64 ray meets the plane of triangle (`v0`, `v1`, `v2`), or `fallback`
/// when the ray is parallel to it: phase two's f64 refinement of an f32 hit.
// Inlined into the traversal's caller: as a call, its three vertices went through memory
// (2% of a camera-rays-only kitchen frame's instructions).
#[inline(always)]
pub fn plane_t(origin: DVec3, dir: DVec3, v: [DVec3; 3], fallback: f64) -> f64 {
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let t = n.dot(v[0] - origin) / n.dot(dir);
    if t.is_finite() && t > 0.0 {
        t
    } else {
        fallback
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: [[f32; 3]; 4] = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];

    fn hits(r: &ShearedRay) -> usize {
        [[0, 1, 2], [0, 2, 3]]
            .iter()
            .filter(|[a, b, c]| {
                r.intersect(&QUAD[*a], &QUAD[*b], &QUAD[*c], f32::INFINITY)
                    .is_some()
            })
            .count()
    }

    /// Where the f32 products overflow (a triangle 10¹³ across seen from as far, and past), the
    /// hit is the one the same ray finds at unit scale: t and barycentrics to f32's precision,
    /// the same hits and misses. (Before the f64 fallback, every hit was lost from 10¹³ on.)
    #[test]
    fn overflowing_triangles_hit_as_at_unit_scale() {
        let mut hits = 0;
        for scale in [1e13f32, 1e20, 1e29] {
            let quad = QUAD.map(|p| p.map(|x| x * scale));
            for k in 0..400 {
                let o = Vec3::new(
                    (k as f32 * 0.37).sin() * 1.3,
                    (k as f32 * 0.71).cos() * 1.3,
                    2.0,
                );
                let d = Vec3::new(0.2 * (k as f32).sin(), 0.3 * (k as f32).cos(), -1.0);
                let unit = ShearedRay::new(o, d);
                let far = ShearedRay::new(o * scale, d);
                for [a, b, c] in [[0, 1, 2], [0, 2, 3]] {
                    let want = unit.intersect(&QUAD[a], &QUAD[b], &QUAD[c], f32::INFINITY);
                    let got = far.intersect(&quad[a], &quad[b], &quad[c], f32::INFINITY);
                    assert_eq!(want.is_some(), got.is_some(), "scale {scale}, ray {k}");
                    if let (Some(w), Some(g)) = (want, got) {
                        assert!((g.t / scale - w.t).abs() <= 1e-6 * w.t, "{g:?} {w:?}");
                        for (x, y) in g.barycentrics.iter().zip(w.barycentrics) {
                            assert!((x - y).abs() <= 1e-6, "{g:?} {w:?}");
                        }
                        hits += 1;
                    }
                }
            }
        }
        assert!(hits > 400, "{hits}");
    }

    #[test]
    fn hits_with_barycentrics_and_t() {
        let r = ShearedRay::new(Vec3::new(0.5, -0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let h = r
            .intersect(&QUAD[0], &QUAD[1], &QUAD[2], f32::INFINITY)
            .unwrap();
        assert_eq!(h.t, 2.0);
        // (0.5, -0.5) = 0.25·v0 + 0.5·v1 + 0.25·v2.
        let b = h.barycentrics;
        assert!(
            (b[0] - 0.25).abs() < 1e-6 && (b[1] - 0.5).abs() < 1e-6,
            "{b:?}"
        );
        assert!(
            r.intersect(&QUAD[0], &QUAD[1], &QUAD[2], 1.5).is_none(),
            "beyond t_max"
        );
        let behind = ShearedRay::new(Vec3::new(0.5, -0.5, -2.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(
            behind
                .intersect(&QUAD[0], &QUAD[1], &QUAD[2], f32::INFINITY)
                .is_none()
        );
    }

    /// Rays through the shared diagonal (inside the square) and through the centre vertex of a fan
    /// of six triangles, from many directions, hit at least one triangle: the property
    /// Möller–Trumbore in f32 lacks. Every such ray passes through the interior of the closed
    /// surface, so a miss is a crack.
    #[test]
    fn shared_edges_and_vertices_have_no_cracks() {
        let dirs = [
            (0.0, 0.0),
            (0.3, -0.1),
            (-0.7, 0.9),
            (1e-7, 3e-8),
            (0.37, 0.011),
        ];
        let mut tested = 0;
        for k in 1..200 {
            let s = -1.0 + 2.0 * k as f32 / 200.0;
            for (dx, dy) in dirs {
                let target = Vec3::new(s, s, 0.0);
                let dir = Vec3::new(dx, dy, -1.0);
                let r = ShearedRay::new(target - dir * 3.1, dir);
                assert!(hits(&r) >= 1, "crack at diagonal point {s}, dir {dir}");
                tested += 1;
            }
        }
        assert_eq!(tested, 995);
        // A fan of six triangles around a vertex at (0.3, 0.2, 0.1).
        let centre = [0.3f32, 0.2, 0.1];
        let rim: Vec<[f32; 3]> = (0..6)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 6.0;
                [0.3 + a.cos(), 0.2 + a.sin(), 0.1 + 0.2 * (3.0 * a).sin()]
            })
            .collect();
        for (dx, dy) in dirs {
            for origin_shift in [1.0f32, 1.7, 123.4] {
                let dir = Vec3::new(dx, dy, -1.0);
                let r = ShearedRay::new(Vec3::from(centre) - dir * origin_shift, dir);
                let n = (0..6)
                    .filter(|&i| {
                        r.intersect(&centre, &rim[i], &rim[(i + 1) % 6], f32::INFINITY)
                            .is_some()
                    })
                    .count();
                assert!(n >= 1, "crack at the fan's vertex, dir {dir}");
            }
        }
    }

    /// A ray leaving the plane of the quad from a point on it (offset by far less than f32 resolution)
    /// does not hit either triangle: the t bound rejects the rounding-level self-hit.
    #[test]
    fn no_self_hit_from_the_surface() {
        let mut n = 0;
        for k in 0..1000 {
            let x = -0.9 + 1.8 * (k as f32 * 0.618_034).fract();
            let y = -0.9 + 1.8 * (k as f32 * 0.414_213_5).fract();
            let dir = Vec3::new(0.3 * (k as f32).sin(), 0.3 * (k as f32).cos(), 1.0);
            let r = ShearedRay::new(Vec3::new(x, y, 1e-12), dir);
            n += hits(&r);
        }
        assert_eq!(n, 0);
    }

    /// A ray towards a tiny triangle, with a direction as short as the triangle, hits it just as at
    /// unit scale (pbrt-v3's bound, with the scaled z, rejects it at scale 1e-6).
    #[test]
    fn short_directions_hit_small_triangles() {
        for s in [1e-6f32, 1.0, 1e6] {
            let origin = Vec3::new(0.3, -0.2, 0.1) * s;
            let a = [0.0f32, s, 0.0];
            let b = [0.1 * s, s, 0.05 * s];
            let c = [-0.05 * s, s, 0.1 * s];
            let (va, vb, vc) = (Vec3::from(a), Vec3::from(b), Vec3::from(c));
            for target in [(va + vb + vc) / 3.0, va * 0.8 + vb * 0.1 + vc * 0.1] {
                let r = ShearedRay::new(origin, target - origin);
                let hit = r.intersect(&a, &b, &c, f32::INFINITY);
                assert!(
                    hit.is_some_and(|h| (h.t - 1.0).abs() < 1e-5),
                    "scale {s}: {hit:?}"
                );
            }
        }
    }

    #[test]
    fn plane_t_refines_in_f64() {
        let v = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let t = plane_t(
            DVec3::new(0.1, 0.1, 3.0),
            DVec3::new(0.0, 0.0, -1.5),
            v,
            -1.0,
        );
        assert_eq!(t, 2.0);
        assert_eq!(plane_t(DVec3::Z, DVec3::X, v, 7.0), 7.0);
    }
}
