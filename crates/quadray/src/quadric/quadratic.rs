//! The quadratic part A of a quadric's local equation f(u) = uᵀAu + 2bᵀu + c, kept diagonal where
//! it is.
//!
//! The nine named kinds are diagonal in their object frame, and the local frame only scales and
//! shifts the object frame (the clip box becomes [-1, 1]³), so their A stays diagonal: A·v is
//! then three products instead of nine and six sums. The intersector takes A·v twice a test (of
//! the direction, and in f at the re-origined point), and the surface record once more.

use glam::{DMat3, DVec3};

/// A symmetric 3×3 matrix, diagonal or general.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum QuadraticPart {
    /// Only the diagonal is non-zero (the named kinds).
    Diagonal(DVec3),
    /// Any symmetric matrix (quadrics given by their ten coefficients).
    General(DMat3),
}

impl QuadraticPart {
    /// `a`, as a diagonal when its off-diagonal entries are zero.
    pub(super) fn new(a: DMat3) -> QuadraticPart {
        let off = [
            a.x_axis.y, a.x_axis.z, a.y_axis.x, a.y_axis.z, a.z_axis.x, a.z_axis.y,
        ];
        if off.iter().all(|&x| x == 0.0) {
            QuadraticPart::Diagonal(a.diagonal())
        } else {
            QuadraticPart::General(a)
        }
    }

    /// The matrix.
    pub(super) fn matrix(self) -> DMat3 {
        match self {
            QuadraticPart::Diagonal(d) => DMat3::from_diagonal(d),
            QuadraticPart::General(m) => m,
        }
    }

    /// The matrix with every entry replaced by its magnitude.
    pub(super) fn abs(self) -> QuadraticPart {
        match self {
            QuadraticPart::Diagonal(d) => QuadraticPart::Diagonal(d.abs()),
            QuadraticPart::General(m) => QuadraticPart::General(m.abs()),
        }
    }

    /// A·v. For a diagonal, the products alone: the general product adds zeros to them, which
    /// changes nothing but the sign of a zero component.
    #[inline(always)]
    pub(super) fn times(self, v: DVec3) -> DVec3 {
        match self {
            QuadraticPart::Diagonal(d) => d * v,
            QuadraticPart::General(m) => m * v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonal is recognised and multiplies as the matrix does; a general matrix stays one.
    #[test]
    fn diagonal_products_equal_the_general_ones() {
        let diagonal = DMat3::from_diagonal(DVec3::new(1.0, -0.25, 0.0));
        let general = DMat3::from_cols(
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(0.5, -0.25, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
        );
        assert!(matches!(
            QuadraticPart::new(diagonal),
            QuadraticPart::Diagonal(_)
        ));
        assert!(matches!(
            QuadraticPart::new(general),
            QuadraticPart::General(_)
        ));
        for m in [diagonal, general] {
            let part = QuadraticPart::new(m);
            assert_eq!(part.matrix(), m);
            for v in [DVec3::new(0.3, -7.0, 2.5), DVec3::new(-1e-300, 1e300, 3.0)] {
                assert_eq!(part.times(v), m * v, "{m} · {v}");
                assert_eq!(part.abs().times(v), m.abs() * v);
            }
        }
    }
}
