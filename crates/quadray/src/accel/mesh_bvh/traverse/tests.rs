//! The traversals against brute force, across paths and leaf layouts.

use super::super::tests::grid;
use super::*;
use crate::accel::wide::LeafLayout;
use crate::accel::{SimdPath, simd_path};
use glam::Vec3;

/// Every ray through the grid's interior (including along the shared edges and through
/// vertices) hits, at the plane's t; a brute-force scan over the mesh's triangles
/// agrees on the nearest t.
#[test]
fn bvh_traversal_matches_brute_force_and_has_no_cracks() {
    let meshes = [grid(16, 0)];
    let bvh = MeshBvh::build(&meshes, false);
    let mesh = &meshes[0];
    for k in 0..4000 {
        // Inside the grid's border (its outer edges are shared by no second triangle).
        let x = 1.0 + 14.0 * ((k as f32 * 0.618_034).fract());
        let y = 1.0 + 14.0 * ((k as f32 * 0.414_213_5).fract());
        // Every fourth ray aims exactly at a vertex or along a grid line.
        let (x, y) = match k % 4 {
            0 => (x.round(), y.round()),
            1 => (x.round(), y),
            _ => (x, y),
        };
        let dir = Vec3::new(0.1 * (k as f32).sin(), 0.1 * (k as f32).cos(), -1.0);
        let ray = MeshRay::new(Vec3::new(x, y, 0.0) - dir * 5.0, dir);
        let hit = bvh.closest::<false>(&meshes, &ray, f32::INFINITY, None);
        let MeshHit { id, hit: h, .. } = hit.unwrap_or_else(|| panic!("hole at ({x}, {y})"));
        assert!((h.t - 5.0).abs() < 1e-5, "t {}", h.t);
        let brute = (0..mesh.triangle_count() as u32)
            .filter_map(|t| {
                let [a, b, c] = mesh.triangle_positions(t);
                ray.sheared.intersect(a, b, c, f32::INFINITY).map(|h| h.t)
            })
            .fold(f32::INFINITY, f32::min);
        assert_eq!(brute, h.t);
        assert!(bvh.occluded::<false>(&meshes, &ray, 6.0, None));
        assert!(!bvh.occluded::<false>(&meshes, &ray, 4.9, None));
        // Skipping the triangle hit leaves at most its neighbour across an edge or vertex.
        if let Some(MeshHit { id: other, .. }) =
            bvh.closest::<false>(&meshes, &ray, f32::INFINITY, Some(id))
        {
            assert_ne!(other, id);
        }
    }
}

/// A tiny mesh near the origin is hit from very close: no entry clamp loses near hits.
#[test]
fn near_hits_at_any_scale() {
    for scale in [1e-6f32, 1.0, 1e6] {
        let g = grid(4, 0);
        let p: Vec<Vec3> = g.positions().iter().map(|p| *p * scale).collect();
        let meshes = [Mesh::new(p, g.indices().to_vec(), None, 0).unwrap()];
        let bvh = MeshBvh::build(&meshes, false);
        let ray = MeshRay::new(Vec3::new(1.5, 2.5, 1e-3) * scale, Vec3::new(0.0, 0.0, -1.0));
        let MeshHit { hit: h, .. } = bvh
            .closest::<false>(&meshes, &ray, f32::INFINITY, None)
            .expect("hit");
        assert!(
            (h.t / (1e-3 * scale) - 1.0).abs() < 1e-4,
            "scale {scale}: t {}",
            h.t
        );
    }
}

/// Rays from far away aimed exactly at the grid's lines, where leaf boxes meet face to face,
/// all hit: the slab test is conservative for a ray starting at any distance (without the
/// robust exit factor, rays from 10⁴ away slip between two boxes).
#[test]
fn distant_rays_at_box_faces_hit() {
    let meshes = [grid(16, 0)];
    let bvh = MeshBvh::build(&meshes, false);
    let mut holes = 0;
    let mut rays = 0;
    for distance in [1e3f32, 1e4, 1e5] {
        for k in 0..20_000 {
            let along = 1.0 + 14.0 * ((k as f32 * 0.618_034).fract());
            let line = 1.0 + (k % 15) as f32;
            let target = if k % 2 == 0 {
                Vec3::new(line, along, 0.0)
            } else {
                Vec3::new(along, line, 0.0)
            };
            let tilt = Vec3::new(0.3 * (k as f32).sin(), 0.3 * (k as f32).cos(), 1.0);
            let origin = target + tilt.normalize() * distance;
            let ray = MeshRay::new(origin, target - origin);
            holes += bvh
                .closest::<false>(&meshes, &ray, f32::INFINITY, None)
                .is_none() as usize;
            rays += 1;
        }
    }
    assert_eq!(holes, 0, "{holes} of {rays} rays missed");
}

