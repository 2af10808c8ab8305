//! OBJ and glTF files brought into a native scene: `[[mesh]] path = …` (geometry only) and
//! `[[include]] path = …` (geometry, materials, lights and cameras).
//!
//! Paths are resolved against the scene file's folder, with the same tolerance for Windows
//! separators as texture references. The file's materials are appended after the scene's own
//! (named `file:material`), unless the scene overrides them with one of its own.

use crate::error::{LoadError, LoadErrorKind};
use crate::image_file::resolve_reference;
use crate::import::{FileFormat, ImportOptions, Imported, MaterialMap};
use quadray::{Geometry, Material};
use std::path::{Path, PathBuf};

/// The file a scene refers to, resolved against the scene file's folder.
pub fn resolve(scene_file: &Path, reference: &str) -> PathBuf {
    resolve_reference(scene_file.parent().unwrap_or(Path::new(".")), reference)
}

/// Imports the OBJ or glTF file at `path`, chosen by its extension.
pub fn import_file(path: &Path, options: &ImportOptions) -> Result<Imported, LoadError> {
    match FileFormat::of(path) {
        Some(FileFormat::Obj) => crate::obj::import_obj(path, options),
        Some(FileFormat::Gltf) => crate::gltf::import_gltf(path, options),
        Some(FileFormat::Native) | None => Err(LoadError::new(
            path,
            None,
            LoadErrorKind::Unsupported(
                "only .obj, .gltf and .glb files can be included in a scene".into(),
            ),
        )),
    }
}

/// Moves `imported`'s primitives into `geometry` and its materials into `materials`/`names`:
/// with `replace`, every primitive takes that material and the file's are dropped; otherwise the
/// file's materials are appended and its primitives renumbered to match.
pub fn merge(
    mut imported: Imported,
    path: &Path,
    replace: Option<u32>,
    materials: &mut Vec<Material>,
    names: &mut Vec<String>,
    geometry: &mut Geometry,
) -> Result<Imported, LoadError> {
    let label = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match replace {
        Some(id) => imported.remap_materials(path, MaterialMap::Replace(id))?,
        None => {
            imported.remap_materials(path, MaterialMap::Offset(materials.len() as u32))?;
            for (name, m) in imported.materials.drain(..) {
                names.push(format!("{label}:{name}"));
                materials.push(m);
            }
        }
    }
    let g = std::mem::take(&mut imported.geometry);
    geometry.meshes.extend(g.meshes);
    geometry.quadrics.extend(g.quadrics);
    geometry.spheres.extend(g.spheres);
    geometry.planes.extend(g.planes);
    // The file's prototypes follow the scene's: renumber every reference to them.
    let offset = geometry.prototypes.len() as u32;
    let shift = |mut inst: quadray::Instance| {
        inst.prototype += offset;
        inst
    };
    for mut p in g.prototypes {
        p.instances = p.instances.into_iter().map(shift).collect();
        geometry.prototypes.push(p);
    }
    geometry
        .instances
        .extend(g.instances.into_iter().map(shift));
    imported.notes = imported
        .notes
        .into_iter()
        .map(|n| format!("{label}: {n}"))
        .collect();
    Ok(imported)
}
