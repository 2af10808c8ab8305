//! Clipped quadric surfaces: the nine real kinds by name, or the general 10-coefficient form.
//!
//! # Frames
//! A quadric is given in its *object* frame (canonical equation, height axis z), clipped by a box
//! in that frame, and placed in the world by an affine transform. Internally it is intersected in a
//! *local* frame in which the clip box is the cube [-1, 1]³ and the largest coefficient has magnitude
//! one (quadric-numerics.md §5): every quantity the intersector touches is then of order one,
//! whatever the scene's scale or distance from the origin.
//!
//! # Intersection
//! In the local frame the ray o + t·d gives a·t² + 2β·t + γ = 0 with a = dᵀAd, β = dᵀ(Ao + b),
//! γ = f(o). The ray is first clipped to the box (slab test), its origin moved to the box entry so
//! γ carries no cancellation from a far origin, and the roots found with the sign-aware formula
//! ([`solve_quadratic`]). Both roots are tested against the box, so the inside of an open surface
//! shows through the clip opening. Normals come from the gradient ∇f = 2(Ap + b), which is right
//! everywhere the surface is smooth, including where it is not a graph z = f(x, y).
//!
//! [`solve_quadratic`]: crate::math::solve_quadratic

mod classify;
mod conditioning;
mod four;
mod given;
mod quadratic;
#[cfg(test)]
mod tests;
mod visible;

pub use classify::classify;
pub use conditioning::{ROUNDING_WARNING, RoundingSensitivity};
pub use given::{ClipBox, Coefficients, QuadricKind, QuadricSurface};

use quadratic::QuadraticPart;

use crate::material::MaterialId;
use crate::math::{Ray, Transform, discriminant, gamma, orthonormal_basis};
use crate::shape::{SurfaceGeometry, normal_or};
use crate::texture::TexturePoint;
use glam::{DAffine3, DMat3, DVec3};
use std::fmt;

/// The slab test of the ray o + t·d against the cube [-1, 1]³: per axis, the t at which it enters
/// and leaves the axis's slab (NaN for a ray in the plane of a face and parallel to it).
#[inline(always)]
fn unit_cube_slabs(o: DVec3, d: DVec3) -> (DVec3, DVec3) {
    let inv = d.recip();
    let t0 = (-DVec3::ONE - o) * inv;
    let t1 = (DVec3::ONE - o) * inv;
    (t0.min(t1), t0.max(t1))
}

/// The part of (0, `t_max`) in which a ray lies in the cube of its `slabs` ([`unit_cube_slabs`]):
/// their bounds folded as `f64::max` and `min` would fold them (an axis whose bound is NaN leaves
/// the others to decide), by one comparison each instead of those functions' NaN checks. Empty
/// (lo > hi) where the ray misses the cube.
#[inline(always)]
fn unit_cube_interval((near, far): (DVec3, DVec3), t_max: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0, t_max);
    for (n, f) in near.to_array().into_iter().zip(far.to_array()) {
        lo = if n > lo { n } else { lo };
        hi = if f < hi { f } else { hi };
    }
    (lo, hi)
}

/// What a quadric's equation actually describes, found by diagonalising it (Sylvester's law of inertia).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuadricClass {
    /// A surface of one of the nine named kinds.
    Proper(QuadricKind),
    /// Two planes crossing in a line (x² − y² = 0): rendered.
    IntersectingPlanes,
    /// Two parallel planes (x² − 1 = 0): rendered.
    ParallelPlanes,
    /// A single plane counted twice (x² = 0): the gradient vanishes on the whole surface; rejected.
    DoublePlane,
    /// No quadratic terms: a plane; rejected (use a plane primitive).
    Plane,
    /// Only a line satisfies the equation (x² + y² = 0); rejected.
    Line,
    /// Only a point satisfies the equation (x² + y² + z² = 0); rejected.
    Point,
    /// No real point satisfies the equation (x² + y² + z² + 1 = 0); rejected.
    Empty,
    /// Every coefficient is zero; rejected.
    AllZero,
}

impl QuadricClass {
    /// Whether quadray renders this class.
    pub fn is_renderable(self) -> bool {
        matches!(
            self,
            QuadricClass::Proper(_)
                | QuadricClass::IntersectingPlanes
                | QuadricClass::ParallelPlanes
        )
    }
}

