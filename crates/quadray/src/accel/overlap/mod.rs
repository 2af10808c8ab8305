//! How deeply a scene's contents overlap: the most shapes and instance placements one point of
//! the world lies in, counted through nested instances.
//!
//! A ray through a point tests every shape and enters every placement whose box holds the point.
//! Where each level of nested instances places overlapping copies of the next, that number
//! multiplies level by level: thirty levels of two copies put 2³⁰ placements on every ray through
//! them, from a file of sixty lines, and a pile of 65 536 coincident spheres under fourteen such
//! levels a billion. The placement count ([`crate::MAX_PLACEMENTS`]) bounds what a scene holds,
//! not what one ray meets; this bounds the latter, so such a scene is refused instead of
//! rendering for days.
//!
//! The count is bounded from above level by level, children first. A shape (a sphere, a
//! quadric, a mesh, whose own BVH sorts its triangles) weighs one, and an instance one (its own
//! box) plus its prototype's bound; a level's bound is the largest total weight of the boxes
//! that meet one cell of a grid laid over them (all the boxes that hold a point meet that
//! point's cell), or, for a few boxes, that meet one box. Boxes that only touch (by less than a
//! millionth of their size) do not count as meeting: tiles, voxels and lattices of copies side
//! by side count one a level, however deeply they nest. The bound takes each prototype's worst
//! point wherever it lies, so it overstates where instances overlap at one point and their
//! prototypes' worst points lie elsewhere; a forest of instanced trees whose crowns overlap
//! still counts tens or hundreds, not tens of thousands.

mod grid;

use super::build::{Bounds, mesh_bounds, transformed_bounds};
use crate::geometry::{Geometry, Level};
use grid::Grid;

/// The most shapes and placements one point of the world may lie in, through nested instances:
/// a ray through it would test or enter each (about 65 000 cost a few milliseconds a ray, so a
/// frame's rays through such a point take minutes).
pub const MAX_OVERLAP: f64 = (1u64 << 16) as f64;

/// Levels with at most this many boxes weigh each box against every other.
const PAIRWISE: usize = 32;

/// The most sums of a level's grid (16 MiB of them: a cell a sum, and one more along each axis).
const MAX_GRID: usize = 1 << 21;

/// The share of a box's size along each axis by which boxes must overlap to count as meeting.
const TOUCH: f64 = 1e-6;

/// Weights stop growing here: far past [`MAX_OVERLAP`], far inside f64's range.
const CAP: f64 = 1e30;

/// An upper bound on the number of shapes and placements one point of the world lies in, given
/// each level's bounds in its own space (`bounds[0]` the world's, `bounds[p + 1]` prototype
/// `p`'s).
pub(super) fn overlap_depth(g: &Geometry, bounds: &[Option<Bounds>]) -> f64 {
    let n = g.level_count();
    let mut depth = vec![0.0f64; n];
    // Prototypes place only earlier prototypes, so children come first; the world last.
    for level in (1..n).chain([0]) {
        let l = g.level(level);
        let meshes: Vec<Bounds> = (l.meshes.iter())
            .filter(|m| m.triangle_count() > 0)
            .map(mesh_bounds)
            .collect();
        let boxes = || weighted_boxes(l, &meshes, bounds, &depth);
        let count = l.instances.len() + l.spheres.len() + l.quadrics.len() + meshes.len();
        depth[level] = deepest(boxes, count).min(CAP);
    }
    depth[0]
}

/// The boxes of level `l`'s contents with their weights, each shrunk by [`inner`]: its shapes
/// (its non-empty meshes' boxes `meshes`) at one, its instances at one plus their prototype's
/// `depth`.
fn weighted_boxes<'a>(
    l: Level<'a>,
    meshes: &'a [Bounds],
    bounds: &'a [Option<Bounds>],
    depth: &'a [f64],
) -> impl Iterator<Item = (Bounds, f64)> + 'a {
    let instances = (l.instances.iter()).filter_map(|inst| {
        let child = inst.prototype as usize + 1;
        let placed = transformed_bounds((*bounds.get(child)?)?, inst);
        Some((placed, (1.0 + depth[child]).min(CAP)))
    });
    let shapes = (l.spheres.iter().map(|s| s.bounds()))
        .chain(l.quadrics.iter().map(|q| q.bounds()))
        .chain(meshes.iter().copied())
        .map(|b| (b, 1.0));
    instances.chain(shapes).map(|(b, w)| (inner(b), w))
}

/// The box shrunk by [`TOUCH`] of its size along each axis: boxes that touch (tiles, voxels,
/// spheres in a lattice of their diameter, whose padded boxes overlap by a few ulps) then do
/// not meet, while any that overlap by more do. Along an axis where a box is flat, the margin is
/// a millionth of its padding, so flat boxes in one plane still meet. (A box a millionth the
/// size of a neighbour, lying within that neighbour's margin, is not counted as meeting it
/// either; nested, that could hide at most a few levels' overlap, as the coordinate limit
/// bounds how many factors of a million the levels can span.)
fn inner((lo, hi): Bounds) -> Bounds {
    let margin = (hi - lo) * TOUCH;
    (lo + margin, hi - margin)
}

