//! Reference intersection of a ray with a clipped quadric, at high precision.
//!
//! # Inputs (exactly what the oracle believes)
//! The *user's* quadric, not quadray's normalised copy of it: the ten object-frame coefficients
//! `Quadric::surface_description().coefficients()` as f64 values, the object-frame clip box, the
//! object-to-world affine map `Quadric::transform().to_world` (an f64 3×3 matrix M and translation T),
//! the world ray (origin o, direction d, both f64) and `t_max`. Every f64 is a dyadic rational, so the
//! ray in the object frame is exact: X(t) = M⁻¹(o − T + t·d) = (P + t·V)/D with D = det M,
//! P = adj(M)(o − T), V = adj(M)·d. Substituting into f(x) = xᵀAx + 2bᵀx + c and multiplying by D² > 0
//! gives a'·t² + 2β'·t + γ' = 0 with a' = VᵀAV, β' = Vᵀ(AP + D·b), γ' = PᵀAP + 2D·bᵀP + c·D²,
//! all exact dyadics, as is Δ' = β'² − a'γ' and so its sign (hit or miss). Roots use the sign-aware
//! formula with √Δ' and the divisions carried to [`EXACT_BITS`] bits.
//!
//! Two tiers share this code through [`Field`]: [`Dyadic`] (exact ring operations over `num-bigint`,
//! 320-bit division and square root) and `twofloat::TwoFloat` (double-double, ~106 bits: fast, for
//! sweeps, spot-checked against the exact tier in the tests).
//!
//! # Margins
//! Decisions near a boundary are ambiguous for any finite-precision intersector, so the oracle also
//! returns the margin of the case from every boundary it decided, in the quadric's *local* units
//! (the clip box mapped to [-1, 1]³, the frame quadray intersects in): the silhouette margin
//! |Δ/a| / |∇ᵤf(vertex)| (first-order distance the line must move to become tangent), and for every
//! root at or before the chosen one (all roots on a miss) its distance to the nearest clip face and
//! to the ray's ends t = 0 and t = t_max.

mod field;

pub use field::{Dyadic, Field};

use glam::{DAffine3, DMat3, DVec3};
use quadray::{ClipBox, Quadric, Ray};
use twofloat::TwoFloat;

/// Bits carried by the exact tier's divisions and square roots.
pub const EXACT_BITS: u64 = 320;

/// Relative ambiguity margin δ: a case is ambiguous when its margin is below δ·max(1, |L||o − T|).
///
/// |L||o − T| (local units, L the world-to-local map taken entry-wise in absolute value) bounds the
/// rounding of any f64 map of the ray origin into the local frame: an f64 intersector cannot know
/// the ray better than u·|L||o − T| (u = 2⁻⁵³), and 2⁻⁴³ ≈ 1.1e-13 leaves a factor 1024 above that.
pub const DELTA_REL: f64 = 1.1368683772161603e-13;

/// The f64 values the oracle takes from a quadric, stated once (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OracleInput {
    /// Object-frame coefficients A..J of f.
    pub coefficients: [f64; 10],
    /// Object-frame clip box.
    pub clip: ClipBox,
    /// Object-to-world map.
    pub to_world: DAffine3,
}

impl OracleInput {
    /// What the oracle reads from a built quadric.
    pub fn of(q: &Quadric) -> Self {
        OracleInput {
            coefficients: q.surface_description().coefficients().0,
            clip: q.clip(),
            to_world: q.transform().to_world,
        }
    }
}

/// A ray/quadric pair prepared in one tier: the exact line in the object frame and its quadratic.
#[derive(Clone, Debug)]
pub struct Prepared<N: Field> {
    /// a', β', γ' of the scaled quadratic (module docs).
    a: N,
    beta: N,
    gamma: N,
    disc: N,
    /// Object-frame line X(t) = (P + t·V)/D.
    p: [N; 3],
    v: [N; 3],
    det: N,
    det_f: f64,
    t_max: f64,
    input: OracleInput,
    /// f64 copies for margins and condition numbers.
    a_obj: DMat3,
    b_obj: DVec3,
    centre: DVec3,
    half: DVec3,
    origin_local: f64,
    dir_local: f64,
    /// |(|L|·|o − T|)| and |(|L|·|d|)| with L = H⁻¹M⁻¹ the world-to-local map taken entry-wise in
    /// absolute value: the scale of the rounding error of any f64 map of the ray into the local
    /// frame (larger than |oₗ| when the placement is anisotropic and the origin far off-axis).
    origin_scale: f64,
    dir_scale: f64,
}

