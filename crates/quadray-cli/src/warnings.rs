//! Warnings about scenes that load but will not look as their author likely meant: shown by
//! `check` and `render` on stderr, never fatal.

use quadray::quadric::ROUNDING_WARNING;
use quadray::{Geometry, Level, Mesh, Quadric, Scene, Texture};
use std::collections::BTreeMap;
use std::path::Path;

/// Rays per side of the grid `camera_sees_nothing` casts: 32 × 18 camera rays cost well under a
/// millisecond and miss only objects smaller than a grid cell.
const PROBE: (u32, u32) = (32, 18);

/// Prints [`scene_warnings`] on stderr, each after `warning: `.
pub fn print(path: &Path, scene: &Scene, material_names: &[String], width: u32, height: u32) {
    for warning in scene_warnings(path, scene, material_names, width, height) {
        errln!("warning: {warning}");
    }
}

/// What looks wrong about `scene` (loaded from `path` with materials named `material_names`, to
/// be rendered at `width` × `height`), one line each, ready to print after `warning: `.
pub fn scene_warnings(
    path: &Path,
    scene: &Scene,
    material_names: &[String],
    width: u32,
    height: u32,
) -> Vec<String> {
    let mut warnings = Vec::new();
    let name = path.display();
    for (label, q) in quadrics(scene.geometry()) {
        if !q.is_visible() {
            warnings.push(format!(
                "{name}: {label} ({}) does not reach into its clip box: nothing of it will show",
                q.class()
            ));
        } else if let Some(r) = q.rounding_sensitivity()
            && r.relative() > ROUNDING_WARNING
        {
            // Components that are rounding noise beside the shape print as 0.
            let c = r
                .centre
                .map(|v| if v.abs() < 1e-9 * r.size { 0.0 } else { v });
            warnings.push(format!(
                "{name}: {label} ({}): its coefficients cannot hold the surface in 64-bit floating \
                 point: they describe a shape of size {} about an origin {} away, so rounding \
                 alone may move the surface by about {:.1e} ({:.0e} of its size); write the \
                 coefficients about the shape's centre and place it with a transform \
                 (translate = [{}, {}, {}])",
                q.class(),
                three_digits(r.size),
                three_digits(c.length()),
                r.displacement,
                r.relative(),
                c.x,
                c.y,
                c.z
            ));
        }
    }
    warnings
        .extend(missing_texture_coordinates(scene, material_names).map(|w| format!("{name}: {w}")));
    if scene.lights().is_empty() {
        warnings.push(format!(
            "{name}: the scene has no lights: surfaces show only their ambient term \
             (ambient × colour) and what mirrors reflect of it, so the image will be dark; \
             add a [[light]]"
        ));
    }
    if camera_sees_nothing(scene, width as f64 / height.max(1) as f64) {
        warnings.push(format!(
            "{name}: the camera sees none of the scene's surfaces (a grid of {}x{} camera rays \
             hit nothing): the image will show only the background",
            PROBE.0, PROBE.1
        ));
    }
    warnings
}

/// Whether a coarse grid of camera rays over the image misses every surface.
fn camera_sees_nothing(scene: &Scene, aspect: f64) -> bool {
    let Ok(frame) = scene.camera().prepare(aspect) else {
        return false; // the renderer reports an unusable camera itself
    };
    let (nx, ny) = PROBE;
    !(0..ny).any(|j| {
        (0..nx).any(|i| {
            let (u, v) = ((i as f64 + 0.5) / nx as f64, (j as f64 + 0.5) / ny as f64);
            scene.intersect(&frame.ray(u, v)).is_some()
        })
    })
}

/// A loader note as printed on stderr: `note: ...`, or as is when the loader already marked it a
/// `warning: `.
pub fn note_line(note: &str) -> String {
    if note.starts_with("warning: ") {
        note.to_string()
    } else {
        format!("note: {note}")
    }
}

/// `x` to three significant digits, in scientific notation only when very large or small.
fn three_digits(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&x.abs()) {
        let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// Every quadric of the scene with a label naming it: `quadric[i]` in the scene, `quadric[j] of
/// prototype p` inside an instanced prototype.
fn quadrics(g: &Geometry) -> impl Iterator<Item = (String, &Quadric)> {
    levels(g).enumerate().flat_map(|(level, l)| {
        l.quadrics.iter().enumerate().map(move |(i, q)| {
            let label = match level {
                0 => format!("quadric[{i}]"),
                p => format!("quadric[{i}] of prototype {}", p - 1),
            };
            (label, q)
        })
    })
}

/// The scene's own shapes (level 0), then each prototype's.
fn levels(g: &Geometry) -> impl Iterator<Item = Level<'_>> {
    (0..=g.prototypes.len()).map(|level| g.level(level))
}

/// One line per material whose image texture is read through texture coordinates that shapes
/// using it lack: analytic shapes have none, meshes only the sets their file gave them. Such
/// shapes show the image's texel at coordinates (0, 0) everywhere.
fn missing_texture_coordinates<'a>(
    scene: &'a Scene,
    material_names: &'a [String],
) -> impl Iterator<Item = String> + 'a {
    let needs_set = |material: u32| match scene.materials().get(material as usize) {
        Some(m) => match &m.texture {
            Texture::Image(t) => Some(t.map.set as usize),
            _ => None,
        },
        None => None,
    };
    // Material → shape kind → count of its shapes lacking the coordinates.
    let mut lacking: BTreeMap<u32, BTreeMap<&str, usize>> = BTreeMap::new();
    // Every shape as (material, kind, its mesh if it is one).
    let g = scene.geometry();
    let shapes = levels(g)
        .flat_map(|l| {
            let spheres = l.spheres.iter().map(|s| (s.material, "sphere", None));
            let quadrics = l.quadrics.iter().map(|q| (q.material(), "quadric", None));
            let meshes = l.meshes.iter().map(|m| (m.material(), "mesh", Some(m)));
            spheres.chain(quadrics).chain(meshes)
        })
        .chain(g.planes.iter().map(|p| (p.material, "plane", None)));
    for (material, kind, mesh) in shapes {
        let Some(set) = needs_set(material) else {
            continue;
        };
        if mesh.and_then(|m: &Mesh| m.texcoords(set)).is_none() {
            *lacking
                .entry(material)
                .or_default()
                .entry(kind)
                .or_default() += 1;
        }
    }
    lacking.into_iter().map(move |(material, kinds)| {
        let set = needs_set(material).unwrap_or(0);
        let name = match material_names.get(material as usize) {
            Some(n) if !n.is_empty() => format!("material \"{n}\""),
            _ => format!("material {material}"),
        };
        let shapes: Vec<String> = kinds
            .iter()
            .map(|(kind, n)| crate::counted(n, kind))
            .collect();
        format!(
            "{name} has an image texture read through texture coordinates (set {set}), which {} \
             using it lack{}: they show one texel of the image everywhere; give the meshes \
             coordinates, or use a procedural texture (ramp, bands, checker) on analytic shapes",
            shapes.join(" and "),
            if kinds.values().sum::<usize>() == 1 {
                "s"
            } else {
                ""
            }
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_to_three_digits() {
        assert_eq!(three_digits(3.1114), "3.11");
        assert_eq!(three_digits(0.012345), "0.0123");
        assert_eq!(three_digits(123.4), "123");
        assert_eq!(three_digits(1.0e6), "1.00e6");
        assert_eq!(three_digits(2.5e-7), "2.50e-7");
        assert_eq!(three_digits(0.0), "0");
    }
}
