//! The `QUADRAY_quadrics` glTF extension (specified in `docs/gltf-quadrics.md`, schema in
//! `docs/schema/`): analytic quadrics, spheres and planes as glTF content.
//!
//! Shaped like KHR_lights_punctual: the document's `extensions.QUADRAY_quadrics.shapes` array holds
//! shape definitions, and a node's `extensions.QUADRAY_quadrics.shape` instances one, placed by the
//! node's transform. A material may carry `extensions.QUADRAY_quadrics.whitted`, quadray's own
//! material parameters, so that a scene written by quadray reads back exactly.

use crate::import::PlacedShape;
use glam::{DAffine3, DVec3, Vec3};
use gltf::json::Value;
use quadray::{
    ClipBox, Coefficients, Material, Plane, Quadric, QuadricKind, QuadricSurface, SpecularModel,
    Texture, Transform,
};
use serde::{Deserialize, Serialize};

/// The extension's name.
pub const EXTENSION: &str = "QUADRAY_quadrics";

/// The extension object `value` found at `key` (say `nodes[3].extensions.QUADRAY_quadrics`) read
/// as a `T`; on failure the key of the field at fault (`….shapes[2].a`) and the problem in plain
/// words: serde_json alone names no place once the document is a `Value`.
pub(crate) fn read_extension<T: serde::de::DeserializeOwned>(
    value: &Value,
    key: &str,
) -> Result<T, (String, String)> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let inner = e.path().to_string();
        let key = if inner == "." {
            key.to_string()
        } else {
            format!("{key}.{inner}")
        };
        (
            key,
            crate::plain_words::in_plain_words(&e.inner().to_string()),
        )
    })
}

/// The document-level object: every shape definition.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RootExtension {
    /// Shape definitions, referred to by index from nodes.
    pub shapes: Vec<ShapeDef>,
    /// Extension-specific extensions (glTF convention; ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extensions: Option<Value>,
    /// Application data (glTF convention; ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extras: Option<Value>,
}

/// One shape definition: a quadric, a sphere or a plane in the node's local frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeDef {
    /// `"quadric"`, `"sphere"` or `"plane"`.
    #[serde(rename = "type")]
    pub kind: String,
    /// A name for people.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The surface, for `type: "quadric"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadric: Option<QuadricDef>,
    /// The radius, for `type: "sphere"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereDef>,
    /// The clip box (quadrics only); the cube [-1, 1]³ when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip: Option<ClipDef>,
    /// Index into the document's materials; glTF's default material when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<usize>,
    /// Extension-specific extensions (ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extensions: Option<Value>,
    /// Application data (ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extras: Option<Value>,
}

/// A quadric surface: one of the nine kinds with a, b, c, or `general` with ten coefficients.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadricDef {
    /// `ellipsoid`, `hyperboloid1`, …, or `general`.
    pub kind: String,
    /// Semi-axis along x (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<f64>,
    /// Semi-axis along y (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<f64>,
    /// Semi-axis or scale along z (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c: Option<f64>,
    /// A..J of A·x² + B·y² + C·z² + D·xy + E·xz + F·yz + G·x + H·y + I·z + J = 0 (`general` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coefficients: Option<Vec<f64>>,
}

/// A sphere about the node's origin.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDef {
    /// Radius, positive.
    pub radius: f64,
}

/// An axis-aligned box in the node's local frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipDef {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// The node-level object: which shape the node instances.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeExtension {
    /// Index into the root `shapes` array.
    pub shape: usize,
    /// Extension-specific extensions (ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extensions: Option<Value>,
    /// Application data (ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extras: Option<Value>,
}

/// The material-level object: quadray's Whitted parameters, overriding the PBR mapping.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialExtension {
    /// The parameters.
    pub whitted: WhittedDef,
}

/// quadray's material parameters (see `Material` in the core crate).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "camelCase")]
pub struct WhittedDef {
    /// Ambient coefficient.
    pub ambient: f32,
    /// Diffuse coefficient.
    pub diffuse: f32,
    /// Specular coefficient.
    pub specular: f32,
    /// Highlight exponent.
    pub shininess: f32,
    /// `"phong"`, `"blinn"` or `"ggx"`.
    pub specular_model: String,
    /// Mirror reflectivity in [0, 1].
    pub reflectivity: f32,
    /// How far reflections take the base colour, in [0, 1].
    #[serde(default)]
    pub reflection_tint: f32,
    /// How far highlights take the base colour, in [0, 1] (0 when absent: files from before it).
    #[serde(default)]
    pub specular_tint: f32,
    /// Microfacet roughness of reflections and GGX highlights, in [0, 1] (0 when absent).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub roughness: f32,
    /// A procedural texture; the glTF base colour (and its texture) when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureDef>,
}

