//! An imported OBJ or glTF file as a scene of its own, for `quadray render FILE.obj|.gltf|.glb`:
//! the file's camera if it has one (else one framing its bounds), its lights if any (else a
//! default key light), and a note for every assumption.

use crate::error::{LoadError, LoadErrorKind};
use crate::framing::{default_key_light, framing_camera, framing_points};
use crate::import::{Imported, ImportedCamera, Selector};
use crate::native::{LoadedScene, SceneSettings};
use glam::Vec3;
use quadray::SceneDescription;
use std::path::Path;

/// Background of scenes without one of their own: a dark grey, so black objects still show.
pub const DEFAULT_BACKGROUND: Vec3 = Vec3::splat(0.05);

/// What mirrors and metals reflect in a file with no lights of its own: a neutral studio grey,
/// standing in for the environment light glTF viewers surround a model with (a polished white
/// metal shows it at 0.5, about 0.74 on the display), so metals look like metal, not like the
/// dark backdrop.
pub const STUDIO_ENVIRONMENT: Vec3 = Vec3::splat(0.5);

/// Turns an import of `path` into a complete scene, choosing its camera by `camera` when given.
pub fn scene_from_import(
    imported: Imported,
    path: &Path,
    camera: Option<&Selector>,
) -> Result<LoadedScene, LoadError> {
    refuse_without_surfaces(&imported, path)?;
    let mut notes = imported.notes.clone();
    let mut settings = SceneSettings::default();
    if let Some([w, h]) = imported.hints.resolution {
        (settings.width, settings.height) = (w, h);
    }
    let camera = match chosen_camera(&imported, path, camera, &mut notes)? {
        Some(c) => {
            let size = (settings.width, settings.height);
            let given = imported.hints.resolution.is_some();
            let camera;
            (camera, settings.height) = c.placed(&imported.geometry, size, given);
            camera
        }
        None => {
            notes.push(
                "no camera in the file: using one that fits what it holds to the image from the front-right, above"
                    .into(),
            );
            framing_camera(
                &framing_points(&imported.geometry),
                settings.width as f64 / settings.height as f64,
            )
        }
    };
    let mut lights = imported.lights;
    let hints = &imported.hints;
    let mut environment = hints.environment.map(Vec3::from_array);
    if lights.is_empty() {
        notes.push(
            "no lights in the file: using a default key light over the camera's left shoulder, and a grey studio environment for reflections"
                .into(),
        );
        lights.push(default_key_light(&camera));
        environment = environment.or(Some(STUDIO_ENVIRONMENT));
    }
    settings.spp = hints.spp.unwrap_or(settings.spp);
    settings.max_depth = hints.max_depth.unwrap_or(settings.max_depth);
    let background = hints
        .background
        .map_or(DEFAULT_BACKGROUND, Vec3::from_array);
    let (material_names, materials) = imported.materials.into_iter().unzip();
    Ok(LoadedScene {
        description: SceneDescription {
            camera,
            background,
            environment,
            materials,
            lights,
            geometry: imported.geometry,
        },
        settings,
        output: None,
        material_names,
        notes,
    })
}

/// An error naming `path` when its import holds no surface (only points, lines or empty nodes):
/// said, rather than drawn as an empty image.
fn refuse_without_surfaces(imported: &Imported, path: &Path) -> Result<(), LoadError> {
    let g = &imported.geometry;
    if !(g.spheres.is_empty()
        && g.planes.is_empty()
        && g.quadrics.is_empty()
        && g.meshes.is_empty()
        && g.instances.is_empty())
    {
        return Ok(());
    }
    let skipped = if imported.notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", imported.notes.join("; "))
    };
    Err(LoadError::new(
        path,
        None,
        LoadErrorKind::Unsupported(format!(
            "the file holds no surfaces (triangles or quadric shapes): nothing to render{skipped}"
        )),
    ))
}

/// The file's camera that `selector` picks, else its first (with a note when it has several);
/// `None` when it has none.
fn chosen_camera<'a>(
    imported: &'a Imported,
    path: &Path,
    selector: Option<&Selector>,
    notes: &mut Vec<String>,
) -> Result<Option<&'a ImportedCamera>, LoadError> {
    let cameras = &imported.cameras;
    if let Some(sel) = selector {
        return crate::import::select_camera(cameras, sel)
            .map(Some)
            .map_err(|m| LoadError::invalid(path, None, "camera", m));
    }
    if cameras.len() > 1 {
        let name = cameras[0].name.as_deref();
        notes.push(format!(
            "the file has {} cameras; using the first{}",
            cameras.len(),
            name.map(|n| format!(" (\"{n}\")")).unwrap_or_default()
        ));
    }
    Ok(cameras.first())
}