#[test]
fn negative_zero_direction_components_traverse() {
    let meshes = [grid(8, 0)];
    let bvh = MeshBvh::build(&meshes, false);
    let ray = MeshRay::new(Vec3::new(3.3, 4.4, 2.0), Vec3::new(-0.0, -0.0, -1.0));
    assert!(
        bvh.closest::<false>(&meshes, &ray, f32::INFINITY, None)
            .is_some()
    );
}

/// A 48x48 grid bent into hills of height `height`, `waves` giving the bends' frequencies
/// along x and y.
fn bumpy_grid(waves: (f32, f32), height: f32) -> Mesh {
    let flat = grid(48, 0);
    let bumpy: Vec<Vec3> = (flat.positions().iter())
        .map(|p| {
            Vec3::new(
                p.x,
                p.y,
                (p.x * waves.0).sin() * (p.y * waves.1).cos() * height,
            )
        })
        .collect();
    Mesh::new(bumpy, flat.indices().to_vec(), None, 0).unwrap()
}

/// Probe ray `k` of a bumpy grid, from above or below at any slant, and its `t_max` (every
/// third one short).
fn probe(k: u32) -> (MeshRay, f32) {
    let f = k as f32;
    let origin = Vec3::new(
        24.0 + 40.0 * (f * 0.618_034).fract() - 20.0,
        24.0 + 40.0 * (f * 0.414_213_5).fract() - 20.0,
        if k.is_multiple_of(2) { 10.0 } else { -10.0 },
    );
    let target = Vec3::new(
        48.0 * (f * 0.302_775).fract(),
        48.0 * (f * 0.732_05).fract(),
        0.0,
    );
    let t_max = if k.is_multiple_of(3) {
        0.5
    } else {
        f32::INFINITY
    };
    (MeshRay::new(origin, target - origin), t_max)
}

/// The AVX2 path's traversal (its 8-wide nodes tested in AVX registers) finds the same hits
/// as the baseline's, bit for bit, on a bumpy mesh hit from every side; skipped (and said)
/// where this process does not take the AVX2 path.
#[test]
fn avx2_and_baseline_traversals_agree() {
    if simd_path() != SimdPath::Avx2 {
        eprintln!("skipped: this machine or QUADRAY_SIMD does not take the AVX2 path");
        return;
    }
    let meshes = [bumpy_grid((0.7, 0.45), 3.0)];
    let bvh = MeshBvh::build(&meshes, false);
    let mut hits = 0;
    for k in 0..20_000u32 {
        let (ray, t_max) = probe(k);
        let avx = bvh.closest::<true>(&meshes, &ray, t_max, None);
        let base = bvh.closest::<false>(&meshes, &ray, t_max, None);
        let key = |h: Option<MeshHit>| h.map(|h| (h.id, h.hit.t.to_bits(), h.block, h.lane));
        assert_eq!(key(avx), key(base), "ray {k}");
        assert_eq!(
            bvh.occluded::<true>(&meshes, &ray, t_max, None),
            bvh.occluded::<false>(&meshes, &ray, t_max, None),
            "ray {k}"
        );
        hits += base.is_some() as u32;
    }
    assert!(hits > 5000, "{hits} hits");
}

/// Leaves sharing blocks give every hit, t and any-hit answer that leaves in blocks of their
/// own give, on both paths, in fewer blocks.
#[test]
fn shared_and_own_block_leaves_agree() {
    let meshes = [bumpy_grid((0.9, 0.35), 4.0)];
    let shared = MeshBvh::build_in(&meshes, LeafLayout::LONG_TAG);
    let own = MeshBvh::build_in(&meshes, LeafLayout::SHORT_TAG);
    assert!(shared.blocks.len() < own.blocks.len());
    let avx2 = simd_path() == SimdPath::Avx2;
    let mut hits = 0;
    for k in 0..20_000u32 {
        let (ray, t_max) = probe(k);
        let key = |bvh: &MeshBvh, h: Option<MeshHit>| {
            h.map(|h| {
                (
                    h.id,
                    h.hit.t.to_bits(),
                    bvh.vertices(&h).map(|v| v.to_array()),
                )
            })
        };
        let want = key(&own, own.closest::<false>(&meshes, &ray, t_max, None));
        assert_eq!(
            key(&shared, shared.closest::<false>(&meshes, &ray, t_max, None)),
            want
        );
        let blocked = own.occluded::<false>(&meshes, &ray, t_max, None);
        assert_eq!(
            shared.occluded::<false>(&meshes, &ray, t_max, None),
            blocked
        );
        if avx2 {
            assert_eq!(
                key(&shared, shared.closest::<true>(&meshes, &ray, t_max, None)),
                want
            );
            assert_eq!(shared.occluded::<true>(&meshes, &ray, t_max, None), blocked);
        }
        hits += want.is_some() as u32;
    }
    assert!(hits > 5000, "{hits} hits");
}

