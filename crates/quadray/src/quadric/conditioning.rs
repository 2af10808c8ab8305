//! How well a quadric's coefficients hold its surface in f64.
//!
//! Coefficients are rounded when they are read (and when whatever wrote them computed them), and
//! again when the box-normalised local form is built from them, each time by about a unit in the
//! last place of the *largest term* that meets at a surface point. Where those terms are huge beside the shape (a small shape written in
//! coefficients about a far-away origin: (x − 10⁶)² expands to x² − 2·10⁶x + 10¹²), that rounding
//! moves the surface itself by far more than the intersector's own error, and no robust root
//! finding can bring it back. To first order, an error δf in f moves the surface by δf / |∇f|
//! along its normal (Taubin's distance), with
//!
//! δf ≈ u · (|A|x² + |B|y² + |C|z² + |D||xy| + |E||xz| + |F||yz| + |G||x| + |H||y| + |I||z| + |J|)
//!
//! for the ten coefficients in POV-Ray's order and the unit roundoff u = 2⁻⁵³: an estimate of the
//! order of magnitude (on the test case below, 5 times the displacement measured), not a bound.
//! It is scale invariant: only an offset between the coefficients' origin and the shape makes it
//! grow.

use super::Quadric;
use glam::DVec3;

/// Relative displacement ([`RoundingSensitivity::relative`]) above which the rounding of a
/// quadric's coefficients is worth a warning: a hundredth of a pixel when the shape spans a
/// thousand pixels.
pub const ROUNDING_WARNING: f64 = 1e-5;

/// The unit roundoff of f64, 2⁻⁵³.
const UNIT_ROUNDOFF: f64 = f64::EPSILON * 0.5;

/// Grid lines per axis on which surface points are sampled.
const LINES: usize = 9;

/// How far rounding the coefficients may move a quadric's surface (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundingSensitivity {
    /// Largest estimated displacement of the surface over the sampled points, object units.
    pub displacement: f64,
    /// Diagonal of the sampled surface points' bounds, object units.
    pub size: f64,
    /// Centre of those bounds in the object frame: the origin that coefficients written about the
    /// shape (and placed by a translation) would use.
    pub centre: DVec3,
}

impl RoundingSensitivity {
    /// The displacement as a fraction of the shape's size.
    pub fn relative(&self) -> f64 {
        self.displacement / self.size
    }
}

