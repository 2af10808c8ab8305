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
use glam::{DAffine3, DMat3, DVec3};
use quadray::{Camera, Geometry, Light, Material, Projection, Quadric, Sphere, Transform};
use std::path::Path;

/// The kinds of scene file quadray reads, told by the file's extension (in any case).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    /// A native scene: `.toml`.
    Native,
    /// A Wavefront OBJ file (with its MTL materials): `.obj`.
    Obj,
    /// A glTF 2.0 file: `.gltf` or `.glb`.
    Gltf,
}

impl FileFormat {
    /// The format of the file at `path`, or `None` for an extension quadray does not read.
    pub fn of(path: &Path) -> Option<FileFormat> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "toml" => Some(FileFormat::Native),
            "obj" => Some(FileFormat::Obj),
            "gltf" | "glb" => Some(FileFormat::Gltf),
            _ => None,
        }
    }
}

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
    /// The budget the file's textures draw on (shared with the scene that includes the file).
    pub textures: crate::image_file::TextureBudget,
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

impl ImportedCamera {
    /// This camera placed in a scene of `geometry` rendered `width` × `height` pixels: unless
    /// `resolution_given` (the scene file sets one), the height follows the camera's
    /// aspect; the camera is fitted to the image ([`ImportedCamera::fitted`]) and aimed into the
    /// geometry ([`crate::framing::aimed_into`]). Returns the camera and the image's height.
    pub fn placed(
        &self,
        geometry: &Geometry,
        (width, height): (u32, u32),
        resolution_given: bool,
    ) -> (Camera, u32) {
        let height = match self.aspect {
            Some(aspect) if !resolution_given => {
                ((width as f64 / aspect).round() as u32).clamp(1, quadray::render::MAX_SIDE)
            }
            _ => height,
        };
        let camera = crate::framing::aimed_into(
            self.fitted(width as f64 / height as f64),
            crate::framing::geometry_bounds(geometry),
        );
        (camera, height)
    }

    /// The camera for an image of width / height `image_aspect`, fitted as glTF viewers do: the
    /// view the file describes (its vertical field of view over its aspect ratio) stays whole.
    /// An image wider than the file's aspect shows more at the sides; a narrower one widens the
    /// vertical field of view until the file's horizontal extent fits, instead of cropping it.
    pub fn fitted(&self, image_aspect: f64) -> Camera {
        let Some(aspect) = self.aspect else {
            return self.camera;
        };
        if image_aspect >= aspect {
            return self.camera;
        }
        let widen = aspect / image_aspect;
        let projection = match self.camera.projection {
            Projection::Perspective { vfov_deg } => {
                // tan(vfov'/2) = tan(vfov/2)·aspect/image_aspect keeps tan(hfov/2).
                let half: f64 = (vfov_deg.to_radians() * 0.5).tan() * widen;
                Projection::Perspective {
                    vfov_deg: (2.0 * half.atan()).to_degrees(),
                }
            }
            Projection::Orthographic { height } => Projection::Orthographic {
                height: height * widen,
            },
        };
        Camera {
            projection,
            ..self.camera
        }
    }
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
    pub hints: crate::gltf::quadrics_ext::RenderHints,
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
        crate::framing::geometry_bounds(&self.geometry)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_formats_follow_the_extension_in_any_case() {
        let of = |p: &str| FileFormat::of(Path::new(p));
        assert_eq!(of("room.toml"), Some(FileFormat::Native));
        assert_eq!(of("a/teapot.OBJ"), Some(FileFormat::Obj));
        assert_eq!(of("lamp.gltf"), Some(FileFormat::Gltf));
        assert_eq!(of("lamp.Glb"), Some(FileFormat::Gltf));
        for other in ["atoms.ply", "scene", "archive.toml.gz", ".obj"] {
            assert_eq!(of(other), None, "{other}");
        }
    }

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

    /// A camera authored for a 2:1 image keeps its whole view in a narrower image: the points at
    /// the middle of its left and right edges land on the narrower image's edges; a wider image
    /// keeps the vertical field of view and shows more at the sides.
    #[test]
    fn file_cameras_fit_other_aspect_ratios_without_cropping() {
        for projection in [
            Projection::Perspective { vfov_deg: 40.0 },
            Projection::Orthographic { height: 3.0 },
        ] {
            let file = ImportedCamera {
                name: None,
                camera: Camera {
                    from: DVec3::new(1.0, -6.0, 2.0),
                    to: DVec3::new(0.0, 0.0, 0.5),
                    up: DVec3::Z,
                    projection,
                },
                aspect: Some(2.0),
            };
            let authored = file.camera.prepare(2.0).unwrap();
            let edge = |u: f64| {
                let ray = authored.ray(u, 0.5);
                ray.origin + ray.dir * 5.0
            };
            for image_aspect in [1.0, 0.5] {
                let frame = file.fitted(image_aspect).prepare(image_aspect).unwrap();
                for u in [0.0, 1.0] {
                    let p = frame.project(edge(u)).unwrap();
                    assert!((p.x - u).abs() < 1e-12 && (p.y - 0.5).abs() < 1e-12, "{p}");
                }
            }
            assert_eq!(file.fitted(3.0), file.camera);
            assert_eq!(file.fitted(2.0), file.camera);
        }
    }
}
