//! Benchmark-only intersector variants, from the textbook formula in f32 up to the production path
//! plus a Newton step. All work in the quadric's normalised local frame ([`Quadric::local_frame`],
//! [`Quadric::local_coefficients`]) so they differ only in the numerics under test.

use glam::{DMat3, DVec3, Mat3, Vec3};
use quadray::math::{slab_interval, solve_quadratic};
use quadray::{Quadric, Ray};

/// One way of intersecting a ray with a clipped quadric.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Variant {
    /// Textbook (−β ∓ √(β² − aγ))/a in f32 throughout, root kept if its point is in the box.
    NaiveF32,
    /// The same textbook formula in f64.
    NaiveF64,
    /// Sign-aware roots, FMA-compensated discriminant and slab clipping in f64, origin not moved.
    StableF64,
    /// The renderer's own [`Quadric::intersect`].
    Production,
    /// [`Quadric::intersect`] followed by one guarded Newton step on f along the ray.
    ProductionNewton,
}

impl Variant {
    /// Every variant, cheapest numerics first.
    pub const ALL: [Variant; 5] = [
        Variant::NaiveF32,
        Variant::NaiveF64,
        Variant::StableF64,
        Variant::Production,
        Variant::ProductionNewton,
    ];

    /// Short name for tables and plots.
    pub fn name(self) -> &'static str {
        match self {
            Variant::NaiveF32 => "naive-f32",
            Variant::NaiveF64 => "naive-f64",
            Variant::StableF64 => "stable-f64",
            Variant::Production => "production",
            Variant::ProductionNewton => "production+newton",
        }
    }

    /// Whether the variant uses the known-root trick (γ = 0) for rays spawned on the same quadric.
    pub fn knows_spawned_rays(self) -> bool {
        matches!(self, Variant::Production | Variant::ProductionNewton)
    }
}

/// A quadric with every variant's precomputed data (f32 copies for the f32 variant).
#[derive(Clone, Debug)]
pub struct VariantQuadric {
    /// The production quadric.
    pub quadric: Quadric,
    a: DMat3,
    b: DVec3,
    c: f64,
    /// A's diagonal when A is diagonal (the named kinds), so every variant multiplies by A as
    /// production does: three products instead of a matrix product.
    diagonal: Option<DVec3>,
    a32: Mat3,
    b32: Vec3,
    c32: f32,
    m32: Mat3,
    t32: Vec3,
}

impl VariantQuadric {
    /// Precomputes the variants' data for `quadric`.
    pub fn new(quadric: Quadric) -> Self {
        let (a, b, c) = quadric.local_coefficients();
        let from = quadric.local_frame().from_world;
        VariantQuadric {
            diagonal: quadric.local_diagonal(),
            a32: a.as_mat3(),
            b32: b.as_vec3(),
            c32: c as f32,
            m32: from.matrix3.as_mat3(),
            t32: from.translation.as_vec3(),
            a,
            b,
            c,
            quadric,
        }
    }

    /// Nearest hit in (0, `t_max`] by `variant`; `from_self` is honoured only by variants that know
    /// spawned rays ([`Variant::knows_spawned_rays`]).
    #[inline]
    pub fn intersect(
        &self,
        variant: Variant,
        ray: &Ray,
        t_max: f64,
        from_self: bool,
    ) -> Option<f64> {
        match variant {
            Variant::NaiveF32 => self.naive_f32(ray, t_max),
            Variant::NaiveF64 => self.naive_f64(ray, t_max),
            Variant::StableF64 => self.stable_f64(ray, t_max),
            Variant::Production => self.quadric.intersect(ray, t_max, from_self),
            Variant::ProductionNewton => self.newton(ray, t_max, from_self),
        }
    }

    /// A·v, as production computes it.
    #[inline]
    fn a_times(&self, v: DVec3) -> DVec3 {
        match self.diagonal {
            Some(diagonal) => diagonal * v,
            None => self.a * v,
        }
    }

    /// A·v in f32.
    #[inline]
    fn a32_times(&self, v: Vec3) -> Vec3 {
        match self.diagonal {
            Some(diagonal) => diagonal.as_vec3() * v,
            None => self.a32 * v,
        }
    }