impl Quadric {
    /// Estimates how far the rounding of the coefficients may move the surface, from points of
    /// the surface inside the clip box found on a grid of lines along each axis; `None` when no
    /// point was found (the surface misses the box, or is too small for the grid).
    pub fn rounding_sensitivity(&self) -> Option<RoundingSensitivity> {
        let k = self.surface.coefficients().0;
        let (a, b, _) = self.surface.coefficients().to_matrix_form();
        let centre = (self.clip.min + self.clip.max) * 0.5;
        let half = (self.clip.max - self.clip.min) * 0.5;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut displacement: f64 = 0.0;
        let grid = |i: usize| -1.0 + 2.0 * i as f64 / (LINES - 1) as f64;
        for axis in 0..3 {
            let (e, p, q) = (DVec3::AXES[axis], (axis + 1) % 3, (axis + 2) % 3);
            for i in 0..LINES {
                for j in 0..LINES {
                    let mut base = DVec3::ZERO;
                    base[p] = grid(i);
                    base[q] = grid(j);
                    let roots = self.roots_on_line(&|t| base + t * e);
                    for &t in roots.as_slice().iter().filter(|t| t.abs() <= 1.0) {
                        let x = centre + half * (base + t * e);
                        let gradient = 2.0 * (a * x + b);
                        let length = gradient.length();
                        if !(length > 0.0 && length.is_finite()) {
                            continue; // a singular point (a cone's apex): no normal to move along
                        }
                        let ax = x.abs();
                        let terms = [
                            ax.x * ax.x,
                            ax.y * ax.y,
                            ax.z * ax.z,
                            ax.x * ax.y,
                            ax.x * ax.z,
                            ax.y * ax.z,
                            ax.x,
                            ax.y,
                            ax.z,
                            1.0,
                        ];
                        let magnitude: f64 = k.iter().zip(terms).map(|(k, m)| k.abs() * m).sum();
                        displacement = displacement.max(UNIT_ROUNDOFF * magnitude / length);
                        lo = lo.min(x);
                        hi = hi.max(x);
                    }
                }
            }
        }
        let size = (hi - lo).length();
        (lo.x <= hi.x).then(|| RoundingSensitivity {
            displacement,
            // A single sampled point (a tiny shape) has no extent: measure against the box.
            size: if size > 0.0 {
                size
            } else {
                half.length() * 2.0
            },
            centre: (lo + hi) * 0.5,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Ray, Transform};
    use crate::quadric::{ClipBox, Coefficients, QuadricKind, QuadricSurface};

    /// The ellipsoid (x − x0)² + y² + 10⁶z² = 1.21 (semi-axes 1.1, 1.1, 1.1e-3), written as
    /// coefficients about the origin, `g` = −2·x0 and `j` = x0² − 1.21, clipped by a box just
    /// around it.
    fn thin_ellipsoid(x0: f64, g: f64, j: f64) -> Quadric {
        let k = [1.0, 1.0, 1e6, 0.0, 0.0, 0.0, g, 0.0, 0.0, j];
        let margin = DVec3::new(1.2, 1.2, 1.2e-3);
        let centre = DVec3::new(x0, 0.0, 0.0);
        let clip = ClipBox {
            min: centre - margin,
            max: centre + margin,
        };
        Quadric::new(
            QuadricSurface::General(Coefficients(k)),
            clip,
            Transform::IDENTITY,
            0,
        )
        .unwrap()
    }

    /// How far from x0 − 1.1 a ray along the x axis meets the rim.
    fn rim_error(q: &Quadric, x0: f64) -> f64 {
        let ray = Ray::new(DVec3::new(x0 - 1.15, 0.0, 0.0), DVec3::X);
        (q.intersect(&ray, f64::INFINITY, false).unwrap() - 0.05).abs()
    }

    #[test]
    fn a_shape_far_from_its_coefficients_origin_is_flagged() {
        let near = thin_ellipsoid(0.0, 0.0, -1.21);
        let estimate = near.rounding_sensitivity().unwrap();
        assert!(estimate.relative() < 1e-14, "{estimate:?}");
        assert!(
            (estimate.size - 2.2 * 2f64.sqrt()).abs() < 0.05,
            "{estimate:?}"
        );
        assert!(rim_error(&near, 0.0) < 1e-15);
        // The same shape 10⁶ + 1/3 away, its coefficients printed to 17 significant digits as an
        // exporter would. Near x ≈ 10⁶ every term of f is a multiple of 2⁻¹³ ≈ 1.2e-4, so f is
        // known only to that step, and 1.21 is not a multiple of it: the surface moves by up to
        // 6e-5 / |∇f| (2.2 at the rim). The CLI issue's case.
        let x0 = 1e6 + 1.0 / 3.0;
        let far = thin_ellipsoid(x0, -2000000.6666666667, 1000000666665.5677);
        let estimate = far.rounding_sensitivity().unwrap();
        assert!(estimate.relative() > ROUNDING_WARNING, "{estimate:?}");
        assert!((estimate.centre - DVec3::new(x0, 0.0, 0.0)).length() < 0.1);
        // The surface really moves, by the estimate's order of magnitude.
        let moved = rim_error(&far, x0);
        assert!(
            moved <= estimate.displacement && moved >= estimate.displacement / 100.0,
            "moved {moved}, estimated {estimate:?}"
        );
        // 10³ away the estimate is ~1e-10 of the size: nothing to warn about.
        let x0 = 1e3 + 1.0 / 3.0;
        let mid = thin_ellipsoid(x0, -2000.6666666666667, 1000665.5677777778);
        assert!(mid.rounding_sensitivity().unwrap().relative() < ROUNDING_WARNING * 1e-3);
    }

    #[test]
    fn the_estimate_does_not_depend_on_scale() {
        for kind in QuadricKind::ALL {
            let at = |s: f64| {
                Quadric::new(
                    QuadricSurface::Canonical {
                        kind,
                        a: s,
                        b: 2.0 * s,
                        c: 0.5 * s,
                    },
                    ClipBox::cube(3.0 * s),
                    Transform::IDENTITY,
                    0,
                )
                .unwrap()
                .rounding_sensitivity()
                .unwrap()
                .relative()
            };
            for s in [1e-6, 1.0, 1e6] {
                assert!(at(s) < 1e-13, "{kind} at scale {s}: {}", at(s));
            }
        }
    }
}