/// quadray's procedural textures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum TextureDef {
    /// One linear RGB colour.
    Constant {
        /// The colour.
        color: [f32; 3],
    },
    /// Blue → green → yellow over the clipped height range.
    Ramp,
    /// The ramp in flat contour bands.
    Bands {
        /// Number of bands.
        steps: u32,
    },
    /// A 3-D checkerboard in the object frame.
    Checker {
        /// Cube edge length.
        size: f64,
        /// Colour of even cubes.
        even: [f32; 3],
        /// Colour of odd cubes.
        odd: [f32; 3],
    },
}

/// quadray's own render settings, kept in a scene's `extras.quadray` (glTF application data, not
/// part of the extension) so that a converted scene renders as it did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct RenderHints {
    /// Linear RGB background.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<[f32; 3]>,
    /// Linear RGB environment: what reflection rays that hit nothing see.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment: Option<[f32; 3]>,
    /// Width and height in pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<[u32; 2]>,
    /// Samples per pixel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
    /// Most rays in one chain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_depth: Option<u32>,
}

/// Places shape definition `def` in the world by `to_world`, with material index `material`.
pub fn place(def: &ShapeDef, to_world: DAffine3, material: u32) -> Result<PlacedShape, String> {
    let only = |field: bool, name: &str| {
        if field {
            Err(format!("a {} shape has no `{name}`", def.kind))
        } else {
            Ok(())
        }
    };
    match def.kind.as_str() {
        "quadric" => {
            only(def.sphere.is_some(), "sphere")?;
            let q = def
                .quadric
                .as_ref()
                .ok_or("a quadric shape needs `quadric`")?;
            let surface = quadric_surface(q)?;
            let clip = match &def.clip {
                Some(c) => ClipBox {
                    min: DVec3::from_array(c.min),
                    max: DVec3::from_array(c.max),
                },
                None => ClipBox::cube(1.0),
            };
            let t = Transform::new(to_world).ok_or("the node's transform is singular")?;
            Quadric::new(surface, clip, t, material)
                .map(|q| PlacedShape::Quadric(Box::new(q)))
                .map_err(|e| e.to_string())
        }
        "sphere" => {
            only(def.quadric.is_some(), "quadric")?;
            only(def.clip.is_some(), "clip")?;
            let r = def
                .sphere
                .as_ref()
                .ok_or("a sphere shape needs `sphere.radius`")?
                .radius;
            if !(r > 0.0 && r.is_finite()) {
                return Err(format!("sphere radius must be positive, got {r}"));
            }
            crate::import::placed_sphere(to_world, r, material)
        }
        "plane" => {
            only(def.quadric.is_some(), "quadric")?;
            only(def.sphere.is_some(), "sphere")?;
            only(def.clip.is_some(), "clip")?;
            let normal_matrix = to_world.matrix3.inverse().transpose();
            let normal = (normal_matrix * DVec3::Z)
                .try_normalize()
                .filter(|n| n.is_finite())
                .ok_or("the node's transform is singular")?;
            let far = to_world.translation.abs().max_element();
            if far > quadray::MAX_COORDINATE {
                return Err(format!(
                    "the node places the plane {far:e} from the origin; quadray supports \
                     coordinates up to {:e}",
                    quadray::MAX_COORDINATE
                ));
            }
            Ok(PlacedShape::Plane(Plane {
                point: to_world.translation,
                normal,
                material,
            }))
        }
        other => Err(format!(
            "unknown shape type \"{other}\" (quadric, sphere, plane)"
        )),
    }
}

fn quadric_surface(q: &QuadricDef) -> Result<QuadricSurface, String> {
    if q.kind == "general" {
        if q.a.is_some() || q.b.is_some() || q.c.is_some() {
            return Err("a general quadric takes `coefficients`, not a, b, c".into());
        }
        let k = q
            .coefficients
            .as_ref()
            .ok_or("a general quadric needs 10 coefficients")?;
        let arr: [f64; 10] = k
            .as_slice()
            .try_into()
            .map_err(|_| format!("`coefficients` needs exactly 10 numbers, got {}", k.len()))?;
        return Ok(QuadricSurface::General(Coefficients(arr)));
    }
    let kind = QuadricKind::from_name(&q.kind).ok_or_else(|| {
        let names: Vec<_> = QuadricKind::ALL.iter().map(|k| k.name()).collect();
        format!(
            "unknown quadric kind \"{}\" (one of {}, general)",
            q.kind,
            names.join(", ")
        )
    })?;
    if q.coefficients.is_some() {
        return Err("only a `general` quadric takes coefficients".into());
    }
    Ok(QuadricSurface::Canonical {
        kind,
        a: q.a.unwrap_or(1.0),
        b: q.b.unwrap_or(1.0),
        c: q.c.unwrap_or(1.0),
    })
}

