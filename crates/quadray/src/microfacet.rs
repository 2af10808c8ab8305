//! Glossy reflection off rough surfaces: the GGX (Trowbridge–Reitz) microfacet distribution with
//! Smith's height-correlated masking, its visible normals sampled as Heitz describes ("Sampling
//! the GGX Distribution of Visible Normals", JCGT 7(4), 2018).
//!
//! A reflected ray is the view direction mirrored about a microfacet normal drawn from the
//! normals the viewer sees. Its weight in the estimate of the reflected light is then
//! G2(v, l) / G1(v) times the mirror colour: the distribution and the cosines cancel against the
//! sampling density, so the estimate has little noise and converges as samples are added.
//! Conventions: `alpha` = roughness², glTF's; directions are unit vectors pointing away from the
//! surface.

use glam::DVec3;

/// Roughness below which a surface is a mirror: one ray, no noise (α < 10⁻⁴).
pub const MIRROR_ROUGHNESS: f32 = 0.01;

/// The GGX distribution of normals, D(h) = α² / (π ((α² − 1) cos² θ_h + 1)²), for a microfacet
/// normal at cosine `cos_h` to the surface normal.
fn distribution(alpha: f64, cos_h: f64) -> f64 {
    let a2 = alpha * alpha;
    let denominator = (a2 - 1.0) * cos_h * cos_h + 1.0;
    a2 / (std::f64::consts::PI * denominator * denominator)
}

