//! The eye buffer: for rays from a pinhole camera's eye, the few shapes each direction can meet.
//! Such a ray tests those shapes and the planes; a ray that more shapes may meet, or a mesh or an
//! instance among others, traverses the BVH.
//!
//! Why the listed shapes are the only ones. A hit at `p = e + t·d` on a ray from the eye `e` lies
//! in its shape's padded box, and `p − e = t·d` has the direction `d` looked up, so the shape is
//! listed in its cell.
//!
//! Why testing them in the list's order gives the BVH's answer. A sphere's or a quadric's hit
//! below a limit is the hit its test finds with no limit, bit for bit (the quadric's step towards
//! tangency is clamped to its box, not to the limit: `roots_do_not_depend_on_the_limit`), so the
//! nearest of the listed shapes' unbounded hits is the hit the BVH finds in whatever order it
//! tests them. Two shapes hit at exactly the same distance are left to the BVH, whose order
//! decides such ties. A mesh or an instance is listed only alone.

use super::{Candidate, Cube, Shape, finite_in_f32, relative_box};
use crate::accel::Accel;
use crate::geometry::{Geometry, Level};
use crate::math::Ray;
use crate::shape::{LocalPrim, PrimRef};
use glam::DVec3;
use std::collections::HashMap;

/// The eye buffer's cube: 128² cells a face, about 0.7° each, so most cells of a view of a few
/// shapes list one shape or none.
const CUBE: Cube = Cube { n: 128 };
/// A cell no shape is seen through.
const NO_SHAPE: u8 = u8::MAX;
/// A cell the BVH answers for: more than [`MAX_LISTED`] shapes are seen through it, or a mesh
/// or an instance among others, or its list would be one too many.
const MANY_SHAPES: u8 = u8::MAX - 1;
/// Most shapes a cell lists.
const MAX_LISTED: u32 = 4;

/// A ray's nearest hit among a list's shapes: its distance (∞ for none) and its shape.
type Nearest = (f64, Option<PrimRef>);

/// For rays from one point, the few shapes each direction can meet.
#[derive(Clone, Debug)]
pub struct EyeBuffer {
    /// The eye.
    eye: DVec3,
    /// The distinct lists cells hold, one after another: list `k` is
    /// `shapes[starts[k]..starts[k + 1]]`.
    shapes: Vec<Shape>,
    starts: Vec<u16>,
    /// Per cell: a list's index, [`NO_SHAPE`] or [`MANY_SHAPES`].
    cells: Vec<u8>,
    /// The eye in each world quadric's local frame (`Quadric::to_local_point`), mapped once for
    /// all the rays from it.
    eye_local: Vec<DVec3>,
}

impl EyeBuffer {
    /// The buffer of the eye at `eye` over at most 128 `shapes` (a world's 64 spheres and
    /// quadrics and its few other top items, [`Accel::buffered_shapes`]).
    fn new(eye: DVec3, reach: f64, shapes: Vec<Candidate>, eye_local: Vec<DVec3>) -> EyeBuffer {
        assert!(shapes.len() <= 128, "a few shapes");
        // Each cell's shapes as a set of bits, then each distinct set as a list.
        let boxes: Vec<_> = shapes.iter().map(|c| relative_box(c, eye, reach)).collect();
        let mut seen = vec![0u128; CUBE.len()];
        for (k, &(lo, hi)) in boxes.iter().enumerate() {
            CUBE.for_cells_seeing(lo, hi, |cell| seen[cell] |= 1 << k);
        }
        let items = (shapes.iter().enumerate())
            .filter(|(_, c)| matches!(c.shape, Shape::Item(_)))
            .fold(0u128, |set, (k, _)| set | 1 << k);
        // Lists run from the shape whose box is nearest the eye, so that a farther quadric is
        // mostly refused by its slab test once a nearer hit is found.
        let distances: Vec<f64> = boxes.iter().map(|&b| squared_distance(b)).collect();
        let mut by_distance: Vec<usize> = (0..shapes.len()).collect();
        by_distance.sort_by(|&i, &j| distances[i].total_cmp(&distances[j]));
        let (mut listed, mut starts) = (Vec::new(), vec![0u16]);
        let mut lists: HashMap<u128, u8> = HashMap::new();
        let mut list_of = |set: u128| {
            let count = set.count_ones();
            if set == 0 {
                return NO_SHAPE;
            }
            if count > MAX_LISTED || (count > 1 && set & items != 0) {
                return MANY_SHAPES;
            }
            if let Some(&k) = lists.get(&set) {
                return k;
            }
            if lists.len() == MANY_SHAPES as usize {
                return MANY_SHAPES;
            }
            let k = lists.len() as u8;
            let members = by_distance.iter().filter(|&&i| set >> i & 1 == 1);
            listed.extend(members.map(|&i| shapes[i].shape));
            starts.push(listed.len() as u16);
            lists.insert(set, k);
            k
        };
        // Neighbouring cells mostly see the same shapes: a run of equal sets takes the first
        // one's answer instead of hashing each again (the hashing was half of a bunny scene's
        // build, 98 304 cells).
        let mut last: Option<(u128, u8)> = None;
        let cells = (seen.into_iter())
            .map(|set| match last {
                Some((previous, k)) if previous == set => k,
                _ => {
                    let k = list_of(set);
                    last = Some((set, k));
                    k
                }
            })
            .collect();
        EyeBuffer {
            eye,
            shapes: listed,
            starts,
            cells,
            eye_local,
        }
    }

