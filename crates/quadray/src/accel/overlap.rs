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

use super::build::{Bounds, mesh_bounds, transformed_bounds};
use crate::geometry::{Geometry, Level};
use glam::DVec3;

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

/// A grid of cells over a region of a level's boxes, `k[axis]` along each axis.
struct Grid {
    /// The region's corners.
    lo: DVec3,
    hi: DVec3,
    /// Cells per unit length along each axis (0 along an axis the boxes do not extend along).
    scale: DVec3,
    k: [usize; 3],
}

impl Grid {
    /// Cells about as large as the boxes' typical size along each axis (their geometric mean,
    /// which a few huge boxes beside many small ones do not inflate), over the region of the
    /// boxes of about that size (of all of them when `whole`), so a box meets a few cells and a
    /// cell is met by about the boxes that overlap there. A level costs in proportion to what it
    /// holds: eight cells a box at most, and [`MAX_GRID`] in all; where that is too few, the
    /// axis with the most cells gives them up first (boxes flat along an axis ask for many
    /// cells along it, which the others must not pay for).
    ///
    /// A box reaching past the region (a sky dome over a forest) is clamped into its edge cells.
    /// The bound holds all the same: boxes that share a point overlap along each axis, so their
    /// clamped ranges of cells do too, and share a cell.
    fn over<I: Iterator<Item = (Bounds, f64)>>(
        boxes: impl Fn() -> I,
        count: usize,
        whole: bool,
    ) -> Grid {
        let mut log_size = DVec3::ZERO;
        for ((a, b), _) in boxes() {
            // A flat side counts as the least positive size, not as ln 0 = −∞.
            let sides = (b - a).max(DVec3::splat(f64::MIN_POSITIVE));
            log_size += DVec3::from_array(sides.to_array().map(f64::ln));
        }
        let typical = DVec3::from_array((log_size / count.max(1) as f64).to_array().map(f64::exp));
        // The region: the union of the boxes at most HUGE times the typical size on every axis
        // (or of all, where none is).
        const HUGE: f64 = 16.0;
        let union = |only_typical: bool| {
            (boxes())
                .filter(|&((a, b), _)| !only_typical || (b - a).cmple(typical * HUGE).all())
                .fold(
                    (DVec3::INFINITY, DVec3::NEG_INFINITY),
                    |(lo, hi), ((a, b), _)| (lo.min(a), hi.max(b)),
                )
        };
        let (mut lo, mut hi) = union(!whole);
        if !lo.cmple(hi).all() {
            (lo, hi) = union(false);
        }
        let extent = hi - lo;
        // How many places the boxes' centres take along each axis, told apart to a 4096th of
        // the region: cells past that number separate nothing (boxes flat along an axis, tiles
        // on two floors, ask for millions of cells across their thickness, and two do).
        const BINS: usize = 4096;
        let mut taken = vec![false; 3 * BINS];
        for ((a, b), _) in boxes() {
            for axis in 0..3 {
                let at = ((a[axis] + b[axis]) * 0.5 - lo[axis]) / extent[axis] * BINS as f64;
                // NaN (a flat region) and outside the region clamp to its ends.
                let bin = (at.max(0.0) as usize).min(BINS - 1);
                taken[axis * BINS + bin] = true;
            }
        }
        let places = [0, 1, 2].map(|axis| {
            let bins = &taken[axis * BINS..(axis + 1) * BINS];
            bins.iter().filter(|&&t| t).count().max(1) as f64
        });
        // Rounded, not raised: cells of the boxes' own size stay aligned with a lattice of them,
        // whose extent the boxes' padding makes a hair longer than a whole number of boxes.
        let mut k = [0, 1, 2].map(|axis| match typical[axis] > 0.0 && extent[axis] > 0.0 {
            true => (extent[axis] / typical[axis])
                .round()
                .clamp(1.0, places[axis].min(MAX_GRID as f64)) as usize,
            false => 1,
        });
        let budget = (8 * count).min(MAX_GRID) as f64;
        let sums = |k: &[usize; 3]| k.iter().map(|&k| (k + 1) as f64).product::<f64>();
        while sums(&k) > budget {
            let axis = (0..3).max_by_key(|&a| k[a]).expect("three axes");
            k[axis] = k[axis].div_ceil(2);
        }
        let scale = DVec3::from_array([0, 1, 2].map(|axis| match k[axis] > 1 {
            true => k[axis] as f64 / extent[axis],
            false => 0.0,
        }));
        Grid { lo, hi, scale, k }
    }

