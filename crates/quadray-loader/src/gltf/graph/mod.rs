//! A glTF scene's node graph turned into quadray's levels, without expanding it.
//!
//! - A node referenced more than once (glTF asks for trees, but files reuse nodes) becomes one
//!   [`Prototype`] holding its subtree in its own frame, placed by an [`Instance`] per reference:
//!   a node DAG that expands to millions of placements loads in the time of its own size.
//! - A mesh, or a `QUADRAY_quadrics` shape, used by several nodes becomes a prototype of its own,
//!   placed by each node; one used once is placed in its level directly (baked), as before.
//! - Cameras and lights are placed on every path that reaches them (their subtrees are walked
//!   expanded, and only those).

use crate::error::LoadError;
use crate::gltf::document::GltfFile;
use crate::gltf::material::{MaterialUse, Materials};
use crate::gltf::mesh::{self as gltf_mesh, BuildError};
use crate::gltf::node_graph::NodeGraph;
use crate::gltf::quadrics_ext::{self, RootExtension};
use crate::import::{Imported, PlacedShape};
use crate::reach::{self, Mark, PrototypeBoxes};
use glam::DAffine3;
use quadray::{Instance, MAX_COORDINATE, Plane, Prototype, Transform};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

mod lights;

/// Deepest node hierarchy accepted; deeper means a cycle (which glTF forbids) or an absurd file.
pub const MAX_DEPTH: usize = 1024;
/// Most placements of cameras, lights and planes under shared nodes one scene may expand to.
pub const MAX_INSTANCES: usize = 1 << 20;
/// Most triangles one import may store (about 20 GB of meshes and BVH).
pub const MAX_TRIANGLES: usize = 200_000_000;

/// The build of one scene's levels.
pub(crate) struct GraphBuild<'a> {
    file: &'a GltfFile,
    path: &'a Path,
    shapes: &'a RootExtension,
    skip_materials: bool,
    /// Whether what a node places in the world is checked against [`MAX_COORDINATE`] here:
    /// not when the file is placed by a transform of its includer's (a native scene's
    /// `[[include]]` or `[[mesh]]`), which checks what the file places through it, and can tell
    /// the transform's fault from the file's.
    checks_reach: bool,
    graph: NodeGraph,
    /// Node, mesh and shape prototypes built so far.
    node_protos: HashMap<usize, Option<u32>>,
    mesh_protos: HashMap<usize, u32>,
    shape_protos: HashMap<usize, u32>,
    /// The prototypes' boxes, for the reach of instances placed in the world.
    prototype_boxes: PrototypeBoxes,
    /// The materials met so far.
    pub(crate) materials: Materials<'a>,
    /// Notes for the user.
    pub(crate) notes: Vec<String>,
    /// Primitives skipped by mode.
    pub(crate) skipped_modes: BTreeMap<&'static str, usize>,
    /// What was not evaluated (skins, morph targets).
    pub(crate) rest_pose: Vec<&'static str>,
    /// Triangles dropped for a repeated vertex index, as instanced.
    pub(crate) degenerate: usize,
    triangles: usize,
    camera_light_placements: usize,
    /// Brightest light intensity, and whether a light's range was ignored.
    pub(crate) brightest: f32,
    /// Whether some light's `range` was ignored.
    pub(crate) range_ignored: bool,
}

impl<'a> GraphBuild<'a> {
    /// Prepares the build of the scene with `roots`.
    pub(crate) fn new(
        file: &'a GltfFile,
        path: &'a Path,
        roots: &[gltf::Node<'_>],
        shapes: &'a RootExtension,
        options: &crate::ImportOptions,
    ) -> Result<GraphBuild<'a>, LoadError> {
        Ok(GraphBuild {
            file,
            path,
            shapes,
            skip_materials: options.skip_materials,
            checks_reach: options.transform.is_none(),
            graph: NodeGraph::new(&file.document, roots, shapes, path)?,
            node_protos: HashMap::new(),
            mesh_protos: HashMap::new(),
            shape_protos: HashMap::new(),
            prototype_boxes: PrototypeBoxes::default(),
            materials: Materials::new(file, options.textures.clone()),
            notes: Vec::new(),
            skipped_modes: BTreeMap::new(),
            rest_pose: Vec::new(),
            degenerate: 0,
            triangles: 0,
            camera_light_placements: 0,
            brightest: 0.0,
            range_ignored: false,
        })
    }