    /// How many shapes the buffer tests for this ray, or `None` where the BVH answers.
    #[cfg(test)]
    pub(crate) fn listed(&self, ray: &Ray) -> Option<usize> {
        self.seen_finite(ray).map(<[Shape]>::len)
    }

    /// The shapes listed in `cell`, or `None` where the BVH answers or there is no such cell.
    #[inline(always)]
    fn in_cell(&self, cell: usize) -> Option<&[Shape]> {
        match *self.cells.get(cell)? {
            NO_SHAPE => Some(&[]),
            MANY_SHAPES => None,
            k => Some(self.list(k)),
        }
    }

    /// Whether the cells of four rays list the same spheres and quadrics (at least one): what
    /// [`Accel::closest_each_from_eye`] tests four rays at once.
    #[cfg(test)]
    pub(crate) fn lists_alike(&self, rays: &[Ray; 4]) -> bool {
        let first = self.seen_finite(&rays[0]);
        first.is_some_and(|list| !list.is_empty())
            && rays[1..].iter().all(|ray| {
                self.seen_finite(ray)
                    .zip(first)
                    .is_some_and(|(s, f)| std::ptr::eq(s, f))
            })
    }

    /// For a ray: the shapes it can meet (none, when it starts at the eye and can meet none), or
    /// `None` when the BVH must tell. The ray starts at the eye bit for bit (a zero's sign
    /// included), so the eye's local points are its origin's, and is finite in f32, as the BVH
    /// traverses it ([`Cube::cell_from`]).
    #[inline(always)]
    fn seen_finite(&self, ray: &Ray) -> Option<&[Shape]> {
        self.in_cell(CUBE.cell_from(self.eye, ray)?)
    }

    /// [`EyeBuffer::seen_finite`] of each ray into `seen` (as long), the cells of four rays
    /// found together. Out of line: inlined, its loop made the batch loop around it dearer than
    /// the lookups saved.
    #[inline(never)]
    fn seen_finite_each<'a>(&'a self, rays: &[Ray], seen: &mut [Option<&'a [Shape]>]) {
        let (fours, rest) = rays.as_chunks::<4>();
        // Indexed loops: zipped iterators over the lanes kept their state on the stack.
        for (k, four) in fours.iter().enumerate() {
            let cells = CUBE.cells_from(self.eye, four);
            for lane in 0..4 {
                // NO_CELL is beyond every cell: `in_cell` finds none there.
                seen[4 * k + lane] = self.in_cell(cells[lane] as usize);
            }
        }
        let done = 4 * fours.len();
        for (s, ray) in seen[done..].iter_mut().zip(rest) {
            *s = self.seen_finite(ray);
        }
    }

    /// List `k` of those the cells hold.
    #[inline(always)]
    fn list(&self, k: u8) -> &[Shape] {
        let (first, last) = (self.starts[k as usize], self.starts[k as usize + 1]);
        &self.shapes[first as usize..last as usize]
    }

    /// The eye the buffer was made for.
    pub(crate) fn eye(&self) -> DVec3 {
        self.eye
    }

