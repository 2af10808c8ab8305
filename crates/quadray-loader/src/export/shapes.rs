//! The shapes of a scene as glTF nodes, instancing kept: a prototype's mesh is written once and
//! every node that places it points at it; a prototype's quadric or sphere is one
//! `QUADRAY_quadrics` shape that every placement's node names; each instance is a node with its
//! matrix whose children place the prototype's contents, so the hierarchy survives.
//!
//! glTF asks for a node tree (no node with two parents), so nested instances are written as one
//! node per placement: up to [`MAX_EXPORT_NODES`]; meshes and shapes are never copied.

use crate::export::ExportError;
use crate::export::document::{Document, MeshData, set_matrix};
use crate::gltf::quadrics_ext::{self, NodeExtension, ShapeDef, SphereDef};
use crate::tessellate;
use quadray::{Geometry, MaterialId};
use serde_json::{Value, json};
use std::collections::HashMap;

/// Most nodes an export may write for the shapes (each placement of a nested instance is one).
pub const MAX_EXPORT_NODES: usize = 1 << 20;
/// Grid cells along a quadric's clip box for its fallback mesh.
const QUADRIC_CELLS: u32 = 24;
/// Longitude segments of a sphere's fallback mesh (half as many latitude rings).
const SPHERE_SEGMENTS: u32 = 32;

/// What a glTF file holds for one kind of shape of one level, under one material.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Mesh {
        level: usize,
        index: usize,
        material: MaterialId,
    },
    Quadric {
        level: usize,
        index: usize,
        material: MaterialId,
    },
    Sphere {
        level: usize,
        index: usize,
        material: MaterialId,
    },
}

/// Writes a scene's shapes into a [`Document`], each mesh and shape once.
pub(crate) struct ShapeWriter<'g> {
    g: &'g Geometry,
    /// glTF mesh index (for meshes) or (shape index, fallback mesh) written per key.
    written: HashMap<Key, (usize, Option<usize>)>,
    nodes: usize,
}