    fn invalid(&self, key: String, message: impl Into<String>) -> LoadError {
        LoadError::invalid(self.path, None, key, message.into())
    }

    /// Node placements once the graph is expanded (what the file stands for, saturating).
    pub(crate) fn node_placements(&self) -> u64 {
        self.graph
            .placements
            .iter()
            .fold(0u64, |s, &p| s.saturating_add(p))
    }

    /// Places `roots` under `root` into `out`'s world.
    pub(crate) fn place_roots(
        &mut self,
        roots: &[gltf::Node<'_>],
        root: DAffine3,
        out: &mut Imported,
    ) -> Result<(), LoadError> {
        let mut walk = Walk {
            steps: Vec::new(),
            levels: vec![Prototype::default()],
            planes: Vec::new(),
            prototypes: Vec::new(),
        };
        for node in roots {
            walk.steps.push(Step::Node {
                node: node.clone(),
                to_level: root,
                depth: 0,
            });
            self.walk(&mut walk)?;
            self.place_cameras_and_lights(node, root, out)?;
        }
        let Walk {
            mut levels,
            mut planes,
            prototypes,
            ..
        } = walk;
        let world = &mut levels[WORLD];
        let g = &mut out.geometry;
        g.spheres.append(&mut world.spheres);
        g.quadrics.append(&mut world.quadrics);
        g.meshes.append(&mut world.meshes);
        g.instances.append(&mut world.instances);
        g.planes.append(&mut planes);
        g.prototypes = prototypes;
        Ok(())
    }

    /// Takes `walk`'s steps until none is left: the depth-first walk, in the file's order, that
    /// a recursion a node at a time would make.
    fn walk(&mut self, walk: &mut Walk<'_>) -> Result<(), LoadError> {
        while let Some(step) = walk.steps.pop() {
            match step {
                Step::Node {
                    node,
                    to_level,
                    depth,
                } => self.place_node(node, to_level, depth, walk)?,
                Step::Children {
                    mut children,
                    to_level,
                    depth,
                } => {
                    if let Some(node) = children.next() {
                        walk.steps.push(Step::Children {
                            children,
                            to_level,
                            depth,
                        });
                        self.place_node(node, to_level, depth, walk)?;
                    }
                }
                Step::Close { node, placed } => self.close_prototype(node, placed, walk)?,
            }
        }
        Ok(())
    }

    /// Places `node` in the walk's innermost open level, its parent's frame mapped into that
    /// level by `to_level`: a node used more than once as an instance of its prototype (opened
    /// here the first time, its contents walked before it closes), any other directly.
    fn place_node<'d>(
        &mut self,
        node: gltf::Node<'d>,
        to_level: DAffine3,
        depth: usize,
        walk: &mut Walk<'d>,
    ) -> Result<(), LoadError> {
        let placed = to_level * self.local_transform(&node)?;
        if self.graph.refs[node.index()] <= 1 {
            return self.place_contents(node, placed, depth, walk);
        }
        match self.node_protos.get(&node.index()) {
            Some(&proto) => self.instance_in_level(proto, placed, node.index(), walk),
            None => {
                walk.steps.push(Step::Close {
                    node: node.index(),
                    placed,
                });
                walk.levels.push(Prototype::default());
                self.place_contents(node, DAffine3::IDENTITY, depth, walk)
            }
        }
    }

    /// Closes the walk's innermost level, the prototype of shared node `node`, and places it by
    /// `placed` in the level around it (an empty prototype is dropped, and places nothing).
    fn close_prototype(
        &mut self,
        node: usize,
        placed: DAffine3,
        walk: &mut Walk<'_>,
    ) -> Result<(), LoadError> {
        let p = walk.levels.pop().expect("a closed prototype was opened");
        let proto = (!is_empty(&p)).then(|| {
            walk.prototypes.push(p);
            walk.prototypes.len() as u32 - 1
        });
        self.node_protos.insert(node, proto);
        self.instance_in_level(proto, placed, node, walk)
    }