    /// Whether no shape can be met by any ray from the eye whose direction lies in the cone of
    /// the four `corners` (rays that all start at the eye): their cells, with a margin of one
    /// cell for the lookup's rounding, lie on one face and away from its edges (where a rounded
    /// direction could be looked up on the next face), and no shape is seen through any of them.
    ///
    /// Why the cone's directions fall in those cells: the directions whose largest component is
    /// one axis, on one side, form a convex cone, so every direction of the corners' cone looks
    /// up the corners' face; and there the cell coordinates are central projections of the
    /// direction, which map the cone onto the quadrilateral of the corners' projections.
    fn sees_nothing_within(&self, corners: &[Ray; 4]) -> bool {
        let n = CUBE.n;
        let (mut face, mut u, mut v) = (None, (n, 0), (n, 0));
        for ray in corners {
            if ray.origin != self.eye {
                return false;
            }
            let Some((f, cu, cv)) = CUBE.face_cell(ray.dir) else {
                return false;
            };
            if *face.get_or_insert(f) != f {
                return false;
            }
            (u, v) = ((u.0.min(cu), u.1.max(cu)), (v.0.min(cv), v.1.max(cv)));
        }
        let Some(face) = face else {
            return false;
        };
        // The checked cells, one beyond the corners' on each side, stay off the face's border.
        if u.0 < 2 || v.0 < 2 || u.1 + 2 >= n || v.1 + 2 >= n {
            return false;
        }
        (u.0 - 1..=u.1 + 1).all(|cu| {
            let row = (face * n + cu) * n;
            self.cells[row + v.0 - 1..=row + v.1 + 1]
                .iter()
                .all(|&c| c == NO_SHAPE)
        })
    }

    /// Phase one of a sphere or quadric for a ray from the eye: a quadric's test starts from the
    /// eye's local point mapped once (the same bits as [`Level::intersect`]).
    #[inline(always)]
    fn intersect(&self, level: Level<'_>, shape: LocalPrim, ray: &Ray, t_max: f64) -> Option<f64> {
        match shape {
            LocalPrim::Quadric(i) => level.quadrics[i as usize].intersect_from_local_point(
                self.eye_local[i as usize],
                ray.dir,
                t_max,
            ),
            _ => level.intersect(shape, ray, t_max, false),
        }
    }

    /// For four rays from the eye whose cells list the same spheres and quadrics `shapes`: each
    /// ray's nearest hit among them (its distance, ∞ for none, and its shape) as
    /// [`EyeBuffer::nearest_listed`] finds it, or `None` for a ray that meets two at exactly the
    /// same distance. A quadric is tested against the four rays at once
    /// ([`Quadric::intersect_four_from_local_point`](crate::quadric::Quadric)), the same hits
    /// bit for bit. `None` when a shape is neither.
    #[inline(always)]
    fn nearest_four(
        &self,
        level: Level<'_>,
        shapes: &[Shape],
        four: &[Ray; 4],
    ) -> Option<[Option<Nearest>; 4]> {
        let dirs = [four[0].dir, four[1].dir, four[2].dir, four[3].dir];
        let (mut best_t, mut best, mut tied) = ([f64::INFINITY; 4], [None; 4], [false; 4]);
        for &shape in shapes {
            let Shape::Analytic(shape) = shape else {
                return None;
            };
            // A limit just past each ray's nearest hit, as `nearest_listed` tests.
            let limits = best_t.map(f64::next_up);
            let ts = match shape {
                LocalPrim::Quadric(q) => level.quadrics[q as usize]
                    .intersect_four_from_local_point(self.eye_local[q as usize], &dirs, limits),
                _ => std::array::from_fn(|k| self.intersect(level, shape, &four[k], limits[k])),
            };
            for (k, t) in ts.into_iter().enumerate() {
                match t {
                    Some(t) if t < best_t[k] => {
                        best_t[k] = t;
                        best[k] = Some(PrimRef::world(shape));
                    }
                    Some(t) if t == best_t[k] => tied[k] = true,
                    _ => {}
                }
            }
        }
        Some(std::array::from_fn(|k| {
            (!tied[k]).then_some((best_t[k], best[k]))
        }))
    }

    /// Lowers `best_t` to the nearest hit of `ray` on the spheres and quadrics `shapes` and sets
    /// `best` to its shape; `false` when a shape is not a sphere or a quadric, or two are hit at
    /// exactly the same distance (the BVH's order decides such ties). Each is tested with a limit
    /// just past `best_t`: their hits below a limit are their unbounded hits, so a hit at
    /// `best_t` itself (a tie) is still found, and a quadric's box beyond it is refused by its
    /// slab test.
    #[inline(never)]
    fn nearest_listed(
        &self,
        g: &Geometry,
        shapes: &[Shape],
        ray: &Ray,
        best_t: &mut f64,
        best: &mut Option<PrimRef>,
    ) -> bool {
        let level = g.level(0);
        for &shape in shapes {
            // Lists of several never hold an item (`EyeBuffer::new`); were one there, the BVH
            // answers.
            let Shape::Analytic(shape) = shape else {
                return false;
            };
            match self.intersect(level, shape, ray, best_t.next_up()) {
                Some(t) if t < *best_t => {
                    *best_t = t;
                    *best = Some(PrimRef::world(shape));
                }
                Some(t) if t == *best_t => return false,
                _ => {}
            }
        }
        true
    }
}

