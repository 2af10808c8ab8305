//! Lights: point (inverse-square falloff), spot (a point light limited to a cone) and directional,
//! all casting hard shadows.

use glam::{DVec3, Vec3};

/// A light source, matched in this file only ([`Light::incident`], [`Light::validate`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// An isotropic point light; irradiance falls off as intensity / distance².
    Point {
        /// Position, world space.
        position: DVec3,
        /// Radiant intensity per colour channel (colour × intensity).
        intensity: Vec3,
    },
    /// A point light whose irradiance does not fall off with distance: POV-Ray's classic light
    /// (no `fade_power`), kept so POV-Ray scenes can be ported and compared pixel for pixel.
    PointNoFalloff {
        /// Position, world space.
        position: DVec3,
        /// Irradiance at normal incidence at any distance, per colour channel.
        irradiance: Vec3,
    },
    /// A light at infinity shining along `direction`.
    Directional {
        /// Direction the light travels (unit length).
        direction: DVec3,
        /// Irradiance on a surface facing the light, per colour channel.
        irradiance: Vec3,
    },
    /// A point light shining into a cone: full intensity within `cos_inner` of its axis, none
    /// beyond `cos_outer`, and between them the smooth falloff of glTF's KHR_lights_punctual:
    /// `s = clamp((cos θ − cos_outer) / (cos_inner − cos_outer), 0, 1)`, attenuation `s²`.
    Spot {
        /// Position, world space.
        position: DVec3,
        /// Unit direction of the cone's axis (the way the light points).
        direction: DVec3,
        /// Radiant intensity along the axis, per colour channel.
        intensity: Vec3,
        /// Cosine of the inner cone's half-angle (full intensity inside).
        cos_inner: f64,
        /// Cosine of the outer cone's half-angle (no light outside); at most `cos_inner`.
        cos_outer: f64,
    },
}

/// Light arriving at a point: unit direction towards the light, distance to it, and irradiance at normal incidence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incident {
    /// Unit vector from the point towards the light.
    pub to_light: DVec3,
    /// Distance to the light (infinite for directional lights).
    pub distance: f64,
    /// Irradiance at normal incidence, before the cosine and shadowing.
    pub irradiance: Vec3,
}

impl Light {
    /// The light arriving at `p`, or `None` when none does: `p` sits on a point or spot light, or
    /// lies outside a spot light's cone (so no shadow ray is wasted on it).
    #[inline(always)]
    pub fn incident(&self, p: DVec3) -> Option<Incident> {
        match self {
            Light::Point {
                position,
                intensity,
            } => inverse_square(*position, *intensity, p),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                let mut inc = inverse_square(*position, *intensity, p)?;
                let cos_theta = direction.dot(-inc.to_light);
                let s =
                    ((cos_theta - cos_outer) / (cos_inner - cos_outer).max(1e-3)).clamp(0.0, 1.0);
                if s <= 0.0 {
                    return None;
                }
                inc.irradiance *= (s * s) as f32;
                Some(inc)
            }
            Light::PointNoFalloff {
                position,
                irradiance,
            } => {
                let v = *position - p;
                let d = v.length();
                (d > 0.0).then(|| Incident {
                    to_light: v / d,
                    distance: d,
                    irradiance: *irradiance,
                })
            }
            Light::Directional {
                direction,
                irradiance,
            } => Some(Incident {
                to_light: -*direction,
                distance: f64::INFINITY,
                irradiance: *irradiance,
            }),
        }
    }

    /// Where the light sits, for the lights at a point (not directional ones).
    pub fn position(&self) -> Option<DVec3> {
        match self {
            Light::Point { position, .. }
            | Light::PointNoFalloff { position, .. }
            | Light::Spot { position, .. } => Some(*position),
            Light::Directional { .. } => None,
        }
    }

    /// Why the light is invalid, if it is: non-finite values, a non-unit direction, a negative
    /// colour, or a spot cone with its inner angle wider than its outer one.
    pub fn validate(&self) -> Result<(), String> {
        let unit = |d: &DVec3| d.is_finite() && (d.length() - 1.0).abs() < 1e-9;
        let colour = |c: &Vec3| c.is_finite() && c.min_element() >= 0.0;
        let ok = match self {
            Light::Point {
                position,
                intensity,
            } => position.is_finite() && colour(intensity),
            Light::PointNoFalloff {
                position,
                irradiance,
            } => position.is_finite() && colour(irradiance),
            Light::Directional {
                direction,
                irradiance,
            } => unit(direction) && colour(irradiance),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                if !(cos_outer.is_finite()
                    && cos_inner.is_finite()
                    && (-1.0..=1.0).contains(cos_outer)
                    && (-1.0..=1.0).contains(cos_inner)
                    && cos_outer <= cos_inner)
                {
                    return Err(format!(
                        "spot cone cosines must lie in [-1, 1] with the outer cone at least as wide as the inner, got inner {cos_inner}, outer {cos_outer}"
                    ));
                }
                position.is_finite() && unit(direction) && colour(intensity)
            }
        };
        if ok {
            Ok(())
        } else {
            Err("must be finite, with a unit direction and non-negative colour".into())
        }
    }
}