impl<'g> ShapeWriter<'g> {
    /// A writer for `g`'s shapes.
    pub(crate) fn new(g: &'g Geometry) -> ShapeWriter<'g> {
        ShapeWriter {
            g,
            written: HashMap::new(),
            nodes: 0,
        }
    }

    /// Nodes for everything `level` holds (the world is level 0), with `material` replacing the
    /// shapes' own when an instance above says so; returns the node indices.
    pub(crate) fn level_nodes(
        &mut self,
        doc: &mut Document,
        level: usize,
        material: Option<MaterialId>,
    ) -> Result<Vec<usize>, ExportError> {
        let prefix = match level {
            0 => String::new(),
            _ => format!("prototype {} ", level - 1),
        };
        let mut nodes = Vec::new();
        self.mesh_nodes(doc, level, &prefix, material, &mut nodes)?;
        self.quadric_nodes(doc, level, &prefix, material, &mut nodes)?;
        self.sphere_nodes(doc, level, &prefix, material, &mut nodes)?;
        self.instance_nodes(doc, level, &prefix, material, &mut nodes)?;
        Ok(nodes)
    }

    /// Nodes for the level's meshes, each glTF mesh written once per material.
    fn mesh_nodes(
        &mut self,
        doc: &mut Document,
        level: usize,
        prefix: &str,
        material: Option<MaterialId>,
        nodes: &mut Vec<usize>,
    ) -> Result<(), ExportError> {
        let l = self.g.level(level);
        for (i, m) in l.meshes.iter().enumerate() {
            let id = material.unwrap_or(m.material());
            let key = Key::Mesh {
                level,
                index: i,
                material: id,
            };
            let mesh = match self.written.get(&key) {
                Some(&(mesh, _)) => mesh,
                None => {
                    let gl_material = doc.mesh_material(m, id);
                    let data = MeshData {
                        positions: m.positions(),
                        normals: m.normals(),
                        texcoords: [m.texcoords(0), m.texcoords(1)],
                        colors: m.colors(),
                        indices: m.indices(),
                    };
                    let mesh = doc.mesh(&format!("{prefix}mesh {i}"), &data, gl_material);
                    self.written.insert(key, (mesh, None));
                    mesh
                }
            };
            nodes.push(self.node(
                doc,
                json!({"name": format!("{prefix}mesh {i}"), "mesh": mesh}),
            )?);
        }
        Ok(())
    }

    /// Nodes for the level's quadrics, each shape written once per material.
    fn quadric_nodes(
        &mut self,
        doc: &mut Document,
        level: usize,
        prefix: &str,
        material: Option<MaterialId>,
        nodes: &mut Vec<usize>,
    ) -> Result<(), ExportError> {
        let l = self.g.level(level);
        for (i, q) in l.quadrics.iter().enumerate() {
            let id = material.unwrap_or(q.material());
            let name = format!("{prefix}quadric {i} ({})", crate::export::describe(q));
            let key = Key::Quadric {
                level,
                index: i,
                material: id,
            };
            let mut node = self.shape_once(doc, key, &name, || {
                let fallback = tessellate::quadric(
                    &q.surface_description().coefficients(),
                    q.clip(),
                    QUADRIC_CELLS,
                );
                let def = quadrics_ext::quadric_def(q, Some(id as usize), Some(name.clone()));
                (def, fallback)
            });
            set_matrix(&mut node, &q.transform().to_world);
            nodes.push(self.node(doc, node)?);
        }
        Ok(())
    }

    /// Nodes for the level's spheres, each shape written once per material.
    fn sphere_nodes(
        &mut self,
        doc: &mut Document,
        level: usize,
        prefix: &str,
        material: Option<MaterialId>,
        nodes: &mut Vec<usize>,
    ) -> Result<(), ExportError> {
        let l = self.g.level(level);
        for (i, s) in l.spheres.iter().enumerate() {
            let id = material.unwrap_or(s.material);
            let name = format!("{prefix}sphere {i}");
            let key = Key::Sphere {
                level,
                index: i,
                material: id,
            };
            let mut node = self.shape_once(doc, key, &name, || {
                let def = ShapeDef {
                    kind: "sphere".into(),
                    name: Some(name.clone()),
                    sphere: Some(SphereDef { radius: s.radius }),
                    material: Some(id as usize),
                    ..ShapeDef::default()
                };
                (
                    def,
                    tessellate::sphere(s.radius, SPHERE_SEGMENTS, SPHERE_SEGMENTS / 2),
                )
            });
            if s.center != glam::DVec3::ZERO {
                node["translation"] = json!(s.center.to_array());
            }
            nodes.push(self.node(doc, node)?);
        }
        Ok(())
    }

    /// Nodes for the level's instances, their prototypes' contents as children.
    fn instance_nodes(
        &mut self,
        doc: &mut Document,
        level: usize,
        prefix: &str,
        material: Option<MaterialId>,
        nodes: &mut Vec<usize>,
    ) -> Result<(), ExportError> {
        let l = self.g.level(level);
        for (k, inst) in l.instances.iter().enumerate() {
            // The outermost override wins, as when rendering.
            let inner = material.or(inst.material);
            let children = self.level_nodes(doc, inst.prototype as usize + 1, inner)?;
            let mut node =
                json!({"name": format!("{prefix}instance {k} of prototype {}", inst.prototype)});
            set_matrix(&mut node, &inst.transform.to_world);
            if !children.is_empty() {
                node["children"] = json!(children);
            }
            nodes.push(self.node(doc, node)?);
        }
        Ok(())
    }

    /// A node naming the `QUADRAY_quadrics` shape of `key`, whose definition and fallback mesh
    /// (from `make`) are written the first time the key is met and shared after.
    fn shape_once(
        &mut self,
        doc: &mut Document,
        key: Key,
        name: &str,
        make: impl FnOnce() -> (ShapeDef, tessellate::TriMesh),
    ) -> Value {
        let (shape, mesh) = *self.written.entry(key).or_insert_with(|| {
            let (def, fallback) = make();
            let material = def.material.unwrap_or(0);
            let mesh = doc.fallback(name, &fallback, material);
            doc.shapes.push(def);
            (doc.shapes.len() - 1, mesh)
        });
        shape_node(name, shape, mesh)
    }

    /// Adds a node, counting it against [`MAX_EXPORT_NODES`].
    fn node(&mut self, doc: &mut Document, node: Value) -> Result<usize, ExportError> {
        self.nodes += 1;
        if self.nodes > MAX_EXPORT_NODES {
            return Err(ExportError::Unsupported(format!(
                "the instances expand to more than {MAX_EXPORT_NODES} glTF nodes (glTF needs a node per placement; meshes are still written once)"
            )));
        }
        Ok(doc.node(node))
    }
}

/// A node naming `QUADRAY_quadrics` shape `shape`, with its fallback mesh for other viewers.
fn shape_node(name: &str, shape: usize, mesh: Option<usize>) -> Value {
    let mut node = json!({
        "name": name,
        "extensions": {quadrics_ext::EXTENSION: NodeExtension { shape, extensions: None, extras: None }},
    });
    if let Some(mesh) = mesh {
        node["mesh"] = json!(mesh);
    }
    node
}
