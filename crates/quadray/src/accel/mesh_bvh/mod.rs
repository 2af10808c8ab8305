//! The bottom level for triangle meshes: an 8-wide BVH of quadray's own layout ([`super::wide`]),
//! collapsed from obvhs' BVH2 build (PLOC, reinsertion) by a plan of least cost ([`MESH_COSTS`]),
//! with leaves of up to eight triangles in blocks of four ([`Tri4`]), each block tested at once
//! and shared by small leaves ([`leaves`]); the children a ray enters are visited nearest first.
//!
//! Eight children a node rather than four (Embree's BVH8 on AVX2): the AVX2 path tests a node in
//! one pass of 8-lane registers, and a ray passes about two thirds as many levels. Measured
//! against the 4-wide layout (`bench rays`, 3 interleaved rounds, 1 thread, AVX2): +8% to +21%
//! on every mesh and ray set. The baseline path tests the same nodes in two 4-lane halves, so
//! both paths visit the same nodes in the same order and give the same hits.
//!
//! The traversals (closest hit and any hit, on each compiled path) are in [`traverse`], the
//! compact BVH's entry points in [`compact`].
//!
//! Leaves hold copies of their triangles' vertices (no index lookups while tracing), or in a
//! compact BVH only their triangles' numbers ([`MeshBvh::numbered`]). A block lane names its triangle by
//! number: over a single mesh the mesh's triangle index, over several meshes an index into a
//! table of (mesh, triangle).

mod compact;
mod leaves;
mod traverse;

use super::tri4::Tri4;
use super::wide::{BoxRay, LeafLayout, Node8, SahCosts, collapse, covering_boxes};
use crate::mesh::Mesh;
use crate::triangle::{ShearedRay, TriangleHit};
use glam::{DVec3, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use rayon::prelude::*;

/// A triangle of a [`MeshBvh`]: index of the mesh among those it was built over, and the triangle.
pub(crate) type TriId = (u32, u32);

/// The most triangles a leaf holds: two blocks. Against leaves of one block (4 triangles), the
/// leaves are fuller (BVH bytes per triangle: dragon 73 -> 60, kitchen 78 -> 67) and rays as
/// fast or faster (3 interleaved rounds, 1 thread: kitchen coherent closest hit -3%, the rest
/// -2% to +19%, most on the dragon's incoherent rays); three blocks were 1-11% slower.
const MESH_LEAF_TRIANGLES: u32 = 8;

/// The costs the collapse weighs ([`SahCosts`]): a block's test about one and a half node tests
/// (about 100 instructions against 65 with the children's ordering, on incoherent rays), and a
/// byte at 4.5e-6 (a node's 224 bytes at 0.001 of the root's area). Without the memory term the
/// blocks held 2.6 triangles rather than 3.2 and the BVH took a fifth more bytes, for 0.5% fewer
/// instructions a ray. Against the greedy collapse, instructions a ray (callgrind, `bench rays`),
/// closest and any hit: bunny incoherent −8.7% and −5.4%, kitchen incoherent −6.0% and −4.5%,
/// dragon incoherent −2.6% and −0.9%, coherent −1.6% to −12.7%; a block test costing 1 to 3 node
/// tests gave the same within 0.5%.
const MESH_COSTS: SahCosts = SahCosts {
    node: 1.0,
    block: 1.5,
    per_byte: 4.5e-6,
};

/// The nearest triangle a ray meets in a [`MeshBvh`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshHit {
    /// Which triangle.
    pub(crate) id: TriId,
    /// Where the f32 test met it.
    pub(crate) hit: TriangleHit,
    /// The leaf block and lane holding its vertices ([`MeshBvh::vertices`]).
    block: u32,
    lane: u32,
}

