//! The native TOML scene format (documented with examples in `docs/scene-format.md`).
//!
//! Every table denies unknown keys. Values are read as `toml::Spanned` so that a semantic error
//! (a negative radius, an unknown material) points at the offending value's line and column.
//! Kinds that select fields (`light.type`, `quadric.kind`, `material.texture`) are plain keys of a
//! flat table rather than serde-tagged enums, because tagged enums lose spans (toml-rs #535).

use crate::error::{LoadError, LoadErrorKind, Location};
use crate::framing::{framing_camera, framing_points};
use crate::import::ImportedCamera;
use crate::import::{ImportOptions, Selector, UpAxis, select_camera};
use crate::include;
use crate::reach::{self, Mark};
use crate::suggest::{did_you_mean, listed, shown};
use glam::{DVec3, Vec3};
use quadray::render::{MAX_DEPTH, MAX_SIDE, MAX_SPP, check_resolution};
use quadray::{
    Camera, ClipBox, Coefficients, Geometry, Light, Material, Mesh, Plane, Projection, Quadric,
    QuadricKind, QuadricSurface, SceneDescription, SpecularModel, Sphere, Texture, Transform,
};
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The scene format version this loader reads.
mod camera;
mod exact;
mod groups;
mod light;
mod material;
mod objects;
pub mod overrides;
mod render;
mod spec;
mod sphere_set;
#[cfg(test)]
mod tests;
mod transform;

use spec::*;

pub const FORMAT_VERSION: i64 = 1;

type V3 = exact::Exact<f64, 3>;

/// Render settings a scene file carries (each overridable on the command line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Most rays in one chain (camera ray included).
    pub max_depth: u32,
    /// Adaptive sampling (`render.target_error` and its companions) instead of `spp`.
    pub adaptive: Option<quadray::Adaptive>,
    /// Anti-aliasing by contrast (`render.antialias_threshold`, `render.antialias_spp`).
    pub antialias: Option<quadray::Antialias>,
    /// Mesh BVHs in their compact form (`render.compact_meshes`:
    /// [`quadray::BuildOptions::compact_meshes`]).
    pub compact_meshes: bool,
}

impl SceneSettings {
    /// The renderer's settings for these values (the integrator's other limits at their defaults).
    pub fn render_settings(&self) -> quadray::RenderSettings {
        quadray::RenderSettings {
            width: self.width,
            height: self.height,
            spp: self.spp,
            adaptive: self.adaptive,
            antialias: self.antialias,
            whitted: quadray::Whitted {
                max_depth: self.max_depth,
                ..quadray::Whitted::default()
            },
            ..quadray::RenderSettings::default()
        }
    }

    /// How the scene's BVH is to be built for these values.
    pub fn build_options(&self) -> quadray::BuildOptions {
        quadray::BuildOptions {
            compact_meshes: self.compact_meshes,
        }
    }
}

/// Samples per pixel of a file that names none (a scene without `render.spp`, an OBJ or glTF
/// file): 4, as the bundled scenes, `quadray quadric` and `quadray gallery` use, enough to smooth
/// edges that one sample at each pixel centre leaves jagged.
pub const DEFAULT_SPP: u32 = 4;

impl Default for SceneSettings {
    fn default() -> Self {
        SceneSettings {
            width: 640,
            height: 480,
            spp: DEFAULT_SPP,
            max_depth: 8,
            adaptive: None,
            antialias: None,
            compact_meshes: false,
        }
    }
}

/// A scene file, loaded and validated.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene, ready for [`quadray::Scene::new`].
    pub description: SceneDescription,
    /// The render settings from the `[render]` table.
    pub settings: SceneSettings,
    /// The image `quadray render` writes when no `-o` is given (the `[output]` table's file,
    /// resolved against the scene file's folder); `None` for the default beside the scene.
    pub output: Option<PathBuf>,
    /// Material names, by material index.
    pub material_names: Vec<String>,
    /// What the loader assumed or skipped (a default camera or light, an unsupported primitive),
    /// for the user to see on stderr.
    pub notes: Vec<String>,
}
/// Reads and validates the scene file at `path`.
pub fn load_scene(path: &Path) -> Result<LoadedScene, LoadError> {
    parse_scene(&read_scene_text(path)?, path)
}

