//! glTF 2.0 scenes (.gltf with external or embedded buffers, .glb): the scene graph walked from the
//! chosen scene's roots, every node's transform composed down the tree (TRS or matrix), its mesh
//! primitives, camera, light and `QUADRAY_quadrics` shape placed in quadray's z-up world.
//!
//! - Scenes: the one chosen by [`ImportOptions::scene`] (index or name), else the file's default
//!   `scene`, else its first; a file with several scenes says which one was used.
//! - A node carrying a `QUADRAY_quadrics` shape renders the analytic shape; its `mesh` is the
//!   tessellated fallback for other viewers and is skipped.
//! - Skins, morph targets and animations are not evaluated: meshes render in their rest pose, placed
//!   by their node, with a note.

use crate::error::LoadError;
use crate::gltf_document::{self, GltfFile};
use crate::gltf_material::{MaterialUse, Materials};
use crate::import::{ImportOptions, Imported, Selector, UpAxis};
use crate::quadrics_ext::{self, NodeExtension, RootExtension};
use crate::{gltf_camera, gltf_light, gltf_mesh};
use glam::DAffine3;
use std::collections::BTreeMap;
use std::path::Path;

/// Deepest node hierarchy accepted; deeper means a cycle (which glTF forbids) or an absurd file.
pub const MAX_DEPTH: usize = 1024;
/// Most node instances one scene may expand to.
pub const MAX_INSTANCES: usize = 1 << 20;
/// Most triangles one import may produce (about 20 GB of meshes and BVH).
pub const MAX_TRIANGLES: usize = 200_000_000;

/// Reads the glTF or GLB file at `path`.
pub fn import_gltf(path: &Path, options: &ImportOptions) -> Result<Imported, LoadError> {
    let file = gltf_document::open(path)?;
    convert(&file, path, options)
}

