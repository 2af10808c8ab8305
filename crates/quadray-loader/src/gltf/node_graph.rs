//! Who references whom among the nodes a glTF scene's roots reach: counted once per node (not per
//! path), with cycles, repeated indices and depth refused, and each node's and mesh's expanded
//! placement count, before anything is built.

use super::graph::MAX_DEPTH;
use crate::error::LoadError;
use crate::gltf::quadrics_ext::{self, NodeExtension, RootExtension};
use std::collections::HashMap;
use std::path::Path;

/// Who references whom among the nodes the chosen roots reach.
pub(super) struct NodeGraph {
    /// References to each node from reached parents and from the roots.
    pub(super) refs: Vec<u32>,
    /// Nodes using each mesh (without a `QUADRAY_quadrics` shape, which replaces the mesh).
    pub(super) mesh_users: Vec<u32>,
    /// Nodes using each `QUADRAY_quadrics` shape.
    pub(super) shape_users: HashMap<usize, u32>,
    /// Whether a node's subtree holds a camera, a light or a `QUADRAY_quadrics` plane: what is
    /// placed on every path that reaches it.
    pub(super) has_camera_or_light: Vec<bool>,
    /// Per node, its children whose subtrees hold one (`has_camera_or_light`), in file order: the
    /// walk of cameras and lights visits only these, so a wide node is not scanned on every path
    /// through it.
    pub(super) lit_children: Vec<Vec<usize>>,
    /// Placements of each node once the graph is expanded (saturating).
    pub(super) placements: Vec<u64>,
    /// Placements of each mesh: its nodes' placements summed.
    pub(super) mesh_placements: Vec<u64>,
    /// The `QUADRAY_quadrics` shape each reached node carries, read once.
    pub(super) node_shapes: Vec<Option<usize>>,
}

/// The `QUADRAY_quadrics` shape a node carries, if any.
fn node_shape(node: &gltf::Node<'_>, path: &Path) -> Result<Option<NodeExtension>, LoadError> {
    node.extension_value(quadrics_ext::EXTENSION)
        .map(|v| {
            let key = format!(
                "nodes[{}].extensions.{}",
                node.index(),
                quadrics_ext::EXTENSION
            );
            quadrics_ext::read_extension::<NodeExtension>(v, &key)
                .map_err(|(key, message)| LoadError::invalid(path, None, key, message))
        })
        .transpose()
}

/// An error at the JSON path `at()` if `indices` names a node twice: glTF's schema makes a node's
/// `children` and a scene's `nodes` `uniqueItems`, and a repeat would place the same subtree twice
/// at the same transform (repeated at every level, 2^levels times: a 62-node file rendered for
/// hours).
pub(crate) fn refuse_repeats(
    indices: impl Iterator<Item = usize>,
    at: impl Fn() -> String,
    path: &Path,
) -> Result<(), LoadError> {
    let mut seen = std::collections::HashSet::new();
    for (k, index) in indices.enumerate() {
        if !seen.insert(index) {
            return Err(LoadError::invalid(
                path,
                None,
                format!("{}[{k}]", at()),
                format!("node {index} is listed twice; glTF requires these indices to be unique"),
            ));
        }
    }
    Ok(())
}

impl NodeGraph {
    /// Walks the graph from `roots` once per node (not per path), rejecting cycles and depth
    /// beyond [`MAX_DEPTH`].
    pub(super) fn new(
        doc: &gltf::Document,
        roots: &[gltf::Node<'_>],
        shapes: &RootExtension,
        path: &Path,
    ) -> Result<NodeGraph, LoadError> {
        let n = doc.nodes().len();
        let mut g = NodeGraph {
            refs: vec![0; n],
            mesh_users: vec![0; doc.meshes().len()],
            shape_users: HashMap::new(),
            has_camera_or_light: vec![false; n],
            lit_children: vec![Vec::new(); n],
            placements: vec![0; n],
            mesh_placements: vec![0; doc.meshes().len()],
            node_shapes: vec![None; n],
        };
        // Iterative depth-first search: 0 unseen, 1 on the current path, 2 done. `order` lists
        // nodes finished, children before parents.
        let mut state = vec![0u8; n];
        let mut order = Vec::new();
        // Nodes in state 1: the depth of the current path (waiting siblings do not count).
        let mut open = 0usize;
        for root in roots {
            g.refs[root.index()] += 1;
            g.placements[root.index()] = g.placements[root.index()].saturating_add(1);
            if state[root.index()] != 0 {
                continue;
            }
            let mut stack: Vec<(gltf::Node<'_>, bool)> = vec![(root.clone(), false)];
            while let Some((node, finished)) = stack.pop() {
                let i = node.index();
                if finished {
                    state[i] = 2;
                    open -= 1;
                    order.push(i);
                    continue;
                }
                if state[i] != 0 {
                    continue;
                }
                state[i] = 1;
                open += 1;
                if open > MAX_DEPTH {
                    return Err(LoadError::invalid(
                        path,
                        None,
                        format!("nodes[{i}]"),
                        format!("the node hierarchy is deeper than {MAX_DEPTH} levels"),
                    ));
                }
                stack.push((node.clone(), true));
                let mut has_plane = false;
                g.node_shapes[i] = node_shape(&node, path)?.map(|ext| ext.shape);
                match g.node_shapes[i] {
                    Some(shape) => {
                        *g.shape_users.entry(shape).or_default() += 1;
                        has_plane = shapes.shapes.get(shape).is_some_and(|d| d.kind == "plane");
                    }
                    None => {
                        if let Some(mesh) = node.mesh() {
                            g.mesh_users[mesh.index()] += 1;
                        }
                    }
                }
                g.has_camera_or_light[i] =
                    node.camera().is_some() || node.light().is_some() || has_plane;
                refuse_repeats(
                    node.children().map(|c| c.index()),
                    || format!("nodes[{i}].children"),
                    path,
                )?;
                for child in node.children() {
                    let c = child.index();
                    g.refs[c] += 1;
                    if state[c] == 1 {
                        return Err(LoadError::invalid(
                            path,
                            None,
                            format!("nodes[{i}].children"),
                            format!("node {c} contains itself (through node {i}): a cycle"),
                        ));
                    }
                    stack.push((child, false));
                }
            }
        }
        g.propagate(doc, &order);
        Ok(g)
    }

    /// Pushes placement counts down from parents to children and meshes, and pulls "holds a
    /// camera or light" up, over `order`, the reached nodes children before parents.
    fn propagate(&mut self, doc: &gltf::Document, order: &[usize]) {
        // Parents after children in `order`: walk it backwards to push placements down, and
        // forwards to pull "holds a camera or light" up.
        for &i in order.iter().rev() {
            let node = doc.nodes().nth(i).expect("reached nodes exist");
            for child in node.children() {
                let c = child.index();
                self.placements[c] = self.placements[c].saturating_add(self.placements[i]);
            }
        }
        for &i in order {
            let node = doc.nodes().nth(i).expect("reached nodes exist");
            if let (Some(mesh), None) = (node.mesh(), self.node_shapes[i]) {
                let p = &mut self.mesh_placements[mesh.index()];
                *p = p.saturating_add(self.placements[i]);
            }
            let lit: Vec<usize> = (node.children())
                .map(|c| c.index())
                .filter(|&c| self.has_camera_or_light[c])
                .collect();
            if !lit.is_empty() {
                self.has_camera_or_light[i] = true;
                self.lit_children[i] = lit;
            }
        }
    }
}