    /// Whether the closed box `b` meets the grid's region.
    fn meets(&self, (lo, hi): Bounds) -> bool {
        meet((lo, hi), (self.lo, self.hi))
    }

    /// The cell along `axis` that coordinate `x` lies in (clamped to the grid; a NaN to 0).
    fn cell(&self, x: f64, axis: usize) -> usize {
        let c = ((x - self.lo[axis]) * self.scale[axis]).floor();
        (c.max(0.0) as usize).min(self.k[axis] - 1)
    }

    /// Each cell's total weight of the boxes meeting it, indexed by [`Grid::index`] (cells
    /// past the last along an axis hold sums of no use): each box adds its weight to the block
    /// of cells it meets, as eight signed corners of a difference array whose prefix sums along
    /// the three axes give every cell's total.
    fn totals(&self, boxes: impl Iterator<Item = (Bounds, f64)>) -> Vec<f64> {
        let [sx, sy, sz] = self.k.map(|k| k + 1);
        let index = |x: usize, y: usize, z: usize| self.index([x, y, z]);
        let mut sums = vec![0.0f64; sx * sy * sz];
        for (b, w) in boxes {
            let (first, last) = self.cells_of(b);
            for corner in 0..8u32 {
                let pick = |axis: usize| match corner >> axis & 1 {
                    0 => first[axis],
                    _ => last[axis] + 1,
                };
                let sign = if corner.count_ones() % 2 == 0 {
                    1.0
                } else {
                    -1.0
                };
                sums[index(pick(0), pick(1), pick(2))] += sign * w;
            }
        }
        // Prefix sums along x, then y, then z: each cell then holds the weight of the boxes
        // meeting it.
        for z in 0..sz {
            for y in 0..sy {
                for x in 1..sx {
                    sums[index(x, y, z)] += sums[index(x - 1, y, z)];
                }
            }
        }
        for z in 0..sz {
            for y in 1..sy {
                for x in 0..sx {
                    sums[index(x, y, z)] += sums[index(x, y - 1, z)];
                }
            }
        }
        for z in 1..sz {
            for y in 0..sy {
                for x in 0..sx {
                    sums[index(x, y, z)] += sums[index(x, y, z - 1)];
                }
            }
        }
        sums
    }

    /// The first and last cell along each axis that the box `b` meets (clamped to the grid).
    fn cells_of(&self, (lo, hi): Bounds) -> ([usize; 3], [usize; 3]) {
        let first = [0, 1, 2].map(|axis| self.cell(lo[axis], axis));
        let last = [0, 1, 2].map(|axis| self.cell(hi[axis], axis).max(first[axis]));
        (first, last)
    }