/// The definition of a quadric in its own object frame (the node supplies its transform).
pub fn quadric_def(q: &Quadric, material: Option<usize>, name: Option<String>) -> ShapeDef {
    let quadric = match q.surface_description() {
        QuadricSurface::Canonical { kind, a, b, c } => QuadricDef {
            kind: kind.name().into(),
            a: Some(a),
            b: Some(b),
            c: Some(c),
            coefficients: None,
        },
        QuadricSurface::General(k) => QuadricDef {
            kind: "general".into(),
            coefficients: Some(k.0.to_vec()),
            ..QuadricDef::default()
        },
    };
    let clip = q.clip();
    ShapeDef {
        kind: "quadric".into(),
        name,
        quadric: Some(quadric),
        clip: Some(ClipDef {
            min: clip.min.to_array(),
            max: clip.max.to_array(),
        }),
        material,
        ..ShapeDef::default()
    }
}

/// quadray's parameters of `m` as the material extension; `None` for the texture when it is an
/// image (carried by the glTF base colour texture instead).
pub fn whitted_def(m: &Material) -> WhittedDef {
    let texture = match &m.texture {
        Texture::Constant(c) => Some(TextureDef::Constant {
            color: c.to_array(),
        }),
        Texture::HeightRamp => Some(TextureDef::Ramp),
        Texture::Bands { steps } => Some(TextureDef::Bands { steps: *steps }),
        Texture::Checker { size, even, odd } => Some(TextureDef::Checker {
            size: *size,
            even: even.to_array(),
            odd: odd.to_array(),
        }),
        Texture::Image(_) => None,
    };
    WhittedDef {
        ambient: m.ambient,
        diffuse: m.diffuse,
        specular: m.specular,
        shininess: m.shininess,
        specular_model: match m.specular_model {
            SpecularModel::Phong => "phong".into(),
            SpecularModel::Blinn => "blinn".into(),
            SpecularModel::Ggx => "ggx".into(),
        },
        reflectivity: m.reflectivity,
        reflection_tint: m.reflection_tint,
        specular_tint: m.specular_tint,
        roughness: m.roughness,
        texture,
    }
}

/// The material described by `def`, keeping `base_texture` (from the glTF base colour) when the
/// definition has no texture of its own.
pub fn whitted_material(def: &WhittedDef, base_texture: Texture) -> Result<Material, String> {
    for (name, v) in [
        ("ambient", def.ambient),
        ("diffuse", def.diffuse),
        ("specular", def.specular),
        ("shininess", def.shininess),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "`{name}` must be a finite non-negative number, got {v}"
            ));
        }
    }
    for (name, v) in [
        ("reflectivity", def.reflectivity),
        ("reflectionTint", def.reflection_tint),
        ("specularTint", def.specular_tint),
        ("roughness", def.roughness),
    ] {
        if !(0.0..=1.0).contains(&v) {
            return Err(format!("`{name}` must be in [0, 1], got {v}"));
        }
    }
    let specular_model = match def.specular_model.as_str() {
        "phong" => SpecularModel::Phong,
        "blinn" => SpecularModel::Blinn,
        "ggx" => SpecularModel::Ggx,
        other => {
            return Err(format!(
                "unknown specularModel \"{other}\" (phong, blinn, ggx)"
            ));
        }
    };
    let colour = |c: [f32; 3]| -> Result<Vec3, String> {
        let v = Vec3::from_array(c);
        if v.is_finite() && v.min_element() >= 0.0 {
            Ok(v)
        } else {
            Err(format!("colours must be finite and non-negative, got {v}"))
        }
    };
    let texture = match &def.texture {
        None => base_texture,
        Some(TextureDef::Constant { color }) => Texture::Constant(colour(*color)?),
        Some(TextureDef::Ramp) => Texture::HeightRamp,
        Some(TextureDef::Bands { steps }) if *steps >= 1 => Texture::Bands { steps: *steps },
        Some(TextureDef::Bands { .. }) => return Err("bands need at least one step".into()),
        Some(TextureDef::Checker { size, even, odd }) => {
            if !(*size > 0.0 && size.is_finite()) {
                return Err(format!("checker size must be positive, got {size}"));
            }
            Texture::Checker {
                size: *size,
                even: colour(*even)?,
                odd: colour(*odd)?,
            }
        }
    };
    Ok(Material {
        texture,
        ambient: def.ambient,
        diffuse: def.diffuse,
        specular: def.specular,
        shininess: def.shininess,
        specular_model,
        reflectivity: def.reflectivity,
        reflection_tint: def.reflection_tint,
        specular_tint: def.specular_tint,
        // glTF's own emissive fields carry emission, for every viewer.
        emission: None,
        roughness: def.roughness,
        transmission: None,
    })
}

