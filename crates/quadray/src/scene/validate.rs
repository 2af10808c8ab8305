//! Validation of a scene description: every level's spheres and instances, and materials with
//! their textures. Values that would render as NaN or negative light are refused with the item
//! they belong to.

use super::{SceneError, invalid};
use crate::geometry::Geometry;
use crate::material::Material;
use crate::texture::Texture;
use glam::Vec3;

/// Checks every level's spheres and instances, rebuilding each instance's inverse and normal
/// matrix from its `to_world` alone, so they always match it.
pub(super) fn validate_levels(g: &mut Geometry) -> Result<(), SceneError> {
    let prototypes = g.prototypes.len();
    let mut levels: Vec<(
        String,
        &[crate::sphere::Sphere],
        &mut [crate::geometry::instance::Instance],
    )> = vec![(String::new(), &g.spheres, &mut g.instances)];
    for (i, p) in g.prototypes.iter_mut().enumerate() {
        levels.push((format!(" of prototype {i}"), &p.spheres, &mut p.instances));
    }
    for (suffix, spheres, instances) in levels {
        for (i, s) in spheres.iter().enumerate() {
            if !(s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0) {
                return Err(invalid(
                    format!("sphere {i}{suffix}"),
                    "centre must be finite and radius positive",
                ));
            }
        }
        for (i, inst) in instances.iter_mut().enumerate() {
            if inst.prototype as usize >= prototypes {
                return Err(invalid(
                    format!("instance {i}{suffix}"),
                    format!(
                        "places prototype {}, but the scene has {prototypes}",
                        inst.prototype
                    ),
                ));
            }
            inst.transform =
                crate::math::Transform::new(inst.transform.to_world).ok_or_else(|| {
                    invalid(
                        format!("instance {i}{suffix}"),
                        "transform must be finite and invertible",
                    )
                })?;
        }
    }
    Ok(())
}

fn non_negative(c: Vec3) -> bool {
    c.is_finite() && c.min_element() >= 0.0
}

pub(super) fn validate_material(m: &Material) -> Result<(), String> {
    for (name, v) in [
        ("ambient", m.ambient),
        ("diffuse", m.diffuse),
        ("specular", m.specular),
        ("shininess", m.shininess),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "{name} must be a finite non-negative number, got {v}"
            ));
        }
    }
    for (name, tint) in [
        ("reflection tint", m.reflection_tint),
        ("specular tint", m.specular_tint),
    ] {
        if !(0.0..=1.0).contains(&tint) {
            return Err(format!("{name} must be in [0, 1], got {tint}"));
        }
    }
    if !(0.0..=1.0).contains(&m.reflectivity) {
        return Err(format!(
            "reflectivity must be in [0, 1], got {}",
            m.reflectivity
        ));
    }
    check_texture(&m.texture)?;
    if !(0.0..=1.0).contains(&m.roughness) {
        return Err(format!("roughness must be in [0, 1], got {}", m.roughness));
    }
    if let Some(t) = &m.transmission {
        t.validate()?;
    }
    match &m.emission {
        Some(emission) => check_texture(emission).map_err(|e| format!("emission: {e}")),
        None => Ok(()),
    }
}

/// Checks a texture's colours and sizes.
fn check_texture(texture: &Texture) -> Result<(), String> {
    match texture {
        Texture::Constant(c) if !non_negative(*c) => {
            Err("colour must be finite and non-negative".into())
        }
        Texture::Checker { size, even, odd }
            if !(*size > 0.0 && size.is_finite() && non_negative(*even) && non_negative(*odd)) =>
        {
            Err("checker size must be positive and colours finite and non-negative".into())
        }
        Texture::Bands { steps: 0 } => Err("bands need at least one step".into()),
        Texture::Image(t) if !non_negative(t.factor) => {
            Err("image colour factor must be finite and non-negative".into())
        }
        _ => Ok(()),
    }
}