/// One root of the exact quadratic and what the oracle decided about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootInfo {
    /// The root (nearest f64).
    pub t: f64,
    /// The part of the root below `t`'s ulp (t* ≈ t + lo).
    pub lo: f64,
    /// Inside the closed clip box, 0 < t ≤ t_max.
    pub valid: bool,
    /// Local-unit distance to the nearest decision boundary (clip face, t = 0, t = t_max).
    pub margin: f64,
}

/// The oracle's verdict for one ray.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// All real roots, ascending (at most two; none when the line lies on the surface).
    pub roots: Vec<RootInfo>,
    /// Index into `roots` of the nearest valid root, if any.
    pub hit: Option<usize>,
    /// Smallest margin of any decision that led to `hit` (local units).
    pub margin: f64,
    /// The silhouette part of `margin` (local units).
    pub silhouette: f64,
    /// The ambiguity threshold δ·max(1, |L||o − T|) of this case (local units).
    pub delta: f64,
    /// The line lies on the surface (a' = β' = γ' = 0): every answer is acceptable.
    pub degenerate_line: bool,
    /// Condition number κ of the hit root (see [`Prepared::condition`]); 1 without a hit.
    pub condition: f64,
    /// |oₗ|: the origin's distance from the clip-box centre in local units.
    pub origin_local: f64,
    /// |Δ'| / (β'² + |a'γ'|): how much the discriminant cancelled (the double-double tier is
    /// trusted only well above its 2⁻¹⁰⁶ precision).
    pub cancellation: f64,
    /// |dₗ|: the direction's length in local units (t·|dₗ| is a local distance).
    pub dir_local: f64,
    /// First-order distance of the ray origin from the surface, local units (for spawned rays, how
    /// far the known-root trick's γ = 0 is from the truth).
    pub origin_distance: f64,
}

impl Reference {
    /// The nearest valid root t*, if any.
    pub fn t(&self) -> Option<f64> {
        self.hit.map(|i| self.roots[i].t)
    }

    /// Whether the case lies within δ of a decision boundary.
    pub fn ambiguous(&self) -> bool {
        self.degenerate_line || self.margin <= self.delta
    }

    /// Whether a ray spawned on the surface, intersected with γ := 0 (its origin taken to be on the
    /// surface), lies near a decision boundary. The root nearest t = 0 is the known root (the origin
    /// itself), decided by construction, so its margins do not count; every other decision is
    /// ambiguous within δ plus four times the origin's true distance from the surface, which is the
    /// perturbation the known-root trick makes.
    pub fn ambiguous_spawned(&self) -> bool {
        if self.degenerate_line {
            return true;
        }
        let limit = self.delta + 4.0 * self.origin_distance;
        let known = (0..self.roots.len())
            .min_by(|&i, &j| self.roots[i].t.abs().total_cmp(&self.roots[j].t.abs()));
        let considered = self.hit.map_or(self.roots.len(), |h| h + 1);
        let roots = self.roots[..considered]
            .iter()
            .enumerate()
            .filter(|&(i, _)| Some(i) != known)
            .map(|(_, r)| r.margin);
        roots.fold(self.silhouette, f64::min) <= limit
    }

    /// Relative error |t − t*|/|t*| of a computed root against the hit root.
    pub fn relative_error(&self, t: f64) -> Option<f64> {
        let r = self.roots[self.hit?];
        Some((((t - r.t) - r.lo) / r.t).abs())
    }

    /// Whether `t` lies nearer to another root of the quadratic than to the hit root (a wrong root).
    pub fn is_wrong_root(&self, t: f64) -> bool {
        let Some(h) = self.hit else { return false };
        let own = (t - self.roots[h].t).abs();
        self.roots
            .iter()
            .enumerate()
            .any(|(i, r)| i != h && (t - r.t).abs() < own)
    }
}

