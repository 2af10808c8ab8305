//! The wide node layout both bottom levels share (meshes and analytic shapes): children's f32
//! boxes in structure-of-arrays form, tested against one ray all at once, and the collapse of
//! obvhs' BVH2 into such nodes ([`collapse()`]). A node has `N` children: 4 ([`Node4`], the
//! analytic level's) or 8 ([`Node8`], the meshes').
//!
//! A node holds its children's boxes as six rows of `N` f32 (structure of arrays): a 4-wide node
//! meets one ray in a dozen `Vec4` operations (glam: SSE2 on x86-64, NEON on aarch64), an 8-wide
//! node in the same operations on one AVX register on the AVX2 path or on two `Vec4` halves on
//! the baseline (the same operations in the same order, so both paths give the same distances
//! and masks). There is no entry clamp:
//! hits at any distance count (obvhs' CWBVH node test clamps entry distances to 1e-4 world units,
//! which breaks scale invariance). Reciprocal directions are clamped only where they would be
//! infinite ([`safe_recip`]) and the near/far planes follow the reciprocal's sign, so a −0.0
//! direction component cannot invert a slab.
//!
//! A child reference is a node index, or a leaf ([`LEAF`] set) whose other 31 bits are a payload
//! the owning BVH defines (which leaf block, or which primitive).

mod collapse;
mod sah_plan;
mod subtrees;

pub(super) use collapse::{LEAF_WEIGHT, LeafLayout, collapse, leaf_blocks, whole_blocks};
use glam::{Vec3A, Vec4};
pub(super) use sah_plan::SahCosts;

/// A child reference with this bit set is a leaf; the other bits are the owner's payload.
pub(super) const LEAF: u32 = 1 << 31;
/// An unused child slot: its box is empty, so no ray finite in f32 enters it (both traversals take
/// only those), and no leaf reference is all ones.
pub(super) const EMPTY: u32 = u32::MAX;

/// `N` children: their boxes as `[min x, max x, min y, max y, min z, max z]` lanes, and their
/// references (a node index, a leaf, or [`EMPTY`]).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Node<const N: usize> {
    pub(super) bounds: [[f32; N]; 6],
    pub(super) children: [u32; N],
}

/// A node of four children (the analytic level's).
pub(super) type Node4 = Node<4>;
/// A node of eight children (the meshes').
pub(super) type Node8 = Node<8>;

impl<const N: usize> Node<N> {
    /// An empty node (no child is ever entered).
    pub(super) const EMPTY: Node<N> = Node {
        bounds: [
            [f32::INFINITY; N],
            [f32::NEG_INFINITY; N],
            [f32::INFINITY; N],
            [f32::NEG_INFINITY; N],
            [f32::INFINITY; N],
            [f32::NEG_INFINITY; N],
        ],
        children: [EMPTY; N],
    };
}

/// An f32 ray prepared for the node test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxRay {
    pub(super) origin: Vec3A,
    pub(super) inv_dir: Vec3A,
    /// The reciprocal widened by 1 + 2γ(3), for exit distances: Ize's robust slab test (pbrt-v3
    /// §3.9.2). It makes the f32 box test conservative for the f32 ray wherever it starts, so no
    /// ray slips between two boxes that meet face to face; scaling the reciprocal once per ray,
    /// rather than each exit distance, keeps the node test's length.
    inv_dir_far: Vec3A,
    /// Whether each reciprocal direction component is negative: the near slab is the high one.
    negative: [bool; 3],
}

/// 1 + 2γ(3) in f32: the factor that makes a slab's exit distance conservative.
const ROBUST_EXIT: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// The reciprocal of a direction's components, three lanes in one division, keeping the sign of
/// zero: only a zero or subnormal component is clamped, to ±2¹²⁶ (the largest reciprocal of a
/// normal f32, so the slab distances stay free of ∞·0). A ray running along a slab then leaves it
/// at 2¹²⁶ times its offset from the face, which no padded box's entry on another axis reaches
/// for any direction longer than about 10⁻³⁰. The clamp at ±1e20 this replaces made a ray of an
/// instance scaled by 10¹⁵ (a direction of length 10⁻¹⁵) leave a box it ran along before
/// entering it.
#[inline(always)]
pub(super) fn safe_recip(x: Vec3A) -> Vec3A {
    let tiny = x.abs().cmplt(Vec3A::splat(f32::MIN_POSITIVE));
    Vec3A::select(
        tiny,
        Vec3A::splat(2f32.powi(126)).copysign(x),
        Vec3A::ONE / x,
    )
}

