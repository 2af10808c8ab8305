//! glTF 2.0 scenes (.gltf with external or embedded buffers, .glb): the scene graph walked from the
//! chosen scene's roots, every node's transform composed down the tree (TRS or matrix), its mesh
//! primitives, camera, light and `QUADRAY_quadrics` shape placed in quadray's z-up world.
//!
//! - Nodes, meshes and shapes used more than once become prototypes placed by instances
//!   (`crate::gltf::graph`): the node graph is never expanded, except to place cameras and lights.
//! - Scenes: the one chosen by [`ImportOptions::scene`] (index or name), else the file's default
//!   `scene`, else its first; a file with several scenes says which one was used.
//! - A node carrying a `QUADRAY_quadrics` shape renders the analytic shape; its `mesh` is the
//!   tessellated fallback for other viewers and is skipped.
//! - Skins, morph targets and animations are not evaluated: meshes render in their rest pose, placed
//!   by their node, with a note.

mod accessor;
mod camera;
pub(crate) mod document;
mod graph;
pub(crate) mod light;
pub(crate) mod material;
mod mesh;
mod node_graph;
pub mod quadrics_ext;
pub(crate) mod resources;
pub mod transmission;

pub use accessor::{MAX_ELEMENTS, MAX_UNBACKED_BYTES};
pub use document::{GltfFile, open_bytes};

use crate::error::LoadError;
use crate::gltf::graph::GraphBuild;
use crate::import::{ImportOptions, Imported, Selector, UpAxis};
use quadrics_ext::{RenderHints, RootExtension};
use std::path::Path;

pub use crate::gltf::graph::{MAX_DEPTH, MAX_INSTANCES, MAX_TRIANGLES};

/// Reads the glTF or GLB file at `path`.
pub fn import_gltf(path: &Path, options: &ImportOptions) -> Result<Imported, LoadError> {
    let file = document::open(path)?;
    convert(&file, path, options)
}

/// Converts an opened glTF file into quadray's world.
pub fn convert(
    file: &GltfFile,
    path: &Path,
    options: &ImportOptions,
) -> Result<Imported, LoadError> {
    let doc = &file.document;
    let mut notes = Vec::new();

    let scene = choose_scene(doc, options.scene.as_ref(), path)?;
    let hints = render_hints(file, scene.as_ref(), path)?;
    let roots = scene_roots(doc, scene.as_ref(), &mut notes, path)?;
    let shapes = root_extension(doc, path)?;

    let mut out = Imported::default();
    let mut build = GraphBuild::new(file, path, &roots, &shapes, options)?;
    build.place_roots(&roots, options.root(UpAxis::Y), &mut out)?;
    out.degenerate = build.degenerate;
    notes.append(&mut build.notes);
    let instances = build.node_placements();
    notes.extend(what_was_left_out(&build, doc, !out.lights.is_empty()));
    out.nodes = usize::try_from(instances).unwrap_or(usize::MAX);
    out.hints = hints;
    out.materials = build.materials.list;
    if out.materials.is_empty() && !options.skip_materials {
        out.materials
            .push(("default".into(), quadray::Material::default()));
    }
    if let Some(note) =
        crate::coincident_note(quadray::coincident::merge_coincident(&mut out.geometry))
    {
        notes.push(note);
    }
    out.notes = notes;
    // The instance limits (nesting, expanded placements), said here with the file's name rather
    // than later in prototype numbers.
    quadray::Placements::new(&out.geometry).map_err(|e| {
        LoadError::invalid(
            path,
            None,
            "nodes",
            format!("the node graph is too large: {e}"),
        )
    })?;
    Ok(out)
}

/// The render hints of `scene` (its `extras.quadray`), or the defaults.
fn render_hints(
    file: &GltfFile,
    scene: Option<&gltf::Scene<'_>>,
    path: &Path,
) -> Result<RenderHints, LoadError> {
    let Some((index, extras)) = scene.and_then(|s| {
        let extras = file.scene_extras.get(s.index())?.as_ref()?;
        Some((s.index(), extras))
    }) else {
        return Ok(RenderHints::default());
    };
    let key = format!("scenes[{index}].extras.quadray");
    let hints: RenderHints = serde_json::from_value(extras.clone()).map_err(|e| {
        let message = crate::plain_words::in_plain_words(&e.to_string());
        LoadError::invalid(path, None, key.clone(), message)
    })?;
    check_render_hints(&hints).map_err(|(field, problem)| {
        LoadError::invalid(path, None, format!("{key}.{field}"), problem)
    })?;
    Ok(hints)
}