/// An upper bound on the largest total weight of the `count` (at most) boxes `boxes` gives
/// that hold one point; `boxes` is asked again for each pass over them.
fn deepest<I: Iterator<Item = (Bounds, f64)>>(boxes: impl Fn() -> I, count: usize) -> f64 {
    deepest_at(boxes, count, 0)
}

/// How many times the boxes outside a grid's region are bounded on a grid of their own before
/// the last grid takes all that are left.
const MAX_REGIONS: usize = 4;

/// [`deepest`], the `regions`-th time over what earlier grids left outside their regions.
///
/// A grid covers the region of the boxes of typical size ([`Grid::over`]). Boxes wholly outside
/// it (a city's buildings around its park) would all be clamped into its edge cells and add up
/// there, though they lie apart, so they are bounded on a grid of their own, and the two bounds
/// add: a point lies in boxes that meet the region (counted in its grid, clamped or not) and in
/// boxes outside it (counted in theirs).
fn deepest_at<I: Iterator<Item = (Bounds, f64)>>(
    boxes: impl Fn() -> I,
    count: usize,
    regions: usize,
) -> f64 {
    if count <= PAIRWISE {
        let boxes: Vec<_> = boxes().collect();
        return (boxes.iter())
            .map(|&(a, _)| {
                (boxes.iter())
                    .filter(|&&(b, _)| meet(a, b))
                    .map(|&(_, w)| w)
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
    }
    let whole = regions + 1 >= MAX_REGIONS;
    let grid = Grid::over(&boxes, count, whole);
    let inside = refined(
        &grid,
        || boxes().filter(|&(b, _)| grid.meets(b)),
        count,
        regions,
    );
    let outside: Vec<(Bounds, f64)> = boxes().filter(|&(b, _)| !grid.meets(b)).collect();
    if outside.is_empty() {
        return inside;
    }
    inside + deepest_of(&outside, regions + 1)
}

/// [`deepest_at`] of the boxes of a slice (one type of closure, so the recursion ends).
fn deepest_of(boxes: &[(Bounds, f64)], regions: usize) -> f64 {
    deepest_at(|| boxes.iter().copied(), boxes.len(), regions)
}

/// Cells whose boxes weigh more than this are bounded again, on a grid of their own boxes.
const REFINE: f64 = 64.0;

/// The largest total weight over `grid`'s cells of the boxes `boxes` gives (`count` at most),
/// where each cell heavier than [`REFINE`] is bounded again by [`deepest_at`] over the boxes
/// that meet it (`regions` counts the grids above), when they are fewer than all: a dense
/// cluster in a sparse world (a park in a city, a blob of particles beside far-off objects)
/// falls into a few cells of a grid sized for the whole, and its own grid tells its boxes
/// apart.
fn refined<I: Iterator<Item = (Bounds, f64)>>(
    grid: &Grid,
    boxes: impl Fn() -> I,
    count: usize,
    regions: usize,
) -> f64 {
    let totals = grid.totals(boxes());
    let heavy: Vec<[usize; 3]> = (grid.cells())
        .filter(|&c| totals[grid.index(c)] > REFINE)
        .collect();
    let light = (grid.cells())
        .map(|c| totals[grid.index(c)])
        .filter(|&t| t <= REFINE)
        .fold(0.0, f64::max);
    if heavy.is_empty() || regions + 1 >= MAX_REGIONS {
        return heavy
            .iter()
            .map(|&c| totals[grid.index(c)])
            .fold(light, f64::max);
    }
    // Each heavy cell's boxes: a box's range of cells is walked, or the heavy cells are, which
    // ever is fewer (a dome over the whole grid meets every heavy cell).
    let slot: std::collections::HashMap<usize, usize> = (heavy.iter().enumerate())
        .map(|(i, &c)| (grid.index(c), i))
        .collect();
    let mut lists: Vec<Vec<(Bounds, f64)>> = vec![Vec::new(); heavy.len()];
    for (b, w) in boxes() {
        let (first, last) = grid.cells_of(b);
        let span: usize = (0..3).map(|a| last[a] - first[a] + 1).product();
        if span <= heavy.len() {
            for z in first[2]..=last[2] {
                for y in first[1]..=last[1] {
                    for x in first[0]..=last[0] {
                        if let Some(&i) = slot.get(&grid.index([x, y, z])) {
                            lists[i].push((b, w));
                        }
                    }
                }
            }
        } else {
            for (i, c) in heavy.iter().enumerate() {
                if (0..3).all(|a| first[a] <= c[a] && c[a] <= last[a]) {
                    lists[i].push((b, w));
                }
            }
        }
    }
    (heavy.iter().zip(&lists))
        .map(|(&c, list)| {
            let total = totals[grid.index(c)];
            match list.len() < count {
                true => deepest_of(list, regions + 1).min(total),
                false => total,
            }
        })
        .fold(light, f64::max)
}

/// Whether two closed boxes share a point.
fn meet((alo, ahi): Bounds, (blo, bhi): Bounds) -> bool {
    alo.cmple(bhi).all() && blo.cmple(ahi).all()
}

#[cfg(test)]
mod tests;
