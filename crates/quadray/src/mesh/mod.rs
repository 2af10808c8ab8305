//! Indexed triangle meshes with optional per-vertex normals, texture coordinates, colours and
//! tangents, intersected in f64, with optional partial coverage and normal maps.
//!
//! Memory: 12 bytes a triangle (indices) plus 12 a vertex (position), and per vertex 12 more for
//! normals, 8 per texture coordinate set, 16 for colours and 16 for tangents, each only when the
//! mesh has them.

use crate::material::MaterialId;
use crate::math::{Ray, gamma};
use crate::shape::{SurfaceGeometry, normal_or};
use crate::texture::{TexturePoint, VertexAttributes};
use crate::triangle::{ShearedRay, plane_t};
use glam::{DVec3, Vec2, Vec3, Vec4};

/// Why a mesh is invalid.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} uses vertex index {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle number.
        triangle: usize,
        /// The offending index.
        index: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A position or normal is NaN or infinite.
    #[error("vertex {0} has a NaN or infinite coordinate")]
    NotFinite(usize),
    /// Normals are given but not one per vertex.
    #[error("the mesh has {vertices} vertices but {normals} normals")]
    NormalCount {
        /// Vertex count.
        vertices: usize,
        /// Normal count.
        normals: usize,
    },
    /// A per-vertex attribute (texture coordinates, colours) is not given once per vertex.
    #[error("the mesh has {vertices} vertices but {count} {what}")]
    AttributeCount {
        /// Which attribute.
        what: &'static str,
        /// Vertex count.
        vertices: usize,
        /// Attribute count.
        count: usize,
    },
    /// A texture coordinate or colour is NaN or infinite.
    #[error("vertex {vertex} has a NaN or infinite {what}")]
    AttributeNotFinite {
        /// Which attribute.
        what: &'static str,
        /// The vertex.
        vertex: usize,
    },
    /// A texture coordinate set other than 0 or 1.
    #[error("texture coordinate set {0} does not exist (0 or 1)")]
    TexCoordSet(usize),
    /// An alpha cutoff or factor outside [0, 1].
    #[error("alpha cutoff and factor must be in [0, 1], got {cutoff} and {factor}")]
    AlphaRange {
        /// The cutoff.
        cutoff: f32,
        /// The factor.
        factor: f32,
    },
    /// A normal map on a mesh without what it needs.
    #[error("a normal map needs {0}")]
    NormalMapNeeds(&'static str),
}

/// A triangle mesh in world space (loaders bake the object's transform into the vertices).
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    indices: Vec<[u32; 3]>,
    material: MaterialId,
    z_range: (f64, f64),
    texcoords: [Option<Vec<Vec2>>; 2],
    colors: Option<Vec<Vec4>>,
    tangents: Option<Vec<Vec4>>,
    normal_map: Option<NormalMap>,
    alpha_mask: Option<AlphaMask>,
    single_sided: bool,
}