/// Light from an isotropic source of `intensity` at `position` arriving at `p`.
#[inline]
fn inverse_square(position: DVec3, intensity: Vec3, p: DVec3) -> Option<Incident> {
    let v = position - p;
    let d2 = v.length_squared();
    if d2 == 0.0 {
        return None;
    }
    let d = d2.sqrt();
    Some(Incident {
        to_light: v / d,
        distance: d,
        irradiance: intensity / d2 as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_light_falls_off_with_distance_squared() {
        let l = Light::Point {
            position: DVec3::new(0.0, 0.0, 2.0),
            intensity: Vec3::splat(8.0),
        };
        let i = l.incident(DVec3::ZERO).unwrap();
        assert_eq!(i.irradiance, Vec3::splat(2.0));
        assert_eq!(i.to_light, DVec3::Z);
        assert_eq!(i.distance, 2.0);
        assert!(l.incident(DVec3::new(0.0, 0.0, 2.0)).is_none());
        let flat = Light::PointNoFalloff {
            position: DVec3::new(0.0, 0.0, 2.0),
            irradiance: Vec3::splat(8.0),
        };
        assert_eq!(
            flat.incident(DVec3::ZERO).unwrap().irradiance,
            Vec3::splat(8.0)
        );
        assert_eq!(
            flat.incident(DVec3::new(0.0, 0.0, -98.0)).unwrap().distance,
            100.0
        );
    }

    #[test]
    fn spot_light_falls_off_between_cones_and_stops_outside() {
        let (inner, outer) = (10f64.to_radians(), 20f64.to_radians());
        let l = Light::Spot {
            position: DVec3::new(0.0, 0.0, 2.0),
            direction: -DVec3::Z,
            intensity: Vec3::splat(8.0),
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
        };
        l.validate().unwrap();
        // On the axis: the point light's inverse square law.
        assert_eq!(
            l.incident(DVec3::ZERO).unwrap().irradiance,
            Vec3::splat(2.0)
        );
        // At 15 degrees off axis (inside the falloff band): s = (cos15 - cos20)/(cos10 - cos20).
        let p = DVec3::new(2.0 * 15f64.to_radians().tan(), 0.0, 0.0);
        let s = (15f64.to_radians().cos() - outer.cos()) / (inner.cos() - outer.cos());
        let expected = 8.0 / p.distance_squared(DVec3::new(0.0, 0.0, 2.0)) * s * s;
        let got = l.incident(p).unwrap().irradiance.x as f64;
        assert!(
            (got - expected).abs() < 1e-5 * expected,
            "{got} vs {expected}"
        );
        // Beyond the outer cone, and behind the light: nothing, so no shadow ray.
        assert!(l.incident(DVec3::new(2.0, 0.0, 0.0)).is_none());
        assert!(l.incident(DVec3::new(0.0, 0.0, 5.0)).is_none());
    }

    #[test]
    fn validation_rejects_inverted_cones_and_bad_directions() {
        let spot = |cos_inner, cos_outer, direction| Light::Spot {
            position: DVec3::ZERO,
            direction,
            intensity: Vec3::ONE,
            cos_inner,
            cos_outer,
        };
        assert!(spot(0.5, 0.9, DVec3::Z).validate().is_err());
        assert!(
            spot(0.9, 0.5, DVec3::new(0.0, 0.0, 2.0))
                .validate()
                .is_err()
        );
        assert!(spot(0.9, 0.5, DVec3::Z).validate().is_ok());
        let d = Light::Directional {
            direction: DVec3::Z,
            irradiance: Vec3::new(1.0, -1.0, 0.0),
        };
        assert!(d.validate().is_err());
    }
}