    /// An instance of node `node`'s prototype `proto` (if it places anything) placed by `placed`
    /// in the walk's innermost level, checked for its reach there when that is the world.
    fn instance_in_level(
        &mut self,
        proto: Option<u32>,
        placed: DAffine3,
        node: usize,
        walk: &mut Walk<'_>,
    ) -> Result<(), LoadError> {
        let Some(proto) = proto else {
            return Ok(());
        };
        let key = format!("nodes[{node}]");
        let in_world = walk.levels.len() - 1 == WORLD;
        let out = walk.levels.last_mut().expect("the world is open");
        let mark = Mark::of(out);
        self.instance(proto, placed, &key, out);
        if in_world {
            self.check_reach(&key, out, &mark, &walk.prototypes)?;
        }
        Ok(())
    }

    /// The node's own transform (its matrix, or translation · rotation · scale).
    fn local_transform(&self, node: &gltf::Node<'_>) -> Result<DAffine3, LoadError> {
        self.file
            .node_transforms
            .get(node.index())
            .cloned()
            .unwrap_or(Ok(DAffine3::IDENTITY))
            .map_err(|m| self.invalid(format!("nodes[{}]", node.index()), m))
    }

    /// An error naming node `key` where what it added to the world's `out` past `mark` (its own
    /// shape, mesh or instance) reaches past [`MAX_COORDINATE`].
    fn check_reach(
        &mut self,
        key: &str,
        out: &Prototype,
        mark: &Mark,
        prototypes: &[Prototype],
    ) -> Result<(), LoadError> {
        if !self.checks_reach {
            return Ok(());
        }
        match reach::too_far(out, mark, prototypes, &mut self.prototype_boxes) {
            None => Ok(()),
            Some(reach::Reach { far, .. }) => Err(self.placed_too_far(key, "its contents", far)),
        }
    }

    /// The error of node `key`, whose transform with its parents' places `what` (its contents,
    /// its camera or its light) at coordinates up to `reach`, past [`MAX_COORDINATE`].
    fn placed_too_far(&self, key: &str, what: &str, reach: f64) -> LoadError {
        // Under an includer's transform, that transform may be the one at fault.
        let by = match self.checks_reach {
            true => "its transform, with its parents',",
            false => "its transform, with its parents' and the one the file is placed by,",
        };
        self.invalid(
            key.to_string(),
            format!(
                "{by} places {what} at coordinates up to {reach:.3e}; quadray supports \
                 magnitudes up to {MAX_COORDINATE:e}"
            ),
        )
    }

    /// The note that node `key`'s singular transform hides what it places.
    fn note_hidden(&mut self, key: &str) {
        self.notes.push(format!(
            "{key}: a singular transform (a zero scale) hides what the node places"
        ));
    }

    /// An instance of `proto` placed by `m` (a singular map hides it, as it would a baked mesh).
    fn instance(&mut self, proto: u32, m: DAffine3, key: &str, out: &mut Prototype) {
        match Transform::new(m) {
            Some(t) => out.instances.push(Instance::new(proto, t)),
            None => self.note_hidden(key),
        }
    }

