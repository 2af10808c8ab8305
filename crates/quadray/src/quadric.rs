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

use crate::material::MaterialId;
use crate::math::{Ray, Transform, discriminant, gamma, slab_interval, solve_quadratic};
use crate::shape::{SurfaceGeometry, normal_or};
use crate::texture::TexturePoint;
use glam::{DAffine3, DMat3, DVec3};
use std::fmt;

/// The nine real non-degenerate quadric kinds, in the seed's two canonical forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QuadricKind {
    /// x²/a² + y²/b² + z²/c² = 1
    Ellipsoid,
    /// x²/a² + y²/b² − z²/c² = 1 (one sheet)
    Hyperboloid1,
    /// x²/a² + y²/b² − z²/c² = −1 (two sheets)
    Hyperboloid2,
    /// x²/a² + y²/b² − z²/c² = 0
    Cone,
    /// x²/a² + y²/b² = 1
    EllipticCylinder,
    /// x²/a² − y²/b² = 1
    HyperbolicCylinder,
    /// x²/a² = z/c
    ParabolicCylinder,
    /// x²/a² + y²/b² = z/c
    EllipticParaboloid,
    /// x²/a² − y²/b² = z/c
    HyperbolicParaboloid,
}

impl QuadricKind {
    /// Every kind, in the seed's order.
    pub const ALL: [QuadricKind; 9] = [
        QuadricKind::Ellipsoid,
        QuadricKind::Hyperboloid1,
        QuadricKind::Hyperboloid2,
        QuadricKind::Cone,
        QuadricKind::EllipticCylinder,
        QuadricKind::HyperbolicCylinder,
        QuadricKind::ParabolicCylinder,
        QuadricKind::EllipticParaboloid,
        QuadricKind::HyperbolicParaboloid,
    ];

