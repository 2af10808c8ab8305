//! What the OBJ and glTF importers produce, the options they take, and how an import becomes a
//! scene of its own (for `quadray render FILE.obj|.gltf|.glb`) or joins a native scene.
//!
//! # Axes
//! quadray is right-handed with +z up; glTF is right-handed with +y up, and most OBJ files follow
//! the same y-up habit (Blender's default export, the Stanford scans, the Utah teapot). Importers
//! therefore rotate the file by +90° about x, which takes the file's (x, y, z) to quadray's
//! (x, −z, y): the file's up (+y) becomes +z and its front (+z, towards a glTF viewer's default
//! camera) becomes −y, the side quadray's cameras usually look from. OBJ files that are already
//! z-up can opt out (`up = "z"`).

use crate::error::{LoadError, LoadErrorKind};
use glam::{DAffine3, DMat3, DVec3, Vec3};
use quadray::{Camera, Geometry, Light, Material, Quadric, Sphere, Transform};
use std::path::Path;

/// Which of several named items (a glTF scene, a camera) to use: by index or by name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Selector {
    /// The item at this index (in file order).
    Index(usize),
    /// The first item with this name.
    Name(String),
}

impl std::fmt::Display for Selector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Selector::Index(i) => write!(f, "#{i}"),
            Selector::Name(n) => write!(f, "\"{n}\""),
        }
    }
}

/// The file's up axis (OBJ only: glTF is always y-up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// +y is up: rotate into quadray's z-up frame (the default, and glTF's rule).
    #[default]
    Y,
    /// +z is up already: take coordinates as they are.
    Z,
}

/// How to import a file.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Extra placement applied after the axis conversion (a native scene's `transform`).
    pub transform: Option<Transform>,
    /// Which glTF scene to import; the file's default scene (or its first) when `None`.
    pub scene: Option<Selector>,
    /// The file's up axis (OBJ only).
    pub up: UpAxis,
    /// Skip the file's materials and textures (every surface gets material 0 of an empty list,
    /// which the caller replaces): for a native scene's material override.
    pub skip_materials: bool,
    /// The output resolution when the caller already knows it (a command line's `--res`): it
    /// replaces the file's own, and a camera made to frame the file fits its aspect.
    pub resolution: Option<[u32; 2]>,
}

/// The rotation taking y-up file coordinates to quadray's z-up world: (x, y, z) → (x, −z, y).
pub const Y_UP_TO_Z_UP: DMat3 = DMat3::from_cols(
    DVec3::new(1.0, 0.0, 0.0),
    DVec3::new(0.0, 0.0, 1.0),
    DVec3::new(0.0, -1.0, 0.0),
);

impl ImportOptions {
    /// The map from file coordinates to quadray world coordinates.
    pub fn root(&self, up: UpAxis) -> DAffine3 {
        let axes = match up {
            UpAxis::Y => DAffine3::from_mat3(Y_UP_TO_Z_UP),
            UpAxis::Z => DAffine3::IDENTITY,
        };
        match &self.transform {
            Some(t) => t.to_world * axes,
            None => axes,
        }
    }
}

/// A camera found in a file, with what it says about the image.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedCamera {
    /// Its name, if the file gives one.
    pub name: Option<String>,
    /// The camera, world space.
    pub camera: Camera,
    /// Width / height the file asks for, if any.
    pub aspect: Option<f64>,
}

/// The camera `sel` picks from `cameras`, or a message listing what there is.
pub fn select_camera<'a>(
    cameras: &'a [ImportedCamera],
    sel: &Selector,
) -> Result<&'a ImportedCamera, String> {
    let found = match sel {
        Selector::Index(i) => cameras.get(*i),
        Selector::Name(n) => cameras
            .iter()
            .find(|c| c.name.as_deref() == Some(n.as_str())),
    };
    found.ok_or_else(|| {
        let names: Vec<String> = cameras
            .iter()
            .enumerate()
            .map(|(i, c)| match &c.name {
                Some(n) => format!("#{i} \"{n}\""),
                None => format!("#{i}"),
            })
            .collect();
        format!(
            "no camera {sel} (the file has {}: {})",
            cameras.len(),
            if names.is_empty() {
                "none".into()
            } else {
                names.join(", ")
            }
        )
    })
}

