//! Instances: a shared prototype placed by an affine transform of its own, and the numbering of
//! every placement in the expanded instance tree.
//!
//! A prototype ([`crate::geometry::Prototype`]: spheres, quadrics, meshes and instances of earlier
//! prototypes) is stored, and its BVHs built, once however many instances place it. Rays are mapped
//! into the prototype's object space (the ray parameter t is unchanged by an affine map),
//! intersected there, and the hit's geometry is mapped back level by level.
//!
//! Nesting is bounded by [`MAX_NESTING`] and the expanded tree by [`MAX_PLACEMENTS`]: a small
//! file whose instances place each other can expand to far more placements than it has lines, and
//! is stored, built and traced at the cost of the file, not of its expansion.

use crate::geometry::Geometry;
use crate::material::MaterialId;
use crate::math::{Ray, Transform, gamma};
use crate::shape::SurfaceGeometry;
use glam::DVec3;

/// Most instances on one path from the world to a primitive (an instance inside a prototype placed
/// by an instance is two).
pub const MAX_NESTING: usize = 32;

/// Most placements the instance tree may expand to (2⁴⁸): placement numbers stay exact in a u64
/// and far below any sum that could overflow.
pub const MAX_PLACEMENTS: u64 = 1 << 48;

/// One placement of a prototype ([`crate::Geometry::prototypes`]) by its parent level (the world,
/// or a later prototype).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`crate::Geometry::prototypes`].
    pub prototype: u32,
    /// The prototype's object space to the parent's space.
    pub transform: Transform,
    /// A material replacing the materials of everything this instance places, if any (the
    /// outermost instance with one wins).
    pub material: Option<MaterialId>,
}

impl Instance {
    /// An instance of `prototype` placed by `transform`, keeping the prototype's materials.
    pub fn new(prototype: u32, transform: Transform) -> Instance {
        Instance {
            prototype,
            transform,
            material: None,
        }
    }

    /// The parent's ray in the prototype's object space, with the same parameterisation.
    #[inline]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        let m = &self.transform.from_world;
        Ray::new(m.transform_point3(ray.origin), m.transform_vector3(ray.dir))
    }

    /// A point of the parent's space in the prototype's object space.
    #[inline]
    pub fn point_to_object(&self, p: DVec3) -> DVec3 {
        self.transform.from_world.transform_point3(p)
    }

    /// Surface geometry computed in object space, mapped to the parent's space: the point by the
    /// transform, normals by its inverse transpose, and the error bound grown by the map's
    /// stretch plus the rounding of the map itself.
    pub fn surface_to_world(&self, g: SurfaceGeometry) -> SurfaceGeometry {
        let m = &self.transform.to_world;
        let point = m.transform_point3(g.point);
        let abs_rows = m.matrix3.transpose().abs();
        // ‖M‖∞ bounds how far the map moves a point `error` away from the surface's image.
        let stretch = [abs_rows.x_axis, abs_rows.y_axis, abs_rows.z_axis]
            .iter()
            .map(|r| r.element_sum())
            .fold(0.0, f64::max);
        // Each world coordinate is three products and three sums: γ(4) of their magnitudes.
        let magnitudes = m.matrix3.abs() * g.point.abs() + m.translation.abs();
        let error = stretch * g.error + gamma(4) * magnitudes.max_element() * 2.0;
        let normal = |n: DVec3| {
            (self.transform.normal_to_world * n)
                .try_normalize()
                .unwrap_or(n)
        };
        SurfaceGeometry {
            point,
            geometric_normal: normal(g.geometric_normal),
            shading_normal: normal(g.shading_normal),
            error,
        }
    }
}

/// Why a scene's instances cannot be numbered.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlacementError {
    /// An instance places a prototype that does not exist, or one that is not earlier than the
    /// prototype holding it (the order that rules out cycles).
    #[error(
        "{what} places prototype {prototype}, but only prototypes 0..{limit} can be placed there"
    )]
    PrototypeOutOfRange {
        /// Which instance.
        what: String,
        /// The prototype it places.
        prototype: u32,
        /// The first index it may not place.
        limit: usize,
    },
    /// Instances nest deeper than [`MAX_NESTING`].
    #[error("instances nest {depth} deep; at most {MAX_NESTING} are supported")]
    TooDeep {
        /// The nesting depth found.
        depth: usize,
    },
    /// The instance tree expands to more than [`MAX_PLACEMENTS`] placements.
    #[error("the instances expand to more than {MAX_PLACEMENTS} placements")]
    TooMany,
}