/// The squared distance from the eye to a box given relative to it (`(lo, hi)` as
/// [`relative_box`] gives it): zero for a box around the eye.
fn squared_distance((lo, hi): (DVec3, DVec3)) -> f64 {
    lo.max(-hi).max(DVec3::ZERO).length_squared()
}

impl Accel {
    /// Whether every camera ray in the cone of the four `corners` (rays from the eye of `eye`)
    /// meets no shape, as [`Accel::closest_from_eye`] would answer each: no shape is seen through
    /// their cells (the planes are the caller's to ask).
    pub(crate) fn eye_sees_nothing(&self, eye: &EyeBuffer, corners: &[Ray; 4]) -> bool {
        corners.iter().all(finite_in_f32) && eye.sees_nothing_within(corners)
    }

    /// The eye buffer of a pinhole camera at `eye`, in a world of few shapes
    /// ([`Accel::buffered_shapes`]) on either path: camera rays ask it one by one only on the
    /// baseline path ([`Accel::eye_answers_rays`]), tiles of pixels on both.
    pub(crate) fn eye_buffer(&self, g: &Geometry, eye: DVec3) -> Option<EyeBuffer> {
        // A cell's shapes are the bits of a u128 (`buffered_shapes` gives at most 72).
        let shapes =
            (self.buffered_shapes(g)).filter(|shapes| eye.is_finite() && shapes.len() <= 128)?;
        let eye_local = g.level(0).quadrics.iter().map(|q| q.to_local_point(eye));
        Some(EyeBuffer::new(
            eye,
            self.reach(eye),
            shapes,
            eye_local.collect(),
        ))
    }

    /// Whether camera rays ask the eye buffer one by one ([`Accel::closest_from_eye`]): on the
    /// baseline path. The AVX2 path's traversal answers a ray about as fast as the lookup (an
    /// eye buffer answering its rays that meet nothing measured the bunny's frame 3% faster and
    /// the kitchen's 4% slower).
    pub(crate) fn eye_answers_rays(&self) -> bool {
        !self.avx2
    }

    /// [`Accel::closest_from_eye`] for each of `rays` into `hits` (one each), the same answers
    /// bit for bit. On the AVX2 path four neighbouring rays whose cells list the same spheres and
    /// quadrics are tested against each quadric at once ([`EyeBuffer::nearest_four`]); on the
    /// baseline path, one by one.
    pub(crate) fn closest_each_from_eye(
        &self,
        g: &Geometry,
        eye: &EyeBuffer,
        rays: &[Ray],
        hits: &mut [Option<(f64, PrimRef)>],
    ) {
        if crate::simd::simd_path() != crate::simd::SimdPath::Avx2 {
            for (ray, hit) in rays.iter().zip(hits) {
                *hit = self.closest_from_eye(g, eye, ray);
            }
            return;
        }
        // Each ray's cell looked up once, a batch of up to 32 at a time.
        const BATCH: usize = 32;
        let level = g.level(0);
        for (rays, hits) in rays.chunks(BATCH).zip(hits.chunks_mut(BATCH)) {
            let mut seen = [None; BATCH];
            eye.seen_finite_each(rays, &mut seen[..rays.len()]);
            let mut k = 0;
            while k < rays.len() {
                // Four neighbouring rays whose cells list the same spheres and quadrics (each
                // distinct list is stored once, so one address means one list).
                if let (Some(list @ [_, ..]), Some(four)) = (seen[k], rays[k..].first_chunk::<4>())
                    && seen[k + 1..k + 4]
                        .iter()
                        .all(|s| s.is_some_and(|s| std::ptr::eq(s, list)))
                    && let Some(nearest) = eye.nearest_four(level, list, four)
                {
                    for (lane, nearest) in nearest.into_iter().enumerate() {
                        let ray = &four[lane];
                        hits[k + lane] = match nearest {
                            Some((mut best_t, mut best)) => {
                                // The planes after the shapes, as `Accel::closest` tests them.
                                self.closest_plane(g, ray, None, &mut best_t, &mut best);
                                best.map(|p| (best_t, p))
                            }
                            // Two shapes hit at the same distance: the BVH's order decides.
                            None => self.closest_impl::<false>(g, ray, f64::INFINITY, None),
                        };
                    }
                    k += 4;
                    continue;
                }
                hits[k] = self.closest_seen_from_eye(g, eye, &rays[k], seen[k]);
                k += 1;
            }
        }
    }