/// A wide BVH over the triangles of one or more meshes.
#[derive(Clone, Debug)]
pub(crate) struct MeshBvh {
    nodes: Vec<Node8>,
    /// The leaf blocks, four triangles each, with copies of their vertices (160 bytes a block):
    /// no lookups while tracing. Empty in a compact BVH.
    blocks: Vec<Tri4>,
    /// A compact BVH's leaf blocks ([`crate::BuildOptions::compact_meshes`]): the triangles'
    /// numbers alone (16 bytes a block), the vertices read from the meshes at each test (the same
    /// f32 values, so the same hits). Empty otherwise.
    numbers: Vec<[u32; 4]>,
    /// (mesh, triangle) of each triangle number (the meshes' triangles numbered in turn); empty
    /// over a single mesh, whose triangle numbers are its triangle indices.
    ids: Vec<TriId>,
    /// Whether any of the meshes has an alpha cut-out.
    masked: bool,
    /// How leaf references name their lanes ([`leaves::layout_for`]).
    layout: LeafLayout,
}

/// An f32 ray in a mesh's space, prepared for the node and triangle tests.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshRay {
    boxes: BoxRay,
    sheared: ShearedRay,
    /// Whether the ray is finite in f32: one that is not meets nothing, and is never traversed
    /// (its slab tests could enter unused child slots).
    finite: bool,
}

impl MeshRay {
    /// Prepares `origin + t·dir` for traversal (a ray that is not finite in f32 meets nothing).
    #[inline]
    pub(crate) fn new(origin: Vec3, dir: Vec3) -> MeshRay {
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        MeshRay {
            boxes: BoxRay::new(o, d),
            sheared: ShearedRay::new(origin, dir),
            finite: crate::math::all_finite(o, d),
        }
    }

    /// The ray's [`coverage_key`](crate::mesh::coverage_key), from its origin and reciprocal
    /// direction (which identify the ray as well as its direction does, and are at hand).
    #[inline]
    fn coverage_key(&self) -> u32 {
        crate::mesh::coverage_key(self.boxes.origin.into(), self.boxes.inv_dir.into())
    }
}

/// (mesh, triangle) of triangle number `number`, the numbers running over the meshes in turn:
/// `ids` names each where there are several meshes, and is empty for one.
#[inline(always)]
fn tri_id(ids: &[TriId], number: u32) -> TriId {
    match ids.get(number as usize) {
        Some(&id) => id,
        None => (0, number),
    }
}

impl MeshBvh {
    /// Builds the BVH over `meshes`, its leaves holding only triangle numbers when `compact`.
    pub(crate) fn build(meshes: &[Mesh], compact: bool) -> MeshBvh {
        let triangles = meshes.iter().map(Mesh::triangle_count).sum();
        let bvh = MeshBvh::build_in(meshes, leaves::layout_for(triangles));
        if compact { bvh.numbered() } else { bvh }
    }

    /// [`MeshBvh::build`] with leaves of `layout`, holding copies of the vertices.
    fn build_in(meshes: &[Mesh], layout: LeafLayout) -> MeshBvh {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in meshes.iter().flat_map(|m| m.positions()) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        // Pad every box by a few ulps of its coordinates and a tiny share of the meshes' size, so
        // a triangle lying in an axis plane gets a slab of non-zero width.
        let pad = Vec3A::splat((hi - lo).max_element().max(0.0) * 1e-6);
        // Triangle numbers run over the meshes in turn; over several meshes `ids` names each.
        let ids: Vec<TriId> = if meshes.len() > 1 {
            (meshes.iter().enumerate())
                .flat_map(|(m, mesh)| (0..mesh.triangle_count() as u32).map(move |t| (m as u32, t)))
                .collect()
        } else {
            Vec::new()
        };
        // Read from the meshes where needed rather than copied out (for the dragon a copy was
        // 31 MB, whose pages alone took milliseconds to fault in).
        let triangle = |p: u32| {
            let (m, tri) = tri_id(&ids, p);
            meshes[m as usize].triangle_positions(tri).map(|v| *v)
        };
        let total: u32 = meshes.iter().map(|m| m.triangle_count() as u32).sum();
        let aabbs: Vec<Aabb> = (0..total)
            .into_par_iter()
            .map(|p| {
                let [a, b, c] = triangle(p).map(Vec3A::from);
                let (l, h) = (a.min(b).min(c), a.max(b).max(c));
                Aabb::new(
                    l - l.abs() * (4.0 * f32::EPSILON) - pad,
                    h + h.abs() * (4.0 * f32::EPSILON) + pad,
                )
            })
            .collect();
        let masked = meshes.iter().any(|m| m.alpha_mask().is_some());
        let mut bvh = MeshBvh {
            nodes: Vec::new(),
            blocks: Vec::new(),
            numbers: Vec::new(),
            ids: Vec::new(),
            masked,
            layout,
        };
        if aabbs.is_empty() {
            return bvh;
        }
        // Single-triangle leaves: the collapse makes its own leaves of 4-triangle blocks (a full
        // block costs one SIMD test, so obvhs' SAH leaf collapse, which counts every triangle,
        // would leave the blocks 60% full). Measured on the kitchen: obvhs' slow build (wider PLOC search, more
        // reinsertion) and spatial pre-splits change throughput by under 2% at 1.2-2x the time.
        let bvh2 = super::build::build_single_leaves(&aabbs);
        let layout = bvh.layout;
        let (nodes, blocks) = collapse(
            &bvh2,
            layout,
            MESH_LEAF_TRIANGLES,
            Some(MESH_COSTS),
            |_| 1,
            |prims, blocks: &mut Vec<Tri4>| leaves::pack_leaf(layout, blocks, prims, triangle),
        );
        let nodes = nodes.into_boxed_slice().into_vec();
        let blocks = blocks.into_boxed_slice().into_vec();
        bvh.ids = ids;
        bvh.nodes = nodes;
        bvh.blocks = blocks;
        bvh
    }