fn dot<N: Field>(a: &[N; 3], b: &[N; 3]) -> N {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}

fn mat_vec<N: Field>(m: &[[N; 3]; 3], v: &[N; 3]) -> [N; 3] {
    [dot(&m[0], v), dot(&m[1], v), dot(&m[2], v)]
}

impl<N: Field> Prepared<N> {
    /// Builds the exact quadratic of `ray` against the quadric described by `input`.
    pub fn new(input: &OracleInput, ray: &Ray, t_max: f64) -> Self {
        let k = input.coefficients;
        let m = input.to_world.matrix3;
        // Row-major M from glam's columns.
        let mr = [
            [m.x_axis.x, m.y_axis.x, m.z_axis.x],
            [m.x_axis.y, m.y_axis.y, m.z_axis.y],
            [m.x_axis.z, m.y_axis.z, m.z_axis.z],
        ];
        let e = |i: usize, j: usize| N::of(mr[i][j]);
        // adj(M)[i][j] = cofactor(j, i).
        let cof = |r: usize, c: usize| {
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            e(r1, c1).mul(&e(r2, c2)).sub(&e(r1, c2).mul(&e(r2, c1)))
        };
        let adj: [[N; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| cof(j, i)));
        let det = e(0, 0)
            .mul(&cof(0, 0))
            .add(&e(0, 1).mul(&cof(0, 1)))
            .add(&e(0, 2).mul(&cof(0, 2)));
        let t = input.to_world.translation;
        let rel: [N; 3] = [
            N::of(ray.origin.x).sub(&N::of(t.x)),
            N::of(ray.origin.y).sub(&N::of(t.y)),
            N::of(ray.origin.z).sub(&N::of(t.z)),
        ];
        let dir = [N::of(ray.dir.x), N::of(ray.dir.y), N::of(ray.dir.z)];
        let p = mat_vec(&adj, &rel);
        let v = mat_vec(&adj, &dir);
        // A (halved off-diagonals are exact in binary) and b = (G, H, I)/2.
        let h = |x: f64| N::of(x * 0.5);
        let am = [
            [N::of(k[0]), h(k[3]), h(k[4])],
            [h(k[3]), N::of(k[1]), h(k[5])],
            [h(k[4]), h(k[5]), N::of(k[2])],
        ];
        let bv = [h(k[6]), h(k[7]), h(k[8])];
        let c = N::of(k[9]);
        let ap = mat_vec(&am, &p);
        let av = mat_vec(&am, &v);
        let db: [N; 3] = std::array::from_fn(|i| det.mul(&bv[i]));
        let a = dot(&v, &av);
        let beta = dot(&v, &ap).add(&dot(&v, &db));
        let two = N::of(2.0);
        let gamma = dot(&p, &ap)
            .add(&two.mul(&dot(&db, &p)))
            .add(&c.mul(&det).mul(&det));
        let disc = beta.mul(&beta).sub(&a.mul(&gamma));

        let (a_obj, b_obj, _) = quadray::Coefficients(k).to_matrix_form();
        let centre = (input.clip.min + input.clip.max) * 0.5;
        let half = (input.clip.max - input.clip.min) * 0.5;
        let det_f = det.to_f64();
        let to_vec = |x: &[N; 3]| DVec3::new(x[0].to_f64(), x[1].to_f64(), x[2].to_f64());
        let origin_obj = to_vec(&p) / det_f;
        let dir_obj = to_vec(&v) / det_f;
        let lin = (DMat3::from_diagonal(half.recip()) * m.inverse()).transpose();
        let abs_rows = [lin.x_axis.abs(), lin.y_axis.abs(), lin.z_axis.abs()];
        let mag = |v: DVec3| {
            let v = v.abs();
            DVec3::new(abs_rows[0].dot(v), abs_rows[1].dot(v), abs_rows[2].dot(v)).length()
        };
        let origin_scale = mag(ray.origin - t);
        let dir_scale = mag(ray.dir);
        Prepared {
            origin_scale,
            dir_scale,
            a,
            beta,
            gamma,
            disc,
            p,
            v,
            det,
            det_f,
            t_max,
            input: *input,
            a_obj,
            b_obj,
            centre,
            half,
            origin_local: ((origin_obj - centre) / half).length(),
            dir_local: (dir_obj / half).length(),
        }
    }

