//! Packets: up to eight coherent rays (camera rays of a 4×2 pixel block) traced through a mesh
//! BVH together. Each node is fetched and its four boxes tested once for the whole packet (two
//! `Vec4` groups of four rays), and a subtree is entered by the rays that hit its box; leaves run
//! the single-ray [`Tri4`](super::tri4::Tri4) test for each of those rays.
//!
//! The box test is the single-ray test's arithmetic with min/max in place of the sign choice (the
//! rays of a packet may point into different octants), so a packet finds for each ray the same
//! nearest t as [`MeshBvh::closest`]; only which of two triangles with the same t (a shared edge)
//! is reported may differ.

use super::mesh_bvh::{EMPTY, LEAF, LEAF_COUNT_BITS, MeshBvh, MeshRay, TriId};
use crate::mesh::Mesh;
use crate::triangle::TriangleHit;
use glam::Vec4;
use std::cell::RefCell;

/// Most rays in a packet.
pub(crate) const PACKET: usize = 8;

/// A packet's rays in structure-of-arrays form: two groups of four.
pub(crate) struct MeshPacket<'a> {
    rays: &'a [MeshRay],
    origin: [[Vec4; 2]; 3],
    inv_dir: [[Vec4; 2]; 3],
}

impl<'a> MeshPacket<'a> {
    /// Packs up to [`PACKET`] rays; missing lanes repeat the first ray and stay inactive.
    pub(crate) fn new(rays: &'a [MeshRay]) -> MeshPacket<'a> {
        assert!(!rays.is_empty() && rays.len() <= PACKET);
        let ray = |i: usize| rays.get(i).unwrap_or(&rays[0]);
        let gather = |f: &dyn Fn(&MeshRay) -> glam::Vec3A| {
            std::array::from_fn(|axis| {
                std::array::from_fn(|group| {
                    Vec4::from_array(std::array::from_fn(|i| f(ray(group * 4 + i))[axis]))
                })
            })
        };
        MeshPacket {
            rays,
            origin: gather(&|r| r.origin),
            inv_dir: gather(&|r| r.inv_dir),
        }
    }

    /// Bit i set for each ray i of the packet.
    fn all(&self) -> u32 {
        (1 << self.rays.len()) - 1
    }
}

thread_local! {
    /// Packet traversal stack of (child reference, rays entering it), reused across packets.
    static STACK: RefCell<Vec<(u32, u32)>> = const { RefCell::new(Vec::new()) };
}

impl MeshBvh {
    /// For each ray i of the packet, lowers `limits[i]` to its nearest hit in (0, `limits[i]`) and
    /// records it in `best[i]` (the ray's hit is left alone when there is none nearer).
    #[inline(always)]
    pub(crate) fn closest_packet(
        &self,
        meshes: &[Mesh],
        packet: &MeshPacket,
        limits: &mut [f32; PACKET],
        best: &mut [Option<(TriId, TriangleHit)>; PACKET],
    ) {
        if self.nodes.is_empty() {
            return;
        }
        STACK.with_borrow_mut(|stack| {
            stack.clear();
            let (mut current, mut active) = (0u32, packet.all());
            loop {
                if current & LEAF == 0 {
                    let node = &self.nodes[current as usize];
                    let limit = [
                        Vec4::from_slice(&limits[..4]),
                        Vec4::from_slice(&limits[4..]),
                    ];
                    let mut order = [(0u32, 0u32, 0f32); 4];
                    let mut n = 0;
                    for child in 0..4 {
                        if node.children[child] == EMPTY {
                            continue;
                        }
                        let mut mask = 0u32;
                        let mut nearest = f32::INFINITY;
                        #[allow(clippy::needless_range_loop)]
                        for group in 0..2 {
                            let rays = (active >> (4 * group)) & 0xf;
                            if rays == 0 {
                                continue;
                            }
                            let mut enter = Vec4::ZERO;
                            let mut exit = limit[group];
                            for axis in 0..3 {
                                let o = packet.origin[axis][group];
                                let inv = packet.inv_dir[axis][group];
                                let t0 = (Vec4::splat(node.bounds[2 * axis][child]) - o) * inv;
                                let t1 = (Vec4::splat(node.bounds[2 * axis + 1][child]) - o) * inv;
                                enter = enter.max(t0.min(t1));
                                exit = exit.min(t0.max(t1));
                            }
                            let hit = enter.cmple(exit).bitmask() & rays;
                            if hit != 0 {
                                mask |= hit << (4 * group);
                                let e = enter.to_array();
                                for (i, t) in e.iter().enumerate() {
                                    if hit & (1 << i) != 0 {
                                        nearest = nearest.min(*t);
                                    }
                                }
                            }
                        }
                        if mask != 0 {
                            // Insert by entry distance, farthest first.
                            let mut j = n;
                            while j > 0 && order[j - 1].2 < nearest {
                                order[j] = order[j - 1];
                                j -= 1;
                            }
                            order[j] = (node.children[child], mask, nearest);
                            n += 1;
                        }
                    }
                    if n > 0 {
                        stack.extend(order[..n - 1].iter().map(|&(c, m, _)| (c, m)));
                        (current, active) = (order[n - 1].0, order[n - 1].1);
                        continue;
                    }
                } else {
                    let first = (current & !LEAF) >> LEAF_COUNT_BITS;
                    let count = current & ((1 << LEAF_COUNT_BITS) - 1);
                    let mut rays = active;
                    while rays != 0 {
                        let r = rays.trailing_zeros() as usize;
                        rays &= rays - 1;
                        for block in &self.blocks[first as usize..(first + count) as usize] {
                            let (hits, mask) =
                                self.block_hits(meshes, block, &packet.rays[r], limits[r], None);
                            if let Some(h) = hits.nearest(mask) {
                                limits[r] = h.t;
                                let hit = TriangleHit {
                                    t: h.t,
                                    barycentrics: h.barycentrics,
                                };
                                best[r] = Some((self.id(block.tri[h.lane]), hit));
                            }
                        }
                    }
                }
                match stack.pop() {
                    None => return,
                    Some((child, rays)) => (current, active) = (child, rays),
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A bumpy height field of 2·n² triangles over [0, n]².
    fn terrain(n: u32) -> Mesh {
        let mut p = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                let h = 0.3 * ((x as f32 * 0.7).sin() + (y as f32 * 0.45).cos());
                p.push(Vec3::new(x as f32, y as f32, h));
            }
        }
        let v = |x: u32, y: u32| y * (n + 1) + x;
        let mut idx = Vec::new();
        for y in 0..n {
            for x in 0..n {
                idx.push([v(x, y), v(x + 1, y), v(x + 1, y + 1)]);
                idx.push([v(x, y), v(x + 1, y + 1), v(x, y + 1)]);
            }
        }
        Mesh::new(p, idx, None, 0).unwrap()
    }

    /// Packets of one to eight rays, coherent (a pinhole's pixel block) and scattered (different
    /// octants, some missing), find for every ray the same nearest t as the single-ray traversal.
    #[test]
    fn packets_agree_with_single_rays() {
        let meshes = [terrain(24)];
        let bvh = MeshBvh::build(&meshes);
        let eye = Vec3::new(-3.0, -4.0, 6.0);
        let mut compared = 0;
        for block in 0..300 {
            let n = 1 + block % PACKET;
            let rays: Vec<MeshRay> = (0..n)
                .map(|i| {
                    let k = (block * PACKET + i) as f32;
                    let dir = if block % 3 == 0 {
                        // Scattered: any octant, from above or below.
                        Vec3::new((k * 1.3).sin(), (k * 0.7).cos(), (k * 2.1).sin() - 0.4)
                    } else {
                        let (px, py) = ((block % 30) as f32 * 0.8, (block / 30) as f32 * 2.0);
                        Vec3::new(
                            12.0 + px + (i % 4) as f32 * 0.05,
                            10.0 + py + (i / 4) as f32 * 0.05,
                            0.0,
                        ) - eye
                    };
                    MeshRay::new(eye + Vec3::new(0.0, 0.0, (block % 2) as f32 * -7.0), dir)
                })
                .collect();
            let packet = MeshPacket::new(&rays);
            let mut limits = [f32::INFINITY; PACKET];
            let mut best = [None; PACKET];
            bvh.closest_packet(&meshes, &packet, &mut limits, &mut best);
            for (ray, got) in rays.iter().zip(best) {
                let want = bvh.closest(&meshes, ray, f32::INFINITY, None);
                assert_eq!(
                    got.map(|(_, h)| h.t),
                    want.map(|(_, h)| h.t),
                    "block {block}"
                );
                compared += got.is_some() as usize;
            }
        }
        assert!(compared > 100, "{compared} hits compared");
    }
}
