//! Light buffers: for shadow rays ending at a point light, the shapes that can block them.
//!
//! Why every blocker is listed. A blocker's hit at `p = o + t·d`, `0 < t < t_max`, lies in its
//! shape's padded box. The ray ends at `e = o + t_max·d`, within `reach` of the light `l` on every
//! axis (checked per ray): `p = (1 − s)·o + s·e` for some `s` in (0, 1), so `q = p − s·(e − l)`
//! lies on the segment from `o` to `l`, within `reach` of `p`. `q − l = (1 − s)·(o − l)` points the
//! way the looked-up direction `o − l` does, so the shape is listed in its cell.

use super::{Candidate, Cube, Shape, finite_in_f32, relative_box};
use crate::accel::Accel;
use crate::geometry::Geometry;
use crate::math::Ray;
use crate::shape::PrimRef;
use glam::DVec3;

/// The light buffers' cube: 32² cells a face, about 3° each (64² measured no faster on
/// scenes/reflective.toml and scenes/defense.toml).
const CUBE: Cube = Cube { n: 32 };

/// The shapes each direction from one light can meet.
#[derive(Clone, Debug)]
pub struct LightBuffer {
    /// The light's position.
    light: DVec3,
    /// How far a shadow ray's end may miss the light for the buffer to answer (world units).
    reach: f64,
    /// |light|∞, a term of every lookup's rounding bound.
    light_magnitude: f64,
    /// Where each cell's shapes start in `candidates` (one entry more than cells).
    starts: Vec<u32>,
    candidates: Vec<Shape>,
}

impl LightBuffer {
    /// The buffer of a light at `light` over `shapes`; a shape around the light is listed in
    /// every cell.
    fn new(light: DVec3, reach: f64, shapes: &[Candidate]) -> LightBuffer {
        let mut lists: Vec<Vec<Shape>> = vec![Vec::new(); CUBE.len()];
        for candidate in shapes {
            let (lo, hi) = relative_box(candidate, light, reach);
            CUBE.for_cells_seeing(lo, hi, |cell| lists[cell].push(candidate.shape));
        }
        let mut starts = Vec::with_capacity(CUBE.len() + 1);
        let mut candidates = Vec::new();
        for list in lists {
            starts.push(candidates.len() as u32);
            candidates.extend(list);
        }
        starts.push(candidates.len() as u32);
        LightBuffer {
            light,
            reach,
            light_magnitude: light.abs().max_element(),
            starts,
            candidates,
        }
    }

    /// Whether the buffer answers for this shadow ray (else the BVH does).
    #[cfg(test)]
    pub(crate) fn answers(&self, ray: &Ray, t_max: f64) -> bool {
        self.candidates(ray, t_max).is_some()
    }

    /// The shapes a shadow ray may meet, or `None` when the buffer cannot tell: the ray's end
    /// misses the light by more than `reach`, or the ray is not finite.
    #[inline]
    fn candidates(&self, ray: &Ray, t_max: f64) -> Option<&[Shape]> {
        let end = ray.origin + ray.dir * t_max - self.light;
        // The rounding of `end`: three operations, each within half an ulp of its largest term.
        let rounding = (ray.origin.abs().max_element()
            + (ray.dir * t_max).abs().max_element()
            + self.light_magnitude)
            * (4.0 * f64::EPSILON);
        // Also refuses a NaN end (the comparison fails).
        let within = end.abs().max_element() + rounding <= self.reach;
        if !within {
            return None;
        }
        let cell = CUBE.cell(ray.origin - self.light)?;
        let (first, last) = (self.starts[cell], self.starts[cell + 1]);
        Some(&self.candidates[first as usize..last as usize])
    }
}

impl Accel {
    /// The light buffer of a light at `light`, in a world that has buffers
    /// ([`Accel::buffered_shapes`]), on the baseline path (the AVX2 path is taken for worlds of
    /// many triangles, whose shadow rays the buffer would send to the BVH anyway).
    pub(crate) fn light_buffer(&self, g: &Geometry, light: DVec3) -> Option<LightBuffer> {
        if self.avx2 {
            return None;
        }
        let shapes = self.buffered_shapes(g).filter(|_| light.is_finite())?;
        Some(LightBuffer::new(light, self.reach(light), &shapes))
    }

    /// [`Accel::occluded`] for a shadow ray ending at the light of `buffer`: the world's planes,
    /// then the shapes the buffer lists for the ray's direction; or the BVH where the buffer
    /// cannot tell.
    #[inline]
    pub(crate) fn occluded_towards(
        &self,
        g: &Geometry,
        buffer: &LightBuffer,
        ray: &Ray,
        t_max: f64,
        from: Option<PrimRef>,
    ) -> bool {
        let Some(candidates) = buffer.candidates(ray, t_max).filter(|_| finite_in_f32(ray)) else {
            return self.occluded(g, ray, t_max, from);
        };
        if self.plane_blocks(g, ray, t_max, from) {
            return true;
        }
        // No box test before the shapes' own: the BVH's robust slab test would cost about as
        // much as it saves (measured), and obvhs' single-box test is not widened for rounding.
        let level = g.level(0);
        // The world primitive the ray was spawned on, if any: compared with each candidate.
        let from_world = from.filter(|p| p.placement == 0).map(|p| p.local);
        candidates.iter().any(|&c| match c {
            Shape::Analytic(shape) => {
                let from_self = from_world == Some(shape);
                level
                    .intersect_inlined(shape, ray, t_max, from_self)
                    .is_some()
            }
            Shape::Item(item) => self.occluded_world_item(g, item, ray, t_max, from),
        })
    }
}