impl BoxRay {
    /// Prepares `origin + t·dir` for the node test (a ray that is not finite in f32 enters no box).
    #[inline(always)]
    pub(crate) fn new(origin: Vec3A, dir: Vec3A) -> BoxRay {
        let inv = safe_recip(dir);
        BoxRay {
            origin,
            inv_dir: inv,
            inv_dir_far: inv * ROBUST_EXIT,
            negative: [
                inv.x.is_sign_negative(),
                inv.y.is_sign_negative(),
                inv.z.is_sign_negative(),
            ],
        }
    }
}

impl Node4 {
    /// Entry distances of the four children and the mask of those the ray enters in [0, `t_max`].
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &BoxRay, t_max: f32) -> (Vec4, u32) {
        let slab = |axis: usize| {
            // Both rows loaded and swapped: loading the near and far rows by index, as `Node8`
            // does, made the analytic frames 0.1% more instructions (callgrind).
            let (lo, hi) = (self.bounds[2 * axis], self.bounds[2 * axis + 1]);
            let (near, far) = if ray.negative[axis] {
                (hi, lo)
            } else {
                (lo, hi)
            };
            let o = Vec4::splat(ray.origin[axis]);
            let (inv, inv_far) = (
                Vec4::splat(ray.inv_dir[axis]),
                Vec4::splat(ray.inv_dir_far[axis]),
            );
            (
                (Vec4::from(near) - o) * inv,
                (Vec4::from(far) - o) * inv_far,
            )
        };
        let (x0, x1) = slab(0);
        let (y0, y1) = slab(1);
        let (z0, z1) = slab(2);
        let enter = x0.max(y0).max(z0).max(Vec4::ZERO);
        let exit = x1.min(y1).min(z1).min(Vec4::splat(t_max));
        (enter, enter.cmple(exit).bitmask())
    }
}

