//! The 4-wide node layout both bottom levels share (meshes and analytic shapes): children's
//! f32 boxes in structure-of-arrays form, tested against one ray four at a time, and the collapse
//! of obvhs' BVH2 into such nodes ([`collapse`]).
//!
//! A node holds its four children's boxes as six `Vec4`s, so one ray meets all four in a dozen
//! SIMD operations (glam's `Vec4`: SSE2 on x86-64, NEON on aarch64). There is no entry clamp:
//! hits at any distance count (obvhs' CWBVH node test clamps entry distances to 1e-4 world units,
//! which breaks scale invariance). Reciprocal directions are clamped only where they would be
//! infinite ([`safe_recip`]) and the near/far planes follow the reciprocal's sign, so a −0.0
//! direction component cannot invert a slab.
//!
//! A child reference is a node index, or a leaf ([`LEAF`] set) whose other 31 bits are a payload
//! the owning BVH defines (which leaf block, or which primitive).

mod collapse;

pub(super) use collapse::{LEAF_WEIGHT, collapse, leaf_blocks};
use glam::{Vec3A, Vec4};

/// A child reference with this bit set is a leaf; the other bits are the owner's payload.
pub(super) const LEAF: u32 = 1 << 31;
/// An unused child slot (its box is empty, so no ray enters it).
pub(super) const EMPTY: u32 = LEAF;

/// Four children: their boxes as `[min x, max x, min y, max y, min z, max z]` lanes, and their
/// references (a node index, a leaf, or [`EMPTY`]).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Node4 {
    pub(super) bounds: [[f32; 4]; 6],
    pub(super) children: [u32; 4],
}

/// An empty node (no child is ever entered).
pub(super) const EMPTY_NODE: Node4 = Node4 {
    bounds: [
        [f32::INFINITY; 4],
        [f32::NEG_INFINITY; 4],
        [f32::INFINITY; 4],
        [f32::NEG_INFINITY; 4],
        [f32::INFINITY; 4],
        [f32::NEG_INFINITY; 4],
    ],
    children: [EMPTY; 4],
};

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

    /// Pushes the children in `mask` onto `stack` far to near, with their entry distances, and
    /// returns the nearest (not pushed). `mask` has at least two lanes; `prefetch` is asked to
    /// start loading each pushed child.
    #[inline(always)]
    pub(super) fn push_ordered(
        &self,
        enter: Vec4,
        mask: u32,
        stack: &mut Vec<(u32, f32)>,
        prefetch: impl Fn(u32),
    ) -> u32 {
        let enter = enter.to_array();
        let mut order = [(0u32, 0f32); 4];
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

/// The boxes of the root's children's children (at most 16): their union holds every primitive,
/// and they hug the content far closer than one box once rotated.
pub(super) fn covering_boxes(nodes: &[Node4]) -> Vec<(glam::DVec3, glam::DVec3)> {
    let Some(root) = nodes.first() else {
        return Vec::new();
    };
    let mut boxes = Vec::new();
    for lane in 0..4 {
        let child = root.children[lane];
        if child & LEAF != 0 {
            boxes.extend(root.child_box(lane));
            continue;
        }
        let node = &nodes[child as usize];
        boxes.extend((0..4).filter_map(|l| node.child_box(l)));
    }
    boxes
}