/// What an importer read: materials, primitives, lights and cameras, in world space.
#[derive(Clone, Debug, Default)]
pub struct Imported {
    /// Materials with their names; primitives refer to them by index.
    pub materials: Vec<(String, Material)>,
    /// The primitives.
    pub geometry: Geometry,
    /// Light sources.
    pub lights: Vec<Light>,
    /// Cameras, in file order.
    pub cameras: Vec<ImportedCamera>,
    /// Scene-graph node instances visited (glTF; 0 for OBJ).
    pub nodes: usize,
    /// Degenerate triangles (a repeated vertex index) dropped from glTF primitives.
    pub degenerate: usize,
    /// Render settings the file carries for quadray (a glTF scene's `extras.quadray`).
    pub hints: crate::quadrics_ext::RenderHints,
    /// What the importer assumed, skipped or could not find, for the user to read.
    pub notes: Vec<String>,
}

impl Imported {
    /// Shifts every primitive's material index by `offset` (to append these materials to others),
    /// or points them all at `replace` (a material override).
    pub fn remap_materials(&mut self, path: &Path, map: MaterialMap) -> Result<(), LoadError> {
        let f = |id: u32| match map {
            MaterialMap::Offset(o) => id + o,
            MaterialMap::Replace(r) => r,
        };
        let g = &mut self.geometry;
        for p in &mut g.planes {
            p.material = f(p.material);
        }
        remap_level(
            &mut g.spheres,
            &mut g.quadrics,
            &mut g.meshes,
            &mut g.instances,
            &f,
            path,
        )?;
        for p in &mut g.prototypes {
            remap_level(
                &mut p.spheres,
                &mut p.quadrics,
                &mut p.meshes,
                &mut p.instances,
                &f,
                path,
            )?;
        }
        Ok(())
    }

    /// Number of triangles as instanced: each placement of a prototype counts its triangles again
    /// (saturating).
    pub fn triangle_count(&self) -> usize {
        let g = &self.geometry;
        let mut counts: Vec<u64> = Vec::with_capacity(g.prototypes.len());
        let level = |l: quadray::Level<'_>, counts: &[u64]| {
            let own: u64 = l.meshes.iter().map(|m| m.triangle_count() as u64).sum();
            l.instances.iter().fold(own, |sum, inst| {
                sum.saturating_add(counts.get(inst.prototype as usize).copied().unwrap_or(0))
            })
        };
        for i in 0..g.prototypes.len() {
            let c = level(g.level(i + 1), &counts);
            counts.push(c);
        }
        usize::try_from(level(g.level(0), &counts)).unwrap_or(usize::MAX)
    }

    /// Bounds of every bounded primitive (planes are unbounded and ignored), if there is any.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        geometry_bounds(&self.geometry)
    }
}

/// Applies `f` to the material of every shape of one level and to its instances' overrides.
fn remap_level(
    spheres: &mut [Sphere],
    quadrics: &mut Vec<Quadric>,
    meshes: &mut Vec<quadray::Mesh>,
    instances: &mut [quadray::Instance],
    f: &impl Fn(u32) -> u32,
    path: &Path,
) -> Result<(), LoadError> {
    for s in spheres {
        s.material = f(s.material);
    }
    for m in std::mem::take(meshes) {
        let id = f(m.material());
        meshes.push(m.with_material(id));
    }
    for q in std::mem::take(quadrics) {
        // Quadric keeps its material private; rebuilding it with the same parameters cannot fail
        // in principle, but an error is still reported rather than unwrapped.
        let q = Quadric::new(
            q.surface_description(),
            q.clip(),
            *q.transform(),
            f(q.material()),
        )
        .map_err(|e| LoadError::new(path, None, LoadErrorKind::Unsupported(e.to_string())))?;
        quadrics.push(q);
    }
    for inst in instances {
        inst.material = inst.material.map(f);
    }
    Ok(())
}

/// How [`Imported::remap_materials`] changes material indices.
#[derive(Clone, Copy, Debug)]
pub enum MaterialMap {
    /// Add this to every index.
    Offset(u32),
    /// Use this index everywhere.
    Replace(u32),
}

/// Bounds of the bounded primitives of `g`, instances included, if any (for framing a camera).
///
/// Mesh vertices are placed through every instance path, so the box is the one the same scene
/// written flat would have, as long as the expansion stays small (at most [`EXACT_BOUNDS_WORK`]
/// vertex placements); beyond, each prototype's box is placed by its instances instead (a box of
/// boxes: never smaller, possibly larger). Spheres and quadrics under instances contribute their
/// boxes' placed corners.
pub fn geometry_bounds(g: &Geometry) -> Option<(DVec3, DVec3)> {
    let mut acc = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut budget = EXACT_BOUNDS_WORK;
    if exact_bounds(g, 0, DAffine3::IDENTITY, &mut acc, &mut budget) {
        return (acc.0.cmple(acc.1).all()).then_some(acc);
    }
    boxed_bounds(g)
}