    /// The node's own shape or mesh placed by `m` in the walk's innermost level, and the step of
    /// its children (`depth` + 1) below it.
    fn place_contents<'d>(
        &mut self,
        node: gltf::Node<'d>,
        m: DAffine3,
        depth: usize,
        walk: &mut Walk<'d>,
    ) -> Result<(), LoadError> {
        let key = format!("nodes[{}]", node.index());
        if depth >= MAX_DEPTH {
            return Err(self.invalid(
                key,
                format!("the node hierarchy is deeper than {MAX_DEPTH} levels"),
            ));
        }
        // A zero scale hides the node and everything below it (glTF's way to hide a node), as it
        // hides an instance: one note for the node, none for its descendants, which it flattens
        // too. A map that is not finite is left to the checks of how far things reach.
        if m.is_finite() && !Transform::is_invertible(&m) {
            self.note_hidden(&key);
            return Ok(());
        }
        let in_world = walk.levels.len() - 1 == WORLD;
        let out = walk.levels.last_mut().expect("the world is open");
        let planes = in_world.then_some(&mut walk.planes);
        let prototypes = &mut walk.prototypes;
        let mark = Mark::of(out);
        if let Some(shape) = self.graph.node_shapes[node.index()] {
            self.place_shape(shape, m, &key, out, planes, prototypes)?;
        } else if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                self.rest_pose.push("skins");
            }
            if self.graph.mesh_users[mesh.index()] > 1 {
                let proto = match self.mesh_protos.get(&mesh.index()) {
                    Some(&p) => p,
                    None => {
                        let mut p = Prototype::default();
                        let copies = self.graph.mesh_placements[mesh.index()];
                        self.build_mesh(&mesh, DAffine3::IDENTITY, &key, &mut p, copies)?;
                        prototypes.push(p);
                        let index = prototypes.len() as u32 - 1;
                        self.mesh_protos.insert(mesh.index(), index);
                        index
                    }
                };
                self.instance(proto, m, &key, out);
            } else {
                let copies = self.graph.placements[node.index()];
                self.build_mesh(&mesh, m, &key, out, copies)?;
            }
        }
        // In the world (where `planes` go), what the node placed itself is checked here, so the
        // error can name the node.
        if in_world {
            self.check_reach(&key, out, &mark, prototypes)?;
        }
        walk.steps.push(Step::Children {
            children: node.children(),
            to_level: m,
            depth: depth + 1,
        });
        Ok(())
    }

    /// `QUADRAY_quadrics` shape `shape` placed by `m`: an instance of its prototype when several
    /// nodes use it (a plane, unbounded, is always placed in the world).
    fn place_shape(
        &mut self,
        shape: usize,
        m: DAffine3,
        key: &str,
        out: &mut Prototype,
        planes: Option<&mut Vec<Plane>>,
        prototypes: &mut Vec<Prototype>,
    ) -> Result<(), LoadError> {
        let ext_key = format!("{key}.extensions.{}.shape", quadrics_ext::EXTENSION);
        let def = self.shapes.shapes.get(shape).ok_or_else(|| {
            self.invalid(
                ext_key.clone(),
                format!(
                    "shape {shape} does not exist ({} defined)",
                    self.shapes.shapes.len()
                ),
            )
        })?;
        let material = match def.material {
            _ if self.skip_materials => 0,
            Some(i) => {
                let doc = &self.file.document;
                let mat = doc.materials().nth(i).ok_or_else(|| {
                    self.invalid(
                        ext_key.clone(),
                        format!("shape {shape} uses material {i}, which does not exist"),
                    )
                })?;
                // The material's own error is located at the material, not at its user.
                self.materials
                    .get(&mat, &mut self.notes)
                    .map_err(|m| self.invalid(format!("materials[{i}]"), m))?
                    .id
            }
            None => self.materials.default_material().id,
        };
        let def_key = format!("extensions.{}.shapes[{shape}]", quadrics_ext::EXTENSION);
        let shared = self.graph.shape_users.get(&shape).is_some_and(|&n| n > 1);
        let is_plane = def.kind == "plane";
        if is_plane && planes.is_none() {
            // Under a node placed more than once: the expanded walk places it on every path.
            return Ok(());
        }
        if shared && !is_plane {
            let proto = match self.shape_protos.get(&shape) {
                Some(&p) => p,
                None => {
                    let mut p = Prototype::default();
                    let placed = quadrics_ext::place(def, DAffine3::IDENTITY, material)
                        .map_err(|e| self.invalid(def_key.clone(), e))?;
                    add_shape(placed, &mut p, None).map_err(|e| self.invalid(def_key, e))?;
                    prototypes.push(p);
                    let index = prototypes.len() as u32 - 1;
                    self.shape_protos.insert(shape, index);
                    index
                }
            };
            self.instance(proto, m, key, out);
            return Ok(());
        }
        let placed = quadrics_ext::place(def, m, material).map_err(|e| self.invalid(def_key, e))?;
        add_shape(placed, out, planes).map_err(|e| self.invalid(key.to_string(), e))
    }

    /// Every surface primitive of `mesh`, placed by `m` (node `key`'s map), into `out`, which
    /// the expanded scene holds `copies` times (for the count of dropped triangles).
    fn build_mesh(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        m: DAffine3,
        key: &str,
        out: &mut Prototype,
        copies: u64,
    ) -> Result<(), LoadError> {
        if mesh.primitives().next().is_none() {
            return Err(self.invalid(
                format!("meshes[{}].primitives", mesh.index()),
                "a mesh needs at least one primitive (glTF requires it)",
            ));
        }
        if mesh
            .primitives()
            .any(|p| p.morph_targets().next().is_some())
        {
            self.rest_pose.push("morph targets");
        }
        for primitive in mesh.primitives() {
            let pkey = format!("meshes[{}].primitives[{}]", mesh.index(), primitive.index());
            if !gltf_mesh::is_surface(primitive.mode()) {
                *self
                    .skipped_modes
                    .entry(gltf_mesh::mode_name(primitive.mode()))
                    .or_default() += 1;
                continue;
            }
            let material = if self.skip_materials {
                // Geometry only: the scene's material, seen from both sides like every native
                // surface.
                MaterialUse {
                    id: 0,
                    mask: None,
                    uv_transform: None,
                    single_sided: false,
                    normal_map: None,
                }
            } else {
                let used = primitive.material();
                // The material's own error is located at the material, not at its user.
                let key = match used.index() {
                    Some(i) => format!("materials[{i}]"),
                    None => pkey.clone(),
                };
                self.materials
                    .get(&used, &mut self.notes)
                    .map_err(|e| self.invalid(key, e))?
            };
            let built =
                gltf_mesh::build(&primitive, self.file, m, &material).map_err(|e| match e {
                    BuildError::Data(message) => self.invalid(pkey.clone(), message),
                    BuildError::PlacedTooFar { reach } => {
                        self.placed_too_far(key, "its contents", reach)
                    }
                })?;
            if let Some(why) = built.normal_map_skipped {
                self.notes
                    .push(format!("{pkey}: normal map left off: {why}"));
            }
            let dropped = (built.degenerate as u64).saturating_mul(copies);
            self.degenerate = self
                .degenerate
                .saturating_add(usize::try_from(dropped).unwrap_or(usize::MAX));
            if let Some(mesh) = built.mesh {
                self.triangles += mesh.triangle_count();
                if self.triangles > MAX_TRIANGLES {
                    return Err(self.invalid(
                        pkey,
                        format!("the scene stores more than {MAX_TRIANGLES} triangles"),
                    ));
                }
                out.meshes.push(mesh);
            }
        }
        Ok(())
    }
}