    /// At most `max` boxes whose union holds every triangle, hugging the mesh far closer than one
    /// box once rotated (the root's children, opened one level where `max` allows).
    pub(crate) fn covering_boxes(&self, max: usize) -> Vec<(glam::DVec3, glam::DVec3)> {
        covering_boxes(&self.nodes, max)
    }

    /// Bytes of the wide nodes, the triangle blocks and the id table.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node8>()
            + self.blocks.capacity() * size_of::<Tri4>()
            + self.numbers.capacity() * size_of::<[u32; 4]>()
            + self.ids.capacity() * size_of::<TriId>()
    }

    /// (mesh, triangle) of triangle number `number`.
    #[inline(always)]
    fn id(&self, number: u32) -> TriId {
        tri_id(&self.ids, number)
    }

    /// The vertices of `hit`'s triangle, from the leaf block's copies: the mesh's own values, so
    /// the f64 refinement of a hit needs no lookup in the mesh (on the dragon's rays that lookup
    /// was a quarter of a closest-hit query). A compact BVH has no copies: see
    /// [`MeshBvh::mesh_vertices`].
    #[inline(always)]
    pub(crate) fn vertices(&self, hit: &MeshHit) -> [DVec3; 3] {
        self.blocks[hit.block as usize].vertices(hit.lane as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::MaterialId;

    /// A grid of n×n unit quads in the plane z = 0 (2n² triangles).
    pub(super) fn grid(n: u32, material: MaterialId) -> Mesh {
        let mut p = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                p.push(Vec3::new(x as f32, y as f32, 0.0));
            }
        }
        let mut idx = Vec::new();
        let v = |x: u32, y: u32| y * (n + 1) + x;
        for y in 0..n {
            for x in 0..n {
                idx.push([v(x, y), v(x + 1, y), v(x + 1, y + 1)]);
                idx.push([v(x, y), v(x + 1, y + 1), v(x, y + 1)]);
            }
        }
        Mesh::new(p, idx, None, material).unwrap()
    }

    /// The covering boxes of a mesh's BVH are several (an instance of it is boxed tightly), at
    /// most the number asked for, and hold every vertex.
    #[test]
    fn covering_boxes_are_few_and_hold_the_mesh() {
        let meshes = [grid(64, 0)];
        let bvh = MeshBvh::build(&meshes, false);
        for max in [8, 16, 64] {
            let boxes = bvh.covering_boxes(max);
            assert!(
                boxes.len() > 1 && boxes.len() <= max,
                "{} boxes",
                boxes.len()
            );
            for p in meshes[0].positions() {
                let p = p.as_dvec3();
                assert!(
                    boxes
                        .iter()
                        .any(|(lo, hi)| lo.cmple(p).all() && p.cmple(*hi).all()),
                    "{p} outside"
                );
            }
        }
        // 16 boxes allow opening the 8-wide root's children: more boxes than the root alone.
        assert!(bvh.covering_boxes(16).len() > bvh.covering_boxes(8).len());
    }
}