impl Mesh {
    /// A validated mesh: every index in range, every coordinate finite, one normal per vertex if any.
    pub fn new(
        positions: Vec<Vec3>,
        indices: Vec<[u32; 3]>,
        normals: Option<Vec<Vec3>>,
        material: MaterialId,
    ) -> Result<Mesh, MeshError> {
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NotFinite(i));
        }
        if let Some(n) = &normals {
            if n.len() != positions.len() {
                return Err(MeshError::NormalCount {
                    vertices: positions.len(),
                    normals: n.len(),
                });
            }
            if let Some(i) = n.iter().position(|v| !v.is_finite()) {
                return Err(MeshError::NotFinite(i));
            }
        }
        for (triangle, tri) in indices.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: positions.len(),
                });
            }
        }
        let (lo, hi) = positions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.z as f64), hi.max(p.z as f64))
            });
        Ok(Mesh {
            positions,
            normals,
            indices,
            material,
            z_range: (lo, hi),
            texcoords: [None, None],
            colors: None,
            tangents: None,
            normal_map: None,
            alpha_mask: None,
            single_sided: false,
        })
    }

    /// Adds texture coordinate set `set` (0 or 1), one per vertex, in the image convention (v down).
    pub fn with_texcoords(mut self, set: usize, uv: Vec<Vec2>) -> Result<Mesh, MeshError> {
        if set > 1 {
            return Err(MeshError::TexCoordSet(set));
        }
        self.check_attribute("texture coordinates", uv.len())?;
        if let Some(vertex) = uv.iter().position(|t| !t.is_finite()) {
            return Err(MeshError::AttributeNotFinite {
                what: "texture coordinate",
                vertex,
            });
        }
        self.texcoords[set] = Some(uv);
        Ok(self)
    }

    /// Adds linear RGBA vertex colours, one per vertex.
    pub fn with_colors(mut self, colors: Vec<Vec4>) -> Result<Mesh, MeshError> {
        self.check_attribute("colours", colors.len())?;
        if let Some(vertex) = colors.iter().position(|c| !c.is_finite()) {
            return Err(MeshError::AttributeNotFinite {
                what: "colour",
                vertex,
            });
        }
        self.colors = Some(colors);
        Ok(self)
    }

    /// Makes the mesh a cut-out: hits whose alpha is below the mask's cutoff are ignored.
    pub fn with_alpha_mask(mut self, mask: AlphaMask) -> Result<Mesh, MeshError> {
        if !((0.0..=1.0).contains(&mask.cutoff) && (0.0..=1.0).contains(&mask.factor)) {
            return Err(MeshError::AlphaRange {
                cutoff: mask.cutoff,
                factor: mask.factor,
            });
        }
        self.alpha_mask = Some(mask);
        Ok(self)
    }

    /// Makes the mesh single-sided (glTF's `doubleSided: false`) or two-sided (the default).
    /// Every ray (camera, reflection and shadow) passes through the back of a single-sided mesh's
    /// triangles, the side from which their vertices turn clockwise: a culled face is not part of
    /// the scene (glTF's NegativeScaleTest and TextureSettingsTest show shadows of culled faces
    /// as the failure).
    pub fn with_single_sided(mut self, single_sided: bool) -> Mesh {
        self.single_sided = single_sided;
        self
    }

    /// Whether camera and reflection rays see only the front of the triangles.
    pub fn single_sided(&self) -> bool {
        self.single_sided
    }

    /// Whether `dir` meets triangle `tri` from the back: along its winding normal, the side from
    /// which its vertices turn clockwise (glTF's and OpenGL's convention: counter-clockwise is the
    /// front). A ray in the triangle's plane meets it from the front.
    pub fn faces_away(&self, tri: u32, dir: DVec3) -> bool {
        let [v0, v1, v2] = self.vertices(tri);
        (v1 - v0).cross(v2 - v0).dot(dir) > 0.0
    }

    fn check_attribute(&self, what: &'static str, count: usize) -> Result<(), MeshError> {
        if count != self.positions.len() {
            return Err(MeshError::AttributeCount {
                what,
                vertices: self.positions.len(),
                count,
            });
        }
        Ok(())
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Per-vertex normals, if any.
    pub fn normals(&self) -> Option<&[Vec3]> {
        self.normals.as_deref()
    }

    /// Triangles as vertex index triples.
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// Texture coordinate set `set` (0 or 1), if present.
    pub fn texcoords(&self, set: usize) -> Option<&[Vec2]> {
        self.texcoords.get(set).and_then(|t| t.as_deref())
    }

    /// Vertex colours, if present.
    pub fn colors(&self) -> Option<&[Vec4]> {
        self.colors.as_deref()
    }

    /// The alpha cut-out, if any.
    pub fn alpha_mask(&self) -> Option<&AlphaMask> {
        self.alpha_mask.as_ref()
    }

    /// Material index.
    pub fn material(&self) -> MaterialId {
        self.material
    }

    /// The same mesh with another material (a scene file's material override).
    pub fn with_material(mut self, material: MaterialId) -> Mesh {
        self.material = material;
        self
    }

    /// Bytes of geometry and attribute memory the mesh holds (not counting the BVH).
    pub fn memory_bytes(&self) -> usize {
        let v = self.positions.len();
        let per_vertex = 12
            + self.normals.as_ref().map_or(0, |_| 12)
            + self.texcoords.iter().flatten().count() * 8
            + self.colors.as_ref().map_or(0, |_| 16);
        v * per_vertex + self.indices.len() * 12
    }

    /// Whether the vertices carry colours (which multiply the material's colour).
    #[inline]
    pub fn has_colors(&self) -> bool {
        self.colors.is_some()
    }

    /// Whether hits carry interpolated attributes (texture coordinates or colours).
    #[inline]
    pub fn has_attributes(&self) -> bool {
        self.texcoords.iter().any(Option::is_some) || self.colors.is_some()
    }

    /// Vertex attributes at barycentric coordinates `b` of triangle `tri`.
    #[inline]
    fn attributes_at(&self, tri: u32, b: [f32; 3]) -> VertexAttributes {
        let idx = self.indices[tri as usize].map(|i| i as usize);
        let mut out = VertexAttributes::default();
        for (set, uv) in self.texcoords.iter().enumerate() {
            if let Some(uv) = uv {
                out.uv[set] = uv[idx[0]] * b[0] + uv[idx[1]] * b[1] + uv[idx[2]] * b[2];
            }
        }
        if let Some(c) = &self.colors {
            out.color = c[idx[0]] * b[0] + c[idx[1]] * b[1] + c[idx[2]] * b[2];
        }
        out
    }

    /// Interpolated vertex attributes at `point` on triangle `tri` (defaults when the mesh has none).
    pub fn attributes(&self, tri: u32, point: DVec3) -> VertexAttributes {
        if !self.has_attributes() {
            return VertexAttributes::default();
        }
        let [v0, v1, v2] = self.vertices(tri);
        let [b0, b1, b2] = barycentrics(v1 - v0, v2 - v0, point - v0);
        self.attributes_at(tri, [b0 as f32, b1 as f32, b2 as f32])
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The vertices of triangle `tri`, in f64.
    #[inline]
    pub(crate) fn vertices(&self, tri: u32) -> [DVec3; 3] {
        let [a, b, c] = self.indices[tri as usize];
        [a, b, c].map(|i| self.positions[i as usize].as_dvec3())
    }

    /// Bounds of triangle `tri`, world space.
    pub fn triangle_bounds(&self, tri: u32) -> (DVec3, DVec3) {
        let [a, b, c] = self.vertices(tri);
        (a.min(b).min(c), a.max(b).max(c))
    }

    /// The watertight test ([`crate::triangle`]) on the f32 rounding of `ray`, then refined in f64:
    /// parameter t in (0, `t_max`) where the ray meets triangle `tri`. A ray spawned on a triangle
    /// cannot meet that (planar) triangle again. The BVH traversal runs the same test.
    pub fn intersect(&self, tri: u32, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        if from_self {
            return None;
        }
        let sheared = ShearedRay::from_f64(ray.origin, ray.dir);
        let [a, b, c] = self.triangle_positions(tri);
        let hit = sheared.intersect(a, b, c, f32::INFINITY)?;
        if self.alpha_mask.is_some()
            && !self.covers(tri, hit.barycentrics, || {
                coverage_key(ray.origin.as_vec3(), ray.dir.as_vec3())
            })
        {
            return None;
        }
        let t = self.refine_t(tri, ray, hit.t as f64);
        (t < t_max).then_some(t)
    }

    /// The f64 parameter where `ray` meets the plane of triangle `tri`, from the f32 test's `t`.
    #[inline]
    pub fn refine_t(&self, tri: u32, ray: &Ray, t: f64) -> f64 {
        plane_t(ray.origin, ray.dir, self.vertices(tri), t)
    }

    /// The three vertex positions of triangle `tri`, as arrays for the watertight test.
    #[inline(always)]
    pub(crate) fn triangle_positions(&self, tri: u32) -> [&[f32; 3]; 3] {
        let [a, b, c] = self.indices[tri as usize];
        [a, b, c].map(|i| self.positions[i as usize].as_ref())
    }

    /// Surface geometry where `ray` meets triangle `tri` at parameter `t`.
    pub fn surface(&self, tri: u32, ray: &Ray, t: f64) -> SurfaceGeometry {
        let [v0, v1, v2] = self.vertices(tri);
        let e1 = v1 - v0;
        let e2 = v2 - v0;
        let geometric_normal = normal_or(e1.cross(e2), -ray.dir);
        // Barycentrics of the ray point, then the point rebuilt from them: it lies in the triangle's
        // plane up to a few roundings of the vertex magnitudes, whatever t's error.
        let [b0, b1, b2] = barycentrics(e1, e2, ray.at(t) - v0);
        let point = v0 + e1 * b1 + e2 * b2;
        let error = gamma(7) * (v0.abs() + e1.abs() + e2.abs()).max_element() * 2.0;
        let shading_normal = match &self.normals {
            Some(n) => {
                let [a, b, c] = self.indices[tri as usize];
                let interp = n[a as usize].as_dvec3() * b0
                    + n[b as usize].as_dvec3() * b1
                    + n[c as usize].as_dvec3() * b2;
                let mut s = normal_or(interp, geometric_normal);
                if let Some(map) = &self.normal_map {
                    s = self.bend(map, tri, [b0, b1, b2], s);
                }
                // Keep the shading normal on the geometric normal's side.
                if s.dot(geometric_normal) < 0.0 { -s } else { s }
            }
            None => geometric_normal,
        };
        SurfaceGeometry {
            point,
            geometric_normal,
            shading_normal,
            error,
        }
    }

    /// Texture coordinates of a surface point: the point itself, height over the mesh's z extent.
    pub fn texture_point(&self, point: DVec3) -> TexturePoint {
        let (lo, hi) = self.z_range;
        let height = if hi > lo {
            ((point.z - lo) / (hi - lo)) as f32
        } else {
            0.5
        };
        TexturePoint {
            local: point,
            height,
        }
    }

    /// How the texture coordinates change along the vector `v` (they are affine in the point).
    pub fn texture_offset(&self, v: DVec3) -> TexturePoint {
        let (lo, hi) = self.z_range;
        TexturePoint {
            local: v,
            height: if hi > lo {
                (v.z / (hi - lo)) as f32
            } else {
                0.0
            },
        }
    }
}

/// Barycentric coordinates (clamped into the triangle) of `p` (relative to `v0`) in the triangle
/// spanned by edges `e1`, `e2` from `v0`.
#[inline]
fn barycentrics(e1: DVec3, e2: DVec3, p: DVec3) -> [f64; 3] {
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (p1, p2) = (p.dot(e1), p.dot(e2));
    let denom = d11 * d22 - d12 * d12;
    // Huge (finite) coordinates can overflow these products into NaN, on which `clamp` panics:
    // such a point falls back to the first vertex.
    let within = |x: f64, hi: f64| if x.is_nan() { 0.0 } else { x.clamp(0.0, hi) };
    let b1 = within((d22 * p1 - d12 * p2) / denom, 1.0);
    let b2 = within((d11 * p2 - d12 * p1) / denom, 1.0 - b1);
    [1.0 - b1 - b2, b1, b2]
}

mod coverage;
mod normal_map;

pub use coverage::AlphaMask;
pub(crate) use coverage::coverage_key;
pub use normal_map::NormalMap;
#[cfg(test)]
mod tests;
