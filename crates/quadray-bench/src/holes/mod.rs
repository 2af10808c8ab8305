//! Hole maps: one primary ray through every pixel centre of a scene made of quadrics, intersected
//! by each variant and by the oracle; pixels where the variant's hit/miss or hit object differs
//! from the oracle's are marked.
//!
//! The oracle's verdict for a pixel is the nearest valid root over all quadrics (each from
//! [`oracle::checked`]). A pixel is **ambiguous** when a decision that could change which object it
//! shows lies within the oracle's margin δ ([`Reference::ambiguous`]) for some quadric whose clip
//! box the ray enters no later than the oracle's hit, or when the two nearest hits on different
//! quadrics are closer than production's error bound (64·u·κ·t each, docs/numerics.md). Ambiguous
//! pixels are shown and counted apart; a difference there is not a failure.
//!
//! The production row is the renderer's own path: [`Whitted::intersect`] through the scene's BVH.
//! The other variants test every quadric of the scene ([`VariantQuadric::intersect`]) and keep
//! the nearest hit.

use crate::oracle::{self, Reference};
use crate::variants::{Variant, VariantQuadric};
use glam::DVec3;
use quadray::math::slab_interval;
use quadray::{Quadric, Ray, Scene, Whitted};
use rayon::prelude::*;

/// Why a hole map cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HoleError {
    /// The oracle intersects quadrics only.
    #[error(
        "hole maps need a scene made of quadrics only (the oracle intersects quadrics), but it has {spheres} spheres, {planes} planes and {meshes} meshes"
    )]
    NotQuadricsOnly {
        /// Spheres in the scene.
        spheres: usize,
        /// Planes in the scene.
        planes: usize,
        /// Meshes in the scene.
        meshes: usize,
    },
    /// The scene has no quadric at all.
    #[error("the scene has no quadric")]
    Empty,
    /// The resolution is outside the renderer's limits.
    #[error("{0}")]
    Render(#[from] quadray::RenderError),
}

/// A scene to map, with its name and resolution.
#[derive(Clone, Debug)]
pub struct HoleScene {
    /// Short name, used in file names and tables.
    pub name: String,
    /// What makes the scene hard.
    pub about: String,
    /// The scene (quadrics only).
    pub scene: Scene,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// What the oracle says one pixel shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OraclePixel {
    /// Index into the scene's quadrics of the nearest hit, if any.
    pub object: Option<u32>,
    /// Ray parameter of that hit.
    pub t: Option<f64>,
    /// A decision that could change the answer lies within the oracle's margin.
    pub ambiguous: bool,
}

/// One variant's per-pixel answers (quadric index of the nearest hit, if any), row-major.
pub type VariantPixels = Vec<Option<u32>>;

/// How one pixel of a variant compares with the oracle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelClass {
    /// Same hit object, or both miss.
    Agrees,
    /// The oracle hits, the variant misses.
    Hole,
    /// The variant hits, the oracle misses.
    Phantom,
    /// Both hit, different objects.
    WrongObject,
}

impl PixelClass {
    /// Compares a variant's answer with the oracle's.
    pub fn of(oracle: Option<u32>, got: Option<u32>) -> PixelClass {
        match (oracle, got) {
            (Some(a), Some(b)) if a != b => PixelClass::WrongObject,
            (Some(_), None) => PixelClass::Hole,
            (None, Some(_)) => PixelClass::Phantom,
            _ => PixelClass::Agrees,
        }
    }
}

/// Checks that the scene is made of quadrics only and the resolution is renderable.
pub fn check(scene: &Scene, width: u32, height: u32) -> Result<(), HoleError> {
    let g = scene.geometry();
    if !(g.spheres.is_empty() && g.planes.is_empty() && g.meshes.is_empty()) {
        return Err(HoleError::NotQuadricsOnly {
            spheres: g.spheres.len(),
            planes: g.planes.len(),
            meshes: g.meshes.len(),
        });
    }
    if g.quadrics.is_empty() {
        return Err(HoleError::Empty);
    }
    quadray::RenderSettings {
        width,
        height,
        ..quadray::RenderSettings::default()
    }
    .validate()?;
    Ok(())
}

/// The primary ray through the centre of pixel (x, y), as the renderer's one-sample render casts it.
fn pixel_rays(scene: &Scene, width: u32, height: u32) -> Result<Vec<Ray>, HoleError> {
    let frame = scene
        .camera()
        .prepare(width as f64 / height as f64)
        .map_err(quadray::RenderError::from)?;
    Ok((0..height)
        .flat_map(|y| {
            (0..width).map(move |x| {
                frame.ray(
                    (x as f64 + 0.5) / width as f64,
                    (y as f64 + 0.5) / height as f64,
                )
            })
        })
        .collect())
}