impl Node8 {
    /// Entry distances of the eight children and the mask of those the ray enters in
    /// [0, `t_max`], in AVX registers on the AVX2 path (`AVX2`, which a caller sets only in code
    /// compiled for AVX2 and run where the CPU has it), else in two halves of four. Both do
    /// [`Node4::intersect`]'s operations in its order, so they give the same bits.
    #[inline(always)]
    pub(super) fn intersect<const AVX2: bool>(&self, ray: &BoxRay, t_max: f32) -> ([f32; 8], u32) {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            debug_assert_eq!(super::simd_path(), super::SimdPath::Avx2);
            // SAFETY: `AVX2` is set only on the path chosen where the CPU has AVX2 (`simd_path`):
            // by `Accel`'s `#[target_feature]` functions, which run only where `Accel::avx2`.
            return unsafe { self.intersect_avx2(ray, t_max) };
        }
        self.intersect_halves(ray, t_max)
    }

    /// [`Node8::intersect`] in two SSE2 (or NEON) halves.
    // `Node4::intersect`'s slab code written again: shared through a function over row
    // accessors, it compiled to 2-3% more instructions in the analytic traversal (callgrind,
    // scenes/reflective.toml), which uses `Node4`.
    #[inline(always)]
    fn intersect_halves(&self, ray: &BoxRay, t_max: f32) -> ([f32; 8], u32) {
        let half = |h: usize| {
            let lanes = |row: usize| Vec4::from_slice(&self.bounds[row][4 * h..4 * h + 4]);
            let slab = |axis: usize| {
                // The near and far rows loaded by index rather than both loaded and swapped: a
                // branch and two register moves an axis less (3% fewer instructions in a
                // camera-rays-only kitchen frame).
                let n = usize::from(ray.negative[axis]);
                let (near, far) = (lanes(2 * axis + n), lanes(2 * axis + 1 - n));
                let o = Vec4::splat(ray.origin[axis]);
                (
                    (near - o) * Vec4::splat(ray.inv_dir[axis]),
                    (far - o) * Vec4::splat(ray.inv_dir_far[axis]),
                )
            };
            let (x0, x1) = slab(0);
            let (y0, y1) = slab(1);
            let (z0, z1) = slab(2);
            let enter = x0.max(y0).max(z0).max(Vec4::ZERO);
            let exit = x1.min(y1).min(z1).min(Vec4::splat(t_max));
            (enter, enter.cmple(exit).bitmask())
        };
        let ((low, low_mask), (high, high_mask)) = (half(0), half(1));
        let mut enter = [0f32; 8];
        low.write_to_slice(&mut enter[..4]);
        high.write_to_slice(&mut enter[4..]);
        (enter, low_mask | high_mask << 4)
    }

    /// [`Node8::intersect`] in AVX registers.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    fn intersect_avx2(&self, ray: &BoxRay, t_max: f32) -> ([f32; 8], u32) {
        use std::arch::x86_64::*;
        let rows = self.bounds.as_ptr().cast::<f32>();
        // SAFETY: row r (r = 2·axis or 2·axis + 1, below 6) is the bounds' eight floats at 8·r;
        // unaligned loads and stores.
        unsafe {
            let slab = |axis: usize| {
                let n = usize::from(ray.negative[axis]);
                let near = _mm256_loadu_ps(rows.add(8 * (2 * axis + n)));
                let far = _mm256_loadu_ps(rows.add(8 * (2 * axis + 1 - n)));
                let o = _mm256_set1_ps(ray.origin[axis]);
                (
                    _mm256_mul_ps(_mm256_sub_ps(near, o), _mm256_set1_ps(ray.inv_dir[axis])),
                    _mm256_mul_ps(_mm256_sub_ps(far, o), _mm256_set1_ps(ray.inv_dir_far[axis])),
                )
            };
            let (x0, x1) = slab(0);
            let (y0, y1) = slab(1);
            let (z0, z1) = slab(2);
            let zero = _mm256_setzero_ps();
            let enter = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(x0, y0), z0), zero);
            let limit = _mm256_set1_ps(t_max);
            let exit = _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(x1, y1), z1), limit);
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(enter, exit)) as u32;
            let mut distances = [0f32; 8];
            _mm256_storeu_ps(distances.as_mut_ptr(), enter);
            (distances, mask)
        }
    }
}

impl<const N: usize> Node<N> {
    /// Pushes the children in `mask` onto `stack` far to near, with their entry distances
    /// (`enter`), and returns the nearest (not pushed). `mask` has at least two lanes;
    /// `prefetch` is asked to start loading each pushed child.
    #[inline(always)]
    pub(super) fn push_ordered(
        &self,
        enter: [f32; N],
        mask: u32,
        stack: &mut Vec<(u32, f32)>,
        prefetch: impl Fn(u32),
    ) -> u32 {
        let rest = mask & (mask - 1);
        if rest & (rest - 1) == 0 {
            // Two children, lanes a < b: the order the sort below gives (the farther pushed, the
            // nearer kept; on a tie the later lane kept), without its loop over every lane.
            let (a, b) = (
                mask.trailing_zeros() as usize,
                rest.trailing_zeros() as usize,
            );
            let (far, near) = if enter[a] < enter[b] { (b, a) } else { (a, b) };
            prefetch(self.children[far]);
            stack.push((self.children[far], enter[far]));
            return self.children[near];
        }
        let mut order = [(0u32, 0f32); N];
        let mut n = 0;
        for (lane, (&child, &t)) in self.children.iter().zip(&enter).enumerate() {
            if mask & (1 << lane) != 0 {
                let mut j = n;
                while j > 0 && order[j - 1].1 < t {
                    order[j] = order[j - 1];
                    j -= 1;
                }
                order[j] = (child, t);
                n += 1;
            }
        }
        // One push per entry: `extend_from_slice` of a run this short compiled to a call to
        // `memcpy` (4% of a camera-ray frame's profile).
        for &entry in &order[..n - 1] {
            prefetch(entry.0);
            stack.push(entry);
        }
        order[n - 1].0
    }