/// The text of the scene file at `path`: a regular file within the scene-file limit, in UTF-8.
fn read_scene_text(path: &Path) -> Result<String, LoadError> {
    let bytes = crate::read_limited::read(path, crate::read_limited::MAX_SCENE_BYTES)
        .map_err(|e| LoadError::new(path, None, LoadErrorKind::Io(e)))?;
    String::from_utf8(bytes).map_err(|e| {
        LoadError::new(
            path,
            None,
            LoadErrorKind::Syntax(format!("the file is not UTF-8 text ({e})")),
        )
    })
}

/// [`load_scene`] with command-line overrides of the file's values (`--set render.spp=64`),
/// validated as if the file said so. An error about an overridden value names the override.
pub fn load_scene_with(
    path: &Path,
    overrides: &[overrides::Override],
) -> Result<LoadedScene, LoadError> {
    if overrides.is_empty() {
        return load_scene(path);
    }
    let text = read_scene_text(path)?;
    let edited = overrides::apply(&text, overrides).map_err(|(o, message)| {
        let set = o.to_string();
        LoadError::new(path, None, LoadErrorKind::Override { set, message })
    })?;
    parse_scene(&edited, path).map_err(|mut e| {
        // A value of the wrong type fails the parse, at a place in the edited text, which is not
        // the file's. When the file itself parses, the overrides made the error: name them, not
        // a place; when it does not, its own error is the one to report.
        if let LoadErrorKind::Syntax(message) = &mut e.kind {
            if toml::from_str::<SceneFile>(&text).is_err() {
                return parse_scene(&text, path).err().unwrap_or(e);
            }
            e.location = None;
            // The overrides that fail the parse alone, else (only together) all of them.
            let fails_alone = |o: &&overrides::Override| {
                overrides::apply(&text, std::slice::from_ref(*o))
                    .is_ok_and(|t| toml::from_str::<SceneFile>(&t).is_err())
            };
            let mut culprits: Vec<&overrides::Override> =
                overrides.iter().filter(fails_alone).collect();
            if culprits.is_empty() {
                culprits = overrides.iter().collect();
            }
            let sets: Vec<String> = culprits.iter().map(ToString::to_string).collect();
            message.push_str(&format!(" (the value comes from {})", sets.join(", ")));
            return e;
        }
        // The edited line is not what the file says: name the override instead of a place.
        if let LoadErrorKind::Invalid { key, message } = &mut e.kind
            && let Some(o) = overrides.iter().rev().find(|o| {
                key.strip_prefix(o.key.as_str())
                    .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
            })
        {
            e.location = None;
            message.push_str(&format!(" (the value comes from {o})"));
        }
        e
    })
}

/// Parses and validates scene text; `path` names the file in errors.
pub fn parse_scene(text: &str, path: &Path) -> Result<LoadedScene, LoadError> {
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let location = e.span().map(|s| Location::from_offset(text, s.start));
        LoadError::new(
            path,
            location,
            LoadErrorKind::Syntax(format!(
                "{}{}",
                crate::plain_words::in_plain_words(e.message().trim()),
                crate::suggest::for_unknown_field(e.message())
            )),
        )
    })?;
    Builder {
        path,
        text,
        textures: Default::default(),
    }
    .build(file)
}

/// The largest magnitude of any number in a scene file: quadray's coordinate limit
/// ([`quadray::MAX_COORDINATE`], set by its f32 bounding boxes), applied to every number so that
/// none becomes infinite later (as an f32, or once transformed) far from its line.
pub(crate) const MAX_NUMBER: f64 = quadray::MAX_COORDINATE;

/// The message for a number `x` beyond [`MAX_NUMBER`], in the scene or in a file it reads.
pub(crate) fn beyond_limit(x: f64) -> String {
    format!("{x:e} is beyond the limit of ±{MAX_NUMBER:e} for numbers in a scene")
}