    /// [`Accel::closest`] for a ray spawned on nothing: through `eye` when the ray starts there
    /// and its cell lists the shapes it can meet, else through the BVH.
    #[inline(never)]
    pub(crate) fn closest_from_eye(
        &self,
        g: &Geometry,
        eye: &EyeBuffer,
        ray: &Ray,
    ) -> Option<(f64, PrimRef)> {
        self.closest_seen_from_eye(g, eye, ray, eye.seen_finite(ray))
    }

    /// [`Accel::closest_from_eye`] for a ray whose cell's shapes are `seen`
    /// ([`EyeBuffer::seen_finite`]).
    #[inline(always)]
    fn closest_seen_from_eye(
        &self,
        g: &Geometry,
        eye: &EyeBuffer,
        ray: &Ray,
        seen: Option<&[Shape]>,
    ) -> Option<(f64, PrimRef)> {
        if let Some(seen) = seen {
            let mut best_t = f64::INFINITY;
            let mut best = None;
            let answered = match *seen {
                [] => true,
                // One shape, most cells: `nearest_listed` would answer the same, but through its
                // call and loop the quadric grid took 3.4% more instructions.
                [Shape::Analytic(shape)] => {
                    if let Some(t) = eye.intersect(g.level(0), shape, ray, best_t) {
                        best_t = t;
                        best = Some(PrimRef::world(shape));
                    }
                    true
                }
                [Shape::Item(item)] => {
                    self.closest_world_item(g, item, ray, &mut best_t, &mut best);
                    true
                }
                ref shapes => eye.nearest_listed(g, shapes, ray, &mut best_t, &mut best),
            };
            if answered {
                // The planes after the shapes, as `Accel::closest` tests them.
                self.closest_plane(g, ray, None, &mut best_t, &mut best);
                return best.map(|p| (best_t, p));
            }
        }
        self.closest_impl::<false>(g, ray, f64::INFINITY, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::aabb::Aabb;

    /// Every cell lists exactly the shapes whose boxes are seen through it, nearest box first, up
    /// to the cap on distinct lists, past which cells go to the BVH: 64 long boxes scattered
    /// around the eye, whose lists hold more entries than a byte can count.
    #[test]
    fn cells_list_the_shapes_seen_through_them() {
        let mut next = crate::test_rng::centred_stream(0x5eed_e7e5);
        let candidates: Vec<Candidate> = (0..64)
            .map(|k| {
                // Sticks along the three axes in turn, which cross each other in view.
                let centre = DVec3::new(next(), next(), next()) * 20.0;
                let mut half = DVec3::splat(0.1);
                half[k as usize % 3] = 8.0;
                Candidate {
                    bounds: Aabb {
                        min: (centre - half).as_vec3a(),
                        max: (centre + half).as_vec3a(),
                    },
                    shape: Shape::Analytic(LocalPrim::Sphere(k)),
                }
            })
            .collect();
        let (eye, reach) = (DVec3::new(0.5, -0.25, 0.125), 1e-6);
        let buffer = EyeBuffer::new(eye, reach, candidates.clone(), Vec::new());
        let mut seen = vec![0u128; CUBE.len()];
        for (k, candidate) in candidates.iter().enumerate() {
            let (lo, hi) = relative_box(candidate, eye, reach);
            CUBE.for_cells_seeing(lo, hi, |cell| seen[cell] |= 1 << k);
        }
        let distance = |shape: &Shape| {
            let k = candidates.iter().position(|c| c.shape == *shape).unwrap();
            (
                k,
                squared_distance(relative_box(&candidates[k], eye, reach)),
            )
        };
        let mut many = 0;
        for (cell, &set) in seen.iter().enumerate() {
            match buffer.cells[cell] {
                NO_SHAPE => assert_eq!(set, 0, "cell {cell}"),
                // Too many shapes, or a list past the cap.
                MANY_SHAPES => {
                    assert_ne!(set, 0, "cell {cell}");
                    many += 1;
                }
                k => {
                    let listed: Vec<_> = buffer.list(k).iter().map(distance).collect();
                    let set_listed = listed.iter().fold(0u128, |s, &(k, _)| s | 1 << k);
                    assert_eq!(set_listed, set, "cell {cell}");
                    assert!(listed.len() as u32 <= MAX_LISTED);
                    assert!(listed.windows(2).all(|w| w[0].1 <= w[1].1), "cell {cell}");
                }
            }
        }
        // The distinct lists reached the cap, and hold more entries than 255.
        assert_eq!(buffer.starts.len() - 1, MANY_SHAPES as usize);
        assert!(
            buffer.shapes.len() > 255 && many > 0,
            "{}",
            buffer.shapes.len()
        );
    }
}