    #[inline]
    fn eval(&self, u: DVec3) -> f64 {
        u.dot(self.a_times(u)) + 2.0 * self.b.dot(u) + self.c
    }

    /// Textbook roots in f64: a = dᵀAd, β = dᵀ(Ao + b), γ = f(o), (−β ∓ √(β² − aγ))/a.
    #[inline]
    fn naive_f64(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        let Ray { origin: o, dir: d } = self.quadric.local_ray(ray);
        let ad = self.a_times(d);
        let a = d.dot(ad);
        let beta = ad.dot(o) + self.b.dot(d);
        let gamma = self.eval(o);
        let inside = |t: f64| t > 0.0 && t <= t_max && (o + d * t).abs().max_element() <= 1.0;
        if a == 0.0 {
            let t = -gamma / (2.0 * beta);
            return inside(t).then_some(t);
        }
        let disc = beta * beta - a * gamma;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let (t0, t1) = ((-beta - s) / a, (-beta + s) / a);
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if inside(near) {
            Some(near)
        } else if inside(far) {
            Some(far)
        } else {
            None
        }
    }

    /// The textbook formula with the ray, frame and coefficients all in f32.
    #[inline]
    fn naive_f32(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        let o = self.m32 * ray.origin.as_vec3() + self.t32;
        let d = self.m32 * ray.dir.as_vec3();
        let ad = self.a32_times(d);
        let a = d.dot(ad);
        let beta = ad.dot(o) + self.b32.dot(d);
        let gamma = o.dot(self.a32_times(o)) + 2.0 * self.b32.dot(o) + self.c32;
        let t_max = t_max as f32;
        let inside = |t: f32| t > 0.0 && t <= t_max && (o + d * t).abs().max_element() <= 1.0;
        if a == 0.0 {
            let t = -gamma / (2.0 * beta);
            return inside(t).then_some(t as f64);
        }
        let disc = beta * beta - a * gamma;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let (t0, t1) = ((-beta - s) / a, (-beta + s) / a);
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if inside(near) {
            Some(near as f64)
        } else if inside(far) {
            Some(far as f64)
        } else {
            None
        }
    }

    /// Sign-aware roots with the compensated discriminant and slab clipping, origin not moved.
    #[inline]
    fn stable_f64(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        let Ray { origin: o, dir: d } = self.quadric.local_ray(ray);
        let (t_in, t_out) = slab_interval(o, d, -DVec3::ONE, DVec3::ONE);
        let lo = t_in.max(0.0);
        let hi = t_out.min(t_max);
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return None;
        }
        let ad = self.a_times(d);
        let a = d.dot(ad);
        let beta = ad.dot(o) + self.b.dot(d);
        let gamma = self.eval(o);
        let roots = solve_quadratic(a, beta, gamma);
        roots
            .as_slice()
            .iter()
            .copied()
            .find(|&t| t > 0.0 && t >= lo && t <= hi)
    }

    /// Production, then t ← t − g(t)/g'(t) with g(t) = f(o + t·d) evaluated at the box entry's
    /// re-origined point; the step is kept only when finite, small (at most 2⁻²⁰ of the box
    /// crossing) and still inside the slab interval.
    #[inline]
    fn newton(&self, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        let t = self.quadric.intersect(ray, t_max, from_self)?;
        let Ray { origin: o, dir: d } = self.quadric.local_ray(ray);
        let (t_in, t_out) = slab_interval(o, d, -DVec3::ONE, DVec3::ONE);
        let lo = t_in.max(0.0);
        let hi = t_out.min(t_max);
        let base = o + d * lo;
        let p = base + d * (t - lo);
        let g = self.eval(p);
        let slope = 2.0 * d.dot(self.a_times(p) + self.b);
        let step = g / slope;
        let t2 = t - step;
        let guard = (hi - lo).abs() * (1.0 / 1048576.0);
        if step.is_finite() && step.abs() <= guard && t2 > 0.0 && t2 >= lo && t2 <= hi {
            Some(t2)
        } else {
            Some(t)
        }
    }
}
