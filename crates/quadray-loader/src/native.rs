//! The native TOML scene format (documented with examples in `docs/scene-format.md`).
//!
//! Every table denies unknown keys. Values are read as `toml::Spanned` so that a semantic error
//! (a negative radius, an unknown material) points at the offending value's line and column.
//! Kinds that select fields (`light.type`, `quadric.kind`, `material.texture`) are plain keys of a
//! flat table rather than serde-tagged enums, because tagged enums lose spans (toml-rs #535).

use crate::error::{LoadError, LoadErrorKind, Location};
use crate::import::{
    ImportOptions, Selector, UpAxis, framing_camera, geometry_bounds, select_camera,
};
use crate::include;
use glam::{DVec3, Vec3};
use quadray::render::{MAX_DEPTH, MAX_SIDE, MAX_SPP};
use quadray::{
    Camera, ClipBox, Coefficients, Geometry, Light, Material, Mesh, Plane, Projection, Quadric,
    QuadricKind, QuadricSurface, SceneDescription, SpecularModel, Sphere, Texture, Transform,
};
use serde::Deserialize;
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The scene format version this loader reads.
pub const FORMAT_VERSION: i64 = 1;

type V3 = [f64; 3];

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
}

impl SceneSettings {
    /// The renderer's settings for these values (the integrator's other limits at their defaults).
    pub fn render_settings(&self) -> quadray::RenderSettings {
        quadray::RenderSettings {
            width: self.width,
            height: self.height,
            spp: self.spp,
            whitted: quadray::Whitted {
                max_depth: self.max_depth,
                ..quadray::Whitted::default()
            },
            ..quadray::RenderSettings::default()
        }
    }
}

