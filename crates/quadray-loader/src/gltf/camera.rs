//! glTF cameras as quadray cameras.
//!
//! A glTF camera looks down its node's local −z with +y up; its node's world transform (after the
//! y-up to z-up rotation) gives quadray's `from`, view direction and `up`. Perspective `yfov`
//! becomes the vertical field of view and `aspectRatio` the image aspect; orthographic `ymag` is
//! half the viewed height (scaled by the node's scale along its up axis) and `xmag / ymag` the
//! aspect. Near and far planes have no meaning for a ray tracer and are ignored.

use crate::import::ImportedCamera;
use glam::{DAffine3, DVec3};
use quadray::{Camera, MAX_COORDINATE, Projection};

/// The quadray camera for `camera` seen through a node placed by `to_world`; `json` is the
/// camera's JSON, whose numbers are read in f64 when present.
pub fn convert(
    camera: &gltf::Camera<'_>,
    json: Option<&serde_json::Value>,
    to_world: DAffine3,
) -> Result<ImportedCamera, String> {
    let exact = |kind: &str, key: &str, single: f32| -> f64 {
        json.and_then(|j| j.get(kind))
            .and_then(|p| p.get(key))
            .and_then(serde_json::Value::as_f64)
            .unwrap_or(single as f64)
    };
    let from = to_world.translation;
    let forward = to_world.matrix3 * DVec3::NEG_Z;
    let up_axis = to_world.matrix3 * DVec3::Y;
    let (projection, aspect) = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let yfov = exact("perspective", "yfov", p.yfov());
            if !(yfov > 0.0 && yfov < std::f64::consts::PI) {
                return Err(format!("yfov must be in (0, π) radians, got {yfov}"));
            }
            let aspect = p
                .aspect_ratio()
                .map(|a| exact("perspective", "aspectRatio", a));
            (
                Projection::Perspective {
                    vfov_deg: yfov.to_degrees(),
                },
                aspect,
            )
        }
        gltf::camera::Projection::Orthographic(o) => {
            let (xmag, ymag) = (
                exact("orthographic", "xmag", o.xmag()),
                exact("orthographic", "ymag", o.ymag()),
            );
            if !(ymag.is_finite() && ymag != 0.0 && xmag.is_finite() && xmag != 0.0) {
                return Err(format!(
                    "xmag and ymag must be non-zero, got {xmag} and {ymag}"
                ));
            }
            (
                Projection::Orthographic {
                    height: 2.0 * ymag.abs() * up_axis.length(),
                },
                Some(xmag.abs() / ymag.abs()),
            )
        }
    };
    let forward = forward
        .try_normalize()
        .filter(|f| f.is_finite())
        .ok_or("the camera node's transform is singular")?;
    // The target a power of two (exact in the product) at least as far as the position's largest
    // coordinate: one unit ahead of a camera at 1e17 rounds back onto the camera itself.
    let far = from.abs().max_element().max(1.0);
    let mut reach = 2f64.powi(far.log2().ceil() as i32);
    // The target within the coordinate limit, so a camera near the limit is not refused for
    // it: halved while it stays at least 2⁻²⁶ of the position away, where rounding the target
    // turns the view by at most about 2⁻²⁵ radians.
    while (from + forward * reach).abs().max_element() > MAX_COORDINATE
        && reach > far * 2f64.powi(-26)
    {
        reach *= 0.5;
    }
    let camera_out = Camera {
        from,
        to: from + forward * reach,
        up: up_axis.normalize_or_zero(),
        projection,
    };
    camera_out.prepare(1.0).map_err(|e| e.to_string())?;
    let limit = quadray::render::MAX_ASPECT;
    if let Some(a) = aspect
        && !(a.is_finite() && a > 0.0 && (1.0 / limit..=limit).contains(&a))
    {
        return Err(format!(
            "the aspect ratio {a} is outside what quadray renders (1/{limit} to {limit})"
        ));
    }
    Ok(ImportedCamera {
        name: camera.name().map(str::to_string),
        camera: camera_out,
        aspect,
    })
}
