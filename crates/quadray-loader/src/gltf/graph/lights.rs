//! Cameras and lights, placed on every path of the node graph that reaches them (their
//! subtrees walked expanded, and only those), with the planes under nodes placed more than once.

use super::{GraphBuild, MAX_DEPTH, MAX_INSTANCES};
use crate::error::LoadError;
use crate::gltf::{camera as gltf_camera, light as gltf_light};
use crate::import::Imported;
use glam::DAffine3;
use gltf::khr_lights_punctual::Kind;
use quadray::{MAX_COORDINATE, Prototype};

impl GraphBuild<'_> {
    /// Cameras and lights of `root`'s subtree, placed under `to_world`, on every path that
    /// reaches them, and the planes under nodes placed more than once. Walked depth first in the
    /// file's order, on a stack of its own (not the thread's).
    pub(super) fn place_cameras_and_lights(
        &mut self,
        root: &gltf::Node<'_>,
        to_world: DAffine3,
        out: &mut Imported,
    ) -> Result<(), LoadError> {
        // The next node to visit, with its parent's map to the world, depth and whether a node
        // above it is shared; then, for each visited node, its children that hold a camera or
        // light (`lit_children`) with how many were visited, its own map and whether it is shared.
        let mut next = Some((root.index(), to_world, 0, false));
        let mut left: Vec<(usize, usize, DAffine3, usize, bool)> = Vec::new();
        loop {
            if let Some((node, to_world, depth, shared_above)) = next.take()
                && self.graph.has_camera_or_light[node]
                && depth < MAX_DEPTH
            {
                let node = self
                    .file
                    .document
                    .nodes()
                    .nth(node)
                    .expect("a reached node");
                let (world, shared) =
                    self.place_camera_or_light(&node, to_world, out, shared_above)?;
                left.push((node.index(), 0, world, depth + 1, shared));
            }
            let Some((node, visited, world, depth, shared)) = left.last_mut() else {
                return Ok(());
            };
            match self.graph.lit_children[*node].get(*visited) {
                Some(&child) => {
                    *visited += 1;
                    next = Some((child, *world, *depth, *shared));
                }
                None => {
                    left.pop();
                }
            }
        }
    }

    /// `node`'s own camera, light, or plane under a shared node, its parent's frame mapped to
    /// the world by `to_world`; returns its own frame's map and whether it or a node above it
    /// (`shared_above`) is placed more than once.
    fn place_camera_or_light(
        &mut self,
        node: &gltf::Node<'_>,
        to_world: DAffine3,
        out: &mut Imported,
        shared_above: bool,
    ) -> Result<(DAffine3, bool), LoadError> {
        self.camera_light_placements += 1;
        if self.camera_light_placements > MAX_INSTANCES {
            return Err(self.invalid(
                format!("nodes[{}]", node.index()),
                format!(
                    "cameras, lights and planes under nodes placed more than once expand to more \
                     than {MAX_INSTANCES} placements"
                ),
            ));
        }
        let world = to_world * self.local_transform(node)?;
        let shared = shared_above || self.graph.refs[node.index()] > 1;
        if let (true, Some(shape)) = (shared, self.graph.node_shapes[node.index()]) {
            let key = format!("nodes[{}]", node.index());
            if self
                .shapes
                .shapes
                .get(shape)
                .is_some_and(|d| d.kind == "plane")
            {
                let mut p = Prototype::default();
                let mut planes = Vec::new();
                let mut none = Vec::new();
                self.place_shape(shape, world, &key, &mut p, Some(&mut planes), &mut none)?;
                out.geometry.planes.append(&mut planes);
            }
        }
        // A camera, point or spot light placed past the limit is its node's transform's fault
        // (where a directional light stands does not matter).
        let placed = match (node.camera(), node.light()) {
            (Some(_), _) => Some("the camera"),
            (None, Some(light)) if !matches!(light.kind(), Kind::Directional) => Some("the light"),
            _ => None,
        };
        // `max_element` passes over a NaN (an overflowed product times a zero), which is past
        // every limit.
        let reach = match world.translation.is_finite() {
            true => world.translation.abs().max_element(),
            false => f64::INFINITY,
        };
        if let Some(what) = placed
            && reach > MAX_COORDINATE
        {
            let key = format!("nodes[{}]", node.index());
            return Err(self.placed_too_far(&key, what, reach));
        }
        if let Some(camera) = node.camera() {
            let c = gltf_camera::convert(&camera, self.file.cameras.get(camera.index()), world)
                .map_err(|m| self.invalid(format!("cameras[{}]", camera.index()), m))?;
            out.cameras.push(c);
        }
        if let Some(light) = node.light() {
            let l = gltf_light::convert(&light, world).map_err(|m| {
                self.invalid(
                    format!("extensions.KHR_lights_punctual.lights[{}]", light.index()),
                    m,
                )
            })?;
            self.range_ignored |= light.range().is_some();
            self.brightest = self.brightest.max(light.intensity());
            out.lights.push(l);
        }
        Ok((world, shared))
    }
}