/// The numbering of placements: the instance tree expanded depth-first, the world first.
///
/// A level at placement `p` places its instance `k` at `p + offsets[k]`, and that instance's own
/// placements follow it; `sizes` counts a level's placements, itself included. Only these counts
/// are stored, never the expansion.
#[derive(Clone, Debug, Default)]
pub struct Placements {
    /// Per level (0: the world, 1 + i: prototype i), each instance's offset from the level's own
    /// placement.
    offsets: Vec<Vec<u64>>,
    /// Per level, the placements it expands to, itself included.
    sizes: Vec<u64>,
    /// Per level, the deepest nesting of instances below it.
    depths: Vec<usize>,
}

/// The instances from the world down to one placement, outermost first.
#[derive(Clone, Copy, Debug)]
pub struct InstancePath {
    len: usize,
    /// (level, instance index within that level) per step.
    steps: [(u32, u32); MAX_NESTING],
}

/// The world's path, as a static: a reference to it costs nothing (a constant's temporary was a
/// 264-byte copy per hit).
pub static WORLD_PATH: InstancePath = InstancePath::WORLD;

impl InstancePath {
    /// The world itself: no instances.
    pub const WORLD: InstancePath = InstancePath {
        len: 0,
        steps: [(0, 0); MAX_NESTING],
    };

    /// Number of instances on the path.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the path is the world itself.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The instances on the path, outermost first.
    pub fn instances<'a>(&self, g: &'a Geometry) -> impl DoubleEndedIterator<Item = &'a Instance> {
        self.steps[..self.len]
            .iter()
            .map(|&(level, k)| &g.level(level as usize).instances[k as usize])
    }

    /// The level the path ends in (0: the world, 1 + i: prototype i).
    pub fn level(&self, g: &Geometry) -> usize {
        self.instances(g)
            .next_back()
            .map_or(0, |inst| inst.prototype as usize + 1)
    }
}

impl Placements {
    /// Numbers the placements of `g`, checking that every instance places an earlier prototype
    /// (so the graph has no cycle), the nesting depth and the expanded count.
    pub fn new(g: &Geometry) -> Result<Placements, PlacementError> {
        let levels = g.prototypes.len() + 1;
        let mut p = Placements {
            offsets: vec![Vec::new(); levels],
            sizes: vec![0; levels],
            depths: vec![0; levels],
        };
        // Prototypes place only earlier ones, so each level's children are counted before it; the
        // world (level 0) may place any and is counted last.
        for level in (1..levels).chain([0]) {
            let limit = if level == 0 { levels - 1 } else { level - 1 };
            let instances = g.level(level).instances;
            let mut offsets = Vec::with_capacity(instances.len());
            let (mut size, mut depth) = (1u64, 0usize);
            for (k, inst) in instances.iter().enumerate() {
                let child = inst.prototype as usize;
                if child >= limit {
                    return Err(PlacementError::PrototypeOutOfRange {
                        what: match level {
                            0 => format!("instance {k}"),
                            _ => format!("instance {k} of prototype {}", level - 1),
                        },
                        prototype: inst.prototype,
                        limit,
                    });
                }
                offsets.push(size);
                size = size
                    .checked_add(p.sizes[child + 1])
                    .filter(|&s| s <= MAX_PLACEMENTS)
                    .ok_or(PlacementError::TooMany)?;
                depth = depth.max(p.depths[child + 1] + 1);
            }
            if depth > MAX_NESTING {
                return Err(PlacementError::TooDeep { depth });
            }
            p.offsets[level] = offsets;
            p.sizes[level] = size;
            p.depths[level] = depth;
        }
        Ok(p)
    }

    /// Number of placements, the world included (1, the world alone, for the empty numbering).
    pub fn count(&self) -> u64 {
        self.sizes.first().copied().unwrap_or(1)
    }

    /// How far instance `k` of `level` is numbered from the level's own placement.
    #[inline]
    pub fn offset(&self, level: usize, k: usize) -> u64 {
        self.offsets[level][k]
    }

    /// Instance `k` of `level` placed below placement `base` of that level.
    #[inline]
    pub fn child(&self, level: usize, k: usize, base: u64) -> u64 {
        base + self.offsets[level][k]
    }