/// Most vertex and instance placements [`geometry_bounds`] computes before it settles for boxes
/// of boxes.
pub const EXACT_BOUNDS_WORK: u64 = 20_000_000;

/// Grows `acc` by level `level` placed by `m`; false when `budget` runs out.
fn exact_bounds(
    g: &Geometry,
    level: usize,
    m: DAffine3,
    acc: &mut (DVec3, DVec3),
    budget: &mut u64,
) -> bool {
    let l = g.level(level);
    let mut grow = |p: DVec3| {
        acc.0 = acc.0.min(p);
        acc.1 = acc.1.max(p);
    };
    let identity = level == 0;
    // A shape's box costs its eight corners.
    let shapes = 8 * (l.spheres.len() + l.quadrics.len()) as u64;
    if *budget < shapes {
        return false;
    }
    *budget -= shapes;
    for b in l
        .spheres
        .iter()
        .map(|s| s.bounds())
        .chain(l.quadrics.iter().map(|q| q.bounds()))
    {
        if identity {
            grow(b.0);
            grow(b.1);
        } else {
            corners(b).for_each(|c| grow(m.transform_point3(c)));
        }
    }
    for mesh in l.meshes {
        let n = mesh.positions().len() as u64;
        if *budget < n {
            return false;
        }
        *budget -= n;
        for p in mesh.positions() {
            grow(m.transform_point3(p.as_dvec3()));
        }
    }
    l.instances.iter().all(|inst| {
        // Each placement costs one unit, so a deep DAG of shapes without vertices ends too.
        *budget = budget.saturating_sub(1);
        *budget > 0
            && exact_bounds(
                g,
                inst.prototype as usize + 1,
                m * inst.transform.to_world,
                acc,
                budget,
            )
    })
}

/// The eight corners of a box.
fn corners((a, b): (DVec3, DVec3)) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |c| {
        DVec3::new(
            if c & 1 == 0 { a.x } else { b.x },
            if c & 2 == 0 { a.y } else { b.y },
            if c & 4 == 0 { a.z } else { b.z },
        )
    })
}

/// Bounds as boxes of boxes: each prototype's box once, children first, placed by its instances'
/// transforms.
fn boxed_bounds(g: &Geometry) -> Option<(DVec3, DVec3)> {
    let mut boxes: Vec<Option<(DVec3, DVec3)>> = Vec::with_capacity(g.level_count());
    let level_box = |level: quadray::Level<'_>, boxes: &[Option<(DVec3, DVec3)>]| {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut grow = |(a, b): (DVec3, DVec3)| {
            lo = lo.min(a);
            hi = hi.max(b);
        };
        level.spheres.iter().for_each(|s| grow(s.bounds()));
        level.quadrics.iter().for_each(|q| grow(q.bounds()));
        for m in level.meshes {
            for p in m.positions() {
                let p = p.as_dvec3();
                grow((p, p));
            }
        }
        for inst in level.instances {
            let Some(Some((a, b))) = boxes.get(inst.prototype as usize) else {
                continue;
            };
            for c in corners((*a, *b)) {
                let w = inst.transform.to_world.transform_point3(c);
                grow((w, w));
            }
        }
        (lo.cmple(hi).all()).then_some((lo, hi))
    };
    for i in 0..g.prototypes.len() {
        let b = level_box(g.level(i + 1), &boxes);
        boxes.push(b);
    }
    level_box(g.level(0), &boxes)
}

