//! Where the mesh BVH's leaves sit in its blocks. A leaf's triangles take consecutive lanes from
//! a first block and lane, so leaves of one to three triangles share blocks, and a leaf of five
//! to seven may begin in the free lanes of the block before its own. Each leaf tests the blocks
//! it has lanes in and keeps only its own lanes' hits: a lane's test is its own arithmetic, so a
//! triangle gives the same answer whatever shares its block.
//!
//! Why: a leaf is a subtree of at most eight triangles, and one block a leaf left the blocks 3.2
//! triangles full on the dragon (4.0 is full), 50 of its 75 bytes a triangle. Shared, they hold
//! 3.6 ([`WINDOW`]). A leaf still tests no more blocks than its count needs (⌈n/4⌉): a leaf is placed
//! where that holds, else in fresh blocks.
//!
//! A leaf's tag is its first lane (two bits) and its count less one (three bits), so its first
//! block has 26 bits of the reference ([`LeafLayout::LONG_TAG`]). A BVH over more triangles than
//! that many blocks are sure to hold (each holds one at least) gives each leaf blocks of its own
//! from lane 0, as every BVH did before, and tags only the count ([`LeafLayout::SHORT_TAG`],
//! 2²⁸ blocks): the same reading of the tag serves both.

use super::super::tri4::Tri4;
use crate::accel::wide::LeafLayout;

/// How many of the latest blocks a leaf of one to three triangles may join: the fullest of them
/// with room for it (the latest of equals), so shared blocks hold leaves built side by side, near
/// each other in the tree and in space. Blocks the dragon's leaves take: 271 206 in leaves of
/// their own, 242 381 with a window of 4, 235 373 with 16, 217 854 if full. With 16 the kitchen's
/// rays ran 3–4% slower in three alternating rounds of `bench rays` (its leaves' blocks farther
/// apart, or the code's placement, which alone moves these timings by as much), where 4 kept its
/// speed.
const WINDOW: usize = 4;

/// A leaf's triangles: the lanes set in `bits` of the blocks from `first` on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct LeafLanes {
    first: usize,
    bits: u32,
}

impl LeafLanes {
    /// The leaf of reference `leaf` in a BVH of `layout` (made by the collapse from
    /// [`pack_leaf`]'s tag).
    #[inline(always)]
    pub(super) fn of(leaf: u32, layout: LeafLayout) -> LeafLanes {
        // The tag: the first lane (none in a short tag), then the count less one.
        let (first, tag) = layout.parts(leaf);
        LeafLanes {
            first,
            bits: ((2 << (tag & 7)) - 1) << (tag >> 3),
        }
    }

    /// The tag of a leaf of `count` triangles (one to 8) from lane `lane` (below 4).
    fn tag(lane: usize, count: usize) -> u32 {
        // Checked in release builds too: a tag out of range would name other leaves' lanes.
        assert!(
            lane < 4 && (1..=8).contains(&count) && lane + count <= 8,
            "a mesh leaf holds one to 8 triangles in at most two blocks"
        );
        ((lane << 3) | (count - 1)) as u32
    }

    /// The leaf's first block.
    #[inline(always)]
    pub(super) fn first_block(self) -> usize {
        self.first
    }

    /// The leaf's lanes as bits of its blocks' lanes in turn (bit 4k + l: lane l of its k-th
    /// block).
    #[inline(always)]
    pub(super) fn lane_bits(self) -> u32 {
        self.bits
    }
}

/// The layout of a BVH over `triangles`: shared blocks where its blocks fit a long tag's
/// references whatever the leaves, else blocks of their own.
pub(super) fn layout_for(triangles: usize) -> LeafLayout {
    if triangles <= LeafLayout::LONG_TAG.max_blocks() {
        LeafLayout::LONG_TAG
    } else {
        LeafLayout::SHORT_TAG
    }
}