    /// Where cell `[x, y, z]` is in [`Grid::totals`].
    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        let [sx, sy, _] = self.k.map(|k| k + 1);
        (z * sy + y) * sx + x
    }

    /// Every cell of the grid, as its `[x, y, z]`.
    fn cells(&self) -> impl Iterator<Item = [usize; 3]> + '_ {
        let [kx, ky, kz] = self.k;
        (0..kz).flat_map(move |z| (0..ky).flat_map(move |y| (0..kx).map(move |x| [x, y, z])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Prototype;
    use crate::geometry::instance::Instance;
    use crate::math::Transform;
    use crate::sphere::Sphere;
    use glam::{DAffine3, DVec3};

    fn ball() -> Prototype {
        ball_of(1.0)
    }

    fn ball_of(radius: f64) -> Prototype {
        Prototype {
            spheres: vec![Sphere {
                center: DVec3::ZERO,
                radius,
                material: 0,
            }],
            ..Prototype::default()
        }
    }

    fn at(prototype: u32, x: f64, y: f64) -> Instance {
        let t = DAffine3::from_translation(DVec3::new(x, y, 0.0));
        Instance::new(prototype, Transform::new(t).unwrap())
    }

    /// The depth of `g` through the core's own level bounds.
    fn depth(g: &Geometry) -> f64 {
        let layout = super::super::Layout::new(g, None);
        layout.overlap_depth(g)
    }

    /// Nested levels of two overlapping copies double the depth a level: exactly, as two boxes
    /// are weighed pairwise.
    #[test]
    fn overlapping_copies_multiply_level_by_level() {
        for levels in 1..=12u32 {
            let mut g = Geometry {
                prototypes: vec![ball()],
                ..Geometry::default()
            };
            for l in 1..levels {
                g.prototypes.push(Prototype {
                    instances: vec![at(l - 1, 0.0, 0.0), at(l - 1, 0.1, 0.0)],
                    ..Prototype::default()
                });
            }
            g.instances = vec![at(levels - 1, 0.0, 0.0), at(levels - 1, 0.1, 0.0)];
            // 2 + 4 + … + 2^levels instances and 2^levels spheres hold the origin.
            let expected = f64::from(3 * (1u32 << levels) - 2);
            assert_eq!(depth(&g), expected, "{levels} levels");
        }
    }

    /// Copies side by side, apart, count one each however many there are: a grid of 100 × 100
    /// balls two units apart (the grid's cells then hold one or a few boxes), under a level
    /// that places that grid twice far apart.
    #[test]
    fn copies_apart_do_not_add_up() {
        let mut g = Geometry {
            prototypes: vec![ball()],
            ..Geometry::default()
        };
        let row: Vec<Instance> = (0..10_000)
            .map(|i| at(0, f64::from(i % 100) * 3.0, f64::from(i / 100) * 3.0))
            .collect();
        g.prototypes.push(Prototype {
            instances: row,
            ..Prototype::default()
        });
        g.instances = vec![at(1, 0.0, 0.0), at(1, 0.0, 1000.0)];
        let d = depth(&g);
        // One for the grid's instance, then the balls (an instance and its sphere each) that
        // meet one cell of about a ball's size (cells of 2 units: a cell meets at most 2 × 2
        // balls three units apart).
        assert!((3.0..=1.0 + 2.0 * 4.0).contains(&d), "{d}");
    }

    /// Copies that only touch count one a level: spheres of radius 0.5 on a lattice of unit
    /// spacing, 2 × 2 × 2 a level (weighed pairwise) twelve levels deep, and 4 × 4 × 4 a level
    /// (on the grid) five levels deep; with the copies overlapping by a tenth instead, the
    /// 2 × 2 × 2 octree multiplies by eight a level.
    #[test]
    fn touching_copies_count_one_a_level() {
        let nested = |side: u32, levels: u32, spacing: f64| {
            let mut g = Geometry {
                prototypes: vec![ball_of(0.5)],
                ..Geometry::default()
            };
            for l in 0..levels {
                let size = spacing * f64::from(side.pow(l));
                let copies = (0..side.pow(3))
                    .map(|i| {
                        let [x, y, z] = [i % side, i / side % side, i / side / side];
                        let shift = DVec3::new(f64::from(x), f64::from(y), f64::from(z)) * size;
                        let t = DAffine3::from_translation(shift);
                        Instance::new(l, Transform::new(t).unwrap())
                    })
                    .collect();
                g.prototypes.push(Prototype {
                    instances: copies,
                    ..Prototype::default()
                });
            }
            g.instances = vec![at(levels, 0.0, 0.0)];
            depth(&g)
        };
        // A level an instance, and the sphere at the bottom.
        assert_eq!(nested(2, 12, 1.0), 14.0);
        assert_eq!(nested(4, 5, 1.0), 7.0);
        // Overlapping by a tenth of a sphere, eight copies meet at each level's centre.
        assert!(nested(2, 6, 0.9) >= 8f64.powi(5), "{}", nested(2, 6, 0.9));
    }

    /// The grid bounds the depth from above: 40 balls all holding the origin (too many to
    /// compare pairwise) weigh 80 (an instance and its sphere each), and with 60 far-off ones
    /// beside them still 80.
    #[test]
    fn the_grid_counts_every_box_at_a_point() {
        let mut g = Geometry {
            prototypes: vec![ball()],
            ..Geometry::default()
        };
        let mut instances: Vec<Instance> =
            (0..40).map(|i| at(0, f64::from(i) * 0.01, 0.0)).collect();
        assert_eq!(
            depth(&Geometry {
                instances: instances.clone(),
                ..g.clone()
            }),
            80.0
        );
        instances.extend((0..60).map(|i| at(0, 100.0 + f64::from(i) * 10.0, 50.0)));
        g.instances = instances;
        assert_eq!(depth(&g), 80.0);
    }

    /// Shapes count as placements do: 1000 coincident spheres in a prototype placed by three
    /// levels of overlapping pairs put 8 000 spheres (and 14 placements) at the origin; a few
    /// huge boxes beside thousands of small ones apart (a sky dome over a forest) do not coarsen
    /// the grid, so the small ones still count one or a few a cell.
    #[test]
    fn shapes_count_and_huge_boxes_do_not_coarsen_the_grid() {
        let pile = Prototype {
            spheres: vec![
                Sphere {
                    center: DVec3::ZERO,
                    radius: 1.0,
                    material: 0,
                };
                1000
            ],
            ..Prototype::default()
        };
        let mut g = Geometry {
            prototypes: vec![pile],
            ..Geometry::default()
        };
        for l in 1..3 {
            g.prototypes.push(Prototype {
                instances: vec![at(l - 1, 0.0, 0.0), at(l - 1, 0.1, 0.0)],
                ..Prototype::default()
            });
        }
        g.instances = vec![at(2, 0.0, 0.0), at(2, 0.1, 0.0)];
        assert_eq!(depth(&g), 8000.0 + 14.0);

        let mut forest = Geometry {
            prototypes: vec![ball()],
            ..Geometry::default()
        };
        forest.instances = (0..40_000)
            .map(|i| at(0, f64::from(i % 200) * 3.0, f64::from(i / 200) * 3.0))
            .collect();
        forest.spheres = vec![
            Sphere {
                center: DVec3::splat(300.0),
                radius: 1e4,
                material: 0,
            };
            2
        ];
        let d = depth(&forest);
        assert!(d <= 2.0 + 2.0 * 4.0, "{d}");
    }

    /// Two floors of 182 × 182 flat tiles, one above the other: flat boxes ask for many cells
    /// across their plane's thickness, which the other axes must not pay for (they did, and all
    /// tiles met one cell, 66 248). And 2 000 balls in a park, surrounded by 800 buildings apart
    /// of eight overlapping parts each: a grid over the whole city lumps the park into a cell or
    /// two, which are bounded again on their own grid.
    #[test]
    fn flat_tiles_and_buildings_around_a_park_count_what_overlaps() {
        let tile = Prototype {
            meshes: vec![
                crate::Mesh::new(
                    vec![
                        glam::Vec3::ZERO,
                        glam::Vec3::new(1.0, 0.0, 0.0),
                        glam::Vec3::new(0.0, 1.0, 0.0),
                    ],
                    vec![[0, 1, 2]],
                    None,
                    0,
                )
                .unwrap(),
            ],
            ..Prototype::default()
        };
        let mut floors = Geometry {
            prototypes: vec![tile],
            ..Geometry::default()
        };
        floors.instances = (0..2 * 182 * 182)
            .map(|i| {
                let (x, y, z) = (i % 182, i / 182 % 182, i / (182 * 182));
                let t = DAffine3::from_translation(DVec3::new(
                    f64::from(x),
                    f64::from(y),
                    3.0 * f64::from(z),
                ));
                Instance::new(0, Transform::new(t).unwrap())
            })
            .collect();
        let d = depth(&floors);
        assert!(d <= 2.0 * 4.0, "{d}");

        let building = Prototype {
            spheres: (0..8)
                .map(|i| Sphere {
                    center: DVec3::new(f64::from(i) * 2.0, 0.0, 0.0),
                    radius: 10.0,
                    material: 0,
                })
                .collect(),
            ..Prototype::default()
        };
        let mut city = Geometry {
            prototypes: vec![ball_of(0.4), building],
            ..Geometry::default()
        };
        city.instances = (0..2000)
            .map(|i| at(0, f64::from(i % 50), f64::from(i / 50)))
            .chain((0..800).map(|i| {
                let angle = f64::from(i) * std::f64::consts::TAU / 800.0;
                let r = 150.0 * 800.0 / std::f64::consts::TAU;
                at(1, r * angle.cos(), r * angle.sin())
            }))
            .collect();
        let d = depth(&city);
        // A building's eight parts all meet (nine with its instance); the park, which a grid
        // sized for the city puts in two cells (3 440 in one), is bounded again on its own
        // grid, down to a few balls a cell; what is left is at most a cell below REFINE.
        assert!((9.0..=REFINE).contains(&d), "{d}");
    }
}
