//! The scene file's tables as serde reads them: every table denies unknown keys, and every value
//! a later check may reject keeps its span.

use super::V3;
use super::exact::Exact;
use serde::Deserialize;
use toml::Spanned;

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) version: Spanned<i64>,
    pub(super) camera: Option<Spanned<CameraSpec>>,
    #[serde(default)]
    pub(super) render: RenderSpec,
    pub(super) output: Option<Spanned<OutputSpec>>,
    #[serde(default, rename = "material")]
    pub(super) materials: Vec<Spanned<MaterialSpec>>,
    #[serde(default, rename = "sphere")]
    pub(super) spheres: Vec<Spanned<SphereSpec>>,
    #[serde(default, rename = "spheres")]
    pub(super) sphere_sets: Vec<Spanned<SphereSetSpec>>,
    #[serde(default, rename = "plane")]
    pub(super) planes: Vec<Spanned<PlaneSpec>>,
    #[serde(default, rename = "quadric")]
    pub(super) quadrics: Vec<Spanned<QuadricSpec>>,
    #[serde(default, rename = "mesh")]
    pub(super) meshes: Vec<Spanned<MeshSpec>>,
    #[serde(default, rename = "light")]
    pub(super) lights: Vec<Spanned<LightSpec>>,
    #[serde(default, rename = "include")]
    pub(super) includes: Vec<Spanned<IncludeSpec>>,
    #[serde(default, rename = "group")]
    pub(super) groups: Vec<Spanned<GroupSpec>>,
    #[serde(default, rename = "instance")]
    pub(super) instances: Vec<Spanned<InstanceSpec>>,
}

/// `[[group]]`: named shapes, groups and instances placed together by one transform.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GroupSpec {
    pub(super) name: Spanned<String>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    /// Only a definition for instances: not placed where it is written.
    pub(super) template: Option<Spanned<bool>>,
    #[serde(default, rename = "sphere")]
    pub(super) spheres: Vec<Spanned<SphereSpec>>,
    #[serde(default, rename = "spheres")]
    pub(super) sphere_sets: Vec<Spanned<SphereSetSpec>>,
    /// Present only to be refused with a clear message: a plane is unbounded.
    #[serde(default, rename = "plane")]
    pub(super) planes: Vec<Spanned<PlaneSpec>>,
    #[serde(default, rename = "quadric")]
    pub(super) quadrics: Vec<Spanned<QuadricSpec>>,
    #[serde(default, rename = "mesh")]
    pub(super) meshes: Vec<Spanned<MeshSpec>>,
    #[serde(default, rename = "group")]
    pub(super) groups: Vec<Spanned<GroupSpec>>,
    #[serde(default, rename = "instance")]
    pub(super) instances: Vec<Spanned<InstanceSpec>>,
}

/// `[[instance]]`: a named group or shape placed again.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct InstanceSpec {
    pub(super) of: Spanned<String>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) material: Option<Spanned<String>>,
}

/// A glTF scene or camera chosen by index or by name.
#[derive(Clone, Deserialize)]
#[serde(untagged, expecting = "an index (a whole number) or a name (a string)")]
pub(super) enum SelectorSpec {
    Index(i64),
    Name(String),
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct IncludeSpec {
    pub(super) path: Spanned<String>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) scene: Option<Spanned<SelectorSpec>>,
    pub(super) camera: Option<Spanned<SelectorSpec>>,
    pub(super) lights: Option<bool>,
    pub(super) up: Option<Spanned<String>>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    pub(super) projection: Option<Spanned<String>>,
    pub(super) from: Option<Spanned<V3>>,
    pub(super) to: Option<Spanned<V3>>,
    pub(super) up: Option<Spanned<V3>>,
    pub(super) vfov: Option<Spanned<f64>>,
    pub(super) height: Option<Spanned<f64>>,
    pub(super) orbit: Option<Spanned<OrbitSpec>>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OrbitSpec {
    pub(super) yaw: Spanned<f64>,
    pub(super) pitch: Spanned<f64>,
    pub(super) distance: Spanned<f64>,
    pub(super) target: Option<Spanned<V3>>,
}

#[derive(Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderSpec {
    pub(super) resolution: Option<Spanned<Exact<i64, 2>>>,
    pub(super) spp: Option<Spanned<i64>>,
    pub(super) target_error: Option<Spanned<f64>>,
    pub(super) pixel_error: Option<Spanned<f64>>,
    pub(super) spp_budget: Option<Spanned<f64>>,
    pub(super) min_spp: Option<Spanned<i64>>,
    pub(super) max_spp: Option<Spanned<i64>>,
    pub(super) time_limit: Option<Spanned<f64>>,
    pub(super) antialias_threshold: Option<Spanned<f64>>,
    pub(super) antialias_spp: Option<Spanned<i64>>,
    pub(super) max_depth: Option<Spanned<i64>>,
    pub(super) background: Option<Spanned<V3>>,
    pub(super) environment: Option<Spanned<V3>>,
    pub(super) compact_meshes: Option<bool>,
}

