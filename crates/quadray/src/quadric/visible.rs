//! Where a quadric's surface lies inside its clip box: the visible height range the texture ramp
//! spans, and whether anything of the surface shows at all.

use super::Quadric;
use crate::math::{Roots, solve_quadratic};
use glam::DVec3;

impl Quadric {
    /// The local z range of the surface inside the box, or `None` when the surface misses the box.
    ///
    /// Sampled on vertical lines through a grid, sign changes over the top and bottom faces, and the
    /// analytic points where the normal is vertical (inside the box or on its side faces).
    pub(super) fn visible_height_range(&self) -> Option<(f64, f64)> {
        const N: usize = 33;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut note = |z: f64| {
            if (-1.0..=1.0).contains(&z) {
                lo = lo.min(z);
                hi = hi.max(z);
            }
        };
        let (a, b) = (self.a.matrix(), self.b);
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
        for &z in self.roots_on_line(&line).as_slice() {
            if inside(line(z)) {
                note(z);
            }
        }
    }

    /// The parameters t at which the local-frame line `t -> line(t)` (affine in t) meets the
    /// surface: f(line(t)) is quadratic in t, its coefficients recovered from three samples.
    pub(super) fn roots_on_line(&self, line: &impl Fn(f64) -> DVec3) -> Roots {
        let (f0, f1, fm) = (
            self.eval_local(line(0.0)),
            self.eval_local(line(1.0)),
            self.eval_local(line(-1.0)),
        );
        solve_quadratic((f1 + fm) * 0.5 - f0, (f1 - fm) * 0.25, f0)
    }
}
