//! What a ray meets first, with only as much of the hit as shading it needs: in a scene without
//! lights, a surface of constant colour leaves the same radiance whatever the hit, so its surface
//! record (phase two: point, normals, error bound) is never computed.

use super::Scene;
use crate::material::Material;
use crate::math::Ray;
use crate::shape::{PrimRef, SurfaceHit};
use glam::Vec3;

/// What a ray meets first ([`Scene::seen_from`]).
#[derive(Clone, Debug)]
pub enum Seen {
    /// Nothing: the ray leaves the scene.
    Nothing,
    /// A surface whose radiance towards the ray is known without its surface record.
    Constant {
        /// Ray parameter of the hit.
        t: f64,
        /// The radiance the surface leaves ([`Material::unlit_constant_radiance`]).
        radiance: Vec3,
    },
    /// A surface to shade, with its full record.
    Surface(SurfaceHit),
}

/// Per material, its radiance when shading it needs no surface record; empty when every
/// material needs one (a scene with lights or vertex colours).
pub(super) fn constant_radiances(
    materials: &[Material],
    has_lights: bool,
    has_vertex_colors: bool,
) -> Vec<Option<Vec3>> {
    if has_lights || has_vertex_colors {
        return Vec::new();
    }
    let radiances: Vec<_> = materials
        .iter()
        .map(Material::unlit_constant_radiance)
        .collect();
    if radiances.iter().all(Option::is_none) {
        Vec::new()
    } else {
        radiances
    }
}

impl Scene {
    /// What `ray` (spawned on primitive `from`, whose self-hits are skipped) meets first:
    /// [`Scene::intersect_from`], except that a hit on a material of constant radiance
    /// ([`Material::unlit_constant_radiance`], in a scene without lights) skips phase two.
    #[inline]
    pub fn seen_from(&self, ray: &Ray, from: Option<PrimRef>) -> Seen {
        self.seen_given(ray, self.closest(ray, from))
    }

    /// [`Scene::seen_from`] for a ray whose phase one is done: `first` is its nearest hit
    /// ([`Scene::closest`], or [`Scene::closest_each`] for a batch of camera rays).
    #[inline(always)]
    pub(crate) fn seen_given(&self, ray: &Ray, first: Option<(f64, PrimRef)>) -> Seen {
        let Some((t, prim)) = first else {
            return Seen::Nothing;
        };
        let mut slot = None;
        let path = self.path_in(prim.placement, &mut slot);
        let material = self.geometry.material(prim, path);
        if !self.single_sided
            && let Some(&Some(radiance)) = self.constant_radiance.get(material as usize)
        {
            return Seen::Constant { t, radiance };
        }
        match self.hit_seen(ray, (t, prim), path, material) {
            Some(hit) => Seen::Surface(hit),
            None => Seen::Nothing,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection};
    use crate::dielectric::Transmission;
    use crate::footprint::RayCone;
    use crate::geometry::Geometry;
    use crate::integrator::{RayCounts, Whitted};
    use crate::light::Light;
    use crate::material::SpecularModel;
    use crate::plane::Plane;
    use crate::sampler::SampleKey;
    use crate::scene::SceneDescription;
    use crate::shape::LocalPrim;
    use crate::texture::Texture;
    use crate::{Mesh, Sphere};
    use glam::{DVec3, Vec4};

    /// Materials of every kind: constant grey, constant and emissive, a mirror, a checker, GGX,
    /// glass, and one with textured emission.
    fn materials() -> Vec<Material> {
        let grey = Material {
            texture: Texture::Constant(Vec3::new(0.6, 0.5, 0.4)),
            ambient: 0.7,
            ..Material::default()
        };
        vec![
            grey.clone(),
            Material {
                emission: Some(Texture::Constant(Vec3::new(0.2, 0.3, 0.1))),
                ..grey.clone()
            },
            Material {
                reflectivity: 0.5,
                ..grey.clone()
            },
            Material {
                texture: Texture::Checker {
                    size: 0.5,
                    even: Vec3::ONE,
                    odd: Vec3::splat(0.1),
                },
                ..grey.clone()
            },
            Material {
                specular_model: SpecularModel::Ggx,
                ..grey.clone()
            },
            Material {
                transmission: Some(Transmission {
                    factor: 1.0,
                    ior: 1.5,
                    thin_walled: false,
                    attenuation: None,
                }),
                ..grey.clone()
            },
            Material {
                emission: Some(Texture::HeightRamp),
                ..grey
            },
        ]
    }

    /// A row of spheres, one of each material, over a mirror floor, seen from above.
    fn scene(lights: Vec<Light>, meshes: Vec<Mesh>) -> Scene {
        let materials = materials();
        let spheres = (0..materials.len())
            .map(|i| Sphere {
                center: DVec3::new(i as f64 * 2.2 - 6.6, 0.0, 1.0),
                radius: 1.0,
                material: i as u32,
            })
            .collect();
        Scene::new(SceneDescription {
            camera: Camera {
                from: DVec3::new(0.0, -12.0, 9.0),
                to: DVec3::ZERO,
                up: DVec3::Z,
                projection: Projection::Perspective { vfov_deg: 60.0 },
            },
            background: Vec3::new(0.05, 0.1, 0.2),
            environment: Some(Vec3::new(0.3, 0.2, 0.1)),
            materials,
            lights,
            geometry: Geometry {
                spheres,
                planes: vec![Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                    material: 2,
                }],
                meshes,
                ..Geometry::default()
            },
        })
        .unwrap()
    }

