//! The scene's lights as KHR_lights_punctual lights and their nodes, in glTF's photometric units.

use super::{looking, set_matrix};
use crate::export::document::Document;
use crate::gltf::light::LUMENS_PER_WATT;
use glam::{DAffine3, DVec3, Vec3};
use quadray::Light;
use serde_json::json;

/// Adds `lights` to `doc` and returns their nodes. A light without falloff becomes a point light
/// matching its irradiance at `target` (the camera's), with a note; a spot wider than glTF's 90°
/// is written as 90°, with a note.
pub(super) fn light_nodes(
    doc: &mut Document,
    lights: &[Light],
    target: DVec3,
    notes: &mut Vec<String>,
) -> Vec<usize> {
    let mut nodes = Vec::new();
    let scale = (LUMENS_PER_WATT * std::f64::consts::PI) as f32;
    let colour_and_intensity = |c: Vec3| {
        let peak = c.max_element();
        if peak > 0.0 {
            ((c / peak).to_array(), peak * scale)
        } else {
            ([1.0; 3], 0.0)
        }
    };
    for (i, l) in lights.iter().enumerate() {
        let name = format!("light {i}");
        let (light, node_matrix) = match *l {
            Light::Point {
                position,
                intensity,
            } => {
                let (color, intensity) = colour_and_intensity(intensity);
                (
                    json!({"name": name, "type": "point", "color": color, "intensity": intensity}),
                    DAffine3::from_translation(position),
                )
            }
            Light::PointNoFalloff {
                position,
                irradiance,
            } => {
                // glTF point lights fall off with the inverse square: match the irradiance where
                // the camera looks, and say that the falloff differs elsewhere.
                let d2 = (target - position).length_squared().max(1e-12) as f32;
                notes.push(format!(
                    "{name}: a light without falloff is written as a glTF point light matching its irradiance at the camera's target; it falls off elsewhere"
                ));
                let (color, intensity) = colour_and_intensity(irradiance * d2);
                (
                    json!({"name": name, "type": "point", "color": color, "intensity": intensity}),
                    DAffine3::from_translation(position),
                )
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                let (color, intensity) = colour_and_intensity(irradiance);
                (
                    json!({"name": name, "type": "directional", "color": color, "intensity": intensity}),
                    looking(DVec3::ZERO, direction, DVec3::Z),
                )
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                let (color, intensity) = colour_and_intensity(intensity);
                let outer = cos_outer.clamp(-1.0, 1.0).acos();
                let inner = cos_inner.clamp(-1.0, 1.0).acos();
                let limit = std::f64::consts::FRAC_PI_2;
                if outer > limit {
                    notes.push(format!(
                        "{name}: its cone is wider than glTF's 90° limit; written as 90°"
                    ));
                }
                let outer = outer.min(limit);
                let inner = inner.min(outer * 0.999_999);
                (
                    json!({"name": name, "type": "spot", "color": color, "intensity": intensity,
                           "spot": {"innerConeAngle": inner, "outerConeAngle": outer}}),
                    looking(position, direction, DVec3::Z),
                )
            }
        };
        doc.lights.push(light);
        let mut node = json!({
            "name": name,
            "extensions": {"KHR_lights_punctual": {"light": doc.lights.len() - 1}},
        });
        set_matrix(&mut node, &node_matrix);
        nodes.push(doc.node(node));
    }

    nodes
}