/// `[output]`: where `quadray render SCENE` writes when no `-o` is given.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OutputSpec {
    pub(super) file: Spanned<String>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialSpec {
    pub(super) name: Spanned<String>,
    pub(super) color: Option<Spanned<V3>>,
    pub(super) texture: Option<Spanned<String>>,
    pub(super) bands: Option<Spanned<i64>>,
    pub(super) checker_size: Option<Spanned<f64>>,
    pub(super) color2: Option<Spanned<V3>>,
    pub(super) ambient: Option<Spanned<f64>>,
    pub(super) diffuse: Option<Spanned<f64>>,
    pub(super) specular: Option<Spanned<f64>>,
    pub(super) shininess: Option<Spanned<f64>>,
    pub(super) specular_model: Option<Spanned<String>>,
    pub(super) reflectivity: Option<Spanned<f64>>,
    pub(super) reflection_tint: Option<Spanned<f64>>,
    pub(super) specular_tint: Option<Spanned<f64>>,
    pub(super) emission: Option<Spanned<V3>>,
    pub(super) roughness: Option<Spanned<f64>>,
    pub(super) transmission: Option<Spanned<f64>>,
    pub(super) ior: Option<Spanned<f64>>,
    pub(super) thin_walled: Option<Spanned<bool>>,
    pub(super) attenuation_color: Option<Spanned<V3>>,
    pub(super) attenuation_distance: Option<Spanned<f64>>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SphereSpec {
    pub(super) name: Option<Spanned<String>>,
    pub(super) center: Spanned<V3>,
    pub(super) radius: Spanned<f64>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) material: Spanned<String>,
}

/// `[[spheres]]`: one sphere a vertex of a PLY file.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SphereSetSpec {
    pub(super) path: Spanned<String>,
    /// The radius of vertices without a `radius` property.
    pub(super) radius: Option<Spanned<f64>>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) material: Spanned<String>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PlaneSpec {
    pub(super) point: Spanned<V3>,
    pub(super) normal: Spanned<V3>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) material: Spanned<String>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct QuadricSpec {
    pub(super) name: Option<Spanned<String>>,
    pub(super) kind: Spanned<String>,
    pub(super) a: Option<Spanned<f64>>,
    pub(super) b: Option<Spanned<f64>>,
    pub(super) c: Option<Spanned<f64>>,
    pub(super) coefficients: Option<Spanned<Vec<f64>>>,
    pub(super) clip: Spanned<ClipSpec>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) material: Spanned<String>,
}

#[derive(Clone, Deserialize)]
#[serde(
    untagged,
    expecting = "a clip radius (a number) or a box { min = [x, y, z], max = [x, y, z] }"
)]
pub(super) enum ClipSpec {
    Radius(f64),
    Box(ClipBoxSpec),
}

/// A clip box's corners: a struct of its own so an unknown key is refused, which an untagged
/// enum's struct variant cannot ask for.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ClipBoxSpec {
    pub(super) min: V3,
    pub(super) max: V3,
}

#[derive(Clone, Deserialize)]
#[serde(untagged, expecting = "a scale: one number, or [x, y, z]")]
pub(super) enum ScaleSpec {
    Uniform(f64),
    PerAxis(V3),
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TransformSpec {
    pub(super) translate: Option<Spanned<V3>>,
    pub(super) rotate: Option<Spanned<V3>>,
    /// A unit quaternion [x, y, z, w] (glTF's order), instead of `rotate`.
    pub(super) rotation: Option<Spanned<Exact<f64, 4>>>,
    pub(super) scale: Option<Spanned<ScaleSpec>>,
    /// A 4x4 affine matrix, row-major, instead of the other keys.
    pub(super) matrix: Option<Spanned<Exact<Exact<f64, 4>, 4>>>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MeshSpec {
    pub(super) name: Option<Spanned<String>>,
    pub(super) path: Option<Spanned<String>>,
    pub(super) vertices: Option<Spanned<Vec<V3>>>,
    pub(super) indices: Option<Spanned<Vec<Exact<i64, 3>>>>,
    pub(super) normals: Option<Spanned<Vec<V3>>>,
    pub(super) transform: Option<Spanned<TransformSpec>>,
    pub(super) material: Option<Spanned<String>>,
    pub(super) up: Option<Spanned<String>>,
    pub(super) scene: Option<Spanned<SelectorSpec>>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightSpec {
    #[serde(rename = "type")]
    pub(super) kind: Spanned<String>,
    pub(super) position: Option<Spanned<V3>>,
    pub(super) direction: Option<Spanned<V3>>,
    pub(super) color: Option<Spanned<V3>>,
    pub(super) intensity: Option<Spanned<f64>>,
    pub(super) inner_angle: Option<Spanned<f64>>,
    pub(super) outer_angle: Option<Spanned<f64>>,
    pub(super) falloff: Option<Spanned<bool>>,
}
