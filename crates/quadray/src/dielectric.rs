//! Glass: light passing through a surface, bent by Snell's law, split from its reflection by the
//! exact Fresnel equations, and absorbed inside by Beer–Lambert's law.
//!
//! Conventions: `eta` is the relative index of refraction n_t / n_i, the index of the side the
//! light goes into over the side it comes from; directions are unit vectors; a normal `n` passed
//! here faces the side the incoming direction comes from (`d · n < 0`).

use glam::{DVec3, Vec3};

/// How a material lets light through (glTF's KHR_materials_transmission, KHR_materials_ior and
/// KHR_materials_volume).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transmission {
    /// Share of the light the surface does not reflect that passes through, in (0, 1]: glTF's
    /// `transmissionFactor`; the rest is the material's opaque part (ambient and diffuse).
    pub factor: f32,
    /// Index of refraction of the inside, against 1 outside, in [1, [`MAX_IOR`]].
    pub ior: f64,
    /// A thin sheet (glTF's volume thickness 0): light passes straight through, unbent and
    /// unabsorbed; otherwise the surface bounds a solid, entered along its outward normal.
    pub thin_walled: bool,
    /// Absorption inside a solid, or `None` for clear glass.
    pub attenuation: Option<Attenuation>,
}

/// Largest index of refraction a material may have (diamond is 2.42).
pub const MAX_IOR: f64 = 10.0;

impl Default for Transmission {
    fn default() -> Self {
        Transmission {
            factor: 1.0,
            ior: 1.5,
            thin_walled: false,
            attenuation: None,
        }
    }
}

impl Transmission {
    /// Checks the ranges stated on the fields.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.factor > 0.0 && self.factor <= 1.0) {
            return Err(format!(
                "transmission must be in (0, 1], got {}",
                self.factor
            ));
        }
        if !(1.0..=MAX_IOR).contains(&self.ior) {
            return Err(format!("ior must be in [1, {MAX_IOR}], got {}", self.ior));
        }
        if let Some(a) = &self.attenuation {
            a.validate()?;
        }
        Ok(())
    }
}

/// Beer–Lambert absorption, as KHR_materials_volume gives it: white light that travels
/// `distance` inside comes out with the colour `color`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attenuation {
    /// The colour reached after `distance`, each channel in [0, 1] (0: that channel is absorbed
    /// completely by any length inside).
    pub color: Vec3,
    /// The distance, world units, finite and > 0.
    pub distance: f64,
}

impl Attenuation {
    /// Checks the ranges stated on the fields.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.color.cmpge(Vec3::ZERO).all() && self.color.cmple(Vec3::ONE).all()) {
            return Err(format!(
                "the attenuation colour must be in [0, 1] in every channel, got {}",
                self.color
            ));
        }
        if !(self.distance > 0.0 && self.distance.is_finite()) {
            return Err(format!(
                "the attenuation distance must be finite and > 0, got {}",
                self.distance
            ));
        }
        Ok(())
    }

    /// The share of light left after `length` inside: exp(−σ·length) with σ = −ln(color) /
    /// distance, so that `color` is reached at `distance`.
    pub fn after(&self, length: f64) -> Vec3 {
        let k = (length / self.distance) as f32;
        Vec3::new(
            self.color.x.powf(k),
            self.color.y.powf(k),
            self.color.z.powf(k),
        )
    }
}

/// The reflected share of unpolarised light meeting a smooth dielectric boundary: the mean of
/// the s and p Fresnel reflectances,
/// r_s = (cos_i − η cos_t) / (cos_i + η cos_t), r_p = (η cos_i − cos_t) / (η cos_i + cos_t),
/// with cos_i the cosine of incidence (≥ 0), η = n_t / n_i, and sin_t = sin_i / η (Snell).
/// 1 past the critical angle (total internal reflection).
pub fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (r_s * r_s + r_p * r_p)).clamp(0.0, 1.0)
}