/// A compact BVH's answers against the copied one's for one ray, on the `AVX2` path: the
/// hit (mesh, triangle, t and vertices), then skipping that triangle, and any hit with and
/// without the skip. Whether the ray hits.
fn compact_agrees<const AVX2: bool>(
    meshes: &[Mesh],
    (copied, compact): (&MeshBvh, &MeshBvh),
    ray: &MeshRay,
    t_max: f32,
) -> bool {
    let mut stack = Vec::new();
    let mut closest = |skip: Option<TriId>| {
        let want = copied.closest_on::<AVX2>(meshes, ray, t_max, skip, &mut stack);
        let got = compact.closest_compact::<AVX2>(meshes, ray, t_max, skip, &mut stack);
        let want = want.map(|h| (h.id, h.hit.t.to_bits(), copied.vertices(&h)));
        let got = got.map(|h| (h.id, h.hit.t.to_bits(), compact.mesh_vertices(meshes, &h)));
        assert_eq!(got, want, "skipping {skip:?}");
        want.map(|(id, ..)| id)
    };
    let first = closest(None);
    closest(first);
    for skip in [None, first] {
        assert_eq!(
            compact.occluded_compact::<AVX2>(meshes, ray, t_max, skip),
            copied.occluded::<AVX2>(meshes, ray, t_max, skip),
            "skipping {skip:?}"
        );
    }
    first.is_some()
}

/// A compact BVH, whose leaves hold triangle numbers and read the vertices from the meshes,
/// gives every hit, t, vertex and any-hit answer the copied one gives, a triangle skipped or
/// not, on both paths, over two meshes (numbered through the id table), in 16 bytes a leaf
/// block instead of 160.
#[test]
fn compact_and_copied_leaves_agree() {
    let bumpy = bumpy_grid((0.8, 0.5), 3.0);
    let shifted = (bumpy.positions().iter())
        .map(|p| *p + Vec3::new(3.0, 1.0, 2.5))
        .collect();
    let second = Mesh::new(shifted, bumpy.indices().to_vec(), None, 1).unwrap();
    let meshes = [bumpy, second];
    let copied = MeshBvh::build(&meshes, false);
    let compact = MeshBvh::build(&meshes, true);
    assert!(compact.compact() && !copied.compact());
    assert_eq!(compact.numbers.len(), copied.blocks.len());
    // The same nodes and id table; 16 bytes a block instead of 160.
    let saved = copied.memory_bytes() - compact.memory_bytes();
    assert_eq!(saved, copied.blocks.len() * (size_of::<Tri4>() - 16));
    let avx2 = simd_path() == SimdPath::Avx2;
    let mut hits = 0;
    for k in 0..20_000u32 {
        let (ray, t_max) = probe(k);
        let pair = (&copied, &compact);
        hits += compact_agrees::<false>(&meshes, pair, &ray, t_max) as u32;
        if avx2 {
            compact_agrees::<true>(&meshes, pair, &ray, t_max);
        }
    }
    assert!(hits > 5000, "{hits} hits");
}

/// Over several meshes, hits name the right mesh and triangle, and skipping works per mesh.
#[test]
fn several_meshes_share_one_bvh() {
    let lower = grid(4, 0);
    let p: Vec<Vec3> = lower.positions().iter().map(|p| *p + Vec3::Z).collect();
    let upper = Mesh::new(p, lower.indices().to_vec(), None, 1).unwrap();
    let meshes = [lower, upper];
    let bvh = MeshBvh::build(&meshes, false);
    let ray = MeshRay::new(Vec3::new(1.3, 2.6, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let hit = bvh
        .closest::<false>(&meshes, &ray, f32::INFINITY, None)
        .unwrap();
    let MeshHit {
        id: (m, tri),
        hit: h,
        ..
    } = hit;
    assert_eq!((m, h.t), (1, 4.0));
    let vertices = bvh.vertices(&hit);
    // The hit's vertices are the mesh's own (the f64 refinement reads them from the block).
    let mesh_vertices = meshes[1]
        .triangle_positions(tri)
        .map(|p| Vec3::from(*p).as_dvec3());
    assert_eq!(vertices, mesh_vertices);
    let MeshHit {
        id: (m2, _),
        hit: h2,
        ..
    } = bvh
        .closest::<false>(&meshes, &ray, f32::INFINITY, Some((1, tri)))
        .unwrap();
    assert_eq!((m2, h2.t), (0, 5.0));
    assert!(bvh.occluded::<false>(&meshes, &ray, 4.5, None));
    assert!(!bvh.occluded::<false>(&meshes, &ray, 4.5, Some((1, tri))));
}
