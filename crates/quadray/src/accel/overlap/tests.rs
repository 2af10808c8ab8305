//! The overlap bound on scenes whose answers are known: nested pairs, lattices apart and
//! touching, piles, domes, floors and a city.

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
    let mut instances: Vec<Instance> = (0..40).map(|i| at(0, f64::from(i) * 0.01, 0.0)).collect();
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