impl Default for SceneSettings {
    fn default() -> Self {
        SceneSettings {
            width: 640,
            height: 480,
            spp: 1,
            max_depth: 8,
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
    /// Material names, by material index.
    pub material_names: Vec<String>,
    /// What the loader assumed or skipped (a default camera or light, an unsupported primitive),
    /// for the user to see on stderr.
    pub notes: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    version: Spanned<i64>,
    camera: Option<Spanned<CameraSpec>>,
    #[serde(default)]
    render: RenderSpec,
    #[serde(default, rename = "material")]
    materials: Vec<Spanned<MaterialSpec>>,
    #[serde(default, rename = "sphere")]
    spheres: Vec<Spanned<SphereSpec>>,
    #[serde(default, rename = "plane")]
    planes: Vec<Spanned<PlaneSpec>>,
    #[serde(default, rename = "quadric")]
    quadrics: Vec<Spanned<QuadricSpec>>,
    #[serde(default, rename = "mesh")]
    meshes: Vec<Spanned<MeshSpec>>,
    #[serde(default, rename = "light")]
    lights: Vec<Spanned<LightSpec>>,
    #[serde(default, rename = "include")]
    includes: Vec<Spanned<IncludeSpec>>,
}

/// A glTF scene or camera chosen by index or by name.
#[derive(Deserialize)]
#[serde(untagged)]
enum SelectorSpec {
    Index(i64),
    Name(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct IncludeSpec {
    path: Spanned<String>,
    transform: Option<Spanned<TransformSpec>>,
    scene: Option<Spanned<SelectorSpec>>,
    camera: Option<Spanned<SelectorSpec>>,
    lights: Option<bool>,
    up: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    projection: Option<Spanned<String>>,
    from: Option<Spanned<V3>>,
    to: Option<Spanned<V3>>,
    up: Option<Spanned<V3>>,
    vfov: Option<Spanned<f64>>,
    height: Option<Spanned<f64>>,
    orbit: Option<Spanned<OrbitSpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OrbitSpec {
    yaw: Spanned<f64>,
    pitch: Spanned<f64>,
    distance: Spanned<f64>,
    target: Option<Spanned<V3>>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RenderSpec {
    resolution: Option<Spanned<[i64; 2]>>,
    spp: Option<Spanned<i64>>,
    max_depth: Option<Spanned<i64>>,
    background: Option<Spanned<V3>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    name: Spanned<String>,
    color: Option<Spanned<V3>>,
    texture: Option<Spanned<String>>,
    bands: Option<Spanned<i64>>,
    checker_size: Option<Spanned<f64>>,
    color2: Option<Spanned<V3>>,
    ambient: Option<Spanned<f64>>,
    diffuse: Option<Spanned<f64>>,
    specular: Option<Spanned<f64>>,
    shininess: Option<Spanned<f64>>,
    specular_model: Option<Spanned<String>>,
    reflectivity: Option<Spanned<f64>>,
    reflection_tint: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereSpec {
    center: Spanned<V3>,
    radius: Spanned<f64>,
    material: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneSpec {
    point: Spanned<V3>,
    normal: Spanned<V3>,
    material: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct QuadricSpec {
    kind: Spanned<String>,
    a: Option<Spanned<f64>>,
    b: Option<Spanned<f64>>,
    c: Option<Spanned<f64>>,
    coefficients: Option<Spanned<Vec<f64>>>,
    clip: Spanned<ClipSpec>,
    transform: Option<Spanned<TransformSpec>>,
    material: Spanned<String>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ClipSpec {
    Radius(f64),
    Box { min: V3, max: V3 },
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ScaleSpec {
    Uniform(f64),
    PerAxis(V3),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformSpec {
    translate: Option<Spanned<V3>>,
    rotate: Option<Spanned<V3>>,
    scale: Option<Spanned<ScaleSpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshSpec {
    path: Option<Spanned<String>>,
    vertices: Option<Spanned<Vec<V3>>>,
    indices: Option<Spanned<Vec<[i64; 3]>>>,
    normals: Option<Spanned<Vec<V3>>>,
    transform: Option<Spanned<TransformSpec>>,
    material: Option<Spanned<String>>,
    up: Option<Spanned<String>>,
    scene: Option<Spanned<SelectorSpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightSpec {
    #[serde(rename = "type")]
    kind: Spanned<String>,
    position: Option<Spanned<V3>>,
    direction: Option<Spanned<V3>>,
    color: Option<Spanned<V3>>,
    intensity: Option<Spanned<f64>>,
    inner_angle: Option<Spanned<f64>>,
    outer_angle: Option<Spanned<f64>>,
    falloff: Option<Spanned<bool>>,
}

/// Reads and validates the scene file at `path`.
pub fn load_scene(path: &Path) -> Result<LoadedScene, LoadError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| LoadError::new(path, None, LoadErrorKind::Io(e)))?;
    parse_scene(&text, path)
}

/// Parses and validates scene text; `path` names the file in errors.
pub fn parse_scene(text: &str, path: &Path) -> Result<LoadedScene, LoadError> {
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let location = e.span().map(|s| Location::from_offset(text, s.start));
        LoadError::new(
            path,
            location,
            LoadErrorKind::Syntax(e.message().trim().to_string()),
        )
    })?;
    Builder { path, text }.build(file)
}

/// Validation context: the file's path and text, to turn spans into locations.
struct Builder<'a> {
    path: &'a Path,
    text: &'a str,
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
        let d = DVec3::from_array(*v.get_ref());
        if !d.is_finite() {
            return Err(self.err(v.span(), key, format!("must be finite numbers, got {d}")));
        }
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

    fn number(&self, v: &Spanned<f64>, key: &str) -> Result<f64, LoadError> {
        let x = *v.get_ref();
        if !x.is_finite() {
            return Err(self.err(v.span(), key, format!("must be a finite number, got {x}")));
        }
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
                    "unknown material \"{}\" (defined: {})",
                    v.get_ref(),
                    known.join(", ")
                ),
            )
        })
    }

    fn transform(
        &self,
        spec: &Option<Spanned<TransformSpec>>,
        key: &str,
    ) -> Result<Transform, LoadError> {
        let Some(spec) = spec else {
            return Ok(Transform::IDENTITY);
        };
        let t = spec.get_ref();
        let translate = t
            .translate
            .as_ref()
            .map(|v| self.vec3(v, &format!("{key}.translate")))
            .transpose()?;
        let rotate = t
            .rotate
            .as_ref()
            .map(|v| self.vec3(v, &format!("{key}.rotate")))
            .transpose()?;
        let scale = match &t.scale {
            None => DVec3::ONE,
            Some(s) => {
                let v = match s.get_ref() {
                    ScaleSpec::Uniform(k) => DVec3::splat(*k),
                    ScaleSpec::PerAxis(v) => DVec3::from_array(*v),
                };
                if !(v.is_finite() && v.cmpne(DVec3::ZERO).all()) {
                    return Err(self.err(
                        s.span(),
                        format!("{key}.scale"),
                        format!("must be finite and nonzero, got {v}"),
                    ));
                }
                v
            }
        };
        Transform::from_srt(
            scale,
            rotate.unwrap_or_default(),
            translate.unwrap_or_default(),
        )
        .ok_or_else(|| self.err(spec.span(), key, "the transform is singular"))
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
        let (mut settings, background) = self.render(&file.render)?;
        let mut notes = Vec::new();

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

        let mut geometry = Geometry::default();
        for (i, s) in file.spheres.iter().enumerate() {
            let (key, s) = (format!("sphere[{i}]"), s.get_ref());
            geometry.spheres.push(Sphere {
                center: self.vec3(&s.center, &format!("{key}.center"))?,
                radius: self.positive(&s.radius, &format!("{key}.radius"))?,
                material: self.material_id(&names, &s.material, &format!("{key}.material"))?,
            });
        }
        for (i, p) in file.planes.iter().enumerate() {
            let (key, p) = (format!("plane[{i}]"), p.get_ref());
            geometry.planes.push(Plane {
                point: self.vec3(&p.point, &format!("{key}.point"))?,
                normal: self.unit(&p.normal, &format!("{key}.normal"))?,
                material: self.material_id(&names, &p.material, &format!("{key}.material"))?,
            });
        }
        for (i, q) in file.quadrics.iter().enumerate() {
            let key = format!("quadric[{i}]");
            geometry.quadrics.push(self.quadric(q, &key, &names)?);
        }
        for (i, m) in file.meshes.iter().enumerate() {
            let key = format!("mesh[{i}]");
            if m.get_ref().path.is_some() {
                let imported = self.mesh_file(m, &key, &names)?;
                let (path, replace) = imported.1;
                let merged = include::merge(
                    imported.0,
                    &path,
                    replace,
                    &mut materials,
                    &mut material_names,
                    &mut geometry,
                )
                .map_err(|e| self.include_err(m.get_ref().path.as_ref(), &key, e))?;
                notes.extend(merged.notes);
                if !merged.lights.is_empty() || !merged.cameras.is_empty() {
                    notes.push(format!(
                        "{key}: the file's {} light(s) and {} camera(s) are not used by [[mesh]]; [[include]] brings them in",
                        merged.lights.len(),
                        merged.cameras.len()
                    ));
                }
            } else {
                geometry.meshes.push(self.mesh(m, &key, &names)?);
            }
        }
        let mut lights = Vec::new();
        for (i, l) in file.lights.iter().enumerate() {
            lights.push(self.light(l.get_ref(), &format!("light[{i}]"))?);
        }
        let mut included_cameras = Vec::new();
        for (i, inc) in file.includes.iter().enumerate() {
            let key = format!("include[{i}]");
            let spec = inc.get_ref();
            let options = ImportOptions {
                transform: Some(self.transform(&spec.transform, &format!("{key}.transform"))?),
                scene: spec
                    .scene
                    .as_ref()
                    .map(|s| self.selector(s, &format!("{key}.scene")))
                    .transpose()?,
                up: self.up_axis(&spec.up, &format!("{key}.up"))?,
                skip_materials: false,
            };
            let path = include::resolve(self.path, spec.path.get_ref());
            let imported = include::import_file(&path, &options)
                .map_err(|e| self.include_err(Some(&spec.path), &format!("{key}.path"), e))?;
            let mut merged = include::merge(
                imported,
                &path,
                None,
                &mut materials,
                &mut material_names,
                &mut geometry,
            )
            .map_err(|e| self.include_err(Some(&spec.path), &format!("{key}.path"), e))?;
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
        let camera = match &file.camera {
            Some(c) => self.camera(c)?,
            None => match included_cameras.first() {
                Some(c) => {
                    notes.push(format!(
                        "no [camera]: using the included file's camera{}",
                        c.name
                            .as_deref()
                            .map(|n| format!(" \"{n}\""))
                            .unwrap_or_default()
                    ));
                    if let (Some(aspect), None) = (c.aspect, &file.render.resolution) {
                        settings.height =
                            ((settings.width as f64 / aspect).round() as u32).clamp(1, MAX_SIDE);
                    }
                    c.camera
                }
                None => {
                    notes.push("no [camera] and no included camera: using one that frames the scene's bounds".into());
                    framing_camera(geometry_bounds(&geometry))
                }
            },
        };
        Ok(LoadedScene {
            description: SceneDescription {
                camera,
                background,
                materials,
                lights,
                geometry,
            },
            settings,
            material_names,
            notes,
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

    fn selector(&self, s: &Spanned<SelectorSpec>, key: &str) -> Result<Selector, LoadError> {
        match s.get_ref() {
            SelectorSpec::Index(i) if *i >= 0 => Ok(Selector::Index(*i as usize)),
            SelectorSpec::Index(i) => Err(self.err(
                s.span(),
                key,
                format!("an index must not be negative, got {i}"),
            )),
            SelectorSpec::Name(n) => Ok(Selector::Name(n.clone())),
        }
    }

    fn up_axis(&self, up: &Option<Spanned<String>>, key: &str) -> Result<UpAxis, LoadError> {
        match up.as_ref().map(|u| (u.get_ref().as_str(), u.span())) {
            None | Some(("y", _)) => Ok(UpAxis::Y),
            Some(("z", _)) => Ok(UpAxis::Z),
            Some((other, span)) => {
                Err(self.err(span, key, format!("unknown up axis \"{other}\" (y, z)")))
            }
        }
    }

    /// Imports the file of a `[[mesh]] path = …`; returns it with its path and the override material.
    #[allow(clippy::type_complexity)]
    fn mesh_file(
        &self,
        spec: &Spanned<MeshSpec>,
        key: &str,
        names: &HashMap<String, u32>,
    ) -> Result<(crate::import::Imported, (std::path::PathBuf, Option<u32>)), LoadError> {
        let m = spec.get_ref();
        let Some(path_spec) = &m.path else {
            return Err(self.err(spec.span(), key, "needs `path`"));
        };
        for (present, name) in [
            (m.vertices.is_some(), "vertices"),
            (m.indices.is_some(), "indices"),
            (m.normals.is_some(), "normals"),
        ] {
            if present {
                return Err(self.err(
                    spec.span(),
                    format!("{key}.{name}"),
                    "a mesh is either read from `path` or given inline, not both",
                ));
            }
        }
        let replace = m
            .material
            .as_ref()
            .map(|v| self.material_id(names, v, &format!("{key}.material")))
            .transpose()?;
        let options = ImportOptions {
            transform: Some(self.transform(&m.transform, &format!("{key}.transform"))?),
            scene: m
                .scene
                .as_ref()
                .map(|s| self.selector(s, &format!("{key}.scene")))
                .transpose()?,
            up: self.up_axis(&m.up, &format!("{key}.up"))?,
            skip_materials: replace.is_some(),
        };
        let path = include::resolve(self.path, path_spec.get_ref());
        let imported = include::import_file(&path, &options)
            .map_err(|e| self.include_err(Some(path_spec), &format!("{key}.path"), e))?;
        Ok((imported, (path, replace)))
    }

    fn camera(&self, spec: &Spanned<CameraSpec>) -> Result<Camera, LoadError> {
        let c = spec.get_ref();
        let vfov = c
            .vfov
            .as_ref()
            .map(|v| self.number(v, "camera.vfov"))
            .transpose()?
            .unwrap_or(40.0);
        let up =
            c.up.as_ref()
                .map(|v| self.vec3(v, "camera.up"))
                .transpose()?
                .unwrap_or(DVec3::Z);
        let projection = c
            .projection
            .as_ref()
            .map(|p| (p.get_ref().as_str(), p.span()));
        let camera = match (&c.orbit, projection) {
            (Some(orbit), None | Some(("perspective", _))) => {
                if c.from.is_some() {
                    return Err(self.err(
                        spec.span(),
                        "camera",
                        "give either `orbit` or `from`/`to`, not both",
                    ));
                }
                let o = orbit.get_ref();
                let target = o
                    .target
                    .as_ref()
                    .map(|v| self.vec3(v, "camera.orbit.target"))
                    .transpose()?
                    .unwrap_or_default();
                let distance = self.positive(&o.distance, "camera.orbit.distance")?;
                let yaw = self.number(&o.yaw, "camera.orbit.yaw")?;
                let pitch = self.number(&o.pitch, "camera.orbit.pitch")?;
                Camera::orbit(target, yaw, pitch, distance, vfov)
            }
            (Some(orbit), Some(_)) => {
                return Err(self.err(
                    orbit.span(),
                    "camera.orbit",
                    "an orbit camera is perspective",
                ));
            }
            (None, projection) => {
                let from = c.from.as_ref().ok_or_else(|| {
                    self.err(spec.span(), "camera", "needs `from` and `to`, or `orbit`")
                })?;
                let to =
                    c.to.as_ref()
                        .ok_or_else(|| self.err(spec.span(), "camera", "needs `to`"))?;
                let projection = match projection {
                    None | Some(("perspective", _)) => Projection::Perspective { vfov_deg: vfov },
                    Some(("orthographic", span)) => {
                        let h = c.height.as_ref().ok_or_else(|| {
                            self.err(
                                span,
                                "camera.height",
                                "an orthographic camera needs `height`",
                            )
                        })?;
                        Projection::Orthographic {
                            height: self.positive(h, "camera.height")?,
                        }
                    }
                    Some((other, span)) => {
                        return Err(self.err(
                            span,
                            "camera.projection",
                            format!("unknown projection \"{other}\" (perspective, orthographic)"),
                        ));
                    }
                };
                Camera {
                    from: self.vec3(from, "camera.from")?,
                    to: self.vec3(to, "camera.to")?,
                    up,
                    projection,
                }
            }
        };
        camera
            .prepare(1.0)
            .map_err(|e| self.err(spec.span(), "camera", e.to_string()))?;
        Ok(camera)
    }

    fn render(&self, r: &RenderSpec) -> Result<(SceneSettings, Vec3), LoadError> {
        let mut s = SceneSettings::default();
        if let Some(res) = &r.resolution {
            let [w, h] = *res.get_ref();
            if !(1..=MAX_SIDE as i64).contains(&w) || !(1..=MAX_SIDE as i64).contains(&h) {
                return Err(self.err(
                    res.span(),
                    "render.resolution",
                    format!("each side must be between 1 and {MAX_SIDE}, got {w}x{h}"),
                ));
            }
            (s.width, s.height) = (w as u32, h as u32);
        }
        if let Some(v) = &r.spp {
            s.spp = self.count(v, "render.spp", MAX_SPP)?;
        }
        if let Some(v) = &r.max_depth {
            s.max_depth = self.count(v, "render.max_depth", MAX_DEPTH)?;
        }
        let background = r
            .background
            .as_ref()
            .map(|v| self.colour(v, "render.background"))
            .transpose()?
            .unwrap_or(Vec3::ZERO);
        Ok((s, background))
    }

    fn material(&self, m: &MaterialSpec, key: &str) -> Result<Material, LoadError> {
        let defaults = Material::default();
        let color = m
            .color
            .as_ref()
            .map(|c| self.colour(c, &format!("{key}.color")))
            .transpose()?;
        let texture_name = m.texture.as_ref().map(|t| (t.get_ref().as_str(), t.span()));
        let only_for = |field: bool, name: &str, texture: &str| -> Result<(), LoadError> {
            if field {
                return Err(LoadError::invalid(
                    self.path,
                    None,
                    format!("{key}.{name}"),
                    format!("only applies to texture = \"{texture}\""),
                ));
            }
            Ok(())
        };
        if !matches!(texture_name, Some(("bands", _))) {
            only_for(m.bands.is_some(), "bands", "bands")?;
        }
        if !matches!(texture_name, Some(("checker", _))) {
            only_for(
                m.checker_size.is_some() || m.color2.is_some(),
                "checker_size/color2",
                "checker",
            )?;
        }
        let texture = match texture_name {
            None | Some(("constant", _)) => Texture::Constant(color.unwrap_or(Vec3::splat(0.8))),
            Some(("ramp", _)) => Texture::HeightRamp,
            Some(("bands", _)) => {
                let steps = m
                    .bands
                    .as_ref()
                    .map(|b| self.count(b, &format!("{key}.bands"), 1024))
                    .transpose()?
                    .unwrap_or(8);
                Texture::Bands { steps }
            }
            Some(("checker", _)) => {
                let even = color.unwrap_or(Vec3::splat(0.4));
                let size = m
                    .checker_size
                    .as_ref()
                    .map(|s| self.positive(s, &format!("{key}.checker_size")))
                    .transpose()?
                    .unwrap_or(1.0);
                let odd = m
                    .color2
                    .as_ref()
                    .map(|c| self.colour(c, &format!("{key}.color2")))
                    .transpose()?;
                Texture::Checker {
                    size,
                    even,
                    odd: odd.unwrap_or(quadray::texture::lighten(even)),
                }
            }
            Some((other, span)) => {
                return Err(self.err(
                    span,
                    format!("{key}.texture"),
                    format!("unknown texture \"{other}\" (constant, ramp, bands, checker)"),
                ));
            }
        };
        let specular_model = match m
            .specular_model
            .as_ref()
            .map(|s| (s.get_ref().as_str(), s.span()))
        {
            None | Some(("phong", _)) => SpecularModel::Phong,
            Some(("blinn", _)) => SpecularModel::Blinn,
            Some((other, span)) => {
                return Err(self.err(
                    span,
                    format!("{key}.specular_model"),
                    format!("unknown model \"{other}\" (phong, blinn)"),
                ));
            }
        };
        let reflectivity =
            self.non_negative(&m.reflectivity, &format!("{key}.reflectivity"), 0.0)?;
        if reflectivity > 1.0 {
            let span = m
                .reflectivity
                .as_ref()
                .map(|r| r.span())
                .unwrap_or_default();
            return Err(self.err(
                span,
                format!("{key}.reflectivity"),
                format!("must be in [0, 1], got {reflectivity}"),
            ));
        }
        Ok(Material {
            texture,
            ambient: self.non_negative(
                &m.ambient,
                &format!("{key}.ambient"),
                defaults.ambient as f64,
            )?,
            diffuse: self.non_negative(
                &m.diffuse,
                &format!("{key}.diffuse"),
                defaults.diffuse as f64,
            )?,
            specular: self.non_negative(
                &m.specular,
                &format!("{key}.specular"),
                defaults.specular as f64,
            )?,
            shininess: self.non_negative(
                &m.shininess,
                &format!("{key}.shininess"),
                defaults.shininess as f64,
            )?,
            specular_model,
            reflectivity,
            reflection_tint: match &m.reflection_tint {
                None => 0.0,
                Some(v) => {
                    let t = self.number(v, &format!("{key}.reflection_tint"))?;
                    if !(0.0..=1.0).contains(&t) {
                        return Err(self.err(
                            v.span(),
                            format!("{key}.reflection_tint"),
                            format!("must be in [0, 1], got {t}"),
                        ));
                    }
                    t as f32
                }
            },
        })
    }

    fn quadric(
        &self,
        spec: &Spanned<QuadricSpec>,
        key: &str,
        names: &HashMap<String, u32>,
    ) -> Result<Quadric, LoadError> {
        let q = spec.get_ref();
        let param = |v: &Option<Spanned<f64>>, name: &str| -> Result<f64, LoadError> {
            v.as_ref()
                .map(|v| self.positive(v, &format!("{key}.{name}")))
                .transpose()
                .map(|x| x.unwrap_or(1.0))
        };
        let kind = q.kind.get_ref().as_str();
        let surface = if kind == "general" {
            if q.a.is_some() || q.b.is_some() || q.c.is_some() {
                return Err(self.err(
                    spec.span(),
                    key,
                    "a general quadric takes `coefficients`, not a, b, c",
                ));
            }
            let k = q.coefficients.as_ref().ok_or_else(|| {
                self.err(
                    q.kind.span(),
                    format!("{key}.coefficients"),
                    "a general quadric needs 10 coefficients",
                )
            })?;
            let arr: [f64; 10] = k.get_ref().as_slice().try_into().map_err(|_| {
                self.err(
                    k.span(),
                    format!("{key}.coefficients"),
                    format!("needs exactly 10 numbers (A..J), got {}", k.get_ref().len()),
                )
            })?;
            QuadricSurface::General(Coefficients(arr))
        } else {
            let kind = QuadricKind::from_name(kind).ok_or_else(|| {
                let names: Vec<_> = QuadricKind::ALL.iter().map(|k| k.name()).collect();
                self.err(
                    q.kind.span(),
                    format!("{key}.kind"),
                    format!(
                        "unknown kind \"{kind}\" (one of {}, general)",
                        names.join(", ")
                    ),
                )
            })?;
            if let Some(k) = &q.coefficients {
                return Err(self.err(
                    k.span(),
                    format!("{key}.coefficients"),
                    "only a `general` quadric takes coefficients",
                ));
            }
            QuadricSurface::Canonical {
                kind,
                a: param(&q.a, "a")?,
                b: param(&q.b, "b")?,
                c: param(&q.c, "c")?,
            }
        };
        let clip = match q.clip.get_ref() {
            ClipSpec::Radius(r) => ClipBox::cube(*r),
            ClipSpec::Box { min, max } => ClipBox {
                min: DVec3::from_array(*min),
                max: DVec3::from_array(*max),
            },
        };
        let transform = self.transform(&q.transform, &format!("{key}.transform"))?;
        let material = self.material_id(names, &q.material, &format!("{key}.material"))?;
        Quadric::new(surface, clip, transform, material).map_err(|e| {
            let span = match &e {
                quadray::QuadricError::EmptyClipBox { .. } => q.clip.span(),
                quadray::QuadricError::BadTransform => {
                    q.transform.as_ref().map_or(spec.span(), |t| t.span())
                }
                _ => spec.span(),
            };
            self.err(span, key, e.to_string())
        })
    }

    fn mesh(
        &self,
        spec: &Spanned<MeshSpec>,
        key: &str,
        names: &HashMap<String, u32>,
    ) -> Result<Mesh, LoadError> {
        let m = spec.get_ref();
        let missing = |name: &str| {
            self.err(
                spec.span(),
                format!("{key}.{name}"),
                format!("an inline mesh needs `{name}` (or give `path` to read a file)"),
            )
        };
        let vertices = m.vertices.as_ref().ok_or_else(|| missing("vertices"))?;
        let indices_spec = m.indices.as_ref().ok_or_else(|| missing("indices"))?;
        let material_spec = m.material.as_ref().ok_or_else(|| missing("material"))?;
        for (present, name) in [(m.up.is_some(), "up"), (m.scene.is_some(), "scene")] {
            if present {
                return Err(self.err(
                    spec.span(),
                    format!("{key}.{name}"),
                    "only applies to a mesh read from `path`",
                ));
            }
        }
        let transform = self.transform(&m.transform, &format!("{key}.transform"))?;
        let positions: Vec<Vec3> = vertices
            .get_ref()
            .iter()
            .map(|v| {
                transform
                    .to_world
                    .transform_point3(DVec3::from_array(*v))
                    .as_vec3()
            })
            .collect();
        let vertex_count = positions.len() as i64;
        let mut indices = Vec::with_capacity(indices_spec.get_ref().len());
        let flip = transform.to_world.matrix3.determinant() < 0.0;
        for (t, tri) in indices_spec.get_ref().iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| !(0..vertex_count).contains(&i)) {
                return Err(self.err(
                    indices_spec.span(),
                    format!("{key}.indices[{t}]"),
                    format!(
                        "vertex index {bad} is out of range (the mesh has {vertex_count} vertices)"
                    ),
                ));
            }
            // A mirroring transform would turn the triangle's front face away: keep the winding's meaning.
            let t = tri.map(|i| i as u32);
            indices.push(if flip { [t[0], t[2], t[1]] } else { t });
        }
        let normals = m.normals.as_ref().map(|n| {
            n.get_ref()
                .iter()
                .map(|v| {
                    (transform.normal_to_world * DVec3::from_array(*v))
                        .normalize_or_zero()
                        .as_vec3()
                })
                .collect()
        });
        let material = self.material_id(names, material_spec, &format!("{key}.material"))?;
        Mesh::new(positions, indices, normals, material)
            .map_err(|e| self.err(spec.span(), key, e.to_string()))
    }

    fn light(&self, l: &LightSpec, key: &str) -> Result<Light, LoadError> {
        let color = l
            .color
            .as_ref()
            .map(|c| self.colour(c, &format!("{key}.color")))
            .transpose()?
            .unwrap_or(Vec3::ONE);
        let intensity = self.non_negative(&l.intensity, &format!("{key}.intensity"), 1.0)?;
        let unused = |field: &Option<Spanned<V3>>, name: &str, kind: &str| match field {
            Some(v) => Err(self.err(
                v.span(),
                format!("{key}.{name}"),
                format!("a {kind} light has no {name}"),
            )),
            None => Ok(()),
        };
        let kind = l.kind.get_ref().as_str();
        if kind != "spot" {
            for (field, name) in [
                (&l.inner_angle, "inner_angle"),
                (&l.outer_angle, "outer_angle"),
            ] {
                if let Some(v) = field {
                    return Err(self.err(
                        v.span(),
                        format!("{key}.{name}"),
                        format!("a {kind} light has no {name} (only spot lights do)"),
                    ));
                }
            }
        }
        match kind {
            "spot" => {
                if let Some(f) = l.falloff.as_ref().filter(|f| !*f.get_ref()) {
                    return Err(self.err(
                        f.span(),
                        format!("{key}.falloff"),
                        "a spot light always falls off with the inverse square of the distance",
                    ));
                }
                let need = |name: &str| {
                    self.err(
                        l.kind.span(),
                        format!("{key}.{name}"),
                        format!("a spot light needs `{name}`"),
                    )
                };
                let position = l.position.as_ref().ok_or_else(|| need("position"))?;
                let position = self.vec3(position, &format!("{key}.position"))?;
                let direction = l.direction.as_ref().ok_or_else(|| need("direction"))?;
                let direction = self.unit(direction, &format!("{key}.direction"))?;
                let angle = |v: &Option<Spanned<f64>>,
                             name: &str,
                             default: f64|
                 -> Result<f64, LoadError> {
                    let Some(v) = v else { return Ok(default) };
                    let a = self.number(v, &format!("{key}.{name}"))?;
                    if !(0.0..=180.0).contains(&a) {
                        return Err(self.err(
                            v.span(),
                            format!("{key}.{name}"),
                            format!("must be an angle in [0, 180] degrees, got {a}"),
                        ));
                    }
                    Ok(a)
                };
                let inner = angle(&l.inner_angle, "inner_angle", 0.0)?;
                let outer = angle(&l.outer_angle, "outer_angle", 45.0)?;
                if inner > outer {
                    let span = l.inner_angle.as_ref().map_or(l.kind.span(), |v| v.span());
                    return Err(self.err(
                        span,
                        format!("{key}.inner_angle"),
                        format!("must not exceed outer_angle ({outer}), got {inner}"),
                    ));
                }
                Ok(Light::Spot {
                    position,
                    direction,
                    intensity: color * intensity,
                    cos_inner: inner.to_radians().cos(),
                    cos_outer: outer.to_radians().cos(),
                })
            }
            "point" => {
                unused(&l.direction, "direction", "point")?;
                let p = l.position.as_ref().ok_or_else(|| {
                    self.err(
                        l.kind.span(),
                        format!("{key}.position"),
                        "a point light needs `position`",
                    )
                })?;
                let position = self.vec3(p, &format!("{key}.position"))?;
                // `falloff = false`: POV-Ray's classic light, the same irradiance at any distance.
                if l.falloff.as_ref().is_some_and(|f| !*f.get_ref()) {
                    return Ok(Light::PointNoFalloff {
                        position,
                        irradiance: color * intensity,
                    });
                }
                Ok(Light::Point {
                    position,
                    intensity: color * intensity,
                })
            }
            "directional" => {
                unused(&l.position, "position", "directional")?;
                if let Some(f) = &l.falloff {
                    return Err(self.err(
                        f.span(),
                        format!("{key}.falloff"),
                        "a directional light has no falloff",
                    ));
                }
                let d = l.direction.as_ref().ok_or_else(|| {
                    self.err(
                        l.kind.span(),
                        format!("{key}.direction"),
                        "a directional light needs `direction`",
                    )
                })?;
                Ok(Light::Directional {
                    direction: self.unit(d, &format!("{key}.direction"))?,
                    irradiance: color * intensity,
                })
            }
            other => Err(self.err(
                l.kind.span(),
                format!("{key}.type"),
                format!("unknown light type \"{other}\" (point, directional, spot)"),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
version = 1
[camera]
from = [0, -5, 1]
to = [0, 0, 0]
[[material]]
name = "red"
color = [0.8, 0.1, 0.1]
"#;

    fn parse(extra: &str) -> Result<LoadedScene, LoadError> {
        parse_scene(&format!("{MINIMAL}{extra}"), Path::new("t.toml"))
    }

    fn error(extra: &str) -> String {
        parse(extra).unwrap_err().to_string()
    }

    #[test]
    fn loads_every_kind_of_item() {
        let s = parse(
            r#"
[render]
resolution = [320, 200]
spp = 4
background = [0.1, 0.2, 0.3]
[[material]]
name = "ramp"
texture = "ramp"
reflectivity = 0.5
[[sphere]]
center = [0, 0, 1]
radius = 1
material = "red"
[[plane]]
point = [0, 0, 0]
normal = [0, 0, 2]
material = "red"
[[quadric]]
kind = "cone"
clip = { min = [-1, -1, -1], max = [1, 1, 0.5] }
transform = { translate = [1, 2, 3], rotate = [0, 0, 45], scale = 2 }
material = "ramp"
[[quadric]]
kind = "general"
coefficients = [1, 1, -1, 0, 0, 0, 0, 0, 0, -1]
clip = 1.5
material = "ramp"
[[mesh]]
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
indices = [[0, 1, 2]]
material = "red"
[[light]]
type = "point"
position = [1, 2, 3]
intensity = 10
[[light]]
type = "directional"
direction = [0, 0, -1]
"#,
        )
        .unwrap();
        let g = &s.description.geometry;
        assert_eq!(
            (
                g.spheres.len(),
                g.planes.len(),
                g.quadrics.len(),
                g.meshes.len()
            ),
            (1, 1, 2, 1)
        );
        assert_eq!(
            s.settings,
            SceneSettings {
                width: 320,
                height: 200,
                spp: 4,
                max_depth: 8
            }
        );
        assert_eq!(g.planes[0].normal, DVec3::Z);
        assert_eq!(s.description.lights.len(), 2);
        assert_eq!(s.material_names, ["red", "ramp"]);
        quadray::Scene::new(s.description).unwrap();
    }

    #[test]
    fn errors_name_file_line_column_and_key() {
        let e = error("[[sphere]]\ncenter = [0, 0, 0]\nradius = -1\nmaterial = \"red\"\n");
        assert!(
            e.starts_with("t.toml:11:10: `sphere[0].radius`: must be positive"),
            "{e}"
        );
        let e = error("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"blue\"\n");
        assert!(
            e.contains(":12:12: `sphere[0].material`: unknown material \"blue\""),
            "{e}"
        );
    }

    #[test]
    fn syntax_and_unknown_keys_are_located() {
        let e = error("[[sphere]]\ncentre = [0, 0, 0]\n");
        assert!(
            e.starts_with("t.toml:10:1:") && e.contains("unknown field `centre`"),
            "{e}"
        );
        let e = parse_scene("version = 1\n[camera\n", Path::new("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("bad.toml:2:"), "{e}");
    }

    #[test]
    fn rejects_nan_degenerate_and_absurd_values() {
        assert!(
            error("[[sphere]]\ncenter = [nan, 0, 0]\nradius = 1\nmaterial = \"red\"\n")
                .contains("finite")
        );
        let e = error(
            "[[quadric]]\nkind = \"general\"\ncoefficients = [0,0,0,0,0,0,0,0,0,0]\nclip = 1\nmaterial = \"red\"\n",
        );
        assert!(
            e.contains("degenerate quadric: all coefficients are zero"),
            "{e}"
        );
        let e = error(
            "[[quadric]]\nkind = \"general\"\ncoefficients = [1,1,1,0,0,0,0,0,0,1]\nclip = 1\nmaterial = \"red\"\n",
        );
        assert!(e.contains("empty"), "{e}");
        let e = error(
            "[[quadric]]\nkind = \"ellipsoid\"\nclip = { min = [0, 0, 0], max = [1, 1, 0] }\nmaterial = \"red\"\n",
        );
        assert!(
            e.contains(":11:8:") && e.contains("clip box is empty"),
            "{e}"
        );
        assert!(error("[render]\nresolution = [100000, 10]\n").contains("render.resolution"));
        assert!(error("[render]\nspp = 0\n").contains("render.spp"));
        let e = error(
            "[[mesh]]\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\nindices = [[0,1,3]]\nmaterial = \"red\"\n",
        );
        assert!(
            e.contains("mesh[0].indices[0]") && e.contains("out of range"),
            "{e}"
        );
        assert!(
            error("[[quadric]]\nkind = \"torus\"\nclip = 1\nmaterial = \"red\"\n")
                .contains("unknown kind \"torus\"")
        );
    }

    #[test]
    fn point_lights_can_drop_their_falloff() {
        let s = parse(
            "[[light]]\ntype = \"point\"\nposition = [0, 0, 5]\nfalloff = false\nintensity = 0.5\n",
        )
        .unwrap();
        assert_eq!(
            s.description.lights[0],
            Light::PointNoFalloff {
                position: DVec3::new(0.0, 0.0, 5.0),
                irradiance: Vec3::splat(0.5),
            }
        );
        let s =
            parse("[[light]]\ntype = \"point\"\nposition = [0, 0, 5]\nfalloff = true\n").unwrap();
        assert!(matches!(s.description.lights[0], Light::Point { .. }));
        let e =
            error("[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\nfalloff = false\n");
        assert!(e.contains("a directional light has no falloff"), "{e}");
    }

    #[test]
    fn camera_variants() {
        let orbit = "version = 1\n[camera]\norbit = { yaw = 30, pitch = 20, distance = 8 }\n";
        let s = parse_scene(orbit, Path::new("o.toml")).unwrap();
        assert!(((s.description.camera.from).length() - 8.0).abs() < 1e-12);
        let ortho = "version = 1\n[camera]\nprojection = \"orthographic\"\nfrom = [0,0,5]\nto = [0,0,0]\nup = [0,1,0]\nheight = 3\n";
        let s = parse_scene(ortho, Path::new("o.toml")).unwrap();
        assert_eq!(
            s.description.camera.projection,
            Projection::Orthographic { height: 3.0 }
        );
        let e = parse_scene(
            "version = 2\n[camera]\nfrom=[0,0,1]\nto=[0,0,0]\n",
            Path::new("v.toml"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("version"));
    }

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("quadray-native-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    const TRIANGLE_OBJ: &str = "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl blue\nf 1 2 3\n";

    #[test]
    fn mesh_files_resolve_against_the_scene_and_take_transforms_and_overrides() {
        let dir = temp_dir("meshfile");
        std::fs::create_dir_all(dir.join("models")).unwrap();
        std::fs::write(dir.join("models/tri.obj"), TRIANGLE_OBJ).unwrap();
        std::fs::write(dir.join("models/tri.mtl"), "newmtl blue\nKd 0 0 1\n").unwrap();
        let text = format!(
            "{MINIMAL}[[mesh]]\npath = \"models\\\\tri.obj\"\ntransform = {{ translate = [0, 0, 5] }}\n\
             [[mesh]]\npath = \"models/tri.obj\"\nup = \"z\"\nmaterial = \"red\"\n"
        );
        let s = parse_scene(&text, &dir.join("scene.toml")).unwrap();
        let g = &s.description.geometry;
        assert_eq!(g.meshes.len(), 2);
        // y-up file rotated to z-up, then moved up by 5: (0, 1, 0) lands at (0, 0, 6).
        assert!(g.meshes[0].positions().contains(&Vec3::new(0.0, 0.0, 6.0)));
        assert_eq!(s.material_names, ["red", "tri.obj:blue"]);
        assert_eq!(g.meshes[0].material(), 1);
        assert_eq!(
            s.description.materials[1].texture,
            Texture::Constant(Vec3::Z)
        );
        // The override takes the scene's material, and `up = "z"` keeps coordinates.
        assert_eq!(g.meshes[1].material(), 0);
        assert!(g.meshes[1].positions().contains(&Vec3::new(0.0, 1.0, 0.0)));
        quadray::Scene::new(s.description).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn includes_bring_lights_and_camera_and_errors_name_both_files() {
        let dir = temp_dir("include");
        let inner = parse_scene(
            "version = 1\n[camera]\nfrom = [0, -4, 1]\nto = [0, 0, 0]\n[render]\nresolution = [400, 200]\n\
             [[material]]\nname = \"m\"\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n\
             [[light]]\ntype = \"point\"\nposition = [0, 0, 3]\n",
            Path::new("inner.toml"),
        )
        .unwrap();
        crate::export::export_gltf(&inner, &dir.join("part.gltf")).unwrap();
        let text = "version = 1\n[[material]]\nname = \"red\"\n\
                    [[include]]\npath = \"part.gltf\"\ntransform = { translate = [10, 0, 0] }\n\
                    [[sphere]]\ncenter = [0, 0, 0]\nradius = 0.5\nmaterial = \"red\"\n";
        let s = parse_scene(text, &dir.join("scene.toml")).unwrap();
        let g = &s.description.geometry;
        assert_eq!(g.spheres.len(), 2);
        assert!((g.spheres[1].center - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
        assert_eq!(s.description.lights.len(), 1);
        // No [camera]: the included one, moved with the include, and its aspect.
        assert!((s.description.camera.from - DVec3::new(10.0, -4.0, 1.0)).length() < 1e-9);
        assert_eq!((s.settings.width, s.settings.height), (640, 320));
        assert!(
            s.notes.iter().any(|n| n.contains("included file's camera")),
            "{:?}",
            s.notes
        );
        let no_lights = text.replace("[[sphere]]", "lights = false\n[[sphere]]");
        let s = parse_scene(&no_lights, &dir.join("scene.toml")).unwrap();
        assert!(s.description.lights.is_empty());
        // A missing file: the scene, the line of `path`, and the file that is missing.
        let e = parse_scene(
            &text.replace("part.gltf", "gone.glb"),
            &dir.join("scene.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("scene.toml:5:8: `include[0].path`") && e.contains("gone.glb"),
            "{e}"
        );
        let e = parse_scene(
            "version = 1\n[[include]]\npath = \"part.gltf\"\ncamera = \"nope\"\n",
            &dir.join("scene.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("include[0].camera") && e.contains("no camera \"nope\""),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn spot_lights_and_mesh_form_errors() {
        let s = parse(
            "[[light]]\ntype = \"spot\"\nposition = [0, 0, 5]\ndirection = [0, 0, -1]\ninner_angle = 10\nouter_angle = 20\n",
        )
        .unwrap();
        let Light::Spot {
            cos_inner,
            cos_outer,
            ..
        } = s.description.lights[0]
        else {
            panic!("not a spot light")
        };
        assert!((cos_inner - 10f64.to_radians().cos()).abs() < 1e-15);
        assert!((cos_outer - 20f64.to_radians().cos()).abs() < 1e-15);
        assert!(
            error("[[light]]\ntype = \"spot\"\nposition = [0, 0, 5]\n")
                .contains("needs `direction`")
        );
        assert!(error("[[light]]\ntype = \"spot\"\nposition = [0,0,5]\ndirection = [0,0,-1]\ninner_angle = 30\nouter_angle = 20\n").contains("must not exceed"));
        assert!(
            error("[[light]]\ntype = \"point\"\nposition = [0,0,5]\nouter_angle = 20\n")
                .contains("only spot lights")
        );
        let e = error("[[mesh]]\npath = \"a.obj\"\nvertices = [[0,0,0]]\n");
        assert!(e.contains("either read from `path` or given inline"), "{e}");
        assert!(
            error("[[mesh]]\nvertices = [[0,0,0]]\nindices = [[0,0,0]]\n")
                .contains("needs `material`")
        );
        let e = error("[[mesh]]\npath = \"model.ply\"\n");
        assert!(
            e.contains("`mesh[0].path`") && e.contains("only .obj, .gltf and .glb"),
            "{e}"
        );
    }
}