    /// The instances leading to `placement`, outermost first (the world for 0 or an unknown one).
    pub fn path(&self, g: &Geometry, placement: u64) -> InstancePath {
        let mut path = InstancePath::WORLD;
        let (mut level, mut rest) = (0usize, placement);
        if placement >= self.count() {
            return path;
        }
        while rest != 0 && path.len < MAX_NESTING {
            let offsets = &self.offsets[level];
            // The last instance whose subtree starts at or before `rest` holds it.
            let k = offsets.partition_point(|&o| o <= rest) - 1;
            path.steps[path.len] = (level as u32, k as u32);
            path.len += 1;
            rest -= offsets[k];
            level = g.level(level).instances[k].prototype as usize + 1;
        }
        path
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Prototype;
    use glam::DAffine3;

    fn at(x: f64) -> Transform {
        Transform::new(DAffine3::from_translation(DVec3::new(x, 0.0, 0.0))).unwrap()
    }

    /// A binary DAG: prototype i + 1 places prototype i twice, so the world's one instance of the
    /// last of `depth` prototypes expands to 2^depth - 1 placements below it.
    fn dag(depth: u32) -> Geometry {
        let mut prototypes = vec![Prototype::default()];
        for i in 1..depth {
            prototypes.push(Prototype {
                instances: vec![Instance::new(i - 1, at(0.0)), Instance::new(i - 1, at(1.0))],
                ..Prototype::default()
            });
        }
        Geometry {
            prototypes,
            instances: vec![Instance::new(depth - 1, Transform::IDENTITY)],
            ..Geometry::default()
        }
    }

    #[test]
    fn placements_number_the_expanded_tree_without_expanding_it() {
        let g = dag(30);
        let p = Placements::new(&g).unwrap();
        // The world, then 2^30 - 1 placements of the tree's nodes.
        assert_eq!(p.count(), 1 << 30);
        // Every path decodes to the placement it names: walk to a leaf by always taking the
        // second instance, counting offsets as traversal does.
        let (mut level, mut placement) = (0usize, 0u64);
        let mut expected = Vec::new();
        while !g.level(level).instances.is_empty() {
            let k = g.level(level).instances.len() - 1;
            expected.push((level as u32, k as u32));
            placement = p.child(level, k, placement);
            level = g.level(level).instances[k].prototype as usize + 1;
        }
        let path = p.path(&g, placement);
        assert_eq!(path.len(), 30);
        assert_eq!(&path.steps[..path.len()], &expected[..]);
        assert_eq!(path.level(&g), 1);
        assert!(p.path(&g, 0).is_empty());
    }

    #[test]
    fn distinct_paths_have_distinct_numbers() {
        let g = dag(6);
        let p = Placements::new(&g).unwrap();
        let mut seen = std::collections::HashSet::new();
        // Enumerate every placement by a depth-first walk; numbers must be 0..count, each once,
        // and decode back to the same path.
        let mut todo = vec![(0usize, 0u64, Vec::new())];
        while let Some((level, placement, steps)) = todo.pop() {
            assert!(seen.insert(placement));
            let path = p.path(&g, placement);
            assert_eq!(&path.steps[..path.len()], &steps[..]);
            for (k, inst) in g.level(level).instances.iter().enumerate() {
                let mut s = steps.clone();
                s.push((level as u32, k as u32));
                todo.push((inst.prototype as usize + 1, p.child(level, k, placement), s));
            }
        }
        assert_eq!(seen.len() as u64, p.count());
        assert!(seen.iter().all(|&n| n < p.count()));
    }

    #[test]
    fn cycles_depth_and_size_are_errors() {
        // A prototype placing itself (or a later one) could be a cycle: refused by the order.
        let mut g = dag(3);
        g.prototypes[1].instances.push(Instance::new(2, at(0.0)));
        assert!(matches!(
            Placements::new(&g),
            Err(PlacementError::PrototypeOutOfRange {
                prototype: 2,
                limit: 1,
                ..
            })
        ));
        assert!(matches!(
            Placements::new(&dag(MAX_NESTING as u32 + 2)),
            Err(PlacementError::TooDeep { .. })
        ));
        // Depth 30 of fan-out 8 expands to 8^30 placements: past the maximum.
        let mut g = dag(30);
        for p in &mut g.prototypes[1..] {
            let first = p.instances[0];
            p.instances = vec![first; 8];
        }
        assert_eq!(Placements::new(&g).unwrap_err(), PlacementError::TooMany);
    }
}
