//! How far from the origin what a node puts in the world reaches, so that coordinates past
//! quadray's limit ([`MAX_COORDINATE`]) are reported with the node that put them there rather
//! than, later, as the whole scene's.

use glam::{DAffine3, DVec3};
use quadray::{MAX_COORDINATE, Prototype};
use std::collections::HashMap;

/// A box, corners low and high.
type Bounds = (DVec3, DVec3);

/// How much a level held before a node's contents were added to it.
pub(super) struct Mark {
    spheres: usize,
    quadrics: usize,
    meshes: usize,
    instances: usize,
}

impl Mark {
    /// What `level` holds now.
    pub(super) fn of(level: &Prototype) -> Mark {
        Mark {
            spheres: level.spheres.len(),
            quadrics: level.quadrics.len(),
            meshes: level.meshes.len(),
            instances: level.instances.len(),
        }
    }

    /// Nothing held.
    fn empty() -> Mark {
        Mark {
            spheres: 0,
            quadrics: 0,
            meshes: 0,
            instances: 0,
        }
    }
}

/// The prototypes' boxes in their own frames, each found once (`None`: the prototype holds
/// nothing).
#[derive(Default)]
pub(super) struct PrototypeBoxes(HashMap<u32, Option<Bounds>>);

impl PrototypeBoxes {
    /// The box of everything prototype `p` of `prototypes` holds, in its own frame.
    fn of(&mut self, prototypes: &[Prototype], p: u32) -> Option<Bounds> {
        if let Some(&b) = self.0.get(&p) {
            return b;
        }
        let proto = &prototypes[p as usize];
        let mut b = contents_box(proto, &Mark::empty());
        // Nested prototypes come earlier in the list, so this ends.
        for inst in &proto.instances {
            if let Some(inner) = self.of(prototypes, inst.prototype) {
                b = union(b, placed_box(inner, &inst.transform.to_world));
            }
        }
        self.0.insert(p, b);
        b
    }
}

/// The union of two boxes, either missing.
fn union(a: Option<Bounds>, b: Bounds) -> Option<Bounds> {
    Some(a.map_or(b, |(lo, hi)| (lo.min(b.0), hi.max(b.1))))
}

/// The box of `b`'s eight corners placed by `m`.
fn placed_box((lo, hi): Bounds, m: &DAffine3) -> Bounds {
    let corners = (0..8).map(|i| {
        let pick = |bit: u32, l: f64, h: f64| if i & bit == 0 { l } else { h };
        m.transform_point3(DVec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        ))
    });
    corners.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), c| {
        (l.min(c), h.max(c))
    })
}

/// The box of the spheres, quadrics and meshes `level` holds past `mark` (not its instances).
fn contents_box(level: &Prototype, mark: &Mark) -> Option<Bounds> {
    let boxes = (level.spheres[mark.spheres..].iter().map(|s| s.bounds()))
        .chain(level.quadrics[mark.quadrics..].iter().map(|q| q.bounds()));
    let points = (level.meshes[mark.meshes..].iter())
        .flat_map(|m| m.positions().iter().map(|p| (p.as_dvec3(), p.as_dvec3())));
    boxes.chain(points).fold(None, union)
}

/// The largest coordinate magnitude of what `level` holds past `mark`, its instances placed,
/// where it exceeds [`MAX_COORDINATE`] (or is not a number); `None` within the limit. Values that
/// are not numbers are the loaders' and the scene's own checks to report.
pub(super) fn too_far(
    level: &Prototype,
    mark: &Mark,
    prototypes: &[Prototype],
    boxes: &mut PrototypeBoxes,
) -> Option<f64> {
    let mut b = contents_box(level, mark);
    for inst in &level.instances[mark.instances..] {
        if let Some(inner) = boxes.of(prototypes, inst.prototype) {
            b = union(b, placed_box(inner, &inst.transform.to_world));
        }
    }
    let (lo, hi) = b?;
    let reach = lo.abs().max(hi.abs()).max_element();
    (reach.is_nan() || reach > MAX_COORDINATE).then_some(reach)
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadray::{Instance, Sphere, Transform};

    /// A sphere far out is found directly, and through two levels of instances; one within the
    /// limit is not; what was there before the mark does not count.
    #[test]
    fn reach_is_found_through_instances() {
        let sphere = |x: f64| Sphere {
            center: DVec3::new(x, 0.0, 0.0),
            radius: 1.0,
            material: 0,
        };
        let mut boxes = PrototypeBoxes::default();
        let near = Prototype {
            spheres: vec![sphere(0.0)],
            ..Prototype::default()
        };
        let scaled = |s: f64| Transform::new(DAffine3::from_scale(DVec3::splat(s))).unwrap();
        let middle = Prototype {
            instances: vec![Instance::new(0, scaled(1e16))],
            ..Prototype::default()
        };
        let prototypes = [near, middle];
        let mut world = Prototype::default();
        let mark = Mark::of(&world);
        world.instances.push(Instance::new(1, scaled(1e15)));
        let reach = too_far(&world, &mark, &prototypes, &mut boxes).unwrap();
        assert!((reach / 1e31 - 1.0).abs() < 1e-9, "{reach:e}");
        // Past the mark only: the far instance is now behind it.
        let mark = Mark::of(&world);
        world.spheres.push(sphere(5.0));
        assert_eq!(too_far(&world, &mark, &prototypes, &mut boxes), None);
        world.spheres.push(sphere(2e30));
        assert!(too_far(&world, &mark, &prototypes, &mut boxes).is_some());
    }
}
