//! How a quadric's surface is given: one of the nine kinds by name with its semi-axes, or the ten
//! general coefficients, and the box that clips it.

use glam::{DMat3, DVec3};
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