/// Converts an opened glTF file into quadray's world.
pub fn convert(
    file: &GltfFile,
    path: &Path,
    options: &ImportOptions,
) -> Result<Imported, LoadError> {
    let doc = &file.document;
    let invalid = |key: String, message: String| LoadError::invalid(path, None, key, message);
    let mut notes = Vec::new();

    let scene_count = doc.scenes().len();
    let scene = match &options.scene {
        Some(Selector::Index(i)) => Some(doc.scenes().nth(*i).ok_or_else(|| {
            invalid(
                "scene".into(),
                format!("scene #{i} does not exist (the file has {scene_count})"),
            )
        })?),
        Some(Selector::Name(n)) => Some(
            doc.scenes()
                .find(|s| s.name() == Some(n.as_str()))
                .ok_or_else(|| {
                    let names: Vec<String> = doc
                        .scenes()
                        .map(|s| {
                            s.name()
                                .map_or(format!("#{}", s.index()), |n| format!("\"{n}\""))
                        })
                        .collect();
                    invalid(
                        "scene".into(),
                        format!("no scene is named \"{n}\" (scenes: {})", names.join(", ")),
                    )
                })?,
        ),
        None => doc.default_scene().or_else(|| doc.scenes().next()),
    };
    let mut hints = crate::quadrics_ext::RenderHints::default();
    if let Some(extras) = scene
        .as_ref()
        .and_then(|s| file.scene_extras.get(s.index()))
        .and_then(Option::as_ref)
    {
        hints = serde_json::from_value(extras.clone())
            .map_err(|e| invalid("scenes[].extras.quadray".into(), e.to_string()))?;
    }
    let roots: Vec<gltf::Node<'_>> = match &scene {
        Some(s) => {
            if scene_count > 1 {
                notes.push(format!(
                    "the file has {scene_count} scenes; using scene #{}{}",
                    s.index(),
                    s.name().map(|n| format!(" \"{n}\"")).unwrap_or_default()
                ));
            }
            s.nodes().collect()
        }
        None => {
            // No scene at all: show every node that is nobody's child.
            let mut is_child = vec![false; doc.nodes().len()];
            doc.nodes()
                .flat_map(|n| n.children())
                .for_each(|c| is_child[c.index()] = true);
            let roots: Vec<_> = doc.nodes().filter(|n| !is_child[n.index()]).collect();
            if !roots.is_empty() {
                notes.push("the file defines no scene; showing all root nodes".into());
            }
            roots
        }
    };

    let shapes: RootExtension = match doc.extension_value(quadrics_ext::EXTENSION) {
        Some(v) => serde_json::from_value(v.clone()).map_err(|e| {
            invalid(
                format!("extensions.{}", quadrics_ext::EXTENSION),
                e.to_string(),
            )
        })?,
        None => RootExtension::default(),
    };

    let mut out = Imported::default();
    let mut materials = Materials::new(file);
    let mut skipped_modes: BTreeMap<&'static str, usize> = BTreeMap::new();
    let mut rest_pose = Vec::new();
    let root = options.root(UpAxis::Y);
    let mut stack: Vec<(gltf::Node<'_>, DAffine3, usize)> =
        roots.into_iter().rev().map(|n| (n, root, 0)).collect();
    let mut instances = 0usize;
    let mut triangles = 0usize;
    let mut brightest = 0f32;
    let mut range_ignored = false;
    while let Some((node, parent, depth)) = stack.pop() {
        let key = format!("nodes[{}]", node.index());
        if depth >= MAX_DEPTH {
            return Err(invalid(
                key,
                format!(
                    "the node hierarchy is deeper than {MAX_DEPTH} levels (does a node contain itself?)"
                ),
            ));
        }
        instances += 1;
        if instances > MAX_INSTANCES {
            return Err(invalid(
                key,
                format!("the scene expands to more than {MAX_INSTANCES} node instances"),
            ));
        }
        let local = file
            .node_transforms
            .get(node.index())
            .cloned()
            .unwrap_or(Ok(DAffine3::IDENTITY))
            .map_err(|m| invalid(key.clone(), m))?;
        let world = parent * local;
        let shape = match node.extension_value(quadrics_ext::EXTENSION) {
            Some(v) => Some(
                serde_json::from_value::<NodeExtension>(v.clone()).map_err(|e| {
                    invalid(
                        format!("{key}.extensions.{}", quadrics_ext::EXTENSION),
                        e.to_string(),
                    )
                })?,
            ),
            None => None,
        };
        if let Some(ext) = &shape {
            let ext_key = format!("{key}.extensions.{}.shape", quadrics_ext::EXTENSION);
            let def = shapes.shapes.get(ext.shape).ok_or_else(|| {
                invalid(
                    ext_key.clone(),
                    format!(
                        "shape {} does not exist ({} defined)",
                        ext.shape,
                        shapes.shapes.len()
                    ),
                )
            })?;
            let material = match def.material {
                _ if options.skip_materials => 0,
                Some(i) => {
                    let m = doc.materials().nth(i).ok_or_else(|| {
                        invalid(
                            ext_key.clone(),
                            format!(
                                "shape {} uses material {i}, which does not exist",
                                ext.shape
                            ),
                        )
                    })?;
                    materials
                        .get(&m, &mut notes)
                        .map_err(|m| invalid(ext_key.clone(), m))?
                        .id
                }
                None => materials.default_material().id,
            };
            let placed = quadrics_ext::place(def, world, material).map_err(|m| {
                invalid(
                    format!(
                        "extensions.{}.shapes[{}]",
                        quadrics_ext::EXTENSION,
                        ext.shape
                    ),
                    m,
                )
            })?;
            placed.add_to(&mut out.geometry);
        } else if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                rest_pose.push("skins");
            }
            if mesh
                .primitives()
                .any(|p| p.morph_targets().next().is_some())
            {
                rest_pose.push("morph targets");
            }
            for primitive in mesh.primitives() {
                let pkey = format!("meshes[{}].primitives[{}]", mesh.index(), primitive.index());
                if !gltf_mesh::is_surface(primitive.mode()) {
                    *skipped_modes
                        .entry(gltf_mesh::mode_name(primitive.mode()))
                        .or_default() += 1;
                    continue;
                }
                let material = if options.skip_materials {
                    MaterialUse {
                        id: 0,
                        mask: None,
                        uv_transform: None,
                    }
                } else {
                    materials
                        .get(&primitive.material(), &mut notes)
                        .map_err(|m| invalid(pkey.clone(), m))?
                };
                let built = gltf_mesh::build(&primitive, file, world, &material)
                    .map_err(|m| invalid(pkey.clone(), m))?;
                out.degenerate += built.degenerate;
                if let Some(m) = built.mesh {
                    triangles += m.triangle_count();
                    if triangles > MAX_TRIANGLES {
                        return Err(invalid(
                            pkey,
                            format!("the scene expands to more than {MAX_TRIANGLES} triangles"),
                        ));
                    }
                    out.geometry.meshes.push(m);
                }
            }
        }
        if let Some(camera) = node.camera() {
            let c = gltf_camera::convert(&camera, file.cameras.get(camera.index()), world)
                .map_err(|m| invalid(format!("cameras[{}]", camera.index()), m))?;
            out.cameras.push(c);
        }
        if let Some(light) = node.light() {
            let l = gltf_light::convert(&light, world).map_err(|m| {
                invalid(
                    format!("extensions.KHR_lights_punctual.lights[{}]", light.index()),
                    m,
                )
            })?;
            range_ignored |= light.range().is_some();
            brightest = brightest.max(light.intensity());
            out.lights.push(l);
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }

    if out.degenerate > 0 {
        notes.push(format!(
            "dropped {} degenerate triangles (a vertex index repeated: they have no area)",
            out.degenerate
        ));
    }
    if !skipped_modes.is_empty() {
        let list: Vec<String> = skipped_modes
            .iter()
            .map(|(m, n)| format!("{n} {m}"))
            .collect();
        notes.push(format!(
            "skipped primitives that are not surfaces: {} (quadray renders triangles only)",
            list.join(", ")
        ));
    }
    rest_pose.sort_unstable();
    rest_pose.dedup();
    if doc.animations().next().is_some() {
        rest_pose.push("animations");
    }
    if !rest_pose.is_empty() {
        notes.push(format!(
            "{} not evaluated: meshes are shown in their rest pose",
            rest_pose.join(", ")
        ));
    }
    if range_ignored {
        notes.push("light `range` ignored: quadray's lights fall off with the inverse square, without cutoff".into());
    }
    if !out.lights.is_empty() && brightest <= 10.0 {
        notes.push(
            "every light's intensity is at most 10 cd or lx: if the file meant unitless values it will render dark (quadray divides glTF intensities by 683·π, see docs)".into(),
        );
    }
    if let Some(n) = materials.ignored_note() {
        notes.push(n);
    }
    out.nodes = instances;
    out.hints = hints;
    out.materials = materials.list;
    if out.materials.is_empty() && !options.skip_materials {
        out.materials
            .push(("default".into(), quadray::Material::default()));
    }
    out.notes = notes;
    Ok(out)
}
