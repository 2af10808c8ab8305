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

/// The most cells of a level's grid in all (16 MiB of sums).
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
/// a millionth of its padding, so flat boxes in one plane still meet.
fn inner((lo, hi): Bounds) -> Bounds {
    let margin = (hi - lo) * TOUCH;
    (lo + margin, hi - margin)
}

/// An upper bound on the largest total weight of the `count` (at most) boxes `boxes` gives
/// that hold one point; `boxes` is asked again for each pass over them.
fn deepest<I: Iterator<Item = (Bounds, f64)>>(boxes: impl Fn() -> I, count: usize) -> f64 {
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
    Grid::over(&boxes, count).deepest(boxes())
}

/// Whether two closed boxes share a point.
fn meet((alo, ahi): Bounds, (blo, bhi): Bounds) -> bool {
    alo.cmple(bhi).all() && blo.cmple(ahi).all()
}

/// A grid of cells over the union of a level's boxes, `k[axis]` along each axis.
struct Grid {
    lo: DVec3,
    /// Cells per unit length along each axis (0 along an axis the boxes do not extend along).
    scale: DVec3,
    k: [usize; 3],
}

impl Grid {
    /// Cells about as large as the boxes' typical size along each axis (their geometric mean,
    /// which a few huge boxes beside many small ones do not inflate), over the region of the
    /// boxes of about that size, so a box meets a few cells and a cell is met by about the boxes
    /// that overlap there; eight cells a box at most, and [`MAX_GRID`] in all (coarser where the
    /// boxes are small and far apart).
    ///
    /// A box reaching past the region (a sky dome over a forest) is clamped into its edge cells.
    /// The bound holds all the same: boxes that share a point overlap along each axis, so their
    /// clamped ranges of cells do too, and share a cell.
    fn over<I: Iterator<Item = (Bounds, f64)>>(boxes: impl Fn() -> I, count: usize) -> Grid {
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
        let (mut lo, mut hi) = union(true);
        if !lo.cmple(hi).all() {
            (lo, hi) = union(false);
        }
        let extent = hi - lo;
        let mut size = typical;
        let cells = |size: DVec3| {
            [0, 1, 2].map(|axis| match size[axis] > 0.0 && extent[axis] > 0.0 {
                // Rounded, not raised: cells of the boxes' own size stay aligned with a lattice
                // of them, whose extent the boxes' padding makes a hair longer than a whole
                // number of boxes.
                true => (extent[axis] / size[axis])
                    .round()
                    .clamp(1.0, MAX_GRID as f64) as usize,
                false => 1,
            })
        };
        // Eight cells a box at most, so a level costs in proportion to what it holds.
        let budget = (8 * count).min(MAX_GRID);
        let mut k = cells(size);
        while k.iter().map(|&k| k as f64).product::<f64>() > budget as f64 {
            size *= 2.0;
            k = cells(size);
        }
        let scale = DVec3::from_array([0, 1, 2].map(|axis| match k[axis] > 1 {
            true => k[axis] as f64 / extent[axis],
            false => 0.0,
        }));
        Grid { lo, scale, k }
    }

    /// The cell along `axis` that coordinate `x` lies in (clamped to the grid; a NaN to 0).
    fn cell(&self, x: f64, axis: usize) -> usize {
        let c = ((x - self.lo[axis]) * self.scale[axis]).floor();
        (c.max(0.0) as usize).min(self.k[axis] - 1)
    }

    /// The largest total weight of the boxes meeting one cell: each box adds its weight to the
    /// block of cells it meets, as eight signed corners of a difference array whose prefix sums
    /// along the three axes give every cell's total.
    fn deepest(&self, boxes: impl Iterator<Item = (Bounds, f64)>) -> f64 {
        let [sx, sy, sz] = self.k.map(|k| k + 1);
        let index = |x: usize, y: usize, z: usize| (z * sy + y) * sx + x;
        let mut sums = vec![0.0f64; sx * sy * sz];
        for ((lo, hi), w) in boxes {
            let first = [0, 1, 2].map(|axis| self.cell(lo[axis], axis));
            let last = [0, 1, 2].map(|axis| (self.cell(hi[axis], axis) + 1).max(first[axis] + 1));
            for corner in 0..8u32 {
                let pick = |axis: usize| match corner >> axis & 1 {
                    0 => first[axis],
                    _ => last[axis],
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
        let [kx, ky, kz] = self.k;
        (0..kz)
            .flat_map(|z| (0..ky).flat_map(move |y| (0..kx).map(move |x| (x, y, z))))
            .map(|(x, y, z)| sums[index(x, y, z)])
            .fold(0.0, f64::max)
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
}
