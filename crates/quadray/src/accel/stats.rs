//! What the acceleration structure stores and what it stands for: counts and memory per level,
//! for `--stats`, `quadray check` and the memory reports.

use super::analytic::AnalyticBvh;
use super::mesh_bvh::MeshBvh;
use super::{Accel, LevelAccel, Placed, TopItem};
use crate::geometry::Geometry;
use obvhs::aabb::Aabb;

/// What the acceleration structure stores and what it stands for ([`Accel::stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AccelStats {
    /// Prototypes (shapes stored once, placed by instances).
    pub prototypes: usize,
    /// Instances written in the scene (each one placement of a prototype by its parent).
    pub instances: usize,
    /// Placements of prototypes in the expanded instance tree (the world not counted).
    pub placements: u64,
    /// Spheres, quadrics and triangles stored, each level's once.
    pub primitives_stored: usize,
    /// Triangles stored.
    pub triangles_stored: usize,
    /// Triangles as instanced: each placement's triangles counted again (saturating).
    pub triangles_instanced: u64,
    /// Bytes of the bottom-level BVHs (over shapes).
    pub bottom_bytes: usize,
    /// Bytes of the tops (over each level's shape BVHs and instances).
    pub top_bytes: usize,
}

impl LevelAccel {
    /// Bytes of the bottom-level BVHs (over shapes).
    fn bottom_bytes(&self) -> usize {
        self.analytic.as_ref().map_or(0, AnalyticBvh::memory_bytes)
            + self.meshes.as_ref().map_or(0, MeshBvh::memory_bytes)
            + self
                .compact_meshes
                .as_ref()
                .map_or(0, MeshBvh::memory_bytes)
    }

    /// Bytes of the top (over the level's items).
    fn top_bytes(&self) -> usize {
        let bvh = self.top.as_ref().map_or(0, |b| {
            b.nodes.capacity() * std::mem::size_of::<obvhs::bvh2::node::Bvh2Node>()
                + b.primitive_indices.capacity() * std::mem::size_of::<u32>()
        });
        bvh + self.items.capacity() * std::mem::size_of::<TopItem>()
            + self.item_boxes.capacity() * std::mem::size_of::<Aabb>()
            + self.placed.capacity() * std::mem::size_of::<Placed>()
    }
}

impl Accel {
    /// Bytes the acceleration structure keeps allocated: every level's BVHs and index lists (memory
    /// reports; the build's transient buffers are not counted).
    pub fn memory_bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| l.bottom_bytes() + l.top_bytes())
            .sum()
    }

    /// Counts and memory of what is stored and what it expands to.
    pub fn stats(&self, g: &Geometry) -> AccelStats {
        // Triangles each level stands for once expanded: its own plus its instances' (children
        // first, saturating: a deep DAG can stand for more than a u64 counts).
        let n = g.level_count();
        let mut expanded = vec![0u64; n];
        for level in (1..n).chain([0]) {
            let l = g.level(level);
            let own: u64 = l.meshes.iter().map(|m| m.triangle_count() as u64).sum();
            expanded[level] = l.instances.iter().fold(own, |sum, inst| {
                sum.saturating_add(expanded[inst.prototype as usize + 1])
            });
        }
        AccelStats {
            prototypes: g.prototypes.len(),
            instances: (0..n).map(|l| g.level(l).instances.len()).sum(),
            placements: self.placements.count().saturating_sub(1),
            primitives_stored: self.bounded_count(),
            triangles_stored: self.triangles,
            triangles_instanced: expanded[0],
            bottom_bytes: self.levels.iter().map(LevelAccel::bottom_bytes).sum(),
            top_bytes: self.levels.iter().map(LevelAccel::top_bytes).sum(),
        }
    }
}
