//! `[[sphere]]`, `[[plane]]`, `[[quadric]]` and `[[mesh]]` (inline or from an OBJ/glTF file), and the glTF selectors the
//! latter take.

use super::*;
use crate::import::{FileFormat, PlacedShape, placed_sphere};
use crate::reach::{self, Mark, PrototypeBoxes, Reach};
use quadray::Prototype;

/// A sphere of `radius` at `center` into `out`, placed by `to_world` when given: a sphere, or the
/// ellipsoid a non-uniform scale makes of it (a clipped quadric). `[[sphere]]` and every vertex
/// of `[[spheres]]` are placed here.
pub(super) fn push_sphere(
    out: &mut Prototype,
    to_world: Option<glam::DAffine3>,
    center: DVec3,
    radius: f64,
    material: u32,
) -> Result<(), String> {
    let Some(to_world) = to_world else {
        out.spheres.push(Sphere {
            center,
            radius,
            material,
        });
        return Ok(());
    };
    let to_parent = to_world * glam::DAffine3::from_translation(center);
    match placed_sphere(to_parent, radius, material)? {
        PlacedShape::Sphere(s) => out.spheres.push(s),
        PlacedShape::Quadric(q) => out.quadrics.push(*q),
        PlacedShape::Plane(_) => return Err("a sphere was placed as a plane".into()),
    }
    Ok(())
}