impl fmt::Display for QuadricClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            QuadricClass::Proper(k) => write!(f, "{k}"),
            QuadricClass::IntersectingPlanes => f.write_str("a pair of intersecting planes"),
            QuadricClass::ParallelPlanes => f.write_str("a pair of parallel planes"),
            QuadricClass::DoublePlane => f.write_str(
                "a double plane (like x² = 0), whose gradient vanishes everywhere on it",
            ),
            QuadricClass::Plane => {
                f.write_str("a plane (no quadratic terms); use a plane primitive")
            }
            QuadricClass::Line => f.write_str("a single line (like x² + y² = 0)"),
            QuadricClass::Point => f.write_str("a single point (like x² + y² + z² = 0)"),
            QuadricClass::Empty => {
                f.write_str("empty: no real point satisfies it (like x² + y² + z² + 1 = 0)")
            }
            QuadricClass::AllZero => f.write_str("all coefficients are zero"),
        }
    }
}

/// Why a quadric cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum QuadricError {
    /// A parameter a, b or c is not a positive finite number.
    #[error("parameter {name} must be a positive finite number, got {value}")]
    BadParameter {
        /// "a", "b" or "c".
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A parameter a, b or c so small or large that its coefficient ±1/a² is not a normal f64.
    #[error(
        "parameter {name} = {value:?} is out of range: its coefficient 1/{name}² must be a \
         normal f64 (about 1e-154 < {name} < 1e154)"
    )]
    ParameterRange {
        /// "a", "b" or "c".
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A clip box so much smaller or larger than the surface's own scale that the coefficients
    /// in its frame under- or overflow f64 (and would describe another surface).
    #[error(
        "the clip box (half extents {:?}) is too far from the surface's own scale: its \
         coefficients in the box's frame under- or overflow f64",
        half.to_array()
    )]
    ClipScale {
        /// The box's half extents.
        half: DVec3,
    },
    /// A general coefficient is NaN or infinite.
    #[error("coefficient {index} is not finite ({value})")]
    NonFiniteCoefficient {
        /// Position 0..10 in A..J order.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// The clip box is empty, inverted or not finite on some axis.
    #[error("clip box is empty: min {min} must be below max {max} on every axis")]
    EmptyClipBox {
        /// Lower corner given.
        min: DVec3,
        /// Upper corner given.
        max: DVec3,
    },
    /// The equation does not describe a surface quadray can render.
    #[error("degenerate quadric: {0}")]
    Degenerate(QuadricClass),
    /// The placement transform is singular or not finite.
    #[error("the transform is singular or not finite")]
    BadTransform,
}

/// A quadric surface clipped by a box and placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadric {
    surface: QuadricSurface,
    clip: ClipBox,
    transform: Transform,
    material: MaterialId,
    class: QuadricClass,
    /// Local frame (clip box = [-1, 1]³) to world.
    local: Transform,
    /// The placement's translation (the object frame's origin in the world), exactly as given.
    world_origin: DVec3,
    /// The clip box centre in local units (centre / half extent), so world points map to the local
    /// frame as M⁻¹(p − world_origin) − centre_local without rounding the two offsets together.
    centre_local: DVec3,
    /// Normalised local coefficients: f(u) = uᵀAu + 2bᵀu + c.
    a: QuadraticPart,
    b: DVec3,
    c: f64,
    /// Entry-wise absolute values of `a` and `b`, for rounding-error bounds.
    abs_a: QuadraticPart,
    abs_b: DVec3,
    /// Upper bound on how much the local-to-world map stretches lengths.
    stretch: f64,
    /// Local z range of the surface inside the box (the texture ramp's extent).
    height: (f64, f64),
}

impl Quadric {
    /// Builds a quadric: validates parameters and box, normalises it to its clip box, and classifies it.
    pub fn new(
        surface: QuadricSurface,
        clip: ClipBox,
        transform: Transform,
        material: MaterialId,
    ) -> Result<Quadric, QuadricError> {
        if let QuadricSurface::Canonical { a, b, c, .. } = surface {
            for (name, value) in [("a", a), ("b", b), ("c", c)] {
                if !(value > 0.0 && value.is_finite()) {
                    return Err(QuadricError::BadParameter { name, value });
                }
                if !(1.0 / (value * value)).is_normal() {
                    return Err(QuadricError::ParameterRange { name, value });
                }
            }
        }
        let coefficients = surface.coefficients();
        if let Some((index, &value)) = coefficients
            .0
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite())
        {
            return Err(QuadricError::NonFiniteCoefficient { index, value });
        }
        if !(clip.min.is_finite() && clip.max.is_finite() && clip.min.cmplt(clip.max).all()) {
            return Err(QuadricError::EmptyClipBox {
                min: clip.min,
                max: clip.max,
            });
        }
        if coefficients.0.iter().all(|&k| k == 0.0) {
            return Err(QuadricError::Degenerate(QuadricClass::AllZero));
        }