    /// The kind's name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            QuadricKind::Ellipsoid => "ellipsoid",
            QuadricKind::Hyperboloid1 => "hyperboloid1",
            QuadricKind::Hyperboloid2 => "hyperboloid2",
            QuadricKind::Cone => "cone",
            QuadricKind::EllipticCylinder => "elliptic-cylinder",
            QuadricKind::HyperbolicCylinder => "hyperbolic-cylinder",
            QuadricKind::ParabolicCylinder => "parabolic-cylinder",
            QuadricKind::EllipticParaboloid => "elliptic-paraboloid",
            QuadricKind::HyperbolicParaboloid => "hyperbolic-paraboloid",
        }
    }

    /// The kind with this name, if any.
    pub fn from_name(name: &str) -> Option<QuadricKind> {
        QuadricKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The canonical equation, as text.
    pub fn equation(self) -> &'static str {
        match self {
            QuadricKind::Ellipsoid => "x²/a² + y²/b² + z²/c² = 1",
            QuadricKind::Hyperboloid1 => "x²/a² + y²/b² − z²/c² = 1",
            QuadricKind::Hyperboloid2 => "x²/a² + y²/b² − z²/c² = −1",
            QuadricKind::Cone => "x²/a² + y²/b² − z²/c² = 0",
            QuadricKind::EllipticCylinder => "x²/a² + y²/b² = 1",
            QuadricKind::HyperbolicCylinder => "x²/a² − y²/b² = 1",
            QuadricKind::ParabolicCylinder => "x²/a² = z/c",
            QuadricKind::EllipticParaboloid => "x²/a² + y²/b² = z/c",
            QuadricKind::HyperbolicParaboloid => "x²/a² − y²/b² = z/c",
        }
    }

    /// The general coefficients of the canonical equation with parameters a, b, c.
    pub fn coefficients(self, a: f64, b: f64, c: f64) -> Coefficients {
        let (ia, ib, ic) = (1.0 / (a * a), 1.0 / (b * b), 1.0 / (c * c));
        let k = match self {
            QuadricKind::Ellipsoid => [ia, ib, ic, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::Hyperboloid1 => [ia, ib, -ic, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::Hyperboloid2 => [ia, ib, -ic, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            QuadricKind::Cone => [ia, ib, -ic, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            QuadricKind::EllipticCylinder => [ia, ib, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::HyperbolicCylinder => [ia, -ib, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::ParabolicCylinder => {
                [ia, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0 / c, 0.0]
            }
            QuadricKind::EllipticParaboloid => {
                [ia, ib, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0 / c, 0.0]
            }
            QuadricKind::HyperbolicParaboloid => {
                [ia, -ib, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0 / c, 0.0]
            }
        };
        Coefficients(k)
    }
}

impl fmt::Display for QuadricKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// General quadric coefficients in POV-Ray's order:
/// f(x, y, z) = A·x² + B·y² + C·z² + D·xy + E·xz + F·yz + G·x + H·y + I·z + J.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients(pub [f64; 10]);

impl Coefficients {
    /// Splits into the symmetric form f(p) = pᵀAp + 2bᵀp + c.
    pub fn to_matrix_form(&self) -> (DMat3, DVec3, f64) {
        let k = &self.0;
        let a = DMat3::from_cols(
            DVec3::new(k[0], k[3] * 0.5, k[4] * 0.5),
            DVec3::new(k[3] * 0.5, k[1], k[5] * 0.5),
            DVec3::new(k[4] * 0.5, k[5] * 0.5, k[2]),
        );
        (a, DVec3::new(k[6], k[7], k[8]) * 0.5, k[9])
    }

    /// f at `p`.
    pub fn eval(&self, p: DVec3) -> f64 {
        let (a, b, c) = self.to_matrix_form();
        p.dot(a * p) + 2.0 * b.dot(p) + c
    }
}

/// How a quadric's surface is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum QuadricSurface {
    /// One of the nine kinds with its parameters a, b, c (parameters a kind does not use are ignored).
    Canonical {
        /// Which kind.
        kind: QuadricKind,
        /// Semi-axis along x.
        a: f64,
        /// Semi-axis along y.
        b: f64,
        /// Semi-axis (or paraboloid scale) along z.
        c: f64,
    },
    /// The ten general coefficients.
    General(Coefficients),
}

impl QuadricSurface {
    /// The general coefficients of this surface.
    pub fn coefficients(&self) -> Coefficients {
        match *self {
            QuadricSurface::Canonical { kind, a, b, c } => kind.coefficients(a, b, c),
            QuadricSurface::General(k) => k,
        }
    }
}

/// An axis-aligned clip box in the quadric's object frame; only the part of the surface inside it is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipBox {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl ClipBox {
    /// The seed's cube [-r, r]³ of "bounding box radius" r.
    pub fn cube(r: f64) -> ClipBox {
        ClipBox {
            min: DVec3::splat(-r),
            max: DVec3::splat(r),
        }
    }
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
    a: DMat3,
    b: DVec3,
    c: f64,
    /// Entry-wise absolute values of `a` and `b`, for rounding-error bounds.
    abs_a: DMat3,
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
        let mut b = h * (ao * centre + bo);
        let mut c = centre.dot(ao * centre) + 2.0 * bo.dot(centre) + co;
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
        let box_to_object = DAffine3::from_mat3_translation(h, centre);
        let local =
            Transform::new(transform.to_world * box_to_object).ok_or(QuadricError::BadTransform)?;
        let abs = |m: DMat3| DMat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
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
            a,
            b,
            c,
            abs_a: abs(a),
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
        (self.a, self.b, self.c)
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
    fn to_local_point(&self, p: DVec3) -> DVec3 {
        self.local.from_world.matrix3 * (p - self.world_origin) - self.centre_local
    }

    /// The implicit function in the normalised local frame.
    #[inline]
    fn eval_local(&self, u: DVec3) -> f64 {
        u.dot(self.a * u) + 2.0 * self.b.dot(u) + self.c
    }

    /// Nearest t in (0, `t_max`) where the ray meets the clipped surface.
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
        let Ray { origin: o, dir: d } = self.local_ray(ray);
        let (t_in, t_out) = slab_interval(o, d, -DVec3::ONE, DVec3::ONE);
        let lo = t_in.max(0.0);
        let hi = t_out.min(t_max);
        // Also rejects NaN bounds (a zero direction).
        if lo.partial_cmp(&hi).is_none_or(|o| o.is_gt()) {
            return None;
        }
        let ad = self.a * d;
        let a = d.dot(ad);
        if from_self {
            let beta = ad.dot(o) + self.b.dot(d);
            let t = -2.0 * beta / a;
            return (t > 0.0 && t >= lo && t <= hi).then_some(t);
        }
        // Re-origin at the box entry (or keep the origin when it is inside the box).
        let mut base = lo;
        let mut o = o + d * lo;
        let mut beta = ad.dot(o) + self.b.dot(d);
        let mut gamma_ = self.eval_local(o);
        let (bb, ag) = (beta * beta, a * gamma_);
        if (bb - ag).abs() * 1024.0 < bb + ag.abs() {
            let s = (-beta / a).clamp(0.0, hi - lo);
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
        let half_grad = self.a * u + self.b;
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

    /// Bound on the world distance from the computed hit `point` (local `u`) to the true surface.
    ///
    /// First-order distance |f(u)|/|∇f| (Taubin), with f's rounding error γ₁₂·(|u|ᵀ|A||u| + 2|b|·|u| + |c|)
    /// added to |f| and the gradient taken in the *world* (Lᵀ∇ᵤf), so an anisotropic placement (a
    /// thin ellipsoid) is not charged its largest stretch along its thin normal; near a singular point
    /// (cone apex, ∇f → 0) the second-order bound √|f| (local units, times the frame's stretch) takes
    /// over. The rounding of the world point and of the frame map is added. Doubled for safety.
    fn point_error(&self, point: DVec3, u: DVec3, half_grad: DVec3) -> f64 {
        let au = u.abs();
        let magnitude = au.dot(self.abs_a * au) + 2.0 * self.abs_b.dot(au) + self.c.abs();
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

    /// The local z range of the surface inside the box, or `None` when the surface misses the box.
    ///
    /// Sampled on vertical lines through a grid, sign changes over the top and bottom faces, and the
    /// analytic points where the normal is vertical (inside the box or on its side faces).
    fn visible_height_range(&self) -> Option<(f64, f64)> {
        const N: usize = 33;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut note = |z: f64| {
            if (-1.0..=1.0).contains(&z) {
                lo = lo.min(z);
                hi = hi.max(z);
            }
        };
        let (a, b) = (self.a, self.b);
        let inside = |p: DVec3| p.abs().max_element() <= 1.0 + 1e-12;
        let grid = |i: usize| -1.0 + 2.0 * i as f64 / (N - 1) as f64;
        // Roots along the vertical line through (x, y).
        let vertical = |x: f64, y: f64| {
            let p = DVec3::new(x, y, 0.0);
            solve_quadratic(
                a.z_axis.z,
                a.z_axis.x * x + a.z_axis.y * y + b.z,
                self.eval_local(p),
            )
        };
        for i in 0..N {
            for j in 0..N {
                for &z in vertical(grid(i), grid(j)).as_slice() {
                    note(z);
                }
            }
        }
        // The surface crosses the top or bottom face where f changes sign over it.
        for z in [-1.0, 1.0] {
            let (mut neg, mut pos) = (false, false);
            for i in 0..N {
                for j in 0..N {
                    let f = self.eval_local(DVec3::new(grid(i), grid(j), z));
                    neg |= f <= 0.0;
                    pos |= f >= 0.0;
                }
            }
            if neg && pos {
                note(z);
            }
        }
        // Vertical-normal points: ∂f/∂x = ∂f/∂y = 0 gives (x, y) linear in z; f along that line is quadratic in z.
        let m = glam::DMat2::from_cols(
            glam::DVec2::new(a.x_axis.x, a.x_axis.y),
            glam::DVec2::new(a.y_axis.x, a.y_axis.y),
        );
        if m.determinant().abs() > 1e-12 {
            let inv = m.inverse();
            let slope = -(inv * glam::DVec2::new(a.z_axis.x, a.z_axis.y));
            let base = -(inv * glam::DVec2::new(b.x, b.y));
            let line = |z: f64| DVec3::new(base.x + slope.x * z, base.y + slope.y * z, z);
            self.note_line_roots(line, &inside, &mut note);
        }
        // Same on the side faces x = ±1 (∂f/∂y = 0) and y = ±1 (∂f/∂x = 0).
        for s in [-1.0, 1.0] {
            if a.y_axis.y.abs() > 1e-12 {
                let line = |z: f64| {
                    DVec3::new(s, -(a.x_axis.y * s + a.z_axis.y * z + b.y) / a.y_axis.y, z)
                };
                self.note_line_roots(line, &inside, &mut note);
            }
            if a.x_axis.x.abs() > 1e-12 {
                let line = |z: f64| {
                    DVec3::new(-(a.y_axis.x * s + a.z_axis.x * z + b.x) / a.x_axis.x, s, z)
                };
                self.note_line_roots(line, &inside, &mut note);
            }
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// Notes the z of points on the line `z -> line(z)` (affine in z) where f = 0 inside the box.
    fn note_line_roots(
        &self,
        line: impl Fn(f64) -> DVec3,
        inside: &impl Fn(DVec3) -> bool,
        note: &mut impl FnMut(f64),
    ) {
        // f(line(z)) is quadratic in z: recover its coefficients from three samples.
        let (f0, f1, fm) = (
            self.eval_local(line(0.0)),
            self.eval_local(line(1.0)),
            self.eval_local(line(-1.0)),
        );
        let qa = (f1 + fm) * 0.5 - f0;
        let qb = (f1 - fm) * 0.25;
        for &z in solve_quadratic(qa, qb, f0).as_slice() {
            if inside(line(z)) {
                note(z);
            }
        }
    }
}

/// Classifies f(u) = uᵀAu + 2bᵀu + c (coefficients normalised to magnitude ≤ 1) by diagonalising A,
/// completing the square on its nonzero eigen-directions, and reading rank, signs and constant.
///
/// Every threshold is relative, so a shape's class does not depend on its size against its clip box:
/// A is first equilibrated to a unit diagonal by the congruence S·A·S with S = diag(1/√|Aᵢᵢ|), which
/// keeps the signature (Sylvester's law of inertia) but makes the eigenvalues of graded matrices such
/// as an ellipsoid with axes 1e-4 : 1 : 1e4 (A = diag(1, 1e-8, 1e-16)) well separated from zero; an
/// eigenvalue is zero below 1e-10 of the largest, a linear term below 1e-10 of the largest coefficient,
/// and the completed constant k = c − Σ bᵢ²/λᵢ is zero when it cancels to below 1e-10 of its terms.
pub fn classify(a: DMat3, b: DVec3, c: f64) -> QuadricClass {
    const TOL: f64 = 1e-10;
    let diag = DVec3::new(a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let s = DVec3::select(diag.cmpne(DVec3::ZERO), diag.abs().powf(-0.5), DVec3::ONE);
    let sm = DMat3::from_diagonal(s);
    let a = sm * a * sm;
    let b = s * b;
    let (values, vectors) = symmetric_eigen(a);
    let largest = values.abs().max_element();
    let scale = largest.max(b.abs().max_element()).max(c.abs());
    let b_rot = vectors.transpose() * b;
    let mut positive = 0;
    let mut negative = 0;
    let mut constant = c;
    let mut completed = c.abs();
    let mut linear = false;
    for i in 0..3 {
        let l = values[i];
        if l.abs() > TOL * largest {
            if l > 0.0 {
                positive += 1
            } else {
                negative += 1
            }
            let term = b_rot[i] * b_rot[i] / l;
            constant -= term;
            completed += term.abs();
        } else if b_rot[i].abs() > TOL * scale {
            linear = true;
        }
    }
    // Orient so that the majority of eigenvalues is positive (f and −f describe the same surface).
    if negative > positive {
        std::mem::swap(&mut positive, &mut negative);
        constant = -constant;
    }
    let k = if constant.abs() <= TOL * completed {
        0.0
    } else {
        constant
    };
    use QuadricKind as K;
    match (positive, negative, linear) {
        (3, 0, _) if k < 0.0 => QuadricClass::Proper(K::Ellipsoid),
        (3, 0, _) if k > 0.0 => QuadricClass::Empty,
        (3, 0, _) => QuadricClass::Point,
        (2, 1, _) if k < 0.0 => QuadricClass::Proper(K::Hyperboloid1),
        (2, 1, _) if k > 0.0 => QuadricClass::Proper(K::Hyperboloid2),
        (2, 1, _) => QuadricClass::Proper(K::Cone),
        (2, 0, true) => QuadricClass::Proper(K::EllipticParaboloid),
        (1, 1, true) => QuadricClass::Proper(K::HyperbolicParaboloid),
        (2, 0, false) if k < 0.0 => QuadricClass::Proper(K::EllipticCylinder),
        (2, 0, false) if k > 0.0 => QuadricClass::Empty,
        (2, 0, false) => QuadricClass::Line,
        (1, 1, false) if k != 0.0 => QuadricClass::Proper(K::HyperbolicCylinder),
        (1, 1, false) => QuadricClass::IntersectingPlanes,
        (1, 0, true) => QuadricClass::Proper(K::ParabolicCylinder),
        (1, 0, false) if k < 0.0 => QuadricClass::ParallelPlanes,
        (1, 0, false) if k > 0.0 => QuadricClass::Empty,
        (1, 0, false) => QuadricClass::DoublePlane,
        (0, 0, true) => QuadricClass::Plane,
        (0, 0, false) if k != 0.0 => QuadricClass::Empty,
        _ => QuadricClass::AllZero,
    }
}

/// Eigenvalues and eigenvectors (as columns) of a symmetric 3×3 matrix, by cyclic Jacobi rotations.
fn symmetric_eigen(m: DMat3) -> (DVec3, DMat3) {
    let mut a = m.to_cols_array_2d();
    let mut v = DMat3::IDENTITY.to_cols_array_2d();
    for _sweep in 0..64 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-32 * diag || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let cs = 1.0 / (t * t + 1.0).sqrt();
            let sn = t * cs;
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            let r = 3 - p - q;
            let (arp, arq) = (a[r][p], a[r][q]);
            a[r][p] = cs * arp - sn * arq;
            a[p][r] = a[r][p];
            a[r][q] = sn * arp + cs * arq;
            a[q][r] = a[r][q];
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = cs * vp - sn * vq;
                row[q] = sn * vp + cs * vq;
            }
        }
    }
    // `v` was filled row-major as v[row][col]; convert to glam's column-major.
    let vectors = DMat3::from_cols_array_2d(&v).transpose();
    (DVec3::new(a[0][0], a[1][1], a[2][2]), vectors)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quadric(kind: QuadricKind, a: f64, b: f64, c: f64, r: f64) -> Quadric {
        Quadric::new(
            QuadricSurface::Canonical { kind, a, b, c },
            ClipBox::cube(r),
            Transform::IDENTITY,
            0,
        )
        .unwrap()
    }

    fn gradient(k: &Coefficients, p: DVec3) -> DVec3 {
        let (a, b, _) = k.to_matrix_form();
        2.0 * (a * p + b)
    }

    #[test]
    fn names_round_trip_and_classify_as_themselves() {
        for kind in QuadricKind::ALL {
            assert_eq!(QuadricKind::from_name(kind.name()), Some(kind));
            let q = quadric(kind, 0.7, 1.3, 0.9, 2.0);
            assert_eq!(q.class(), QuadricClass::Proper(kind), "{kind}");
        }
        assert_eq!(QuadricKind::from_name("torus"), None);
    }

    #[test]
    fn classification_survives_rotation_and_translation() {
        let t = Transform::from_srt(
            DVec3::new(1.0, 2.0, 0.5),
            DVec3::new(20.0, -35.0, 70.0),
            DVec3::new(3.0, -1.0, 2.0),
        )
        .unwrap();
        for kind in QuadricKind::ALL {
            let q = Quadric::new(
                QuadricSurface::Canonical {
                    kind,
                    a: 1.0,
                    b: 1.5,
                    c: 0.5,
                },
                ClipBox {
                    min: DVec3::new(-2.0, -1.0, -0.5),
                    max: DVec3::new(1.0, 3.0, 2.0),
                },
                t,
                0,
            )
            .unwrap();
            assert_eq!(q.class(), QuadricClass::Proper(kind));
        }
    }

    #[test]
    fn degenerate_inputs_are_classified_and_rejected() {
        let general = |k: [f64; 10]| {
            Quadric::new(
                QuadricSurface::General(Coefficients(k)),
                ClipBox::cube(2.0),
                Transform::IDENTITY,
                0,
            )
        };
        let e = |class| Err(QuadricError::Degenerate(class));
        assert_eq!(general([0.0; 10]), e(QuadricClass::AllZero));
        assert_eq!(
            general([1.0, 0., 0., 0., 0., 0., 0., 0., 0., 0.]),
            e(QuadricClass::DoublePlane)
        );
        assert_eq!(
            general([1.0, 1.0, 1.0, 0., 0., 0., 0., 0., 0., 1.0]),
            e(QuadricClass::Empty)
        );
        assert_eq!(
            general([1.0, 1.0, 1.0, 0., 0., 0., 0., 0., 0., 0.0]),
            e(QuadricClass::Point)
        );
        assert_eq!(
            general([0.0, 0.0, 0.0, 0., 0., 0., 1., 0., 0., 0.0]),
            e(QuadricClass::Plane)
        );
        assert_eq!(
            general([1.0, 1.0, 0.0, 0., 0., 0., 0., 0., 0., 0.0]),
            e(QuadricClass::Line)
        );
        let pair = general([1.0, 0., 0., 0., 0., 0., 0., 0., 0., -1.0]).unwrap();
        assert_eq!(pair.class(), QuadricClass::ParallelPlanes);
        let cross = general([1.0, -1.0, 0., 0., 0., 0., 0., 0., 0., 0.0]).unwrap();
        assert_eq!(cross.class(), QuadricClass::IntersectingPlanes);
    }

    #[test]
    fn rejects_bad_parameters_and_boxes() {
        let s = QuadricSurface::Canonical {
            kind: QuadricKind::Ellipsoid,
            a: -1.0,
            b: 1.0,
            c: 1.0,
        };
        assert!(matches!(
            Quadric::new(s, ClipBox::cube(1.0), Transform::IDENTITY, 0),
            Err(QuadricError::BadParameter { name: "a", .. })
        ));
        let s = QuadricSurface::Canonical {
            kind: QuadricKind::Ellipsoid,
            a: 1.0,
            b: f64::NAN,
            c: 1.0,
        };
        assert!(Quadric::new(s, ClipBox::cube(1.0), Transform::IDENTITY, 0).is_err());
        let s = QuadricSurface::Canonical {
            kind: QuadricKind::Ellipsoid,
            a: 1.0,
            b: 1.0,
            c: 1.0,
        };
        let flat = ClipBox {
            min: DVec3::new(-1.0, -1.0, 0.0),
            max: DVec3::new(1.0, 1.0, 0.0),
        };
        assert!(matches!(
            Quadric::new(s, flat, Transform::IDENTITY, 0),
            Err(QuadricError::EmptyClipBox { .. })
        ));
    }

    #[test]
    fn analytic_hits_per_kind() {
        let inf = f64::INFINITY;
        let down = |x: f64, y: f64| Ray::new(DVec3::new(x, y, 10.0), -DVec3::Z);
        let along_x = |y: f64, z: f64| Ray::new(DVec3::new(-10.0, y, z), DVec3::X);
        // Ellipsoid a=2,b=1,c=0.5 from above: z = 0.5.
        let q = quadric(QuadricKind::Ellipsoid, 2.0, 1.0, 0.5, 3.0);
        assert!((q.intersect(&down(0.0, 0.0), inf, false).unwrap() - 9.5).abs() < 1e-14);
        // From inside, the far wall.
        let inside = Ray::new(DVec3::ZERO, DVec3::X);
        assert!((q.intersect(&inside, inf, false).unwrap() - 2.0).abs() < 1e-14);
        // Hyperboloid of one sheet: waist radius 1 along x at z = 0 -> t = 9.
        let q = quadric(QuadricKind::Hyperboloid1, 1.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&along_x(0.0, 0.0), inf, false).unwrap() - 9.0).abs() < 1e-14);
        // Two sheets: vertex at z = c = 1 from above.
        let q = quadric(QuadricKind::Hyperboloid2, 1.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&down(0.0, 0.0), inf, false).unwrap() - 9.0).abs() < 1e-14);
        // Cone x²+y² = z²: at height z = 2 along x, x = -2 -> t = 8.
        let q = quadric(QuadricKind::Cone, 1.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&along_x(0.0, 2.0), inf, false).unwrap() - 8.0).abs() < 1e-14);
        // Elliptic cylinder a = 2: t = 8 along x.
        let q = quadric(QuadricKind::EllipticCylinder, 2.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&along_x(0.0, 0.5), inf, false).unwrap() - 8.0).abs() < 1e-14);
        // Hyperbolic cylinder x² − y² = 1: at y = 0, x = -1 -> t = 9.
        let q = quadric(QuadricKind::HyperbolicCylinder, 1.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&along_x(0.0, 0.0), inf, false).unwrap() - 9.0).abs() < 1e-14);
        // Parabolic cylinder z = x²: from above at x = 1 -> z = 1, t = 9.
        let q = quadric(QuadricKind::ParabolicCylinder, 1.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&down(1.0, 0.7), inf, false).unwrap() - 9.0).abs() < 1e-14);
        // Elliptic paraboloid exactly along its axis (a = 0 in the quadratic): vertex at t = 10.
        let q = quadric(QuadricKind::EllipticParaboloid, 1.0, 1.0, 1.0, 3.0);
        assert_eq!(q.intersect(&down(0.0, 0.0), inf, false), Some(10.0));
        // Saddle z = x² − y² at (1, 0.5): z = 0.75 -> t = 9.25.
        let q = quadric(QuadricKind::HyperbolicParaboloid, 1.0, 1.0, 1.0, 3.0);
        assert!((q.intersect(&down(1.0, 0.5), inf, false).unwrap() - 9.25).abs() < 1e-14);
    }

    #[test]
    fn far_root_through_the_clip_opening() {
        // A paraboloid cup z = x² + y² clipped at |z| <= 1: looking down the axis at x = 0.5 the outer
        // wall (z = 0.25) is hit; looking in through the rim from the side, the near root is outside the
        // box and only the far wall counts.
        let q = quadric(QuadricKind::EllipticParaboloid, 1.0, 1.0, 1.0, 1.0);
        let r = Ray::new(DVec3::new(-3.0, 0.0, 0.9), DVec3::new(1.0, 0.0, 0.0));
        // Roots at x = ±√0.9 ≈ ±0.949, both inside the box: the near one wins.
        let t = q.intersect(&r, f64::INFINITY, false).unwrap();
        assert!((t - (3.0 - 0.9f64.sqrt())).abs() < 1e-14);
        // Through the top opening, aimed down and sideways: the near root lies above the box (z > 1).
        // Through (-0.5, 0, 1): backwards the line meets the paraboloid at x ≈ -3.1, z ≈ 9.7 (outside).
        let dir = DVec3::new(0.3, 0.0, -1.0);
        let o = DVec3::new(-0.5, 0.0, 1.0) - dir * 2.0;
        let r = Ray::new(o, dir);
        let t = q.intersect(&r, f64::INFINITY, false).unwrap();
        let p = r.at(t);
        assert!(p.z <= 1.0 && (p.z - (p.x * p.x + p.y * p.y)).abs() < 1e-12);
        assert!(p.x > -1.0, "hit the far inner wall, x = {}", p.x);
    }

    #[test]
    fn normals_equal_normalised_gradient_and_finite_differences() {
        let t = Transform::from_srt(
            DVec3::new(1.5, 0.7, 1.2),
            DVec3::new(10.0, 20.0, 30.0),
            DVec3::new(0.5, -1.0, 2.0),
        )
        .unwrap();
        for kind in QuadricKind::ALL {
            let surface = QuadricSurface::Canonical {
                kind,
                a: 0.8,
                b: 1.1,
                c: 0.9,
            };
            let q = Quadric::new(surface, ClipBox::cube(1.5), t, 0).unwrap();
            let k = surface.coefficients();
            let mut hits = 0;
            for i in 0..40 {
                let ang = i as f64 * 0.7;
                let target = t.to_world.transform_point3(DVec3::new(
                    ang.cos() * 1.1,
                    ang.sin() * 0.4,
                    1.2 * (i as f64 * 1.3).sin(),
                ));
                let from = target + DVec3::new(ang.sin(), 2.0, 1.0 + ang.cos()) * 6.0;
                let ray = Ray::new(from, (target - from).normalize());
                let Some(th) = q.intersect(&ray, f64::INFINITY, false) else {
                    continue;
                };
                hits += 1;
                let s = q.surface(&ray, th);
                let p_obj = t.from_world.transform_point3(s.point);
                // Gradient in the object frame, mapped to world by the inverse transpose.
                let expected = (t.normal_to_world * gradient(&k, p_obj)).normalize();
                assert!(s.geometric_normal.dot(expected) > 1.0 - 1e-9, "{kind}");
                // Central differences of f in world coordinates.
                let fw = |p: DVec3| k.eval(t.from_world.transform_point3(p));
                let h = 1e-6;
                let fd = DVec3::new(
                    fw(s.point + DVec3::X * h) - fw(s.point - DVec3::X * h),
                    fw(s.point + DVec3::Y * h) - fw(s.point - DVec3::Y * h),
                    fw(s.point + DVec3::Z * h) - fw(s.point - DVec3::Z * h),
                )
                .normalize();
                assert!(
                    s.geometric_normal.dot(fd) > 1.0 - 1e-6,
                    "{kind}: {} vs {}",
                    s.geometric_normal,
                    fd
                );
                assert!((s.geometric_normal.length() - 1.0).abs() < 1e-12);
            }
            assert!(hits > 5, "{kind}: only {hits} hits");
        }
    }

    #[test]
    fn spawned_rays_never_self_hit_but_find_concave_second_hits() {
        // Inside a paraboloid cup a reflected ray crosses to the opposite wall.
        let q = quadric(QuadricKind::EllipticParaboloid, 1.0, 1.0, 1.0, 1.0);
        let r = Ray::new(DVec3::new(0.5, 0.0, 5.0), -DVec3::Z);
        let t = q.intersect(&r, f64::INFINITY, false).unwrap();
        let s = q.surface(&r, t);
        let n = s.geometric_normal;
        let refl = r.dir - 2.0 * r.dir.dot(n) * n;
        let spawned = Ray::new(crate::math::offset_origin(s.point, n, s.error, refl), refl);
        let t2 = q
            .intersect(&spawned, f64::INFINITY, true)
            .expect("concave second hit");
        assert!(t2 > 0.1);
        // Leaving the outside of an ellipsoid: no hit.
        let e = quadric(QuadricKind::Ellipsoid, 1.0, 2.0, 0.5, 3.0);
        let r = Ray::new(DVec3::new(0.1, 0.2, 5.0), -DVec3::Z);
        let t = e.intersect(&r, f64::INFINITY, false).unwrap();
        let s = e.surface(&r, t);
        let out = Ray::new(
            crate::math::offset_origin(s.point, s.geometric_normal, s.error, DVec3::Z),
            DVec3::Z,
        );
        assert_eq!(e.intersect(&out, f64::INFINITY, true), None);
    }

    #[test]
    fn cone_apex_gets_a_finite_normal() {
        let q = quadric(QuadricKind::Cone, 1.0, 1.0, 1.0, 1.0);
        let r = Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y);
        let t = q
            .intersect(&r, f64::INFINITY, false)
            .expect("the apex is on the surface");
        assert!((t - 5.0).abs() < 1e-12);
        let s = q.surface(&r, t);
        assert!(
            s.geometric_normal.is_finite() && (s.geometric_normal.length() - 1.0).abs() < 1e-12
        );
        assert!(s.error.is_finite());
    }

    #[test]
    fn height_range_follows_the_visible_surface() {
        // Ellipsoid with c = 0.5 inside a cube of radius 2: the ramp spans z in [-0.5, 0.5].
        let q = quadric(QuadricKind::Ellipsoid, 1.0, 1.0, 0.5, 2.0);
        let (lo, hi) = q.height;
        assert!(
            (lo * 2.0 + 0.5).abs() < 1e-9 && (hi * 2.0 - 0.5).abs() < 1e-9,
            "{lo} {hi}"
        );
        // A cylinder spans the whole box.
        let q = quadric(QuadricKind::EllipticCylinder, 1.0, 1.0, 1.0, 2.0);
        assert_eq!(q.height, (-1.0, 1.0));
        // A sphere outside its box is invisible.
        let s = QuadricSurface::Canonical {
            kind: QuadricKind::Ellipsoid,
            a: 0.1,
            b: 0.1,
            c: 0.1,
        };
        let far = ClipBox {
            min: DVec3::splat(1.0),
            max: DVec3::splat(2.0),
        };
        assert!(
            !Quadric::new(s, far, Transform::IDENTITY, 0)
                .unwrap()
                .is_visible()
        );
    }
}