    /// Pushes the children in `mask` (at least one) onto `stack` in lane order but the last,
    /// and returns the last: the any-hit traversals' order (no child ordering), the one
    /// popping them all would give, without the last one's push and pop. `prefetch` is asked to
    /// start loading each pushed child (as the closest-hit traversal's: the dragon's incoherent
    /// any hits +6%).
    #[inline(always)]
    pub(super) fn push_all_but_last(
        &self,
        mask: u32,
        stack: &mut Vec<(u32, f32)>,
        prefetch: impl Fn(u32),
    ) -> u32 {
        let last = 31 - mask.leading_zeros();
        let mut rest = mask & !(1 << last);
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            prefetch(self.children[lane]);
            stack.push((self.children[lane], 0.0));
        }
        self.children[last as usize]
    }

    /// The box of child `lane`, `None` for an unused slot.
    pub(super) fn child_box(&self, lane: usize) -> Option<(glam::DVec3, glam::DVec3)> {
        let b = &self.bounds;
        let lo = glam::DVec3::new(b[0][lane] as f64, b[2][lane] as f64, b[4][lane] as f64);
        let hi = glam::DVec3::new(b[1][lane] as f64, b[3][lane] as f64, b[5][lane] as f64);
        lo.cmple(hi).all().then_some((lo, hi))
    }
}

/// The next pending child of a closest-hit traversal the ray enters no farther than `limit` (the
/// best hit so far), dropping those beyond it; `None` when none is left.
#[inline(always)]
pub(super) fn pop_nearer(stack: &mut Vec<(u32, f32)>, limit: f32) -> Option<u32> {
    loop {
        match stack.pop()? {
            (child, enter) if enter <= limit => return Some(child),
            _ => {}
        }
    }
}