/// A sphere of `radius` at the origin of `to_world`: a [`Sphere`] when the map is a similarity
/// (uniform scale, rotation, translation), else the ellipsoid it becomes, as a clipped quadric.
pub fn placed_sphere(
    to_world: DAffine3,
    radius: f64,
    material: u32,
) -> Result<PlacedShape, String> {
    let m = to_world.matrix3;
    let lens = DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
    let s = lens.x;
    let orthogonal = m.x_axis.dot(m.y_axis).abs() <= 1e-9 * s * s
        && m.x_axis.dot(m.z_axis).abs() <= 1e-9 * s * s
        && m.y_axis.dot(m.z_axis).abs() <= 1e-9 * s * s;
    if orthogonal && (lens - DVec3::splat(s)).abs().max_element() <= 1e-9 * s {
        return Ok(PlacedShape::Sphere(Sphere {
            center: to_world.translation,
            radius: radius * s,
            material,
        }));
    }
    let t = Transform::new(to_world).ok_or("the sphere's transform is singular")?;
    Quadric::new(
        quadray::QuadricSurface::Canonical {
            kind: quadray::QuadricKind::Ellipsoid,
            a: radius,
            b: radius,
            c: radius,
        },
        quadray::ClipBox::cube(radius),
        t,
        material,
    )
    .map(|q| PlacedShape::Quadric(Box::new(q)))
    .map_err(|e| e.to_string())
}

/// An analytic shape placed in the world.
#[derive(Clone, Debug)]
pub enum PlacedShape {
    /// A clipped quadric (or a sphere a transform stretched); boxed, being much larger than the rest.
    Quadric(Box<Quadric>),
    /// A sphere under a similarity.
    Sphere(Sphere),
    /// An infinite plane.
    Plane(quadray::Plane),
}

impl PlacedShape {
    /// Adds the shape to `geometry`.
    pub fn add_to(self, geometry: &mut Geometry) {
        match self {
            PlacedShape::Quadric(q) => geometry.quadrics.push(*q),
            PlacedShape::Sphere(s) => geometry.spheres.push(s),
            PlacedShape::Plane(p) => geometry.planes.push(p),
        }
    }
}

/// The default key light when a file brings none: a directional light over the camera's left
/// shoulder, so that the visible sides are lit and shadows fall away to the lower right.
pub fn default_key_light(camera: &Camera) -> Light {
    let forward = (camera.to - camera.from).normalize_or(DVec3::Y);
    let right = forward.cross(camera.up).normalize_or(DVec3::X);
    let up = right.cross(forward);
    let towards_light = (-forward + up * 1.2 - right * 0.6).normalize();
    Light::Directional {
        direction: -towards_light,
        irradiance: Vec3::ONE,
    }
}

/// Share of the image's width and height the framed bounds may fill: a 5% margin on each side.
const FRAMING_FILL: f64 = 0.9;

