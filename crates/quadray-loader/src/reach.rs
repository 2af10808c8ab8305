//! How far from the origin what an item of a file (a glTF node, a native scene's shape) puts in
//! the world reaches, so that coordinates past quadray's limit ([`MAX_COORDINATE`]) are reported
//! with the item that put them there rather than, later, as the whole scene's.

use crate::framing::level_box;
use glam::DVec3;
use quadray::{Geometry, Level, MAX_COORDINATE, Prototype};

/// How much a level held before a node's contents were added to it.
#[derive(Default)]
pub(crate) struct Mark {
    spheres: usize,
    quadrics: usize,
    meshes: usize,
    instances: usize,
}

impl Mark {
    /// What `level` holds now.
    pub(crate) fn of(level: &Prototype) -> Mark {
        Mark::of_level(level_of(level))
    }

    /// What the world of `g` holds now.
    pub(crate) fn of_world(g: &Geometry) -> Mark {
        Mark::of_level(g.level(0))
    }

    fn of_level(level: Level<'_>) -> Mark {
        Mark {
            spheres: level.spheres.len(),
            quadrics: level.quadrics.len(),
            meshes: level.meshes.len(),
            instances: level.instances.len(),
        }
    }
}

/// A prototype as a level.
fn level_of(p: &Prototype) -> Level<'_> {
    Level {
        spheres: &p.spheres,
        quadrics: &p.quadrics,
        meshes: &p.meshes,
        instances: &p.instances,
    }
}

/// What `level` holds past `mark`.
fn since<'a>(level: Level<'a>, mark: &Mark) -> Level<'a> {
    Level {
        spheres: &level.spheres[mark.spheres..],
        quadrics: &level.quadrics[mark.quadrics..],
        meshes: &level.meshes[mark.meshes..],
        instances: &level.instances[mark.instances..],
    }
}

/// The prototypes' boxes in their own frames, by prototype (`None`: it holds nothing), each
/// found once. A prototype is complete once listed, and nests only earlier ones, so the list
/// grows in order.
#[derive(Default)]
pub(crate) struct PrototypeBoxes(Vec<Option<(DVec3, DVec3)>>);

impl PrototypeBoxes {
    /// The boxes of every prototype in `prototypes`.
    fn of_all(&mut self, prototypes: &[Prototype]) -> &[Option<(DVec3, DVec3)>] {
        for p in &prototypes[self.0.len().min(prototypes.len())..] {
            let b = level_box(level_of(p), &self.0);
            self.0.push(b);
        }
        &self.0
    }

    /// How far `next`, the prototype to follow `prototypes`, reaches in its own frame, where it
    /// passes [`MAX_COORDINATE`]; within the limit its box is kept, found once, for the caller
    /// to push `next` after `prototypes`.
    pub(crate) fn admit(&mut self, prototypes: &[Prototype], next: &Prototype) -> Option<Reach> {
        let bounds = level_box(level_of(next), self.of_all(prototypes));
        if let Some(reach) = bounds.and_then(reach_of) {
            return Some(reach);
        }
        self.0.push(bounds);
        None
    }
}

/// What an item put past [`MAX_COORDINATE`]: how far.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach {
    /// The largest coordinate magnitude.
    pub(crate) far: f64,
}

/// How far what `level` holds past `mark` reaches, its instances placed, where it passes
/// [`MAX_COORDINATE`]; `None` within the limit. Values that are not numbers are the loaders' and
/// the scene's own checks to report.
pub(crate) fn too_far(
    level: &Prototype,
    mark: &Mark,
    prototypes: &[Prototype],
    boxes: &mut PrototypeBoxes,
) -> Option<Reach> {
    reach_past(since(level_of(level), mark), prototypes, boxes)
}

/// [`too_far`] for what the world of `g` holds past `mark`, its instances placing `g`'s
/// prototypes, whose boxes `boxes` keeps from one call to the next.
pub(crate) fn too_far_in_world(
    g: &Geometry,
    mark: &Mark,
    boxes: &mut PrototypeBoxes,
) -> Option<Reach> {
    reach_past(since(g.level(0), mark), &g.prototypes, boxes)
}

/// How far `level` reaches, where it passes [`MAX_COORDINATE`].
fn reach_past(
    level: Level<'_>,
    prototypes: &[Prototype],
    boxes: &mut PrototypeBoxes,
) -> Option<Reach> {
    level_box(level, boxes.of_all(prototypes)).and_then(reach_of)
}

/// How far the box `(lo, hi)` reaches, where it passes [`MAX_COORDINATE`].
fn reach_of((lo, hi): (DVec3, DVec3)) -> Option<Reach> {
    let far = lo.abs().max(hi.abs()).max_element();
    (far > MAX_COORDINATE).then_some(Reach { far })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DAffine3;
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
        let reach = too_far(&world, &mark, &prototypes, &mut boxes).unwrap().far;
        assert!((reach / 1e31 - 1.0).abs() < 1e-9, "{reach:e}");
        // Past the mark only: the far instance is now behind it.
        let mark = Mark::of(&world);
        world.spheres.push(sphere(5.0));
        assert!(too_far(&world, &mark, &prototypes, &mut boxes).is_none());
        world.spheres.push(sphere(2e30));
        assert!(too_far(&world, &mark, &prototypes, &mut boxes).is_some());
    }

    /// A prototype admitted within the limit keeps its box, which what places it is then
    /// measured with; one whose own contents pass the limit is refused, and keeps none.
    #[test]
    fn admitted_prototypes_keep_their_boxes() {
        let ball = |x: f64| Prototype {
            spheres: vec![Sphere {
                center: DVec3::new(x, 0.0, 0.0),
                radius: 1.0,
                material: 0,
            }],
            ..Prototype::default()
        };
        let mut boxes = PrototypeBoxes::default();
        let mut prototypes = Vec::new();
        assert!(boxes.admit(&prototypes, &ball(3.0)).is_none());
        prototypes.push(ball(3.0));
        assert_eq!(boxes.0.len(), 1);
        let far = boxes
            .admit(&prototypes, &ball(2e30))
            .expect("past the limit");
        assert!((far.far / 2e30 - 1.0).abs() < 1e-9, "{}", far.far);
        assert_eq!(boxes.0.len(), 1);
        let mut world = Prototype::default();
        let mark = Mark::of(&world);
        let t = Transform::new(DAffine3::from_scale(DVec3::splat(1e30))).unwrap();
        world.instances.push(Instance::new(0, t));
        let reach = too_far(&world, &mark, &prototypes, &mut boxes).unwrap().far;
        assert!((reach / 4e30 - 1.0).abs() < 1e-9, "{reach:e}");
    }
}
