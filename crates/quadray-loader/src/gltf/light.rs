//! KHR_lights_punctual lights as quadray lights.
//!
//! # Units
//! glTF gives point and spot intensities in candela (lm/sr) and directional ones in lux (lm/m²).
//! quadray's lights are radiometric and its diffuse term omits Lambert's 1/π (a white surface
//! facing an irradiance of 1 shows its full colour). So a glTF value is divided by 683 lm/W (the
//! photometric-to-radiometric factor at 555 nm, the one Blender's exporter multiplies by) and by
//! π: Blender's default 1000 W point light (54 351 cd) then lights its default cube as Blender
//! shows it. Files authored with "unitless" intensities near 1 render dark; the loader notes it.
//!
//! A light points along its node's local −z. `range` is ignored: quadray's falloff is the
//! inverse-square law without a cutoff.

use glam::{DAffine3, DVec3, Vec3};
use gltf::khr_lights_punctual::Kind;
use quadray::Light;

/// Lumens per watt of the photometric–radiometric conversion.
pub const LUMENS_PER_WATT: f64 = 683.0;

/// Factor from a glTF intensity (cd or lx) to quadray's intensity or irradiance.
pub fn gltf_to_quadray_scale() -> f32 {
    (1.0 / (LUMENS_PER_WATT * std::f64::consts::PI)) as f32
}

/// The quadray light for `light` on a node placed by `to_world`.
pub fn convert(
    light: &gltf::khr_lights_punctual::Light<'_>,
    to_world: DAffine3,
) -> Result<Light, String> {
    let intensity = light.intensity();
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(format!(
            "intensity must be finite and non-negative, got {intensity}"
        ));
    }
    let power = Vec3::from_array(light.color()) * intensity * gltf_to_quadray_scale();
    let position = to_world.translation;
    let direction = || {
        (to_world.matrix3 * DVec3::NEG_Z)
            .try_normalize()
            .filter(|d| d.is_finite())
            .ok_or_else(|| "the light node's transform is singular".to_string())
    };
    let out = match light.kind() {
        Kind::Point => Light::Point {
            position,
            intensity: power,
        },
        Kind::Directional => Light::Directional {
            direction: direction()?,
            irradiance: power,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => Light::Spot {
            position,
            direction: direction()?,
            intensity: power,
            cos_inner: (inner_cone_angle as f64).cos(),
            cos_outer: (outer_cone_angle as f64).cos(),
        },
    };
    out.validate()?;
    Ok(out)
}