/// The oracle's verdict for one ray against every quadric (see the module docs for ambiguity).
fn oracle_pixel(quadrics: &[Quadric], ray: &Ray) -> OraclePixel {
    let refs: Vec<Reference> = quadrics
        .iter()
        .map(|q| oracle::checked(q, ray, f64::INFINITY))
        .collect();
    let mut hits: Vec<(f64, usize)> = refs
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.t().map(|t| (t, i)))
        .collect();
    hits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let nearest = hits.first().copied();
    let reach = nearest.map_or(f64::INFINITY, |(t, _)| t * (1.0 + 1e-6));
    // A quadric matters when the ray enters its clip box no later than the nearest hit.
    let matters = |q: &Quadric| {
        let local = q.local_ray(ray);
        let (t_in, t_out) = slab_interval(local.origin, local.dir, -DVec3::ONE, DVec3::ONE);
        !(t_in > t_out || t_out < 0.0 || t_in > reach)
    };
    let mut ambiguous = quadrics
        .iter()
        .zip(&refs)
        .any(|(q, r)| r.ambiguous() && matters(q));
    if let [(t0, i0), (t1, i1), ..] = hits[..] {
        // Production's bound 64·u·κ·|t| on each root (docs/numerics.md): nearer than both, a tie.
        let bound = |t: f64, i: usize| 64.0 * f64::EPSILON * 0.5 * refs[i].condition * t.abs();
        ambiguous |= (t1 - t0) <= bound(t0, i0) + bound(t1, i1);
    }
    OraclePixel {
        object: nearest.map(|(_, i)| i as u32),
        t: nearest.map(|(t, _)| t),
        ambiguous,
    }
}

/// The oracle's verdict for every pixel, row-major (parallel over rows on the current rayon pool).
pub fn oracle_pixels(
    scene: &Scene,
    width: u32,
    height: u32,
) -> Result<Vec<OraclePixel>, HoleError> {
    check(scene, width, height)?;
    let rays = pixel_rays(scene, width, height)?;
    let quadrics = &scene.geometry().quadrics;
    Ok(rays
        .par_chunks(width as usize)
        .flat_map_iter(|row| row.iter().map(|ray| oracle_pixel(quadrics, ray)))
        .collect())
}

/// The nearest hit object of every pixel by `variant`, row-major. [`Variant::Production`] goes
/// through the renderer's own path ([`Whitted::intersect`], BVH included).
pub fn variant_pixels(
    scene: &Scene,
    width: u32,
    height: u32,
    variant: Variant,
) -> Result<VariantPixels, HoleError> {
    check(scene, width, height)?;
    let rays = pixel_rays(scene, width, height)?;
    if variant == Variant::Production {
        let whitted = Whitted::default();
        return Ok(rays
            .par_iter()
            .map(|ray| {
                // Object indices are 1-based and count quadrics last; `check` admitted quadrics only.
                whitted
                    .intersect(scene, ray, None)
                    .map(|hit| scene.geometry().object_index(hit.prim) - 1)
            })
            .collect());
    }
    Ok(brute_force(scene, &rays, variant))
}

/// Every quadric tested by `variant`, nearest hit kept (no BVH).
fn brute_force(scene: &Scene, rays: &[Ray], variant: Variant) -> VariantPixels {
    let quadrics: Vec<VariantQuadric> = scene
        .geometry()
        .quadrics
        .iter()
        .cloned()
        .map(VariantQuadric::new)
        .collect();
    rays.par_iter()
        .map(|ray| {
            let mut best: Option<(f64, u32)> = None;
            for (i, q) in quadrics.iter().enumerate() {
                if let Some(t) = q.intersect(variant, ray, f64::INFINITY, false)
                    && best.is_none_or(|(bt, _)| t < bt)
                {
                    best = Some((t, i as u32));
                }
            }
            best.map(|(_, i)| i)
        })
        .collect()
}

/// Production's intersector tested on every quadric without the BVH, for checking that the BVH
/// loses nothing (the result must equal [`variant_pixels`] for [`Variant::Production`]).
pub fn production_without_bvh(
    scene: &Scene,
    width: u32,
    height: u32,
) -> Result<VariantPixels, HoleError> {
    check(scene, width, height)?;
    let rays = pixel_rays(scene, width, height)?;
    Ok(brute_force(scene, &rays, Variant::Production))
}

/// Pixel counts of one variant against the oracle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HoleCounts {
    /// Pixels in the image.
    pub pixels: usize,
    /// Pixels where the oracle hits something.
    pub oracle_hits: usize,
    /// Ambiguous pixels (within the oracle's margin).
    pub ambiguous: usize,
    /// Unambiguous pixels the oracle hits and the variant misses.
    pub holes: usize,
    /// Unambiguous pixels the variant hits and the oracle misses.
    pub phantoms: usize,
    /// Unambiguous pixels where both hit, different objects.
    pub wrong_object: usize,
    /// Ambiguous pixels where the variant's answer differs (not failures).
    pub ambiguous_differing: usize,
}

