//! The eye buffer: for rays from a pinhole camera's eye, the one shape each direction can meet,
//! where there is at most one. Such a ray tests that shape and the planes; a ray that two shapes or
//! more may meet traverses the BVH, so hits tied at equal distances resolve as they always did.
//! (Testing several listed shapes here would not give the BVH's bits either: a quadric's t
//! depends in its last bits on the limit it is tested with, since its tangency step is clamped
//! to it, and the BVH lowers that limit in its own order.)
//!
//! Why the one shape is the only one. A hit at `p = e + t·d` on a ray from the eye `e` lies in its
//! shape's padded box, and `p − e = t·d` has the direction `d` looked up, so the shape is listed
//! in its cell.

use super::{Candidate, Cube, Shape, finite_in_f32, relative_box};
use crate::accel::Accel;
use crate::geometry::Geometry;
use crate::math::Ray;
use crate::shape::PrimRef;
use glam::DVec3;

/// The eye buffer's cube: 128² cells a face, about 0.7° each, so most cells of a view of a few
/// shapes see one shape or none.
const CUBE: Cube = Cube { n: 128 };
/// A cell no shape is seen through.
const NO_SHAPE: u8 = u8::MAX;
/// A cell two shapes or more are seen through.
const MANY_SHAPES: u8 = u8::MAX - 1;

/// For rays from one point, the one shape each direction can meet, where there is at most one.
#[derive(Clone, Debug)]
pub struct EyeBuffer {
    /// The eye.
    eye: DVec3,
    shapes: Vec<Shape>,
    /// Per cell: an index into `shapes`, [`NO_SHAPE`] or [`MANY_SHAPES`].
    cells: Vec<u8>,
}

impl EyeBuffer {
    /// The buffer of the eye at `eye` over at most [`MANY_SHAPES`] `shapes`.
    fn new(eye: DVec3, reach: f64, shapes: Vec<Candidate>) -> EyeBuffer {
        assert!(shapes.len() < MANY_SHAPES as usize, "a few shapes");
        let mut cells = vec![NO_SHAPE; CUBE.len()];
        for (k, candidate) in shapes.iter().enumerate() {
            let (lo, hi) = relative_box(candidate, eye, reach);
            CUBE.for_cells_seeing(lo, hi, |cell| {
                cells[cell] = if cells[cell] == NO_SHAPE {
                    k as u8
                } else {
                    MANY_SHAPES
                };
            });
        }
        let shapes = shapes.iter().map(|c| c.shape).collect();
        EyeBuffer { eye, shapes, cells }
    }

    /// Whether the buffer answers for this ray (else the BVH does).
    #[cfg(test)]
    pub(crate) fn answers(&self, ray: &Ray) -> bool {
        self.seen(ray).is_some()
    }

    /// For a ray: `Some(None)` when it starts at the eye and can meet no shape, `Some(Some(shape))`
    /// when only that one, `None` when the BVH must tell.
    #[inline]
    fn seen(&self, ray: &Ray) -> Option<Option<Shape>> {
        if ray.origin != self.eye {
            return None;
        }
        match self.cells[CUBE.cell(ray.dir)?] {
            NO_SHAPE => Some(None),
            MANY_SHAPES => None,
            k => Some(Some(self.shapes[k as usize])),
        }
    }
}

impl Accel {
    /// The eye buffer of a pinhole camera at `eye`, in a world that has buffers
    /// ([`Accel::buffered_shapes`]).
    pub(crate) fn eye_buffer(&self, g: &Geometry, eye: DVec3) -> Option<EyeBuffer> {
        let shapes = self.buffered_shapes(g).filter(|_| eye.is_finite())?;
        Some(EyeBuffer::new(eye, self.reach(eye), shapes))
    }

    /// [`Accel::closest`] for a ray spawned on nothing: through `eye` when the ray starts there
    /// and meets at most one shape, else through the BVH.
    #[inline(never)]
    pub(crate) fn closest_from_eye(
        &self,
        g: &Geometry,
        eye: &EyeBuffer,
        ray: &Ray,
    ) -> Option<(f64, PrimRef)> {
        let Some(seen) = eye.seen(ray).filter(|_| finite_in_f32(ray)) else {
            return self.closest_impl::<false>(g, ray, f64::INFINITY, None);
        };
        let mut best_t = f64::INFINITY;
        let mut best = None;
        match seen {
            None => {}
            Some(Shape::Analytic(shape)) => {
                if let Some(t) = g.level(0).intersect(shape, ray, best_t, false) {
                    best_t = t;
                    best = Some(PrimRef::world(shape));
                }
            }
            Some(Shape::Item(item)) => {
                self.closest_world_item(g, item, ray, &mut best_t, &mut best);
            }
        }
        // The planes after the shapes, as `Accel::closest` tests them.
        self.closest_plane(g, ray, None, &mut best_t, &mut best);
        best.map(|p| (best_t, p))
    }
}
