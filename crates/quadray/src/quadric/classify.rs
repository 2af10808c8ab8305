//! What a quadric's equation describes: its class from the signature of its matrix (Sylvester's law
//! of inertia) after completing the square.

use super::{QuadricClass, QuadricKind};
use glam::{DMat3, DVec3};

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