    /// The real roots of a'·t² + 2β'·t + γ' = 0, ascending (sign-aware formula, no cancellation);
    /// `None` when every t is a root (the line lies on the surface).
    fn roots(&self) -> Option<Vec<N>> {
        let zero = N::of(0.0);
        if self.a.sign() == 0 {
            if self.beta.sign() == 0 {
                return if self.gamma.sign() == 0 {
                    None
                } else {
                    Some(vec![])
                };
            }
            // 2β't + γ' = 0.
            return Some(vec![self.gamma.neg().div(&N::of(2.0).mul(&self.beta))]);
        }
        if self.disc.sign() < 0 {
            return Some(vec![]);
        }
        let root = self.disc.sqrt();
        let q = if self.beta.sign() >= 0 {
            self.beta.add(&root).neg()
        } else {
            root.sub(&self.beta)
        };
        if q.sign() == 0 {
            // β' = Δ' = 0 with a' ≠ 0 forces γ' = 0: a double root at 0.
            return Some(vec![zero.clone(), zero]);
        }
        let (r0, r1) = (q.div(&self.a), self.gamma.div(&q));
        Some(if r0.sub(&r1).sign() <= 0 {
            vec![r0, r1]
        } else {
            vec![r1, r0]
        })
    }

    /// Object-frame point X(t) in f64 (for margins and gradients).
    fn point(&self, t: &N) -> DVec3 {
        let c = |i: usize| self.p[i].add(&t.mul(&self.v[i])).to_f64() / self.det_f;
        DVec3::new(c(0), c(1), c(2))
    }

    /// Gradient of f in local units, ∇ᵤf = H·2(A·x + b), at an object-frame point.
    fn local_gradient(&self, x: DVec3) -> DVec3 {
        self.half * (2.0 * (self.a_obj * x + self.b_obj))
    }

    /// |f| magnitude in local units at an object-frame point: |u|ᵀ|Aᵤ||u| + 2|bᵤ|·|u| + |cᵤ| (the
    /// scale of f's rounding error when evaluated in the local frame).
    fn local_magnitude(&self, x: DVec3) -> f64 {
        let hm = DMat3::from_diagonal(self.half);
        let au = hm * self.a_obj * hm;
        let bu = self.half * (self.a_obj * self.centre + self.b_obj);
        let cu = quadray::Coefficients(self.input.coefficients).eval(self.centre);
        let abs = |m: DMat3| DMat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        let u = ((x - self.centre) / self.half).abs();
        u.dot(abs(au) * u) + 2.0 * bu.abs().dot(u) + cu.abs()
    }

    /// Root validity and margin: inside the closed box and 0 < t ≤ t_max, exactly; margin in local units.
    fn judge(&self, t: &N) -> RootInfo {
        let tf = t.to_f64();
        let lo = t.sub(&N::of(tf)).to_f64();
        let mut valid = t.sign() > 0 && tf <= self.t_max;
        let mut face = f64::INFINITY;
        let dsign = self.det.sign();
        for i in 0..3 {
            // Exact side tests: (P + tV − bound·D)·sign(D) against 0.
            let num = self.p[i].add(&t.mul(&self.v[i]));
            let (min, max) = (self.input.clip.min[i], self.input.clip.max[i]);
            let below = num.sub(&N::of(min).mul(&self.det)).sign() * dsign < 0;
            let above = num.sub(&N::of(max).mul(&self.det)).sign() * dsign > 0;
            valid &= !(below || above);
            let c = N::of(self.centre[i]).mul(&self.det);
            let u = num.sub(&c).to_f64() / (self.det_f * self.half[i]);
            face = face.min((1.0 - u.abs()).abs());
        }
        let along = self.dir_local * tf.abs();
        let end = if self.t_max.is_finite() {
            self.dir_local * (self.t_max - tf).abs()
        } else {
            f64::INFINITY
        };
        RootInfo {
            t: tf,
            lo,
            valid,
            margin: face.min(along).min(end),
        }
    }