/// The index of the world among a walk's open levels.
const WORLD: usize = 0;

/// The state of the walk that places a scene's nodes ([`GraphBuild::place_roots`]): an explicit
/// stack of steps instead of a recursion a node at a time, whose frames took megabytes of a
/// thread's stack on a chain [`MAX_DEPTH`] nodes deep.
struct Walk<'d> {
    /// What is left to do, the next step last.
    steps: Vec<Step<'d>>,
    /// The levels being filled: the world first, then the prototypes of the shared nodes being
    /// walked, each inside the one before it; steps place into the last.
    levels: Vec<Prototype>,
    /// The world's planes.
    planes: Vec<Plane>,
    /// The finished prototypes.
    prototypes: Vec<Prototype>,
}

/// One step of a [`Walk`].
enum Step<'d> {
    /// Place `node` in the innermost open level, its parent's frame mapped into that level by
    /// `to_level`, `depth` nodes below a root.
    Node {
        node: gltf::Node<'d>,
        to_level: DAffine3,
        depth: usize,
    },
    /// Place the nodes `children` has left, one at a time (each child's own steps come before
    /// its next sibling's), `depth` nodes below a root, their parent's frame mapped into the
    /// innermost open level by `to_level`. A node's children wait as their iterator, so a node
    /// of a million children takes one step, not a million.
    Children {
        children: gltf::scene::iter::Children<'d>,
        to_level: DAffine3,
        depth: usize,
    },
    /// Close the innermost open level, the prototype of shared node `node`, whose contents are
    /// all placed, and instance it by `placed` in the level around it.
    Close { node: usize, placed: DAffine3 },
}

/// Whether a prototype places nothing.
fn is_empty(p: &Prototype) -> bool {
    p.spheres.is_empty() && p.quadrics.is_empty() && p.meshes.is_empty() && p.instances.is_empty()
}

/// Adds a placed shape to a level; a plane goes to `planes`, which only the world has.
fn add_shape(
    shape: PlacedShape,
    out: &mut Prototype,
    planes: Option<&mut Vec<Plane>>,
) -> Result<(), String> {
    match shape {
        PlacedShape::Quadric(q) => out.quadrics.push(*q),
        PlacedShape::Sphere(s) => out.spheres.push(s),
        PlacedShape::Plane(p) => match planes {
            Some(planes) => planes.push(p),
            None => {
                return Err(
                    "a plane is unbounded and cannot be under a node that is placed more than once"
                        .into(),
                );
            }
        },
    }
    Ok(())
}