/// Places a leaf's triangles `prims` (one to 8; `triangle` gives each one's vertices) in
/// `blocks` and returns its first block and its tag for the collapse ([`LeafLanes::of`] reads
/// them back). With [`LeafLayout::LONG_TAG`] the leaf joins blocks the vector already holds where
/// it fits; with [`LeafLayout::SHORT_TAG`] it takes blocks of its own from lane 0.
pub(super) fn pack_leaf(
    layout: LeafLayout,
    blocks: &mut Vec<Tri4>,
    prims: &[u32],
    triangle: impl Fn(u32) -> [[f32; 3]; 3],
) -> (usize, u32) {
    let n = prims.len();
    let start = match n {
        _ if layout == LeafLayout::SHORT_TAG => None,
        // The fullest of the latest blocks with room, the latest of equals.
        1..=3 => (blocks.len().saturating_sub(WINDOW)..blocks.len())
            .map(|b| (b, blocks[b].lanes_used()))
            .filter(|&(_, used)| used + n <= 4)
            .max_by_key(|&(b, used)| (used, b)),
        // The last block's free lanes and one block more, if they hold it.
        5.. => (blocks.len().checked_sub(1))
            .map(|b| (b, blocks[b].lanes_used()))
            .filter(|&(_, used)| used + n <= 8),
        _ => None,
    };
    let (first, lane) = start.unwrap_or((blocks.len(), 0));
    // Checked before any lane is written.
    let tag = LeafLanes::tag(lane, n);
    for (k, &p) in prims.iter().enumerate() {
        let (block, slot) = (first + (lane + k) / 4, (lane + k) % 4);
        if block == blocks.len() {
            blocks.push(Tri4::EMPTY);
        }
        blocks[block].set(slot, triangle(p), p);
    }
    (first, tag)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::wide::LEAF;

    /// Packs leaves of the given sizes in turn, numbering their triangles 0, 1, 2, … (each
    /// triangle's vertices its number), and returns the blocks and each leaf's lanes.
    fn packed(sizes: &[usize]) -> (Vec<Tri4>, Vec<LeafLanes>) {
        let (mut blocks, mut leaves, mut next) = (Vec::new(), Vec::new(), 0u32);
        for &n in sizes {
            let prims: Vec<u32> = (next..next + n as u32).collect();
            next += n as u32;
            let (first, tag) = pack_leaf(LeafLayout::LONG_TAG, &mut blocks, &prims, |p| {
                [[p as f32; 3]; 3]
            });
            leaves.push(LeafLanes::of(
                LEAF | (first as u32) << 5 | tag,
                LeafLayout::LONG_TAG,
            ));
        }
        (blocks, leaves)
    }

    /// Every leaf finds exactly its own triangles in its lanes, in at most ⌈n/4⌉ blocks, and no
    /// lane holds two triangles.
    #[test]
    fn each_leaf_reads_back_its_own_triangles() {
        let sizes: Vec<usize> = (0..400)
            .map(|i| [3, 1, 2, 7, 2, 5, 4, 8, 6, 1][i % 10])
            .collect();
        let (blocks, leaves) = packed(&sizes);
        let mut next = 0u32;
        for (&n, leaf) in sizes.iter().zip(&leaves) {
            let mut got = Vec::new();
            let mut bits = leaf.lane_bits();
            let mut block = leaf.first_block();
            let mut spanned = 0;
            while bits != 0 {
                for lane in 0..4 {
                    if bits & (1 << lane) != 0 {
                        got.push(blocks[block].tri[lane]);
                    }
                }
                (bits, block, spanned) = (bits >> 4, block + 1, spanned + 1);
            }
            let want: Vec<u32> = (next..next + n as u32).collect();
            assert_eq!(got, want, "leaf {leaf:?}");
            assert!(spanned <= n.div_ceil(4), "leaf of {n} in {spanned} blocks");
            next += n as u32;
        }
        let filled: usize = blocks.iter().map(Tri4::lanes_used).sum();
        assert_eq!(filled, next as usize);
    }

    /// Small leaves share blocks: a run of leaves of one to three triangles fills its blocks,
    /// where leaves of their own would leave them about half empty.
    #[test]
    fn small_leaves_share_blocks() {
        let sizes: Vec<usize> = (0..300).map(|i| [1, 3, 2, 2][i % 4]).collect();
        let (blocks, _) = packed(&sizes);
        assert_eq!(blocks.len(), 600 / 4);
        // A leaf of five continues in the free lanes of the block before.
        let (blocks, leaves) = packed(&[3, 5]);
        assert_eq!(blocks.len(), 2);
        assert_eq!(leaves[1].lane_bits(), 0b1111_1000);
    }

    /// Leaves in blocks of their own read back their lanes from lane 0; the long tag is taken
    /// while every block is sure to fit a reference.
    #[test]
    fn own_block_leaves_and_the_layout_choice() {
        let mut blocks = Vec::new();
        let (first, tag) = pack_leaf(
            LeafLayout::SHORT_TAG,
            &mut blocks,
            &[7, 8, 9, 10, 11],
            |p| [[p as f32; 3]; 3],
        );
        let leaf = LeafLanes::of(LEAF | (first as u32) << 3 | tag, LeafLayout::SHORT_TAG);
        assert_eq!((leaf.first_block(), leaf.lane_bits()), (0, 0b1_1111));
        assert_eq!(blocks[1].tri[0], 11);
        assert_eq!(layout_for(1 << 20), LeafLayout::LONG_TAG);
        assert_eq!(layout_for((1 << 26) - 2), LeafLayout::LONG_TAG);
        assert_eq!(layout_for((1 << 26) - 1), LeafLayout::SHORT_TAG);
    }
}