        // Object -> local: x = centre + H·u with H the box's half extents.
        let centre = (clip.min + clip.max) * 0.5;
        let half = (clip.max - clip.min) * 0.5;
        let (ao, bo, co) = coefficients.to_matrix_form();
        let h = DMat3::from_diagonal(half);
        let mut a = h * ao * h;
        let linear = ao * centre + bo;
        let mut b = h * linear;
        let mut c = centre.dot(ao * centre) + 2.0 * bo.dot(centre) + co;
        // A coefficient that is not zero but under- or overflows in the box's frame (a clip of
        // 1e-200 around a unit sphere) would leave the equation of another surface.
        let lost = |given: f64, framed: f64| given != 0.0 && !framed.is_normal();
        let pairs = (0..3)
            .flat_map(|i| (0..3).map(move |j| (ao.col(i)[j], a.col(i)[j])))
            .chain((0..3).map(|i| (linear[i], b[i])));
        if pairs.into_iter().any(|(given, framed)| lost(given, framed)) || !c.is_finite() {
            return Err(QuadricError::ClipScale { half });
        }
        let scale = [a.x_axis, a.y_axis, a.z_axis, b]
            .iter()
            .map(|v| v.abs().max_element())
            .fold(c.abs(), f64::max);
        if scale == 0.0 || !scale.is_finite() {
            return Err(QuadricError::Degenerate(QuadricClass::AllZero));
        }
        a *= 1.0 / scale;
        b /= scale;
        c /= scale;