/// The direction unit vector `d` takes through a boundary with unit normal `n` (facing `d`'s
/// side, `d · n < 0`) and relative index `eta` = n_t / n_i: Snell's law in vector form,
/// t = d/η + (cos_i/η − cos_t)·n. `None` past the critical angle.
pub fn refract(d: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((d / eta + n * (cos_i / eta - cos_t)).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_reflects_the_textbook_share() {
        for n in [1.0f64, 1.33, 1.5, 2.42] {
            let want = ((n - 1.0) / (n + 1.0)).powi(2);
            assert!((fresnel(1.0, n) - want).abs() < 1e-15, "{n}");
            // The same from inside: the boundary reflects alike both ways at normal incidence.
            assert!((fresnel(1.0, 1.0 / n) - want).abs() < 1e-15, "{n}");
        }
        assert_eq!(fresnel(1.0, 1.0), 0.0, "no boundary, no reflection");
    }

    #[test]
    fn past_the_critical_angle_all_light_is_reflected() {
        let n: f64 = 1.5;
        let critical = (1.0 / n).asin();
        for angle in [critical + 1e-9, critical + 0.1, 1.5] {
            let cos_i = angle.cos();
            assert_eq!(fresnel(cos_i, 1.0 / n), 1.0, "{angle}");
            let d = DVec3::new(angle.sin(), 0.0, -cos_i);
            assert_eq!(refract(d, DVec3::Z, 1.0 / n), None);
        }
        // Just below it, light still gets out, most of it reflected.
        let cos_i = (critical - 1e-3).cos();
        let f = fresnel(cos_i, 1.0 / n);
        assert!(f > 0.5 && f < 1.0, "{f}");
        // Grazing from outside: all reflected in the limit.
        assert!(fresnel(1e-9, n) > 0.999_999);
    }

    #[test]
    fn refraction_follows_snells_law() {
        let n = 1.5;
        for angle in [0.0f64, 0.3, 0.8, 1.4] {
            let d = DVec3::new(angle.sin(), 0.0, -angle.cos());
            let t = refract(d, DVec3::Z, n).unwrap();
            assert!((t.length() - 1.0).abs() < 1e-15);
            assert!(t.z < 0.0, "goes through");
            // n_i sin_i = n_t sin_t, in the plane of incidence.
            assert!((angle.sin() - n * t.x).abs() < 1e-15, "{angle}");
            assert_eq!(t.y, 0.0);
        }
        // Index 1: straight on.
        let d = DVec3::new(0.6, 0.0, -0.8);
        assert!((refract(d, DVec3::Z, 1.0).unwrap() - d).length() < 1e-15);
    }

    #[test]
    fn fresnel_is_a_share_and_grows_towards_grazing() {
        let mut last = 0.0;
        for k in 0..=1000 {
            let cos_i = 1.0 - k as f64 / 1000.0;
            let f = fresnel(cos_i, 1.5);
            assert!((0.0..=1.0).contains(&f));
            assert!(f >= last - 1e-15, "{cos_i}");
            last = f;
        }
    }

    #[test]
    fn attenuation_reaches_its_colour_at_its_distance() {
        let a = Attenuation {
            color: Vec3::new(0.5, 0.8, 1.0),
            distance: 2.0,
        };
        assert!((a.after(2.0) - a.color).abs().max_element() < 1e-6);
        assert!((a.after(4.0) - a.color * a.color).abs().max_element() < 1e-6);
        assert_eq!(a.after(0.0), Vec3::ONE);
        assert!(a.validate().is_ok());
        let bad = Attenuation {
            color: Vec3::new(1.5, 1.0, 1.0),
            distance: 1.0,
        };
        assert!(bad.validate().is_err());
        let opaque_red = Attenuation {
            color: Vec3::new(0.0, 1.0, 1.0),
            distance: 1.0,
        };
        assert!(opaque_red.validate().is_ok());
        assert_eq!(opaque_red.after(0.5).x, 0.0);
        assert_eq!(opaque_red.after(0.0).x, 1.0);
        let t = Transmission {
            ior: 0.5,
            ..Transmission::default()
        };
        assert!(t.validate().unwrap_err().contains("ior"));
    }
}
