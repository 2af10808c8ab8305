//! Compact mesh BVHs ([`crate::BuildOptions::compact_meshes`]): leaf blocks that hold their four
//! triangles' numbers (16 bytes) instead of copies of their vertices (160), each block's vertices
//! read from the meshes when it is tested. The tree and its leaves are the copied BVH's, and the
//! vertices read are the same f32 values, so every hit is the same; the traversals are the same
//! generic code ([`MeshBvh::traverse_closest`] with `COMPACT`), entered here, out of line, so the
//! copied BVH's traversals keep their code.

use super::{MeshBvh, MeshHit, MeshRay, TriId};
use crate::accel::tri4::Tri4;
use crate::mesh::Mesh;
use glam::DVec3;

impl MeshBvh {
    /// The same BVH with its blocks' triangle numbers in place of their vertices. Packed with
    /// the copies first, so both kinds of leaves are the same leaves (the copies' bytes are
    /// needed only while building).
    pub(super) fn numbered(self) -> MeshBvh {
        let numbers = self.blocks.iter().map(|block| block.tri).collect();
        MeshBvh {
            blocks: Vec::new(),
            numbers,
            ..self
        }
    }

    /// Whether the leaves hold triangle numbers instead of vertices ([`MeshBvh::numbered`]).
    #[inline(always)]
    pub(crate) fn compact(&self) -> bool {
        !self.numbers.is_empty()
    }

    /// A compact BVH's block of triangles `numbers`, lanes `lanes` (bit l for lane l) read from
    /// `meshes` and the others unused.
    #[inline(always)]
    pub(super) fn read(&self, meshes: &[Mesh], numbers: [u32; 4], lanes: u32) -> Tri4 {
        let mut block = Tri4::EMPTY;
        for (lane, number) in numbers.into_iter().enumerate() {
            if lanes & (1 << lane) != 0 {
                let (m, tri) = self.id(number);
                let vertices = meshes[m as usize].triangle_positions(tri).map(|v| *v);
                block.set(lane, vertices, number);
            }
        }
        block
    }

    /// [`MeshBvh::vertices`] for a compact BVH, read from `meshes`.
    #[inline(always)]
    pub(crate) fn mesh_vertices(&self, meshes: &[Mesh], hit: &MeshHit) -> [DVec3; 3] {
        let (m, tri) = hit.id;
        meshes[m as usize].vertices(tri)
    }

    /// [`MeshBvh::closest_on`] for a compact BVH ([`MeshBvh::numbered`]), out of line on both
    /// paths: the copied leaves' traversals, inlined into their callers, keep their code.
    #[inline(never)]
    pub(crate) fn closest_compact<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set on the AVX2 path only, chosen where the CPU has AVX2 and FMA.
            return unsafe { self.closest_compact_avx2(meshes, ray, t_max, skip, stack) };
        }
        self.traverse_closest::<false, true>(meshes, ray, t_max, skip, stack)
    }

    /// [`MeshBvh::closest_compact`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn closest_compact_avx2(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
        stack: &mut Vec<(u32, f32)>,
    ) -> Option<MeshHit> {
        self.traverse_closest::<true, true>(meshes, ray, t_max, skip, stack)
    }

    /// [`MeshBvh::occluded`] for a compact BVH, out of line on both paths (as
    /// [`MeshBvh::closest_compact`]).
    #[inline(never)]
    pub(crate) fn occluded_compact<const AVX2: bool>(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set on the AVX2 path only, chosen where the CPU has AVX2 and FMA.
            return unsafe { self.occluded_compact_avx2(meshes, ray, t_max, skip) };
        }
        self.traverse_occluded::<false, true>(meshes, ray, t_max, skip)
    }

    /// [`MeshBvh::occluded_compact`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn occluded_compact_avx2(
        &self,
        meshes: &[Mesh],
        ray: &MeshRay,
        t_max: f32,
        skip: Option<TriId>,
    ) -> bool {
        self.traverse_occluded::<true, true>(meshes, ray, t_max, skip)
    }
}