    /// Camera rays over the whole frame.
    fn rays(scene: &Scene) -> impl Iterator<Item = Ray> + '_ {
        let frame = scene.camera().prepare(16.0 / 9.0).unwrap();
        (0..90)
            .flat_map(move |y| (0..160).map(move |x| frame.ray(x as f64 / 160.0, y as f64 / 90.0)))
    }

    #[test]
    fn only_opaque_matte_constant_materials_skip_the_surface_record() {
        let expected = [true, true, false, false, false, false, false];
        for (m, expect) in materials().iter().zip(expected) {
            assert_eq!(m.unlit_constant_radiance().is_some(), expect, "{m:?}");
        }
        let radiances = constant_radiances(&materials(), false, false);
        assert_eq!(radiances.len(), materials().len());
        // Lights or vertex colours make every surface's radiance depend on its hit.
        assert!(constant_radiances(&materials(), true, false).is_empty());
        assert!(constant_radiances(&materials(), false, true).is_empty());
        let matte = Material {
            reflectivity: 0.2,
            ..Material::default()
        };
        assert!(constant_radiances(&[matte], false, false).is_empty());
    }

    /// The radiance without the surface record is the radiance shading computes with it, bit for
    /// bit: camera rays that skip phase two (`camera_ray`) against the AOV path, which always
    /// runs it (`camera_ray_hit`), through mirrors, glass, GGX and textures.
    #[test]
    fn skipping_phase_two_changes_no_radiance() {
        let scene = scene(Vec::new(), Vec::new());
        let whitted = Whitted::default();
        let (mut constant, mut surface) = (0, 0);
        for (i, ray) in rays(&scene).enumerate() {
            let key = SampleKey {
                pattern: i as u32,
                index: 0,
                count: Some(1),
            };
            let mut counts = (RayCounts::default(), RayCounts::default());
            let lazy = whitted.camera_ray(&scene, &ray, RayCone::POINT, key, &mut counts.0);
            let (full, _) =
                whitted.camera_ray_hit(&scene, &ray, RayCone::POINT, key, &mut counts.1);
            assert_eq!(
                lazy.to_array().map(f32::to_bits),
                full.to_array().map(f32::to_bits)
            );
            assert_eq!(counts.0.total(), counts.1.total());
            match scene.seen_from(&ray, None) {
                Seen::Constant { t, radiance } => {
                    constant += 1;
                    let hit = scene.intersect(&ray).expect("a hit");
                    assert_eq!(t, hit.t);
                    assert_eq!(
                        Some(radiance),
                        scene.materials()[hit.material as usize].unlit_constant_radiance()
                    );
                }
                Seen::Surface(_) => surface += 1,
                Seen::Nothing => assert!(scene.intersect(&ray).is_none()),
            }
        }
        assert!(
            constant > 100 && surface > 1000,
            "{constant} constant, {surface} shaded"
        );
    }

    /// Phase one for a batch of camera rays (`Scene::closest_each`) followed by `seen_given`
    /// finds each ray's hit as `Scene::intersect` does ray by ray, unlit and lit; with a
    /// single-sided triangle over the spheres facing away from the camera, which every ray passes
    /// through: the same as without it (the eye buffer's path included where the process takes
    /// the baseline path).
    #[test]
    fn batched_phase_one_sees_what_each_ray_sees() {
        let p = vec![
            Vec3::new(-6.0, -6.0, 2.5),
            Vec3::new(6.0, -6.0, 2.5),
            Vec3::new(0.0, 6.0, 2.5),
        ];
        // Wound clockwise seen from above: its normal faces down, away from the camera.
        let veil = Mesh::new(p, vec![[0, 2, 1]], None, 0)
            .unwrap()
            .with_single_sided(true);
        let light = Light::Point {
            position: DVec3::new(0.0, 0.0, 10.0),
            intensity: Vec3::splat(50.0),
        };
        let key = |s: &Seen| match s {
            Seen::Nothing => (0, 0, 0, 0),
            Seen::Constant { t, radiance } => (1, t.to_bits(), radiance.x.to_bits() as u64, 0),
            Seen::Surface(h) => (2, h.t.to_bits(), h.prim.placement, h.material as u64),
        };
        for lights in [Vec::new(), vec![light]] {
            let (bare, veiled) = (
                scene(lights.clone(), Vec::new()),
                scene(lights, vec![veil.clone()]),
            );
            let rays: Vec<Ray> = rays(&bare).collect();
            let (mut kinds, mut veil_first) = ([0; 3], 0);
            for batch in rays.chunks(37) {
                for scene in [&bare, &veiled] {
                    let mut firsts = vec![None; batch.len()];
                    scene.closest_each(batch, &mut firsts);
                    for (ray, &first) in batch.iter().zip(&firsts) {
                        veil_first += matches!(
                            first,
                            Some((_, p)) if matches!(p.local, LocalPrim::Triangle { .. })
                        ) as usize;
                        let given = key(&scene.seen_given(ray, first));
                        // As the full query finds it, one ray at a time.
                        let hit = scene.intersect(ray);
                        assert_eq!(given.0 == 0, hit.is_none());
                        if let Some(h) = hit {
                            assert_eq!(given.1, h.t.to_bits());
                            if given.0 == 2 {
                                assert_eq!(
                                    (given.2, given.3),
                                    (h.prim.placement, h.material as u64)
                                );
                            }
                        }
                        // Past the veil, t is the sum of its legs': equal to a few ulps. (A
                        // scene with single-sided meshes keeps every surface record.)
                        let unveiled = key(&bare.seen_from(ray, None));
                        let t = f64::from_bits(given.1);
                        assert_eq!(given.0 == 0, unveiled.0 == 0);
                        assert!((t - f64::from_bits(unveiled.1)).abs() <= 1e-12 * t);
                        kinds[given.0 as usize] += 1;
                    }
                }
            }
            assert!(
                kinds[2] > 1000 && veil_first > 1000,
                "{kinds:?}, {veil_first}"
            );
        }
    }

    #[test]
    fn lights_or_vertex_colours_keep_every_surface_record() {
        let lit = scene(
            vec![Light::Point {
                position: DVec3::new(0.0, 0.0, 10.0),
                intensity: Vec3::splat(50.0),
            }],
            Vec::new(),
        );
        let p = vec![
            Vec3::new(-9.0, -9.0, 0.01),
            Vec3::new(9.0, -9.0, 0.01),
            Vec3::new(0.0, 9.0, 0.01),
        ];
        let coloured = Mesh::new(p, vec![[0, 1, 2]], None, 0)
            .unwrap()
            .with_colors(vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 3])
            .unwrap();
        let tinted = scene(Vec::new(), vec![coloured]);
        for scene in [lit, tinted] {
            assert!(
                rays(&scene)
                    .all(|ray| !matches!(scene.seen_from(&ray, None), Seen::Constant { .. }))
            );
        }
    }
}