/// Smith's Λ for GGX with parameter `alpha` at a direction whose cosine with the normal is
/// `cos`: Λ = (−1 + √(1 + α² tan²θ)) / 2.
fn lambda(alpha: f64, cos: f64) -> f64 {
    let cos2 = (cos * cos).max(1e-300);
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// A microfacet normal drawn from the GGX normals visible from `view` (in the frame whose z is
/// the surface normal, `view.z > 0`), for the point `u` in [0, 1)² (Heitz 2018, listing 1, with
/// equal roughness in both directions).
fn visible_normal(view: DVec3, alpha: f64, (u1, u2): (f64, f64)) -> DVec3 {
    // The view in the hemisphere configuration (the distribution stretched to roughness 1).
    let vh = DVec3::new(alpha * view.x, alpha * view.y, view.z).normalize();
    // An orthonormal basis around it.
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        DVec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        DVec3::X
    };
    let t2 = vh.cross(t1);
    // A point on the projected disk, squeezed towards the visible half.
    let r = u1.sqrt();
    let phi = 2.0 * std::f64::consts::PI * u2;
    let (p1, mut p2) = (r * phi.cos(), r * phi.sin());
    let s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    // Back onto the hemisphere, then unstretched.
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// A glossy reflection of the ray arriving along unit `incoming` at a surface with unit normal
/// `n` (facing the ray) and GGX parameter `alpha`, for the sample point `u`: the reflected
/// direction and its weight G2 / G1, or `None` when the drawn microfacet sends it below the
/// surface (that sample reflects nothing).
pub fn reflect_glossy(
    incoming: DVec3,
    n: DVec3,
    alpha: f64,
    u: (f64, f64),
) -> Option<(DVec3, f32)> {
    let (tangent, bitangent) = crate::math::orthonormal_basis(n);
    let to_local = |d: DVec3| DVec3::new(d.dot(tangent), d.dot(bitangent), d.dot(n));
    let view = to_local(-incoming);
    if view.z <= 0.0 {
        return None;
    }
    let m = visible_normal(view, alpha, u);
    let light = m * (2.0 * view.dot(m)) - view;
    if light.z <= 0.0 {
        return None;
    }
    let (lv, ll) = (lambda(alpha, view.z), lambda(alpha, light.z));
    let weight = (1.0 + lv) / (1.0 + lv + ll);
    let world = tangent * light.x + bitangent * light.y + n * light.z;
    Some((world.normalize(), weight as f32))
}

/// Smallest α a GGX highlight is evaluated with: a point light's highlight on a perfect mirror is
/// a point of infinite brightness (the glTF-Sample-Viewer clamps likewise).
const MIN_HIGHLIGHT_ALPHA: f64 = 0.0025;

/// The light a GGX surface sends towards `view` from a light in direction `light` (unit vectors
/// away from the surface, unit normal `n`), per unit irradiance on a surface facing the light,
/// as a factor of the highlight colour at normal incidence `f0`: π·F·D·G2 / (4 cos θ_v), the
/// specular BRDF times cos θ_l, with Schlick's F = f0 + (1 − f0)(1 − v·h)⁵ (π: quadray's light
/// units make a white Lambertian surface facing a light show its irradiance).
pub fn highlight(n: DVec3, view: DVec3, light: DVec3, alpha: f64, f0: glam::Vec3) -> glam::Vec3 {
    let (cos_v, cos_l) = (n.dot(view), n.dot(light));
    if cos_v <= 0.0 || cos_l <= 0.0 {
        return glam::Vec3::ZERO;
    }
    let alpha = alpha.max(MIN_HIGHLIGHT_ALPHA);
    let h = (view + light).normalize();
    let d = distribution(alpha, n.dot(h));
    let g2 = 1.0 / (1.0 + lambda(alpha, cos_v) + lambda(alpha, cos_l));
    let lobe = (std::f64::consts::PI * d * g2 / (4.0 * cos_v)) as f32;
    schlick(f0, view.dot(h)) * lobe
}

/// Schlick's Fresnel, f0 + (1 − f0)(1 − cos)⁵, as glTF's BRDF uses it, for the cosine between
/// the view and the (micro)facet normal.
pub fn schlick(f0: glam::Vec3, cos: f64) -> glam::Vec3 {
    let k = (1.0 - cos.clamp(0.0, 1.0) as f32).powi(5);
    f0 + (glam::Vec3::ONE - f0) * k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Estimates of the directional albedo ∫ f cos over the hemisphere with a white mirror
    /// colour: the share of light a GGX surface reflects from a view direction. With Smith's
    /// height-correlated masking it is below 1 and falls with roughness and at grazing views.
    fn albedo(alpha: f64, view_angle: f64, samples: u32) -> f64 {
        let n = DVec3::Z;
        let incoming = -DVec3::new(view_angle.sin(), 0.0, view_angle.cos());
        let mut sum = 0.0;
        for i in 0..samples {
            let u = crate::sampler::sample_2d(i, samples, 12345);
            if let Some((_, w)) = reflect_glossy(incoming, n, alpha, u) {
                sum += w as f64;
            }
        }
        sum / samples as f64
    }

    #[test]
    fn a_smooth_lobe_is_the_mirror_and_keeps_all_light() {
        let incoming = DVec3::new(0.6, 0.0, -0.8);
        for k in 0..16 {
            let u = crate::sampler::sample_2d(k, 16, 7);
            let (dir, w) = reflect_glossy(incoming, DVec3::Z, 1e-6, u).unwrap();
            assert!((dir - DVec3::new(0.6, 0.0, 0.8)).length() < 1e-5, "{dir}");
            assert!((w - 1.0).abs() < 1e-6);
        }
    }

    /// ∫ f(l) dω over the hemisphere of unit directions l above z = 0 (midpoint rule).
    fn over_hemisphere(f: impl Fn(DVec3) -> f64) -> f64 {
        let (nt, np) = (300, 600);
        let (dt, dp) = (
            std::f64::consts::FRAC_PI_2 / nt as f64,
            std::f64::consts::TAU / np as f64,
        );
        let mut total = 0.0;
        for i in 0..nt {
            let theta = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let phi = (j as f64 + 0.5) * dp;
                let (sin, cos) = theta.sin_cos();
                let l = DVec3::new(sin * phi.cos(), sin * phi.sin(), cos);
                total += f(l) * sin * dt * dp;
            }
        }
        total
    }

    /// The same albedo by quadrature of the BRDF D·G2 / (4 cos θ_v cos θ_l) times cos θ_l over
    /// the hemisphere of light directions: independent of the sampling.
    fn albedo_by_quadrature(alpha: f64, view_angle: f64) -> f64 {
        let v = DVec3::new(view_angle.sin(), 0.0, view_angle.cos());
        over_hemisphere(|l| {
            let h = (v + l).normalize();
            let g2 = 1.0 / (1.0 + lambda(alpha, v.z) + lambda(alpha, l.z));
            distribution(alpha, h.z) * g2 / (4.0 * v.z * l.z) * l.z
        })
    }

    #[test]
    fn sampled_albedo_matches_the_quadrature_of_the_brdf() {
        // Height-correlated Smith masking takes light away as roughness grows: about 0.998 at
        // α = 0.05, 0.92 at 0.25, 0.69 at 0.5 and 0.31 at 1 for a view along the normal.
        for (alpha, angle) in [(0.05, 0.0), (0.25, 0.0), (0.5, 0.0), (1.0, 0.0), (0.5, 1.3)] {
            let (sampled, integrated) = (
                albedo(alpha, angle, 4096),
                albedo_by_quadrature(alpha, angle),
            );
            assert!(
                (sampled - integrated).abs() < 0.01 * integrated,
                "α {alpha}, view {angle}: sampled {sampled}, integrated {integrated}"
            );
        }
    }

    /// A light's highlight integrated over all light directions, per π, is the directional
    /// albedo of the same lobe (with F₀ = 1 Schlick's Fresnel is 1): the highlight of a light
    /// and the glossy reflection of a uniformly bright sky agree.
    #[test]
    fn the_highlight_integrates_to_the_albedo() {
        for (alpha, angle) in [(0.25, 0.0), (0.5, 0.7)] {
            let v = DVec3::new(f64::sin(angle), 0.0, f64::cos(angle));
            let total =
                over_hemisphere(|l| highlight(DVec3::Z, v, l, alpha, glam::Vec3::ONE).x as f64);
            let albedo = albedo_by_quadrature(alpha, angle);
            assert!(
                (total / std::f64::consts::PI - albedo).abs() < 1e-3,
                "{total} {albedo}"
            );
        }
    }

    #[test]
    fn reflected_rays_stay_above_the_surface_and_spread_with_roughness() {
        let incoming = DVec3::new(0.3, 0.2, -0.9).normalize();
        let mirror = incoming - DVec3::Z * (2.0 * incoming.z);
        let spread = |alpha: f64| {
            let mut total = 0.0;
            for k in 0..256 {
                let u = crate::sampler::sample_2d(k, 256, 3);
                if let Some((dir, _)) = reflect_glossy(incoming, DVec3::Z, alpha, u) {
                    assert!(dir.z > 0.0 && (dir.length() - 1.0).abs() < 1e-12);
                    total += dir.angle_between(mirror);
                }
            }
            total / 256.0
        };
        let (a, b, c) = (spread(0.01), spread(0.1), spread(0.5));
        assert!(a < b && b < c, "{a} {b} {c}");
        // A few hundredths of a radian at α = 10⁻⁴: close to the mirror.
        assert!(a < 0.05, "{a}");
    }
}
