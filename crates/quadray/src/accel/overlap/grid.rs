//! The grid a level's boxes are bounded on: cells about the boxes' typical size over the region
//! they take, and each cell's total weight of the boxes meeting it.

use super::{Bounds, MAX_GRID, meet};
use glam::DVec3;

/// A grid of cells over a region of a level's boxes, `k[axis]` along each axis.
pub(super) struct Grid {
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
    pub(super) fn over<I: Iterator<Item = (Bounds, f64)>>(
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
    pub(super) fn meets(&self, (lo, hi): Bounds) -> bool {
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
    pub(super) fn totals(&self, boxes: impl Iterator<Item = (Bounds, f64)>) -> Vec<f64> {
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
    pub(super) fn cells_of(&self, (lo, hi): Bounds) -> ([usize; 3], [usize; 3]) {
        let first = [0, 1, 2].map(|axis| self.cell(lo[axis], axis));
        let last = [0, 1, 2].map(|axis| self.cell(hi[axis], axis).max(first[axis]));
        (first, last)
    }

    /// Where cell `[x, y, z]` is in [`Grid::totals`].
    pub(super) fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        let [sx, sy, _] = self.k.map(|k| k + 1);
        (z * sy + y) * sx + x
    }

    /// Every cell of the grid, as its `[x, y, z]`.
    pub(super) fn cells(&self) -> impl Iterator<Item = [usize; 3]> + '_ {
        let [kx, ky, kz] = self.k;
        (0..kz).flat_map(move |z| (0..ky).flat_map(move |y| (0..kx).map(move |x| [x, y, z])))
    }
}
