//! Arbitrary output variables (AOVs): per-pixel facts about the first surface a camera ray meets,
//! for compositing beside the beauty image.
//!
//! Every surface pass is taken from the **first hit of the first sample** of a pixel, not averaged: an
//! average of depths or object ids across an edge is a value that belongs to no surface. With one
//! sample per pixel that sample is the pixel centre; with more, it is the pixel's first stratified
//! sample, so edges in the passes are aliased while the beauty image is not. Passes are computed
//! only when asked for: a render without them does no extra work. Two passes describe the sampling
//! instead of the surface: the pixel's sample count and the variance of its samples.

use crate::footprint::HitFootprint;
use crate::geometry::Geometry;
use crate::scene::Scene;
use crate::shape::SurfaceHit;
use glam::{DVec3, Vec3};

/// Depth written where a camera ray hits nothing (Blender's convention: far, but finite).
pub const NO_HIT_DEPTH: f32 = 1e10;

/// Object id written where a camera ray hits nothing.
pub const NO_HIT_OBJECT: u32 = 0;

/// Which passes to compute besides the beauty image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSelection {
    /// Distance from the camera along its viewing axis (planar depth, like Blender's Z).
    pub depth: bool,
    /// World-space unit shading normal, turned to face the camera.
    pub normal: bool,
    /// The material's base colour at the hit (its texture), linear RGB.
    pub albedo: bool,
    /// 1-based object index (see [`Geometry::object_index`]); 0 where nothing is hit.
    pub object_id: bool,
    /// Samples the pixel received (the same everywhere unless sampling is adaptive).
    pub sample_count: bool,
    /// Sample variance of the pixel's linear RGB samples ([`crate::film::SecondMoment::variance`]).
    pub variance: bool,
}

impl AovSelection {
    /// No passes at all.
    pub const NONE: AovSelection = AovSelection {
        depth: false,
        normal: false,
        albedo: false,
        object_id: false,
        sample_count: false,
        variance: false,
    };

    /// Every pass.
    pub const ALL: AovSelection = AovSelection {
        depth: true,
        normal: true,
        albedo: true,
        object_id: true,
        sample_count: true,
        variance: true,
    };

    /// Whether any pass is selected.
    pub fn any(&self) -> bool {
        self.depth
            || self.normal
            || self.albedo
            || self.object_id
            || self.sample_count
            || self.variance
    }
}

/// One pixel's values of every pass (unselected ones keep their no-hit value).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AovSample {
    /// Planar depth, or [`NO_HIT_DEPTH`].
    pub depth: f32,
    /// Unit normal facing the camera, or zero.
    pub normal: Vec3,
    /// Base colour, or zero.
    pub albedo: Vec3,
    /// 1-based object index, or [`NO_HIT_OBJECT`].
    pub object_id: u32,
    /// Samples taken in the pixel (filled in after sampling).
    pub sample_count: u32,
    /// Sample variance of the pixel's linear RGB samples (filled in after sampling).
    pub variance: Vec3,
}

impl AovSample {
    /// The values of a pixel whose ray hits nothing.
    pub const MISS: AovSample = AovSample {
        depth: NO_HIT_DEPTH,
        normal: Vec3::ZERO,
        albedo: Vec3::ZERO,
        object_id: NO_HIT_OBJECT,
        sample_count: 0,
        variance: Vec3::ZERO,
    };

    /// Sets the selected sampling passes: the pixel's sample count and its samples' variance
    /// (`None` where it was not estimated, which only happens when the pass is not selected).
    pub fn fill_sampling(&mut self, selection: AovSelection, count: u32, variance: Option<Vec3>) {
        if selection.sample_count {
            self.sample_count = count;
        }
        if selection.variance {
            self.variance = variance.unwrap_or(Vec3::ZERO);
        }
    }

    /// The selected passes of a camera ray starting at `origin` with direction `dir`, given its
    /// first hit and the footprint the albedo averages over; `forward` is the camera's unit
    /// viewing axis.
    pub fn from_hit(
        scene: &Scene,
        selection: AovSelection,
        (origin, dir): (DVec3, DVec3),
        forward: DVec3,
        hit: Option<&SurfaceHit>,
        footprint: &HitFootprint,
    ) -> AovSample {
        let Some(hit) = hit else {
            return AovSample::MISS;
        };
        let g = &hit.geometry;
        let mut out = AovSample::MISS;
        if selection.depth {
            // Planar depth: the hit's distance from the camera along the viewing axis, the same for
            // perspective and orthographic cameras (the latter measured from the image plane).
            out.depth = (g.point - origin).dot(forward) as f32;
        }
        if selection.normal {
            let n = if g.shading_normal.dot(dir) > 0.0 {
                -g.shading_normal
            } else {
                g.shading_normal
            };
            out.normal = n.as_vec3();
        }
        if selection.albedo {
            out.albedo = scene.albedo(hit, footprint);
        }
        if selection.object_id {
            out.object_id = scene.geometry().object_index(hit.prim);
        }
        out
    }
}

/// The passes of a whole image, row-major from the top-left pixel like [`crate::Film`].
#[derive(Clone, Debug, PartialEq)]
pub struct Aovs {
    width: u32,
    height: u32,
    selection: AovSelection,
    samples: Vec<AovSample>,
}

