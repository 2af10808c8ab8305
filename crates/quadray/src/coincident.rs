//! Merging placements that coincide exactly: two instances of the same prototype, with the same
//! transform and the same material, draw the same surface, so one of them is dropped; and two
//! prototypes with equal contents are one prototype, so their placements can coincide too.
//!
//! Without this a small file multiplies work without bound: a group placing another twice at the
//! identity, chained twenty levels deep, is 2²⁰ placements of one sphere, and every ray through it
//! visits all of them. Merged, work follows what is visible, not what is repeated.

use crate::geometry::instance::Instance;
use crate::geometry::{Geometry, Prototype};
use std::collections::HashMap;
use std::hash::BuildHasher;

/// Merges the coincident placements of `g` (see the module documentation) and returns how many
/// instances were dropped. Prototypes made unused stay (nothing places them, so nothing draws
/// them); the world's own shapes are not touched.
pub fn merge_coincident(g: &mut Geometry) -> usize {
    let count = g.prototypes.len();
    // canonical[p]: the first prototype with p's contents (itself if none before).
    let mut canonical: Vec<u32> = (0..count as u32).collect();
    // Prototypes by a cheap key of their contents; equality is then checked in full.
    let mut by_key: HashMap<Key, Vec<u32>> = HashMap::new();
    let mut dropped = 0;
    for p in 0..count {
        dropped += canonicalise(&mut g.prototypes[p].instances, &canonical, p);
        let key = Key::of(&g.prototypes[p]);
        let same = by_key.get(&key).and_then(|candidates| {
            candidates
                .iter()
                .copied()
                .find(|&q| same_contents(&g.prototypes[q as usize], &g.prototypes[p]))
        });
        match same {
            Some(q) => canonical[p] = q,
            None => by_key.entry(key).or_default().push(p as u32),
        }
    }
    dropped + canonicalise(&mut g.instances, &canonical, count)
}

/// Points `instances` (those of prototype `limit`, or of the world when `limit` is the count) at
/// canonical prototypes and drops the repeats; returns how many were dropped. An instance of a
/// prototype at or past `limit` is invalid (a cycle) and is left for validation to report.
fn canonicalise(instances: &mut Vec<Instance>, canonical: &[u32], limit: usize) -> usize {
    for inst in instances.iter_mut() {
        if (inst.prototype as usize) < limit {
            inst.prototype = canonical[inst.prototype as usize];
        }
    }
    let before = instances.len();
    // Repeats found through a 64-bit hash of the exact bits, then confirmed with `==`, and
    // dropped in place: the first instance of each hash is remembered by its place among those
    // kept. An instance whose hash meets a different one (a collision, or equal values whose
    // zeros differ in sign) is kept and not remembered, which only costs a missed merge; the
    // hash's key is fixed, so which merges are missed is the same on every run. For a million
    // instances this takes 16 MB where a map from the bits to lists of places took 200 MB, and
    // no second array.
    let hasher = std::hash::BuildHasherDefault::<std::hash::DefaultHasher>::default();
    let mut first: HashMap<u64, u32> = HashMap::with_capacity(before);
    let mut kept = 0;
    for i in 0..before {
        let hash = hasher.hash_one(InstanceBits::of(&instances[i]));
        match first.get(&hash) {
            Some(&k) if instances[k as usize] == instances[i] => continue,
            Some(_) => {}
            None => {
                first.insert(hash, kept as u32);
            }
        }
        instances.swap(kept, i);
        kept += 1;
    }
    instances.truncate(kept);
    before - kept
}

fn same_contents(a: &Prototype, b: &Prototype) -> bool {
    a.instances == b.instances
        && a.spheres == b.spheres
        && a.quadrics == b.quadrics
        && a.meshes == b.meshes
}

/// What two prototypes with equal contents certainly share: their counts, their spheres, each
/// mesh's size and material, and what they place. Enough that prototypes which differ rarely
/// meet in one bucket, where they are compared in full (meshes vertex by vertex).
#[derive(Hash, PartialEq, Eq)]
struct Key {
    counts: [usize; 3],
    spheres: Vec<[u64; 5]>,
    meshes: Vec<(usize, usize, u32)>,
    instances: Vec<InstanceBits>,
}

