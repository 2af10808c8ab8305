//! Front-to-back traversal of a level's top BVH2.

use obvhs::bvh2::Bvh2;

/// Front-to-back iteration over the leaves of the top-level BVH2 that a ray enters, written out
/// (rather than obvhs' closure-taking traversal) so the whole query inlines into one function and
/// the AVX2 path covers it.
pub(super) struct TopLeaves<'a> {
    bvh: &'a Bvh2,
    ray: &'a obvhs::ray::Ray,
    stack: &'a mut Vec<u32>,
}

impl<'a> TopLeaves<'a> {
    #[inline(always)]
    pub(super) fn new(
        bvh: &'a Bvh2,
        ray: &'a obvhs::ray::Ray,
        stack: &'a mut Vec<u32>,
    ) -> TopLeaves<'a> {
        stack.clear();
        if !bvh.nodes.is_empty() {
            stack.push(0);
        }
        TopLeaves { bvh, ray, stack }
    }

    /// The item range of the next leaf whose box the ray enters before `t_max`.
    #[inline(always)]
    pub(super) fn next(&mut self, t_max: f32) -> Option<std::ops::Range<usize>> {
        while let Some(index) = self.stack.pop() {
            let node = &self.bvh.nodes[index as usize];
            if node.aabb().intersect_ray(self.ray) >= t_max {
                continue;
            }
            if node.is_leaf() {
                let first = node.first_index as usize;
                return Some(first..first + node.prim_count as usize);
            }
            // Children are stored as a pair at first_index; visit the nearer one first.
            let (a, b) = (node.first_index, node.first_index + 1);
            let ta = self.bvh.nodes[a as usize].aabb().intersect_ray(self.ray);
            let tb = self.bvh.nodes[b as usize].aabb().intersect_ray(self.ray);
            if ta <= tb {
                self.stack.push(b);
                self.stack.push(a);
            } else {
                self.stack.push(a);
                self.stack.push(b);
            }
        }
        None
    }
}