impl Aovs {
    /// Wraps per-pixel samples; `None` if the count does not match the size.
    pub fn new(
        width: u32,
        height: u32,
        selection: AovSelection,
        samples: Vec<AovSample>,
    ) -> Option<Aovs> {
        (samples.len() == width as usize * height as usize).then_some(Aovs {
            width,
            height,
            selection,
            samples,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The passes these samples hold.
    pub fn selection(&self) -> AovSelection {
        self.selection
    }

    /// All pixels' samples, row-major.
    pub fn samples(&self) -> &[AovSample] {
        &self.samples
    }

    /// The sample at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> AovSample {
        self.samples[y as usize * self.width as usize + x as usize]
    }
}

impl Geometry {
    /// A primitive's 1-based object index: the world's spheres, then planes, then quadrics, then
    /// meshes (a whole mesh is one object), each in the order they were given, then one index per
    /// placement of a prototype, in placement order (a placed copy's own shapes are one object;
    /// instances nested inside it are placements of their own); 0 is left for "no object".
    /// Saturates at `u32::MAX`.
    pub fn object_index(&self, prim: crate::shape::PrimRef) -> u32 {
        use crate::shape::LocalPrim;
        let (s, p, q) = (
            self.spheres.len() as u64,
            self.planes.len() as u64,
            self.quadrics.len() as u64,
        );
        let world = s + p + q + self.meshes.len() as u64;
        let index = if prim.placement > 0 {
            world + prim.placement
        } else {
            1 + match prim.local {
                LocalPrim::Sphere(i) => i as u64,
                LocalPrim::Plane(i) => s + i as u64,
                LocalPrim::Quadric(i) => s + p + i as u64,
                LocalPrim::Triangle { mesh, .. } => s + p + q + mesh as u64,
            }
        };
        index.min(u32::MAX as u64) as u32
    }

    /// The [`Geometry::object_index`]es of the world's planes (empty without planes): the
    /// unbounded objects, whose depths run to the horizon.
    pub fn plane_object_indices(&self) -> std::ops::RangeInclusive<u32> {
        let first = self.spheres.len() as u64 + 1;
        let last = self.spheres.len() as u64 + self.planes.len() as u64;
        let clamp = |i: u64| i.min(u32::MAX as u64) as u32;
        clamp(first)..=clamp(last)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::*;

    /// A unit sphere at the origin in front of a plane at z = -2, seen from +z by an orthographic
    /// camera 10 units up: depths, normals and ids follow from the geometry alone.
    fn scene(with_plane: bool) -> Scene {
        Scene::new(SceneDescription {
            camera: Camera {
                from: DVec3::new(0.0, 0.0, 10.0),
                to: DVec3::ZERO,
                up: DVec3::Y,
                projection: Projection::Orthographic { height: 4.0 },
            },
            background: Vec3::splat(0.5),
            environment: None,
            materials: vec![
                Material {
                    texture: Texture::Constant(Vec3::new(0.2, 0.4, 0.6)),
                    ..Material::default()
                },
                Material::default(),
            ],
            lights: vec![],
            geometry: Geometry {
                spheres: vec![Sphere {
                    center: DVec3::ZERO,
                    radius: 1.0,
                    material: 0,
                }],
                planes: [Plane {
                    point: DVec3::new(0.0, 0.0, -2.0),
                    normal: DVec3::Z,
                    material: 1,
                }]
                .into_iter()
                .filter(|_| with_plane)
                .collect(),
                ..Geometry::default()
            },
        })
        .unwrap()
    }

    #[test]
    fn passes_follow_the_geometry() {
        let s = scene(true);
        let settings = RenderSettings {
            width: 41,
            height: 41,
            ..RenderSettings::default()
        };
        let (rendered, aovs) =
            render_with_aovs(&s, &settings, AovSelection::ALL, &NoProgress).unwrap();
        let aovs = aovs.expect("passes were selected");
        // The centre pixel looks straight down at the sphere's top: depth 10 - 1, normal +z.
        let c = aovs.get(20, 20);
        assert!((c.depth - 9.0).abs() < 1e-5, "{c:?}");
        assert!((c.normal - Vec3::Z).length() < 1e-5);
        assert_eq!(c.albedo, Vec3::new(0.2, 0.4, 0.6));
        assert_eq!(c.object_id, 1);
        // A corner pixel misses the sphere and sees the plane 12 units down.
        let k = aovs.get(0, 0);
        assert!((k.depth - 12.0).abs() < 1e-5, "{k:?}");
        assert_eq!(k.object_id, 2);
        assert_eq!(k.normal, Vec3::Z);
        // The plane's id is the one plane index; the sphere's is not.
        let planes = s.geometry().plane_object_indices();
        assert!(planes.contains(&k.object_id) && !planes.contains(&c.object_id));
        assert!(scene(false).geometry().plane_object_indices().is_empty());
        // The passes do not change the beauty image.
        let plain = render(&s, &settings, &NoProgress).unwrap();
        assert_eq!(plain.film, rendered.film);
        assert_eq!(plain.counts, rendered.counts);
    }

    #[test]
    fn unselected_passes_cost_nothing_and_misses_are_marked() {
        let s = scene(true);
        let settings = RenderSettings {
            width: 8,
            height: 8,
            ..RenderSettings::default()
        };
        let (_, none) = render_with_aovs(&s, &settings, AovSelection::NONE, &NoProgress).unwrap();
        assert!(none.is_none());
        let only_depth = AovSelection {
            depth: true,
            ..AovSelection::NONE
        };
        let open = scene(false);
        let (_, aovs) = render_with_aovs(&open, &settings, only_depth, &NoProgress).unwrap();
        let corner = aovs.unwrap().get(0, 0);
        assert_eq!(corner, AovSample::MISS);
    }
}