impl Builder<'_> {
    /// Refuses what was added to the world's `out` since `mark` (one item: a shape, a mesh, or
    /// an instance of one of `prototypes`, whose boxes `boxes` keeps) where it reaches past
    /// [`quadray::MAX_COORDINATE`] ([`Builder::too_far`] says where); `what` names what it places
    /// ("the shape", "group \"g\""). The scene's own check would name only "geometry".
    pub(super) fn placed_within_limit(
        &self,
        (out, mark): (&Prototype, &Mark),
        (prototypes, boxes): (&[Prototype], &mut PrototypeBoxes),
        placed: (Range<usize>, Option<&Spanned<TransformSpec>>),
        key_and_what: (&str, &str),
    ) -> Result<(), LoadError> {
        match reach::too_far(out, mark, prototypes, boxes) {
            None => Ok(()),
            Some(reach) => Err(self.too_far(reach, placed, key_and_what)),
        }
    }

    /// The error for an item (at `item`, keyed `key`) whose contents, placed by its `transform`
    /// if any, reach past the limit as `reach` says: at the transform when the contents were
    /// within the limit before it, else at the item, with how far they reached before.
    pub(super) fn too_far(
        &self,
        reach: Reach,
        (item, transform): (Range<usize>, Option<&Spanned<TransformSpec>>),
        (key, what): (&str, &str),
    ) -> LoadError {
        let (far, limit) = (reach.far, quadray::MAX_COORDINATE);
        let Some(t) = transform else {
            return self.err(
                item,
                key,
                format!("places {what} at coordinates up to {far:e}; quadray supports magnitudes up to {limit:e}"),
            );
        };
        // Some point of the contents lies at `far` after the transform x ↦ Mx + t, so before it
        // that point reached at least (far − ‖t‖∞) / ‖M‖∞: past the limit, the contents were
        // already at fault, whatever the transform did.
        let before = (self.transform(&Some(t.clone()), key).ok()).map(|placed| {
            let m = placed.to_world;
            (far - m.translation.abs().max_element()) / quadray::math::max_row_sum(m.matrix3)
        });
        match before {
            Some(before) if before > limit => self.err(
                item,
                key,
                format!(
                    "before its transform, {what} reached coordinates of at least {before:e} \
                     ({far:e} after); quadray supports magnitudes up to {limit:e}"
                ),
            ),
            _ => self.err(
                t.span(),
                format!("{key}.transform"),
                format!("places {what} at coordinates up to {far:e}; quadray supports magnitudes up to {limit:e}"),
            ),
        }
    }

    pub(super) fn selector(
        &self,
        s: &Spanned<SelectorSpec>,
        key: &str,
    ) -> Result<Selector, LoadError> {
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

    pub(super) fn up_axis(
        &self,
        up: &Option<Spanned<String>>,
        key: &str,
    ) -> Result<UpAxis, LoadError> {
        match up.as_ref().map(|u| (u.get_ref().as_str(), u.span())) {
            None | Some(("y", _)) => Ok(UpAxis::Y),
            Some(("z", _)) => Ok(UpAxis::Z),
            Some((other, span)) => {
                Err(self.err(span, key, format!("unknown up axis \"{other}\" (y, z)")))
            }
        }
    }

    /// Refuses an import key that the format of the file at `path` does not read, at the key:
    /// `scene` picks one of a glTF file's scenes, which an OBJ file does not have; `up` names an
    /// OBJ file's up axis, where a glTF file is Y-up by its specification. (An extension of
    /// neither format is refused by the import.)
    pub(super) fn keys_for_format(
        &self,
        path: &str,
        up: &Option<Spanned<String>>,
        scene: &Option<Spanned<SelectorSpec>>,
        key: &str,
    ) -> Result<(), LoadError> {
        match (FileFormat::of(std::path::Path::new(path)), up, scene) {
            (Some(FileFormat::Obj), _, Some(scene)) => Err(self.err(
                scene.span(),
                format!("{key}.scene"),
                "only applies to a glTF file (it picks one of the file's scenes); an OBJ file has \
                 none",
            )),
            (Some(FileFormat::Gltf), Some(up), _) => Err(self.err(
                up.span(),
                format!("{key}.up"),
                "only applies to an OBJ file; a glTF file is Y-up by its specification, and is \
                 turned to quadray's Z-up on import",
            )),
            _ => Ok(()),
        }
    }

    /// Imports the file of a `[[mesh]] path = …`; returns it with its path and the override material.
    #[allow(clippy::type_complexity)]
    pub(super) fn mesh_file(
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
        self.keys_for_format(path_spec.get_ref(), &m.up, &m.scene, key)?;
        let replace = m
            .material
            .as_ref()
            .map(|v| self.material_id(names, v, &format!("{key}.material")))
            .transpose()?;
        let options = ImportOptions {
            transform: self.import_transform(&m.transform, &format!("{key}.transform"))?,
            scene: m
                .scene
                .as_ref()
                .map(|s| self.selector(s, &format!("{key}.scene")))
                .transpose()?,
            up: self.up_axis(&m.up, &format!("{key}.up"))?,
            skip_materials: replace.is_some(),
            resolution: None,
            textures: self.textures.clone(),
        };
        let path = include::resolve(self.path, path_spec.get_ref());
        let imported = include::import_file(&path, &options)
            .map_err(|e| self.include_err(Some(path_spec), &format!("{key}.path"), e))?;
        Ok((imported, (path, replace)))
    }

    pub(super) fn quadric(
        &self,
        spec: &Spanned<QuadricSpec>,
        key: &str,
        names: &HashMap<String, u32>,
    ) -> Result<Quadric, LoadError> {
        let q = spec.get_ref();
        let surface = self.quadric_surface(spec, key)?;
        let clip = match q.clip.get_ref() {
            ClipSpec::Radius(r) => {
                if !(*r > 0.0 && r.is_finite()) {
                    return Err(self.err(
                        q.clip.span(),
                        format!("{key}.clip"),
                        format!("a clip radius must be a positive finite number, got {r}"),
                    ));
                }
                self.within_limit([*r], q.clip.span(), &format!("{key}.clip"))?;
                ClipBox::cube(*r)
            }
            ClipSpec::Box(ClipBoxSpec { min, max }) => {
                let corners = min.0.iter().chain(&max.0).copied();
                self.within_limit(corners, q.clip.span(), &format!("{key}.clip"))?;
                ClipBox {
                    min: DVec3::from_array(min.0),
                    max: DVec3::from_array(max.0),
                }
            }
        };
        let transform = self.transform(&q.transform, &format!("{key}.transform"))?;
        let material = self.material_id(names, &q.material, &format!("{key}.material"))?;
        Quadric::new(surface, clip, transform, material).map_err(|e| {
            let (span, key) = match (&e, &q.coefficients) {
                (
                    quadray::QuadricError::EmptyClipBox { .. }
                    | quadray::QuadricError::ClipScale { .. },
                    _,
                ) => (q.clip.span(), format!("{key}.clip")),
                (quadray::QuadricError::ParameterRange { name, .. }, _) => {
                    let given = match *name {
                        "a" => &q.a,
                        "b" => &q.b,
                        _ => &q.c,
                    };
                    (
                        given.as_ref().map_or(spec.span(), |v| v.span()),
                        format!("{key}.{name}"),
                    )
                }
                (quadray::QuadricError::BadTransform, _) => (
                    q.transform.as_ref().map_or(spec.span(), |t| t.span()),
                    format!("{key}.transform"),
                ),
                (
                    quadray::QuadricError::NonFiniteCoefficient { .. }
                    | quadray::QuadricError::Degenerate(_),
                    Some(k),
                ) => (k.span(), format!("{key}.coefficients")),
                _ => (spec.span(), key.to_string()),
            };
            self.err(span, key, e.to_string())
        })
    }

    /// A quadric's surface: a canonical `kind` with its `a`, `b`, `c` (1 where not given), or the
    /// ten `coefficients` of a `general` one; each refused where it belongs to the other.
    fn quadric_surface(
        &self,
        spec: &Spanned<QuadricSpec>,
        key: &str,
    ) -> Result<QuadricSurface, LoadError> {
        let q = spec.get_ref();
        let param = |v: &Option<Spanned<f64>>, name: &str| -> Result<f64, LoadError> {
            v.as_ref()
                .map(|v| self.positive(v, &format!("{key}.{name}")))
                .transpose()
                .map(|x| x.unwrap_or(1.0))
        };
        let kind = q.kind.get_ref().as_str();
        Ok(if kind == "general" {
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
            self.within_limit(arr, k.span(), &format!("{key}.coefficients"))?;
            QuadricSurface::General(Coefficients(arr))
        } else {
            let kind = QuadricKind::from_name(kind).ok_or_else(|| {
                let names: Vec<_> = QuadricKind::ALL.iter().map(|k| k.name()).collect();
                self.err(
                    q.kind.span(),
                    format!("{key}.kind"),
                    format!(
                        "unknown kind \"{kind}\" (one of {}, general){}",
                        names.join(", "),
                        did_you_mean(kind, names.iter().copied().chain(["general"]))
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
        })
    }

    pub(super) fn mesh(
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
                    .transform_point3(DVec3::from_array(v.0))
                    .as_vec3()
            })
            .collect();
        let vertex_count = positions.len() as i64;
        let mut indices = Vec::with_capacity(indices_spec.get_ref().len());
        let flip = transform.to_world.matrix3.determinant() < 0.0;
        for (t, tri) in indices_spec.get_ref().iter().map(|t| t.0).enumerate() {
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
        if let Some(n) = &m.normals
            && let Some(k) = n
                .get_ref()
                .iter()
                .position(|v| !v.0.iter().all(|x| x.is_finite()))
        {
            return Err(self.err(
                n.span(),
                format!("{key}.normals[{k}]"),
                format!("{:?} is not three finite numbers", n.get_ref()[k].0),
            ));
        }
        let normals = m.normals.as_ref().map(|n| {
            n.get_ref()
                .iter()
                .map(|v| {
                    (transform.normal_to_world * DVec3::from_array(v.0))
                        .normalize_or_zero()
                        .as_vec3()
                })
                .collect()
        });
        let material = self.material_id(names, material_spec, &format!("{key}.material"))?;
        Mesh::new(positions, indices, normals, material)
            .map_err(|e| self.err(spec.span(), key, e.to_string()))
    }

    /// A sphere, through its `transform` unless `local` (a non-uniform scale makes it the
    /// ellipsoid it is, as a clipped quadric).
    pub(super) fn sphere(
        &self,
        spec: &Spanned<SphereSpec>,
        key: &str,
        names: &HashMap<String, u32>,
        local: bool,
        out: &mut Prototype,
    ) -> Result<(), LoadError> {
        let s = spec.get_ref();
        let center = self.vec3(&s.center, &format!("{key}.center"))?;
        let radius = self.positive(&s.radius, &format!("{key}.radius"))?;
        let material = self.material_id(names, &s.material, &format!("{key}.material"))?;
        let to_world = match &s.transform {
            Some(_) if !local => {
                Some((self.transform(&s.transform, &format!("{key}.transform"))?).to_world)
            }
            _ => None,
        };
        push_sphere(out, to_world, center, radius, material)
            .map_err(|e| self.err(spec.span(), key, e))
    }

    /// A plane, through its `transform` (the normal by the inverse transpose).
    pub(super) fn plane(
        &self,
        spec: &Spanned<PlaneSpec>,
        key: &str,
        names: &HashMap<String, u32>,
    ) -> Result<Plane, LoadError> {
        let p = spec.get_ref();
        let t = self.transform(&p.transform, &format!("{key}.transform"))?;
        let normal = self.unit(&p.normal, &format!("{key}.normal"))?;
        Ok(Plane {
            point: t
                .to_world
                .transform_point3(self.vec3(&p.point, &format!("{key}.point"))?),
            normal: (t.normal_to_world * normal).normalize(),
            material: self.material_id(names, &p.material, &format!("{key}.material"))?,
        })
    }
}