/// At most `max` boxes whose union holds every primitive, hugging the content far closer than
/// one box once rotated: the root's children's boxes, each opened into its own children's while
/// the count stays within `max` (all of them for a 4-wide tree and `max` 16).
pub(super) fn covering_boxes<const N: usize>(
    nodes: &[Node<N>],
    max: usize,
) -> Vec<(glam::DVec3, glam::DVec3)> {
    let Some(root) = nodes.first() else {
        return Vec::new();
    };
    let lanes: Vec<usize> = (0..N).filter(|&l| root.child_box(l).is_some()).collect();
    let mut count = lanes.len();
    let mut boxes = Vec::new();
    for lane in lanes {
        let child = root.children[lane];
        let opened: Vec<_> = if child & LEAF == 0 {
            let node = &nodes[child as usize];
            (0..N).filter_map(|l| node.child_box(l)).collect()
        } else {
            Vec::new()
        };
        if !opened.is_empty() && count - 1 + opened.len() <= max {
            count += opened.len() - 1;
            boxes.extend(opened);
        } else {
            boxes.extend(root.child_box(lane));
        }
    }
    boxes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic value in [0, 1) from two integers.
    fn hash(i: u32, k: u32) -> f32 {
        let h =
            (i.wrapping_mul(0x9E37_79B9) ^ k.wrapping_mul(0x85EB_CA6B)).wrapping_mul(0xC2B2_AE35);
        (h >> 8) as f32 / (1 << 24) as f32
    }

    /// Children pushed far to near, the nearest returned, and on a tie the later lane nearer:
    /// the order of every mask of entered lanes, two lanes (a path of its own) or more, with
    /// ties, against a stable sort.
    #[test]
    fn children_are_ordered_far_to_near_with_ties_kept_stable() {
        let mut node = Node8::EMPTY;
        node.children = std::array::from_fn(|lane| 10 + lane as u32);
        let mut stack = Vec::new();
        for k in 0..500u32 {
            // Distances from four values, so ties are common.
            let enter: [f32; 8] = std::array::from_fn(|lane| (hash(k, lane as u32) * 4.0).floor());
            for mask in 1u32..256 {
                if mask.count_ones() < 2 {
                    continue;
                }
                stack.clear();
                let nearest = node.push_ordered(enter, mask, &mut stack, |_| {});
                // Lanes by distance, far first; equal distances in lane order, so the last of
                // them is the nearer.
                let mut want: Vec<usize> = (0..8).filter(|l| mask & (1 << l) != 0).collect();
                want.sort_by(|&a, &b| enter[b].total_cmp(&enter[a]));
                let (last, pushed) = want.split_last().unwrap();
                assert_eq!(nearest, node.children[*last], "k {k} mask {mask:#b}");
                let got: Vec<(u32, f32)> = stack.clone();
                let expected: Vec<(u32, f32)> = pushed
                    .iter()
                    .map(|&l| (node.children[l], enter[l]))
                    .collect();
                assert_eq!(got, expected, "k {k} mask {mask:#b}");
            }
        }
    }

    /// The 8-wide test agrees with the 4-wide one on each half, and (where the CPU has AVX2) its
    /// AVX path with its SSE2 path, bit for bit: the SIMD paths' images stay identical.
    #[test]
    fn node8_lanes_match_node4_and_the_avx2_path() {
        let mut entered = 0;
        for k in 0..2000u32 {
            let mut node = Node8::EMPTY;
            for lane in 0..8 {
                // Some lanes empty, some boxes flat on one axis.
                if hash(k, lane as u32 + 100) < 0.1 {
                    continue;
                }
                for axis in 0..3 {
                    let c = hash(k, (lane * 3 + axis) as u32) * 4.0 - 2.0;
                    let half = if hash(k, lane as u32 + 50) < 0.1 {
                        0.0
                    } else {
                        1.0
                    };
                    node.bounds[2 * axis][lane] = c - half;
                    node.bounds[2 * axis + 1][lane] = c + half;
                }
                node.children[lane] = lane as u32;
            }
            // From above and from below, some along a slab, a few not finite (every path must
            // still agree bit for bit).
            let side = if k % 2 == 0 { 1.0 } else { -1.0 };
            let mut origin = Vec3A::new(
                2.0 * hash(k, 200) - 1.0,
                2.0 * hash(k, 201) - 1.0,
                5.0 * side,
            );
            let mut dir = Vec3A::new(hash(k, 202) - 0.5, hash(k, 203) - 0.5, -side);
            if k % 5 == 0 {
                dir.x = -0.0; // along a slab
            }
            match k % 97 {
                1 => origin.y = f32::NAN,
                2 => origin.z = f32::INFINITY,
                3 => dir.y = f32::NAN,
                _ => {}
            }
            let ray = BoxRay::new(origin, dir);
            let t_max = if k % 3 == 0 { f32::INFINITY } else { 5.0 };
            let (enter, mask) = node.intersect::<false>(&ray, t_max);
            for half in 0..2 {
                let mut four = Node4::EMPTY;
                for row in 0..6 {
                    four.bounds[row].copy_from_slice(&node.bounds[row][4 * half..4 * half + 4]);
                }
                let (enter4, mask4) = four.intersect(&ray, t_max);
                let enter4 = enter4.to_array();
                assert_eq!((mask >> (4 * half)) & 0xF, mask4, "ray {k} half {half}");
                for lane in (0..4).filter(|l| mask4 & (1 << l) != 0) {
                    assert_eq!(enter[4 * half + lane].to_bits(), enter4[lane].to_bits());
                }
            }
            entered += mask.count_ones();
            #[cfg(target_arch = "x86_64")]
            if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
                let (enter_avx, mask_avx) = node.intersect::<true>(&ray, t_max);
                assert_eq!(mask_avx, mask, "ray {k}");
                assert_eq!(
                    enter_avx.map(f32::to_bits),
                    enter.map(f32::to_bits),
                    "ray {k}"
                );
            }
        }
        assert!(entered > 1000, "{entered}");
    }
}