/// A perspective camera framing bounds `(lo, hi)` in an image of `aspect` (width / height): from
/// the front-right and above (a three-quarter view; the front of a y-up file faces −y after
/// import), with a 40° vertical field of view. The camera keeps that direction and moves as close
/// as it can while the eight corners of the bounds stay inside the image with a 5% margin, its
/// target shifted sideways so the projected box is centred (as "frame all" does in a modeller).
pub fn framing_camera(bounds: Option<(DVec3, DVec3)>, aspect: f64) -> Camera {
    const VFOV: f64 = 40.0;
    const YAW: f64 = -65.0;
    const PITCH: f64 = 25.0;
    let Some((lo, hi)) = bounds.filter(|(lo, hi)| lo.is_finite() && hi.is_finite()) else {
        return Camera::orbit(DVec3::ZERO, YAW, PITCH, 3.0, VFOV);
    };
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let unit = Camera::orbit(centre, YAW, PITCH, 1.0, VFOV);
    let forward = (unit.to - unit.from).normalize();
    let up = unit.up.normalize();
    let right = forward.cross(up);
    let half_height = (VFOV * 0.5).to_radians().tan() * FRAMING_FILL;
    let half_width = half_height * aspect.clamp(1e-3, 1e3);
    // Each corner as (depth offset along the view, x, y) relative to the centre: at distance d
    // its depth is d + offset, and it is inside when |x − shift| ≤ half_width · depth (same in y).
    let corners: Vec<DVec3> = (0..8)
        .map(|i| {
            let pick = |bit: usize, a: f64, b: f64| if i & bit == 0 { a } else { b };
            let v = DVec3::new(
                pick(1, lo.x, hi.x),
                pick(2, lo.y, hi.y),
                pick(4, lo.z, hi.z),
            ) - centre;
            DVec3::new(v.dot(forward), v.dot(right), v.dot(up))
        })
        .collect();
    // The shifts that keep every corner inside, per axis, at distance d: an interval (maybe empty).
    let shifts = |d: f64, axis: usize, half: f64| {
        corners
            .iter()
            .fold((f64::NEG_INFINITY, f64::INFINITY), |(low, high), c| {
                let depth = d + c.x;
                (
                    low.max(c[axis] - half * depth),
                    high.min(c[axis] + half * depth),
                )
            })
    };
    let fits = |d: f64| {
        let (x, y) = (shifts(d, 1, half_width), shifts(d, 2, half_height));
        corners.iter().all(|c| d + c.x > 0.0) && x.0 <= x.1 && y.0 <= y.1
    };
    // Fitting is monotone in d: bisect between a distance that fits (the bounding sphere's, which
    // any direction and shift 0 satisfies) and zero.
    let mut far = radius / half_height.min(half_width).atan().sin() + radius;
    let mut near = 0.0;
    for _ in 0..64 {
        let mid = 0.5 * (near + far);
        if fits(mid) {
            far = mid;
        } else {
            near = mid;
        }
    }
    // Centre the projected box: the shift at which its projections reach equally far to both
    // sides, (max + min) of (c − s) / depth = 0, decreasing in s; it lies in the shifts that fit.
    let centred = |axis: usize, half: f64| {
        let (mut low, mut high) = shifts(far, axis, half);
        for _ in 0..64 {
            let s = 0.5 * (low + high);
            let (lowest, highest) =
                corners
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
                        let p = (c[axis] - s) / (far + c.x);
                        (a.min(p), b.max(p))
                    });
            if lowest + highest > 0.0 {
                low = s;
            } else {
                high = s;
            }
        }
        0.5 * (low + high)
    };
    let target = centre + right * centred(1, half_width) + up * centred(2, half_height);
    Camera::orbit(target, YAW, PITCH, far, VFOV)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn y_up_becomes_z_up_and_front_faces_minus_y() {
        let r = Y_UP_TO_Z_UP;
        assert_eq!(r * DVec3::Y, DVec3::Z);
        assert_eq!(r * DVec3::Z, -DVec3::Y);
        assert_eq!(r * DVec3::X, DVec3::X);
        assert_eq!(r.determinant(), 1.0);
    }

    #[test]
    fn spheres_stay_spheres_under_similarities_only() {
        let sim = DAffine3::from_scale_rotation_translation(
            DVec3::splat(2.0),
            glam::DQuat::from_rotation_z(0.3),
            DVec3::new(1.0, 2.0, 3.0),
        );
        match placed_sphere(sim, 0.5, 0).unwrap() {
            PlacedShape::Sphere(s) => {
                assert!((s.radius - 1.0).abs() < 1e-12);
                assert_eq!(s.center, DVec3::new(1.0, 2.0, 3.0));
            }
            _ => panic!("a similarity keeps a sphere"),
        }
        let stretch = DAffine3::from_scale(DVec3::new(1.0, 2.0, 1.0));
        assert!(matches!(
            placed_sphere(stretch, 1.0, 0).unwrap(),
            PlacedShape::Quadric(_)
        ));
    }

    #[test]
    fn framing_camera_fits_the_bounds_to_the_image() {
        let lo = DVec3::new(-1.0, -2.0, 0.0);
        let hi = DVec3::new(3.0, 2.0, 1.0);
        for aspect in [0.5, 4.0 / 3.0, 16.0 / 9.0, 3.0] {
            let cam = framing_camera(Some((lo, hi)), aspect);
            let frame = cam.prepare(aspect).unwrap();
            // Project the corners through the camera itself: every one inside the 5% margin, and
            // the box touching the margin on at least one side (the closest such camera).
            let (mut min, mut max) = (glam::DVec2::splat(1.0), glam::DVec2::splat(0.0));
            for i in 0..8 {
                let p = DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let uv = frame.project(p).expect("in front of the camera");
                min = min.min(uv);
                max = max.max(uv);
            }
            assert!(min.min_element() > 0.05 - 1e-9 && max.max_element() < 0.95 + 1e-9);
            let touches = [min.x, min.y, 1.0 - max.x, 1.0 - max.y]
                .iter()
                .any(|m| (m - 0.05).abs() < 1e-6);
            assert!(touches, "aspect {aspect}: {min} .. {max}");
            // Centred: equal margins on opposite sides.
            assert!(
                (min.x - (1.0 - max.x)).abs() < 1e-6,
                "aspect {aspect}: {min} .. {max}"
            );
            assert!(
                (min.y - (1.0 - max.y)).abs() < 1e-6,
                "aspect {aspect}: {min} .. {max}"
            );
            default_key_light(&cam).validate().unwrap();
        }
    }
}