/// The render hints' values within the limits a native scene's `[render]` keeps (resolution,
/// samples, depth, colours), so `check` refuses what `render` would; the field and the problem
/// when not.
fn check_render_hints(hints: &RenderHints) -> Result<(), (&'static str, String)> {
    use quadray::render::{MAX_DEPTH, MAX_SPP, check_resolution};
    if let Some([w, h]) = hints.resolution {
        check_resolution(w, h).map_err(|e| ("resolution", e.to_string()))?;
    }
    let count = |field, value: Option<u32>, max: u32| match value {
        Some(n) if !(1..=max).contains(&n) => {
            Err((field, format!("must be between 1 and {max}, got {n}")))
        }
        _ => Ok(()),
    };
    count("spp", hints.spp, MAX_SPP)?;
    count("maxDepth", hints.max_depth, MAX_DEPTH)?;
    for (field, colour) in [
        ("background", hints.background),
        ("environment", hints.environment),
    ] {
        if let Some(c) = colour.filter(|c| !c.iter().all(|x| x.is_finite() && *x >= 0.0)) {
            let problem = format!("colour components must be finite and non-negative, got {c:?}");
            return Err((field, problem));
        }
    }
    Ok(())
}

/// The file's quadric shapes (the root extension), or none.
fn root_extension(doc: &gltf::Document, path: &Path) -> Result<RootExtension, LoadError> {
    let Some(v) = doc.extension_value(quadrics_ext::EXTENSION) else {
        return Ok(RootExtension::default());
    };
    let key = format!("extensions.{}", quadrics_ext::EXTENSION);
    quadrics_ext::read_extension(v, &key)
        .map_err(|(key, message)| LoadError::invalid(path, None, key, message))
}

/// Notes on what the import of `doc` by `build` left out or assumed: degenerate triangles,
/// primitives that are not surfaces, animation and skinning, light ranges, dim lights (`lit`: the
/// file has lights) and material features.
fn what_was_left_out(build: &GraphBuild<'_>, doc: &gltf::Document, lit: bool) -> Vec<String> {
    let mut notes = Vec::new();
    if build.degenerate > 0 {
        notes.push(format!(
            "dropped {} degenerate triangles (a vertex index repeated: they have no area)",
            build.degenerate
        ));
    }
    if !build.skipped_modes.is_empty() {
        let list: Vec<String> = (build.skipped_modes.iter())
            .map(|(m, n)| format!("{n} {m}"))
            .collect();
        notes.push(format!(
            "skipped primitives that are not surfaces: {} (quadray renders triangles only)",
            list.join(", ")
        ));
    }
    let mut rest_pose = build.rest_pose.clone();
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
    if build.range_ignored {
        notes.push("light `range` ignored: quadray's lights fall off with the inverse square, without cutoff".into());
    }
    if lit && build.brightest <= 10.0 {
        notes.push(
            "every light's intensity is at most 10 cd or lx: if the file meant unitless values it will render dark (quadray divides glTF intensities by 683·π, see docs)".into(),
        );
    }
    notes.extend(build.materials.feature_notes());
    notes
}

/// The scene `selector` names (by index or name), else the file's default scene, else its first;
/// `None` for a file without scenes.
fn choose_scene<'d>(
    doc: &'d gltf::Document,
    selector: Option<&Selector>,
    path: &Path,
) -> Result<Option<gltf::Scene<'d>>, LoadError> {
    let invalid = |key: String, message: String| LoadError::invalid(path, None, key, message);
    let scene_count = doc.scenes().len();
    let scene = match selector {
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
    Ok(scene)
}

/// The root nodes to place: the scene's (each listed once), or without a scene every node that
/// is nobody's child, with a note either way when it is a choice.
fn scene_roots<'d>(
    doc: &'d gltf::Document,
    scene: Option<&gltf::Scene<'d>>,
    notes: &mut Vec<String>,
    path: &Path,
) -> Result<Vec<gltf::Node<'d>>, LoadError> {
    let scene_count = doc.scenes().len();
    Ok(match scene {
        Some(s) => {
            if scene_count > 1 {
                notes.push(format!(
                    "the file has {scene_count} scenes; using scene #{}{}",
                    s.index(),
                    s.name().map(|n| format!(" \"{n}\"")).unwrap_or_default()
                ));
            }
            let nodes: Vec<gltf::Node<'_>> = s.nodes().collect();
            crate::gltf::node_graph::refuse_repeats(
                nodes.iter().map(|n| n.index()),
                || format!("scenes[{}].nodes", s.index()),
                path,
            )?;
            nodes
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
    })
}