    /// Silhouette margin |Δ/a| / (|∇ᵤf(v)| + M(v)), local units, at the vertex v = −β/a of g
    /// clamped to the line's stretch inside the box (∞ when a' = 0 or the line misses the box).
    ///
    /// |Δ/a| is how far g's extremum is from zero: the perturbation of f that makes the line tangent.
    /// An f64 intersector perturbs f by about u·(|oₗ|·|∇f| + M) near v, so dividing by |∇f| + M gives
    /// a length comparable with δ. At a regular tangency this is about half the miss distance; at a
    /// cone apex (∇f → 0) it shrinks like the square of the distance from the apex, as the roots'
    /// sensitivity there does.
    fn silhouette_margin(&self) -> f64 {
        if self.a.sign() == 0 {
            return f64::INFINITY;
        }
        let (t_in, t_out) = self.box_interval();
        if t_in.is_nan() || t_out.is_nan() || t_in > t_out {
            return f64::INFINITY;
        }
        let vertex = self.beta.neg().div(&self.a).to_f64().clamp(t_in, t_out);
        let x = self.point(&N::of(vertex));
        let scale = self.local_gradient(x).length() + self.local_magnitude(x);
        let ext = (self.disc.div(&self.a).to_f64() / (self.det_f * self.det_f)).abs();
        if scale == 0.0 {
            if ext == 0.0 { 0.0 } else { f64::INFINITY }
        } else {
            ext / scale
        }
    }

    /// The line's parameter interval inside the clip box (f64 slab test in the object frame).
    fn box_interval(&self) -> (f64, f64) {
        let o = self.point(&N::of(0.0));
        let d = self.point(&N::of(1.0)) - o;
        quadray::math::slab_interval(o, d, self.input.clip.min, self.input.clip.max)
    }

    /// First-order distance of the ray origin from the surface, local units: |f(o)| / |∇ᵤf(o)|.
    pub fn origin_distance(&self) -> f64 {
        self.residual(0.0)
    }

    /// Condition number κ of root t*: ((|L||o − T| + |t*|·|L||d|)·|∇ᵤf(p*)| + M(p*)) / (|t*|·|g'(t*)|),
    /// at least 1 (|L| the entry-wise absolute world-to-local map, see `origin_scale`).
    ///
    /// g(t) = f(X(t)); an intersector that maps the ray into the local frame with error
    /// u·(|L||o − T| + t·|L||d|) (local units) and evaluates f with error u·M returns a root off by
    /// about u·((|L||o − T| + t·|L||d|)·|∇f| + M)/|g'|: κ is that over u·|t*|.
    pub fn condition(&self, t: &N) -> f64 {
        let x = self.point(t);
        let grad = self.local_gradient(x).length();
        let slope =
            (self.a.mul(t).add(&self.beta).to_f64() * 2.0 / (self.det_f * self.det_f)).abs();
        let tf = t.to_f64().abs();
        let num = (self.origin_scale + tf * self.dir_scale) * grad + self.local_magnitude(x);
        (num / (tf * slope)).max(1.0)
    }

    /// Residual of the exact point X(t) at a computed t: |f|/|∇ᵤf|, in local units (object size 1).
    pub fn residual(&self, t: f64) -> f64 {
        let tn = N::of(t);
        let g = self
            .a
            .mul(&tn)
            .mul(&tn)
            .add(&N::of(2.0).mul(&self.beta).mul(&tn))
            .add(&self.gamma);
        let f = g.to_f64() / (self.det_f * self.det_f);
        let grad = self.local_gradient(self.point(&tn)).length();
        if f == 0.0 { 0.0 } else { f.abs() / grad }
    }

    /// Exact sign of f at the ray origin (sign of γ', as D² > 0).
    pub fn origin_sign(&self) -> i32 {
        self.gamma.sign()
    }

    /// Exact sign of the directional derivative d·∇f at the ray origin (sign of β'·D, D² > 0 aside).
    pub fn origin_slope_sign(&self) -> i32 {
        self.beta.sign()
    }

    /// |Δ'| / (β'² + |a'γ'|), 1 when both terms vanish.
    fn cancellation(&self) -> f64 {
        let scale = self.beta.mul(&self.beta).to_f64() + self.a.mul(&self.gamma).to_f64().abs();
        if scale == 0.0 {
            1.0
        } else {
            self.disc.to_f64().abs() / scale
        }
    }