/// Whether a serialised number is its default, 0 (left out of the file).
fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(json: &str) -> ShapeDef {
        serde_json::from_str(json).unwrap()
    }

    #[test]
    fn places_quadrics_spheres_and_planes() {
        let t = DAffine3::from_translation(DVec3::new(1.0, 2.0, 3.0));
        let q = shape(
            r#"{"type": "quadric", "quadric": {"kind": "cone", "a": 0.5, "b": 0.5, "c": 1}, "clip": {"min": [-1, -1, 0], "max": [1, 1, 1]}, "material": 0}"#,
        );
        let PlacedShape::Quadric(q) = place(&q, t, 4).unwrap() else {
            panic!()
        };
        assert_eq!(q.material(), 4);
        assert_eq!(q.clip().min, DVec3::new(-1.0, -1.0, 0.0));
        assert_eq!(
            q.transform().to_world.translation,
            DVec3::new(1.0, 2.0, 3.0)
        );
        let s = shape(r#"{"type": "sphere", "sphere": {"radius": 2}}"#);
        let PlacedShape::Sphere(s) = place(&s, t, 0).unwrap() else {
            panic!()
        };
        assert_eq!((s.center, s.radius), (DVec3::new(1.0, 2.0, 3.0), 2.0));
        let p = shape(r#"{"type": "plane"}"#);
        let rot = DAffine3::from_rotation_x(std::f64::consts::FRAC_PI_2);
        let PlacedShape::Plane(p) = place(&p, rot, 0).unwrap() else {
            panic!()
        };
        assert!((p.normal - DVec3::NEG_Y).length() < 1e-12);
        let g = shape(
            r#"{"type": "quadric", "quadric": {"kind": "general", "coefficients": [1,1,1,0,0,0,0,0,0,-1]}}"#,
        );
        let PlacedShape::Quadric(g) = place(&g, DAffine3::IDENTITY, 0).unwrap() else {
            panic!()
        };
        assert_eq!(g.clip(), ClipBox::cube(1.0));
    }

    #[test]
    fn bad_definitions_say_what_is_wrong() {
        let e = |j: &str| place(&shape(j), DAffine3::IDENTITY, 0).unwrap_err();
        assert!(e(r#"{"type": "torus"}"#).contains("unknown shape type"));
        assert!(e(r#"{"type": "quadric"}"#).contains("needs `quadric`"));
        assert!(
            e(r#"{"type": "quadric", "quadric": {"kind": "saddle"}}"#)
                .contains("unknown quadric kind")
        );
        assert!(
            e(r#"{"type": "quadric", "quadric": {"kind": "general", "coefficients": [1, 2]}}"#)
                .contains("exactly 10")
        );
        assert!(
            e(r#"{"type": "quadric", "quadric": {"kind": "ellipsoid", "a": -1}}"#).contains("a")
        );
        assert!(e(r#"{"type": "sphere", "sphere": {"radius": 0}}"#).contains("positive"));
        assert!(
            e(r#"{"type": "plane", "clip": {"min": [0,0,0], "max": [1,1,1]}}"#)
                .contains("no `clip`")
        );
        assert!(serde_json::from_str::<ShapeDef>(r#"{"type": "plane", "colour": 1}"#).is_err());
    }

    #[test]
    fn whitted_parameters_round_trip() {
        let m = Material {
            texture: Texture::Checker {
                size: 0.25,
                even: Vec3::new(0.1, 0.2, 0.3),
                odd: Vec3::ONE,
            },
            ambient: 0.05,
            diffuse: 0.7,
            specular: 0.4,
            shininess: 80.0,
            specular_model: SpecularModel::Blinn,
            reflectivity: 0.6,
            reflection_tint: 0.5,
            specular_tint: 0.25,
            emission: None,
            roughness: 0.0,
            transmission: None,
        };
        let def = whitted_def(&m);
        let json = serde_json::to_string(&def).unwrap();
        assert!(json.contains("\"specularModel\":\"blinn\""), "{json}");
        let back: WhittedDef = serde_json::from_str(&json).unwrap();
        assert_eq!(whitted_material(&back, Texture::HeightRamp).unwrap(), m);
        let mut bad = def.clone();
        bad.reflectivity = 2.0;
        assert!(
            whitted_material(&bad, Texture::HeightRamp)
                .unwrap_err()
                .contains("reflectivity")
        );
    }
}
