//! Lights: point (inverse-square falloff) and directional, both casting hard shadows.

use glam::{DVec3, Vec3};

/// A light source, matched in one place ([`Light::incident`]).
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
    /// The light arriving at `p`, or `None` when `p` sits on a point light.
    #[inline]
    pub fn incident(&self, p: DVec3) -> Option<Incident> {
        match self {
            Light::Point {
                position,
                intensity,
            } => {
                let v = *position - p;
                let d2 = v.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let d = d2.sqrt();
                Some(Incident {
                    to_light: v / d,
                    distance: d,
                    irradiance: *intensity / d2 as f32,
                })
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
}