impl Key {
    fn of(p: &Prototype) -> Key {
        Key {
            counts: [p.spheres.len(), p.quadrics.len(), p.meshes.len()],
            spheres: p
                .spheres
                .iter()
                .map(|s| {
                    let [x, y, z] = s.center.to_array().map(f64::to_bits);
                    [x, y, z, s.radius.to_bits(), u64::from(s.material)]
                })
                .collect(),
            meshes: p
                .meshes
                .iter()
                .map(|m| (m.triangle_count(), m.positions().len(), m.material()))
                .collect(),
            instances: p.instances.iter().map(InstanceBits::of).collect(),
        }
    }
}

/// An instance's prototype, material and transform bits, for hashing. Equal instances have equal
/// bits except for the sign of a zero, which `==` then sorts out (such instances are not merged
/// by the hash, which only costs a missed merge).
#[derive(Hash, PartialEq, Eq)]
struct InstanceBits {
    prototype: u32,
    material: Option<u32>,
    matrix: [u64; 12],
}

impl InstanceBits {
    fn of(inst: &Instance) -> InstanceBits {
        let m = inst.transform.to_world;
        let columns = [
            m.matrix3.x_axis,
            m.matrix3.y_axis,
            m.matrix3.z_axis,
            m.translation,
        ];
        let mut matrix = [0u64; 12];
        for (k, v) in columns.iter().flat_map(|c| c.to_array()).enumerate() {
            matrix[k] = v.to_bits();
        }
        InstanceBits {
            prototype: inst.prototype,
            material: inst.material,
            matrix,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Transform;
    use crate::sphere::Sphere;
    use glam::DVec3;

    fn sphere() -> Sphere {
        Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            material: 0,
        }
    }

    /// A chain of groups each placing the one below twice at the identity: 2^levels placements.
    fn doubling_chain(levels: usize) -> Geometry {
        let mut g = Geometry::default();
        g.prototypes.push(Prototype {
            spheres: vec![sphere()],
            ..Prototype::default()
        });
        for k in 0..levels as u32 {
            g.prototypes.push(Prototype {
                instances: vec![Instance::new(k, Transform::IDENTITY); 2],
                ..Prototype::default()
            });
        }
        g.instances = vec![Instance::new(levels as u32, Transform::IDENTITY)];
        g
    }

    #[test]
    fn a_doubling_chain_becomes_one_placement() {
        let mut g = doubling_chain(30);
        // The numbering counts every node of the expanded tree, the world's included.
        assert!(crate::Placements::new(&g).unwrap().count() > 1 << 30);
        assert_eq!(merge_coincident(&mut g), 30);
        assert_eq!(crate::Placements::new(&g).unwrap().count(), 32);
    }

    /// Two prototypes with the same contents count as one, so their placements merge too.
    #[test]
    fn equal_prototypes_are_one() {
        let mut g = Geometry::default();
        for _ in 0..2 {
            g.prototypes.push(Prototype {
                spheres: vec![sphere()],
                ..Prototype::default()
            });
        }
        g.instances = vec![
            Instance::new(0, Transform::IDENTITY),
            Instance::new(1, Transform::IDENTITY),
        ];
        assert_eq!(merge_coincident(&mut g), 1);
        assert_eq!(g.instances, vec![Instance::new(0, Transform::IDENTITY)]);
    }

    /// Placements that differ in anything visible stay: transform, material, prototype.
    #[test]
    fn different_placements_stay() {
        let mut g = Geometry::default();
        g.prototypes.push(Prototype {
            spheres: vec![sphere()],
            ..Prototype::default()
        });
        g.prototypes.push(Prototype {
            spheres: vec![Sphere {
                radius: 2.0,
                ..sphere()
            }],
            ..Prototype::default()
        });
        let moved = Transform::new(glam::DAffine3::from_translation(DVec3::new(
            1e-12, 0.0, 0.0,
        )))
        .unwrap();
        let recoloured = Instance {
            material: Some(1),
            ..Instance::new(0, Transform::IDENTITY)
        };
        g.instances = vec![
            Instance::new(0, Transform::IDENTITY),
            Instance::new(0, moved),
            recoloured,
            Instance::new(1, Transform::IDENTITY),
        ];
        let before = g.instances.clone();
        assert_eq!(merge_coincident(&mut g), 0);
        assert_eq!(g.instances, before);
    }
}