/// Validation context: the file's path and text, to turn spans into locations.
struct Builder<'a> {
    path: &'a Path,
    text: &'a str,
    /// The budget every texture of the scene draws on, through all its meshes and includes.
    textures: crate::image_file::TextureBudget,
}

impl Builder<'_> {
    fn at(&self, span: Range<usize>) -> Option<Location> {
        Some(Location::from_offset(self.text, span.start))
    }

    fn err(
        &self,
        span: Range<usize>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> LoadError {
        LoadError::invalid(self.path, self.at(span), key, message)
    }

    fn vec3(&self, v: &Spanned<V3>, key: &str) -> Result<DVec3, LoadError> {
        let d = DVec3::from_array(v.get_ref().0);
        if !d.is_finite() {
            return Err(self.err(v.span(), key, format!("must be finite numbers, got {d}")));
        }
        self.within_limit(d.to_array(), v.span(), key)?;
        Ok(d)
    }

    fn unit(&self, v: &Spanned<V3>, key: &str) -> Result<DVec3, LoadError> {
        let d = self.vec3(v, key)?;
        d.try_normalize()
            .ok_or_else(|| self.err(v.span(), key, "must not be the zero vector"))
    }

    fn colour(&self, v: &Spanned<V3>, key: &str) -> Result<Vec3, LoadError> {
        let c = self.vec3(v, key)?;
        if c.min_element() < 0.0 {
            return Err(self.err(
                v.span(),
                key,
                format!("colour components must be non-negative, got {c}"),
            ));
        }
        Ok(c.as_vec3())
    }

    /// An error at `span` for the first of `values` beyond [`MAX_NUMBER`]: the one check every
    /// number of the file passes (vectors, scalars, matrices, coefficients, clip boxes).
    fn within_limit(
        &self,
        values: impl IntoIterator<Item = f64>,
        span: Range<usize>,
        key: &str,
    ) -> Result<(), LoadError> {
        match values.into_iter().find(|x| x.abs() > MAX_NUMBER) {
            Some(x) => Err(self.err(span, key, beyond_limit(x))),
            None => Ok(()),
        }
    }

    fn number(&self, v: &Spanned<f64>, key: &str) -> Result<f64, LoadError> {
        let x = *v.get_ref();
        if !x.is_finite() {
            return Err(self.err(v.span(), key, format!("must be a finite number, got {x}")));
        }
        self.within_limit([x], v.span(), key)?;
        Ok(x)
    }

    fn positive(&self, v: &Spanned<f64>, key: &str) -> Result<f64, LoadError> {
        let x = self.number(v, key)?;
        if x <= 0.0 {
            return Err(self.err(v.span(), key, format!("must be positive, got {x}")));
        }
        Ok(x)
    }

    fn non_negative(
        &self,
        v: &Option<Spanned<f64>>,
        key: &str,
        default: f64,
    ) -> Result<f32, LoadError> {
        let Some(v) = v else {
            return Ok(default as f32);
        };
        let x = self.number(v, key)?;
        if x < 0.0 {
            return Err(self.err(v.span(), key, format!("must not be negative, got {x}")));
        }
        Ok(x as f32)
    }

    fn count(&self, v: &Spanned<i64>, key: &str, max: u32) -> Result<u32, LoadError> {
        let x = *v.get_ref();
        if !(1..=max as i64).contains(&x) {
            return Err(self.err(
                v.span(),
                key,
                format!("must be between 1 and {max}, got {x}"),
            ));
        }
        Ok(x as u32)
    }

    fn material_id(
        &self,
        names: &HashMap<String, u32>,
        v: &Spanned<String>,
        key: &str,
    ) -> Result<u32, LoadError> {
        names.get(v.get_ref()).copied().ok_or_else(|| {
            let mut known: Vec<_> = names.keys().map(String::as_str).collect();
            known.sort_unstable();
            self.err(
                v.span(),
                key,
                format!(
                    "unknown material \"{}\" (defined: {}){}",
                    shown(v.get_ref()),
                    listed(known.iter().copied()),
                    did_you_mean(v.get_ref(), known.iter().copied())
                ),
            )
        })
    }

    fn build(&self, file: SceneFile) -> Result<LoadedScene, LoadError> {
        if *file.version.get_ref() != FORMAT_VERSION {
            return Err(self.err(
                file.version.span(),
                "version",
                format!(
                    "this quadray reads scene format version {FORMAT_VERSION}, the file has {}",
                    file.version.get_ref()
                ),
            ));
        }
        let (mut settings, background, environment) = self.render(&file.render)?;
        let output = file
            .output
            .as_ref()
            .map(|o| self.output(o.get_ref()))
            .transpose()?;
        let mut notes = Vec::new();

        let (names, materials, material_names) = self.materials(&file)?;

        // The world and every group, built into prototypes children first (groups.rs).
        let world = groups::Contents::world(&file);
        let mut graph = self.graph(&world, materials, material_names)?;
        let mut top = quadray::Prototype::default();
        let mut planes = Vec::new();
        self.fill(&mut graph, &names, &world, &mut top, Some(&mut planes))?;
        let (mut materials, mut material_names) = (graph.materials, graph.material_names);
        notes.append(&mut graph.notes);
        let mut geometry = Geometry {
            spheres: top.spheres,
            planes,
            quadrics: top.quadrics,
            meshes: top.meshes,
            prototypes: graph.prototypes,
            instances: top.instances,
        };
        let mut merged_placements = quadray::coincident::merge_coincident(&mut geometry);
        // Nesting and expansion limits over groups and imported files together; each group's
        // own depth was checked where it is defined.
        quadray::Placements::new(&geometry).map_err(|e| {
            LoadError::invalid(
                self.path,
                None,
                "instance",
                format!("the scene graph is too large: {e}"),
            )
        })?;
        let mut lights = Vec::new();
        for (i, l) in file.lights.iter().enumerate() {
            lights.push(self.light(l.get_ref(), &format!("light[{i}]"))?);
        }
        let included_cameras = self.include_all(
            &file,
            (&mut materials, &mut material_names),
            &mut geometry,
            &mut lights,
            &mut notes,
        )?;
        if !file.includes.is_empty() {
            merged_placements += quadray::coincident::merge_coincident(&mut geometry);
        }
        if let Some(note) = crate::coincident_note(merged_placements) {
            notes.push(note);
        }
        let camera = self.scene_camera(
            &file,
            &included_cameras,
            &mut settings,
            &geometry,
            &mut notes,
        )?;
        Ok(LoadedScene {
            description: SceneDescription {
                camera,
                background,
                environment,
                materials,
                lights,
                geometry,
            },
            settings,
            output,
            material_names,
            notes,
        })
    }

    /// The file's materials, their names, and the name → index map shapes refer to them by.
    #[allow(clippy::type_complexity)]
    fn materials(
        &self,
        file: &SceneFile,
    ) -> Result<(HashMap<String, u32>, Vec<quadray::Material>, Vec<String>), LoadError> {
        let mut names = HashMap::new();
        let mut materials = Vec::new();
        let mut material_names = Vec::new();
        for (i, m) in file.materials.iter().enumerate() {
            let key = format!("material[{i}]");
            let name = m.get_ref().name.get_ref().clone();
            if names.insert(name.clone(), i as u32).is_some() {
                return Err(self.err(
                    m.get_ref().name.span(),
                    format!("{key}.name"),
                    format!("material \"{name}\" is defined twice"),
                ));
            }
            materials.push(self.material(m.get_ref(), &key)?);
            material_names.push(name);
        }

        Ok((names, materials, material_names))
    }

    /// Imports every `[[include]]` into `geometry`, its materials after the scene's and its
    /// lights (unless `lights = false`) beside the scene's; returns the cameras it brings.
    fn include_all(
        &self,
        file: &SceneFile,
        (materials, material_names): (&mut Vec<quadray::Material>, &mut Vec<String>),
        geometry: &mut Geometry,
        lights: &mut Vec<quadray::Light>,
        notes: &mut Vec<String>,
    ) -> Result<Vec<ImportedCamera>, LoadError> {
        let mut included_cameras = Vec::new();
        // The boxes of the prototypes met so far, each found once however many includes follow.
        let mut boxes = reach::PrototypeBoxes::default();
        for (i, inc) in file.includes.iter().enumerate() {
            let key = format!("include[{i}]");
            let spec = inc.get_ref();
            self.keys_for_format(spec.path.get_ref(), &spec.up, &spec.scene, &key)?;
            let options = ImportOptions {
                transform: self.import_transform(&spec.transform, &format!("{key}.transform"))?,
                scene: spec
                    .scene
                    .as_ref()
                    .map(|s| self.selector(s, &format!("{key}.scene")))
                    .transpose()?,
                up: self.up_axis(&spec.up, &format!("{key}.up"))?,
                skip_materials: false,
                resolution: None,
                textures: self.textures.clone(),
            };
            let path = include::resolve(self.path, spec.path.get_ref());
            let imported = include::import_file(&path, &options)
                .map_err(|e| self.include_err(Some(&spec.path), &format!("{key}.path"), e))?;
            let mark = Mark::of_world(geometry);
            let mut merged =
                include::merge(imported, &path, None, materials, material_names, geometry)
                    .map_err(|e| self.include_err(Some(&spec.path), &format!("{key}.path"), e))?;
            if let Some(reach) = reach::too_far_in_world(geometry, &mark, &mut boxes) {
                let placed = (inc.span(), spec.transform.as_ref());
                return Err(self.too_far(reach, placed, (&key, "the file's contents")));
            }
            notes.append(&mut merged.notes);
            if spec.lights.unwrap_or(true) {
                lights.append(&mut merged.lights);
            }
            let chosen = match &spec.camera {
                Some(sel) => {
                    let s = self.selector(sel, &format!("{key}.camera"))?;
                    let c = select_camera(&merged.cameras, &s)
                        .map_err(|m| self.err(sel.span(), format!("{key}.camera"), m))?;
                    vec![c.clone()]
                }
                None => merged.cameras,
            };
            included_cameras.extend(chosen);
        }
        Ok(included_cameras)
    }

    /// The scene's camera: its `[camera]`, else the first included camera (fitted to the image,
    /// whose height follows that camera's aspect when the file sets no resolution), else one
    /// that frames what the scene holds; the last two with a note.
    fn scene_camera(
        &self,
        file: &SceneFile,
        included_cameras: &[ImportedCamera],
        settings: &mut SceneSettings,
        geometry: &Geometry,
        notes: &mut Vec<String>,
    ) -> Result<quadray::Camera, LoadError> {
        Ok(match &file.camera {
            Some(c) => {
                notes.extend(camera::unused_camera_keys(c.get_ref()));
                self.camera(c)?
            }
            None => match included_cameras.first() {
                Some(c) => {
                    notes.push(format!(
                        "no [camera]: using the included file's camera{}",
                        c.name
                            .as_deref()
                            .map(|n| format!(" \"{n}\""))
                            .unwrap_or_default()
                    ));
                    let size = (settings.width, settings.height);
                    let given = file.render.resolution.is_some();
                    let camera;
                    (camera, settings.height) = c.placed(geometry, size, given);
                    camera
                }
                None => {
                    notes.push("no [camera] and no included camera: using one that frames what the scene holds".into());
                    framing_camera(
                        &framing_points(geometry),
                        settings.width as f64 / settings.height as f64,
                    )
                }
            },
        })
    }

    /// An included file's error, wrapped so that it names the scene, the key and the file.
    fn include_err(&self, path: Option<&Spanned<String>>, key: &str, e: LoadError) -> LoadError {
        LoadError::new(
            self.path,
            path.and_then(|p| self.at(p.span())),
            LoadErrorKind::Include {
                key: key.into(),
                source: Box::new(e),
            },
        )
    }
}