    /// The oracle's verdict.
    pub fn reference(&self) -> Reference {
        let delta = DELTA_REL * self.origin_scale.max(1.0);
        let Some(roots) = self.roots() else {
            return Reference {
                roots: vec![],
                hit: None,
                margin: 0.0,
                silhouette: 0.0,
                delta,
                degenerate_line: true,
                condition: 1.0,
                origin_local: self.origin_local,
                cancellation: 0.0,
                dir_local: self.dir_local,
                origin_distance: 0.0,
            };
        };
        let infos: Vec<RootInfo> = roots.iter().map(|t| self.judge(t)).collect();
        let hit = infos.iter().position(|r| r.valid);
        let considered = hit.map_or(infos.len(), |h| h + 1);
        let silhouette = self.silhouette_margin();
        let mut margin = silhouette;
        for r in &infos[..considered] {
            margin = margin.min(r.margin);
        }
        let condition = hit.map_or(1.0, |h| self.condition(&roots[h]));
        Reference {
            roots: infos,
            hit,
            margin,
            silhouette,
            delta,
            degenerate_line: false,
            condition,
            origin_local: self.origin_local,
            cancellation: self.cancellation(),
            dir_local: self.dir_local,
            origin_distance: self.origin_distance(),
        }
    }
}

/// Exact-tier verdict for `ray` against `q` (see the module docs for what is exact).
pub fn exact(q: &Quadric, ray: &Ray, t_max: f64) -> Reference {
    Prepared::<Dyadic>::new(&OracleInput::of(q), ray, t_max).reference()
}

/// Double-double verdict: the same algorithm in `TwoFloat`, much faster than [`exact`].
pub fn double_double(q: &Quadric, ray: &Ray, t_max: f64) -> Reference {
    Prepared::<TwoFloat>::new(&OracleInput::of(q), ray, t_max).reference()
}

/// Whether a double-double verdict can be trusted: the discriminant kept at least 2⁻⁶⁰ of its terms
/// (so ≥ 40 of double-double's 106 bits survive for its sign) and no decision is within
/// 1e-18·max(1, |oₗ|) local units (double-double carries the line to about 1e-30·|oₗ|).
pub fn double_double_is_reliable(r: &Reference) -> bool {
    !r.degenerate_line
        && r.cancellation >= 2f64.powi(-60)
        && r.margin > 1e-18 * r.origin_local.max(1.0)
}

/// The double-double verdict, replaced by the exact one where it is not reliable.
pub fn checked(q: &Quadric, ray: &Ray, t_max: f64) -> Reference {
    let r = double_double(q, ray, t_max);
    if double_double_is_reliable(&r) {
        r
    } else {
        exact(q, ray, t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadray::{QuadricKind, QuadricSurface, Transform};

    #[test]
    fn unit_sphere_from_far_away() {
        let q = Quadric::new(
            QuadricSurface::Canonical {
                kind: QuadricKind::Ellipsoid,
                a: 1.0,
                b: 1.0,
                c: 1.0,
            },
            ClipBox::cube(2.0),
            Transform::IDENTITY,
            0,
        )
        .unwrap();
        let ray = Ray::new(DVec3::new(0.0, 0.0, 1e8), -DVec3::Z);
        let r = exact(&q, &ray, f64::INFINITY);
        assert_eq!(r.t(), Some(1e8 - 1.0));
        assert!(!r.ambiguous());
        // Grazing by 1e-10 outside: a miss, with a silhouette margin of about 1e-10 / 2 (local units,
        // box half-extent 2; ∇ᵤf = 4 and M = 4·0.25 + 1 at the vertex), below the case's δ (origin 5e7
        // local units away) so ambiguous.
        let ray = Ray::new(DVec3::new(1.0 + 1e-10, 0.0, 1e8), -DVec3::Z);
        let r = exact(&q, &ray, f64::INFINITY);
        assert_eq!(r.t(), None);
        assert!(r.margin > 1e-11 && r.margin < 0.5e-10, "{}", r.margin);
        assert!(r.ambiguous());
        let dd = double_double(&q, &ray, f64::INFINITY);
        assert_eq!(dd.t(), None);
    }
}