        let class = classify(a, b, c);
        if !class.is_renderable() {
            return Err(QuadricError::Degenerate(class));
        }
        let quadratic = QuadraticPart::new(a);
        let box_to_object = DAffine3::from_mat3_translation(h, centre);
        let local =
            Transform::new(transform.to_world * box_to_object).ok_or(QuadricError::BadTransform)?;
        let mut q = Quadric {
            surface,
            clip,
            transform,
            material,
            class,
            stretch: local.max_stretch(),
            local,
            world_origin: transform.to_world.translation,
            centre_local: centre / half,
            a: quadratic,
            b,
            c,
            abs_a: quadratic.abs(),
            abs_b: b.abs(),
            height: (-1.0, 1.0),
        };
        q.height = q.visible_height_range().unwrap_or((-1.0, 1.0));
        Ok(q)
    }

    /// How the surface was given.
    pub fn surface_description(&self) -> QuadricSurface {
        self.surface
    }

    /// The clip box, object frame.
    pub fn clip(&self) -> ClipBox {
        self.clip
    }

    /// Object-to-world placement.
    pub fn transform(&self) -> &Transform {
        &self.transform
    }

    /// Material index.
    pub fn material(&self) -> MaterialId {
        self.material
    }

    /// What the equation describes.
    pub fn class(&self) -> QuadricClass {
        self.class
    }

    /// Whether any part of the surface lies inside the clip box.
    pub fn is_visible(&self) -> bool {
        self.visible_height_range().is_some()
    }

    /// The normalised local frame (clip box = [-1, 1]³) and its map to the world, for benchmark
    /// variants and oracles that must work in the same frame as [`Quadric::intersect`].
    pub fn local_frame(&self) -> &Transform {
        &self.local
    }

    /// The normalised local coefficients (A, b, c) of f(u) = uᵀAu + 2bᵀu + c, largest magnitude one.
    pub fn local_coefficients(&self) -> (DMat3, DVec3, f64) {
        (self.a.matrix(), self.b, self.c)
    }

    /// The diagonal of the local A when A is diagonal (the named kinds), which
    /// [`Quadric::intersect`] multiplies by as three products; `None` for a general A.
    pub fn local_diagonal(&self) -> Option<DVec3> {
        match self.a {
            QuadraticPart::Diagonal(d) => Some(d),
            QuadraticPart::General(_) => None,
        }
    }

    /// The ray in the local frame, computed exactly as [`Quadric::intersect`] computes it (the ray
    /// parameter t is unchanged by the map).
    #[inline]
    pub fn local_ray(&self, ray: &Ray) -> Ray {
        Ray::new(
            self.to_local_point(ray.origin),
            self.local.from_world.matrix3 * ray.dir,
        )
    }

    /// World point to local frame as L·(p − T) − c/h, with L the local-from-world linear map, T the
    /// placement's own translation and c/h the box centre in local units. Subtracting T first keeps
    /// the error relative to |p − T| (the distance from the object), where the affine form L·p + t
    /// would leave an error relative to |p| (the distance from the world origin), and keeping c/h apart
    /// avoids rounding the object's position to the ulp of a far-away world translation.
    #[inline]
    pub(crate) fn to_local_point(&self, p: DVec3) -> DVec3 {
        self.local.from_world.matrix3 * (p - self.world_origin) - self.centre_local
    }

    /// The implicit function in the normalised local frame.
    #[inline]
    fn eval_local(&self, u: DVec3) -> f64 {
        u.dot(self.a.times(u)) + 2.0 * self.b.dot(u) + self.c
    }

    /// Nearest t in (0, `t_max`] where the ray meets the clipped surface (the end included,
    /// where a sphere's test excludes it).
    ///
    /// `from_self` marks a ray spawned on this quadric: its origin is on the surface, so γ = 0 and
    /// the roots are 0 and −2β/a; the second is a genuine re-hit (a concave mirror) and is kept.
    ///
    /// The slab test against the box comes first, so rays that miss the box never reach the
    /// quadratic, and the accepted roots are exactly those in the closed interval [t_in, t_out]. The
    /// origin then moves to the box entry, so a far origin leaves no cancellation in γ, and near
    /// tangency (β² ≈ aγ) once more to the vertex s = −β/a of g, where β ≈ 0 and f is as small as it
    /// gets along the line, so Δ ≈ −aγ carries no cancellation (quadric-numerics.md §2, Wald).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        self.intersect_local(self.local_ray(ray), t_max, from_self)
    }

    /// [`Quadric::intersect`] from `eye_local`, a point's image in the local frame
    /// ([`Quadric::to_local_point`]), along world direction `dir`: the same bits, for rays from
    /// one point (a camera's eye) that share the origin's map.
    #[inline]
    pub(crate) fn intersect_from_local_point(
        &self,
        eye_local: DVec3,
        dir: DVec3,
        t_max: f64,
    ) -> Option<f64> {
        let local = Ray::new(eye_local, self.local.from_world.matrix3 * dir);
        self.intersect_local(local, t_max, false)
    }

    /// [`Quadric::intersect`] of the ray in the local frame ([`Quadric::local_ray`]).
    #[inline(always)]
    fn intersect_local(&self, local: Ray, t_max: f64, from_self: bool) -> Option<f64> {
        let Ray { origin: o, dir: d } = local;
        if from_self {
            let ad = self.a.times(d);
            let a = d.dot(ad);
            let beta = ad.dot(o) + self.b.dot(d);
            let t = -2.0 * beta / a;
            // Only a root ahead of the ray can be a re-hit: the box is asked only then (a shadow
            // ray leaving a convex side never asks it). Within the box's interval or nothing, as
            // after the slab test below (an empty or NaN interval holds no t).
            if t > 0.0 {
                let (lo, hi) = unit_cube_interval(unit_cube_slabs(o, d), t_max);
                return (t >= lo && t <= hi).then_some(t);
            }
            return None;
        }
        let slabs = unit_cube_slabs(o, d);
        let (lo, hi) = unit_cube_interval(slabs, t_max);
        // Also rejects NaN bounds (a zero direction).
        if lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
            return None;
        }
        let ad = self.a.times(d);
        let a = d.dot(ad);
        // Re-origin at the box entry (or keep the origin when it is inside the box).
        let mut base = lo;
        let mut o = o + d * lo;
        let mut beta = ad.dot(o) + self.b.dot(d);
        let mut gamma_ = self.eval_local(o);
        let (bb, ag) = (beta * beta, a * gamma_);
        if (bb - ag).abs() * 1024.0 < bb + ag.abs() {
            // Clamped to the box, not to t_max (its exit ≥ hi ≥ lo): the roots then do not
            // depend on t_max, so a root below t_max is the one an unbounded test finds, whatever
            // order a traversal tests shapes in and whatever limit it has reached
            // (`roots_do_not_depend_on_the_limit`).
            let exit = unit_cube_interval(slabs, f64::INFINITY).1;
            let s = (-beta / a).clamp(0.0, exit - lo);
            if s > 0.0 {
                o += d * s;
                base += s;
                beta = ad.dot(o) + self.b.dot(d);
                gamma_ = self.eval_local(o);
            }
        }
        // solve_quadratic's sign-aware roots, inlined without its bookkeeping: a non-finite root
        // (a = 0 gives q/a = ±∞, a double zero gives NaN) fails the interval test by itself.
        let disc = discriminant(a, beta, gamma_);
        // Negative or NaN: no real root.
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let q = -(beta + disc.sqrt().copysign(beta));
        let (r0, r1) = (base + q / a, base + gamma_ / q);
        let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
        if near >= lo && near > 0.0 && near <= hi {
            Some(near)
        } else if far >= lo && far > 0.0 && far <= hi {
            Some(far)
        } else {
            None
        }
    }

    /// Surface geometry at parameter `t` of `ray`.
    pub fn surface(&self, ray: &Ray, t: f64) -> SurfaceGeometry {
        let point = ray.at(t);
        let u = self.to_local_point(point);
        let half_grad = self.a.times(u) + self.b;
        let geometric_normal = normal_or(self.local.normal_to_world * half_grad, -ray.dir);
        let error = self.point_error(point, u, half_grad);
        SurfaceGeometry {
            point,
            geometric_normal,
            shading_normal: geometric_normal,
            error,
        }
    }

    /// Texture coordinates of a surface point: the point in the object frame, and its height
    /// within the visible part of the surface (the texture ramp's extent).
    pub fn texture_point(&self, point: DVec3) -> TexturePoint {
        let u = self.to_local_point(point);
        let (lo, hi) = self.height;
        let height = if hi > lo {
            ((u.z - lo) / (hi - lo)) as f32
        } else {
            0.5
        };
        TexturePoint {
            local: self.transform.from_world.transform_point3(point),
            height,
        }
    }

    /// How the texture coordinates change along the vector `v` (they are affine in the point).
    pub fn texture_offset(&self, v: DVec3) -> TexturePoint {
        let (lo, hi) = self.height;
        let height = if hi > lo {
            ((self.local.from_world.matrix3 * v).z / (hi - lo)) as f32
        } else {
            0.0
        };
        TexturePoint {
            local: self.transform.from_world.matrix3 * v,
            height,
        }
    }

    /// The larger principal curvature, in magnitude, at a surface point (world units of the
    /// quadric's own space; 0 where the gradient vanishes, at a cone's apex).
    ///
    /// With f(p) = uᵀAu + 2bᵀu + c and u = L(p − T) − c/h, the world gradient is 2Lᵀ(Au + b) and
    /// the Hessian 2LᵀAL; on the tangent plane (unit e₁, e₂ ⟂ the normal) the shape operator is
    /// eᵢᵀLᵀALeⱼ / |Lᵀ(Au + b)|, whose eigenvalues are the principal curvatures.
    pub fn curvature(&self, point: DVec3) -> f64 {
        let u = self.to_local_point(point);
        let l = self.local.from_world.matrix3;
        let half_grad = l.transpose() * (self.a.times(u) + self.b);
        let length = half_grad.length();
        if length.is_nan() || length <= 0.0 {
            return 0.0;
        }
        let (e1, e2) = orthonormal_basis(half_grad / length);
        let (l1, l2) = (l * e1, l * e2);
        let (m11, m12, m22) = (
            l1.dot(self.a.times(l1)) / length,
            l1.dot(self.a.times(l2)) / length,
            l2.dot(self.a.times(l2)) / length,
        );
        // Eigenvalues of the symmetric 2×2: mean ± radius; the larger magnitude is |mean| + radius.
        let mean = 0.5 * (m11 + m22);
        let radius = (0.25 * (m11 - m22) * (m11 - m22) + m12 * m12).sqrt();
        mean.abs() + radius
    }

    /// Bound on the world distance from the computed hit `point` (local `u`) to the true surface.
    ///
    /// First-order distance |f(u)|/|∇f| (Taubin), with f's rounding error γ₁₂·(|u|ᵀ|A||u| + 2|b|·|u| + |c|)
    /// added to |f| and the gradient taken in the *world* (Lᵀ∇ᵤf), so an anisotropic placement (a
    /// thin ellipsoid) is not charged its largest stretch along its thin normal; near a singular point
    /// (cone apex, ∇f → 0) the second-order bound √|f| (local units, times the frame's stretch) takes
    /// over. The rounding of the world point and of the frame map is added. Doubled for safety.
    fn point_error(&self, point: DVec3, u: DVec3, half_grad: DVec3) -> f64 {
        let au = u.abs();
        let magnitude = au.dot(self.abs_a.times(au)) + 2.0 * self.abs_b.dot(au) + self.c.abs();
        let residual = self.eval_local(u).abs() + gamma(12) * magnitude;
        let grad_world = 2.0 * (self.local.normal_to_world * half_grad).length();
        let first_order = residual / grad_world;
        let second_order = residual.sqrt() * self.stretch;
        let world_rounding = gamma(8)
            * (point.abs().max_element() + self.local.to_world.translation.abs().max_element());
        2.0 * (first_order.min(second_order) + world_rounding)
    }

    /// World-space bounds: the transformed clip box.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for i in 0..8 {
            let corner = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            let p = self.local.to_world.transform_point3(corner);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }
}
