//! Validation of a scene description: the camera and backdrop, every level's spheres and
//! instances, planes, lights, materials with their textures, and the reach of every coordinate.
//! Values that would render as NaN or negative light are refused with the item they belong to.

use super::{MAX_COORDINATE, SceneDescription, SceneError, invalid};
use crate::accel::{Layout, MAX_OVERLAP, max_abs_coordinate};
use crate::camera::Projection;
use crate::geometry::Geometry;
use crate::geometry::instance::Placements;
use crate::material::Material;
use crate::texture::Texture;
use glam::Vec3;

/// Checks everything a description holds but the reach of its coordinates: the camera, the
/// background and environment, the materials and every reference to one, every level, the planes
/// and the lights. Returns the instances' placements.
pub(super) fn validate_description(d: &mut SceneDescription) -> Result<Placements, SceneError> {
    d.camera.prepare(1.0)?;
    if !non_negative(d.background) {
        return Err(invalid("background", "must be finite and non-negative"));
    }
    if d.environment.is_some_and(|e| !non_negative(e)) {
        return Err(invalid("environment", "must be finite and non-negative"));
    }
    for (i, m) in d.materials.iter().enumerate() {
        validate_material(m).map_err(|p| invalid(format!("material {i}"), p))?;
    }
    for (what, id) in d.geometry.materials_used() {
        if id as usize >= d.materials.len() {
            return Err(SceneError::MaterialOutOfRange {
                what,
                id,
                count: d.materials.len(),
            });
        }
    }
    validate_levels(&mut d.geometry)?;
    for (i, p) in d.geometry.planes.iter().enumerate() {
        if !(p.point.is_finite() && p.normal.is_finite() && (p.normal.length() - 1.0).abs() < 1e-9)
        {
            return Err(invalid(
                format!("plane {i}"),
                "point must be finite and normal unit length",
            ));
        }
    }
    let placements = Placements::new(&d.geometry)?;
    for (i, l) in d.lights.iter().enumerate() {
        l.validate().map_err(|p| invalid(format!("light {i}"), p))?;
    }
    Ok(placements)
}

/// The BVHs' layout of a validated description, and the largest coordinate a camera ray can
/// start at, once every coordinate is known to stay within [`MAX_COORDINATE`]: the BVHs hold f32
/// boxes, so the coordinates of shapes (in their level and as placed) and of the camera must stay
/// well inside f32's range, or boxes become infinite.
pub(super) fn checked_layout(
    d: &SceneDescription,
    placements: Placements,
) -> Result<(Layout, f64), SceneError> {
    let mut origins = vec![d.camera.from, d.camera.to];
    if let Projection::Orthographic { height } = d.camera.projection {
        // The image plane can reach this far from `from` (any aspect up to the documented maximum).
        origins.push(d.camera.from.abs() + glam::DVec3::splat(height * crate::limits::MAX_ASPECT));
    }
    let origin_extent = max_abs_coordinate(&origins);
    // The camera alone can break the limit only through an orthographic image plane (its `from`
    // and `to` are checked when it is prepared); said as the camera's, not as the geometry's.
    if let Projection::Orthographic { height } = d.camera.projection
        && (origin_extent.is_nan() || origin_extent > MAX_COORDINATE)
    {
        return Err(invalid(
            "camera",
            format!(
                "an orthographic image plane of height {height:e} at `from` (up to {} times as \
                 wide) reaches {origin_extent:e} from the origin; quadray supports magnitudes up \
                 to {MAX_COORDINATE:e}",
                crate::limits::MAX_ASPECT
            ),
        ));
    }
    // Planes are not in the BVHs' boxes, but their points enter the same f32 arithmetic of ray
    // offsets and textures: the same limit.
    for (i, plane) in d.geometry.planes.iter().enumerate() {
        let far = plane.point.abs().max_element();
        if far.is_nan() || far > MAX_COORDINATE {
            return Err(invalid(
                format!("plane {i}"),
                format!(
                    "its point lies {far:e} from the origin; quadray supports magnitudes up to \
                     {MAX_COORDINATE:e}"
                ),
            ));
        }
    }
    let layout = Layout::new(&d.geometry, Some(placements));
    let extent = layout.coordinate_extent(origin_extent);
    if extent.is_nan() || extent > MAX_COORDINATE {
        return Err(invalid(
            "geometry",
            format!(
                "coordinates reach {extent:e}; quadray supports magnitudes up to \
                 {MAX_COORDINATE:e} (its BVHs use f32 boxes)"
            ),
        ));
    }
    let overlap = layout.overlap_depth(&d.geometry);
    if overlap > MAX_OVERLAP {
        return Err(invalid(
            "instances",
            format!(
                "up to {overlap:.0} shapes and placements overlap at one point (nested \
                 instances that each place overlapping copies multiply), and a ray through it \
                 would test every one; at most {MAX_OVERLAP:.0} are supported"
            ),
        ));
    }
    Ok((layout, origin_extent))
}

/// Checks every level's spheres and instances, rebuilding each instance's inverse and normal
/// matrix from its `to_world` alone, so they always match it.
fn validate_levels(g: &mut Geometry) -> Result<(), SceneError> {
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

/// Whether every channel of `c` is finite and at least zero.
fn non_negative(c: Vec3) -> bool {
    c.is_finite() && c.min_element() >= 0.0
}

fn validate_material(m: &Material) -> Result<(), String> {
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