impl HoleCounts {
    /// Compares a variant's answers with the oracle's, pixel by pixel.
    pub fn of(oracle: &[OraclePixel], got: &[Option<u32>]) -> HoleCounts {
        let mut c = HoleCounts {
            pixels: oracle.len(),
            ..HoleCounts::default()
        };
        for (o, &g) in oracle.iter().zip(got) {
            c.oracle_hits += o.object.is_some() as usize;
            let class = PixelClass::of(o.object, g);
            if o.ambiguous {
                c.ambiguous += 1;
                c.ambiguous_differing += (class != PixelClass::Agrees) as usize;
                continue;
            }
            match class {
                PixelClass::Agrees => {}
                PixelClass::Hole => c.holes += 1,
                PixelClass::Phantom => c.phantoms += 1,
                PixelClass::WrongObject => c.wrong_object += 1,
            }
        }
        c
    }

    /// Unambiguous pixels whose hit/miss or object differs from the oracle's.
    pub fn differing(&self) -> usize {
        self.holes + self.phantoms + self.wrong_object
    }
}

/// One scene's hole maps: the oracle's verdicts and every variant's answers and counts.
#[derive(Clone, Debug)]
pub struct SceneHoles {
    /// Scene name.
    pub name: String,
    /// What makes the scene hard.
    pub about: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The oracle's verdicts, row-major.
    pub oracle: Vec<OraclePixel>,
    /// Each variant's answers and counts, in [`Variant::ALL`] order.
    pub variants: Vec<(Variant, VariantPixels, HoleCounts)>,
}

/// Computes the oracle's verdicts and every variant's hole map for one scene.
pub fn scene_holes(s: &HoleScene) -> Result<SceneHoles, HoleError> {
    let oracle = oracle_pixels(&s.scene, s.width, s.height)?;
    let variants = Variant::ALL
        .iter()
        .map(|&v| {
            let got = variant_pixels(&s.scene, s.width, s.height, v)?;
            let counts = HoleCounts::of(&oracle, &got);
            Ok((v, got, counts))
        })
        .collect::<Result<Vec<_>, HoleError>>()?;
    Ok(SceneHoles {
        name: s.name.clone(),
        about: s.about.clone(),
        width: s.width,
        height: s.height,
        oracle,
        variants,
    })
}

impl SceneHoles {
    /// The counts of `variant`.
    pub fn counts(&self, variant: Variant) -> HoleCounts {
        self.variants
            .iter()
            .find(|(v, _, _)| *v == variant)
            .map(|(_, _, c)| *c)
            .unwrap_or_default()
    }
}

mod map;
mod scenes;

pub use map::{AMBIGUOUS, BACKGROUND, HOLE, PHANTOM, WRONG_OBJECT, hole_map_rgb8, markdown};
pub use scenes::{far, moved};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_classes() {
        assert_eq!(PixelClass::of(None, None), PixelClass::Agrees);
        assert_eq!(PixelClass::of(Some(1), Some(1)), PixelClass::Agrees);
        assert_eq!(PixelClass::of(Some(1), None), PixelClass::Hole);
        assert_eq!(PixelClass::of(None, Some(0)), PixelClass::Phantom);
        assert_eq!(PixelClass::of(Some(0), Some(2)), PixelClass::WrongObject);
    }

    #[test]
    fn counts_skip_ambiguous_pixels_and_the_map_marks_them() {
        let px = |object, ambiguous| OraclePixel {
            object,
            t: object.map(|_| 1.0),
            ambiguous,
        };
        let oracle = [
            px(Some(0), false),
            px(Some(0), false),
            px(None, false),
            px(Some(1), false),
            px(Some(1), true),
            px(None, false),
        ];
        let got = [Some(0), None, Some(1), Some(0), None, None];
        let c = HoleCounts::of(&oracle, &got);
        assert_eq!(
            (c.holes, c.phantoms, c.wrong_object, c.ambiguous),
            (1, 1, 1, 1)
        );
        assert_eq!(
            (c.ambiguous_differing, c.differing(), c.oracle_hits),
            (1, 3, 4)
        );
        let map = hole_map_rgb8(&oracle, Some(&got));
        let colours: Vec<[u8; 3]> = map.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        assert_eq!(
            colours,
            vec![
                map::object_colour(0),
                HOLE,
                PHANTOM,
                WRONG_OBJECT,
                AMBIGUOUS,
                BACKGROUND
            ]
        );
    }

    #[test]
    fn scenes_with_other_primitives_are_refused() {
        let mut description = far(8, 4).scene.into_description();
        description.geometry.spheres.push(quadray::Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            material: 0,
        });
        let with_sphere = quadray::Scene::new(description).unwrap();
        assert!(matches!(
            oracle_pixels(&with_sphere, 8, 4),
            Err(HoleError::NotQuadricsOnly { spheres: 1, .. })
        ));
        let s = far(8, 4);
        assert!(matches!(
            variant_pixels(&s.scene, 0, 4, Variant::Production),
            Err(HoleError::Render(_))
        ));
    }
}
