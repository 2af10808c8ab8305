//! Indexed triangle meshes with optional per-vertex normals, texture coordinates and colours,
//! intersected in f64, with optional alpha cut-outs.
//!
//! Memory: 12 bytes a triangle (indices) plus 12 a vertex (position), and per vertex 12 more for
//! normals, 8 per texture coordinate set and 16 for colours, each only when the mesh has them.

use crate::image_texture::ImageMap;
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
}

/// Partial coverage: a cut-out (glTF alpha mode MASK), where hits whose coverage alpha is below
/// `cutoff` are not hits, or stochastic coverage (glTF BLEND), where a hit with alpha a is kept
/// for a share a of rays.
///
/// Alpha at a point = `factor` × the map's alpha × the vertex colour's alpha. The test runs inside
/// BVH traversal, so coverage lets camera, shadow and reflection rays through alike.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMask {
    /// Alpha below this is transparent (glTF alphaCutoff, default 0.5); unused when stochastic.
    pub cutoff: f32,
    /// Whether alpha is a probability instead (glTF BLEND): each ray keeps the hit when alpha
    /// exceeds a value hashed from the ray and the triangle, uniform in [0, 1). Over a pixel's
    /// samples this converges to the blend of the surface over what lies behind, in any order of
    /// layers; at one sample a pixel it dithers.
    pub stochastic: bool,
    /// Constant alpha factor (glTF baseColorFactor's alpha).
    pub factor: f32,
    /// The image whose alpha channel modulates coverage, if any (glTF baseColorTexture).
    pub map: Option<ImageMap>,
}

/// The hash of a ray, from its f32 origin and a direction vector (the BVH passes its reciprocal),
/// that stochastic coverage draws from: the same ray meets the same decision in every query of
/// one kind, different rays independent ones, and the image stays the same for any thread count.
#[inline]
pub(crate) fn coverage_key(origin: Vec3, dir: Vec3) -> u32 {
    [origin.x, origin.y, origin.z, dir.x, dir.y, dir.z]
        .iter()
        .fold(0x2545_F491, |h, c| mix(h ^ c.to_bits()))
}

/// A 32-bit finaliser (the murmur3 mix): every input bit flips each output bit about half the time.
#[inline]
fn mix(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 13;
    h = h.wrapping_mul(0xC2B2_AE35);
    h ^ (h >> 16)
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
    /// Camera and reflection rays pass through the back of a single-sided mesh's triangles, the
    /// side from which their vertices turn clockwise; shadow rays still stop there, as glTF
    /// viewers draw shadows.
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

    /// Whether the coverage at barycentric coordinates `b` of triangle `tri` keeps the hit of the
    /// ray with [`coverage_key`] `key`.
    #[inline]
    fn covered(&self, mask: &AlphaMask, tri: u32, b: [f32; 3], key: u32) -> bool {
        let mut alpha = mask.factor;
        if mask.map.is_some() || self.colors.is_some() {
            let a = self.attributes_at(tri, b);
            alpha *= a.color.w;
            if let Some(map) = &mask.map {
                alpha *= map.sample(&a).w;
            }
        }
        if mask.stochastic {
            // 24 bits of the hash as a uniform value in [0, 1).
            let u = (mix(key ^ tri.wrapping_mul(0x9E37_79B9)) >> 8) as f32 / (1u32 << 24) as f32;
            alpha > u
        } else {
            alpha >= mask.cutoff
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    #[inline]
    fn vertices(&self, tri: u32) -> [DVec3; 3] {
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

    /// Whether the mesh's coverage keeps the point at barycentrics `b` of triangle `tri` (true
    /// without a mask); `key` gives the ray's [`coverage_key`] when stochastic coverage needs it.
    #[inline]
    pub(crate) fn covers(&self, tri: u32, b: [f32; 3], key: impl FnOnce() -> u32) -> bool {
        match &self.alpha_mask {
            Some(mask) => self.covered(mask, tri, b, if mask.stochastic { key() } else { 0 }),
            None => true,
        }
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
                let s = normal_or(interp, geometric_normal);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A zero-area triangle gives 0/0 barycentrics: they fall back to a vertex instead of
    /// panicking inside `clamp` (found by hostile input: a degenerate triangle hit and shaded).
    #[test]
    fn degenerate_triangles_have_finite_barycentrics() {
        for (e1, e2) in [
            (DVec3::ZERO, DVec3::ZERO),
            (DVec3::X, DVec3::X * 2.0),
            (DVec3::splat(1e300), DVec3::splat(-1e300)),
        ] {
            let b = barycentrics(e1, e2, DVec3::new(0.3, 0.2, 0.0));
            assert!(b.iter().all(|x| x.is_finite()), "{b:?}");
        }
    }

    fn quad() -> Mesh {
        let p = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        Mesh::new(p, vec![[0, 1, 2], [0, 2, 3]], None, 0).unwrap()
    }

    #[test]
    fn rejects_out_of_range_indices() {
        let err = Mesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 3]], None, 0).unwrap_err();
        assert_eq!(
            err,
            MeshError::IndexOutOfRange {
                triangle: 0,
                index: 3,
                vertices: 3
            }
        );
        assert!(Mesh::new(vec![Vec3::NAN; 3], vec![[0, 1, 2]], None, 0).is_err());
    }

    #[test]
    fn shared_edge_is_watertight() {
        let m = quad();
        // Rays through the diagonal shared by both triangles hit at least one of them.
        for k in 0..=100 {
            let s = -1.0 + 2.0 * k as f64 / 100.0;
            let r = Ray::new(DVec3::new(s, s, 1.0), -DVec3::Z);
            let hit = (0..2).any(|t| m.intersect(t, &r, f64::INFINITY, false).is_some());
            assert!(hit, "hole at {s}");
        }
    }

    #[test]
    fn normal_faces_by_winding() {
        let m = quad();
        let r = Ray::new(DVec3::new(0.3, -0.2, 2.0), -DVec3::Z);
        let t = m.intersect(0, &r, f64::INFINITY, false).unwrap();
        assert_eq!(t, 2.0);
        let g = m.surface(0, &r, t);
        assert_eq!(g.geometric_normal, DVec3::Z);
        assert!((g.point - DVec3::new(0.3, -0.2, 0.0)).length() < 1e-15);
    }

    #[test]
    fn attributes_interpolate_barycentrically() {
        let m = quad()
            .with_texcoords(
                0,
                vec![
                    Vec2::new(0.0, 1.0),
                    Vec2::new(1.0, 1.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(0.0, 0.0),
                ],
            )
            .unwrap()
            .with_colors(vec![
                Vec4::new(1.0, 0.0, 0.0, 1.0),
                Vec4::new(0.0, 1.0, 0.0, 1.0),
                Vec4::new(0.0, 0.0, 1.0, 1.0),
                Vec4::ONE,
            ])
            .unwrap();
        let a = m.attributes(0, DVec3::new(0.5, -0.5, 0.0));
        // (0.5, -0.5) = 0.25·v0 + 0.5·v1 + 0.25·v2 on triangle 0.
        assert!(
            (a.uv[0] - Vec2::new(0.75, 0.75)).length() < 1e-6,
            "{:?}",
            a.uv
        );
        assert!((a.color - Vec4::new(0.25, 0.5, 0.25, 1.0)).length() < 1e-6);
        assert_eq!(a.uv[1], Vec2::ZERO);
        assert!(matches!(
            quad().with_texcoords(0, vec![Vec2::ZERO; 3]),
            Err(MeshError::AttributeCount { count: 3, .. })
        ));
        assert!(matches!(
            quad().with_texcoords(2, vec![Vec2::ZERO; 4]),
            Err(MeshError::TexCoordSet(2))
        ));
        assert_eq!(m.memory_bytes(), 4 * (12 + 8 + 16) + 2 * 12);
    }

    #[test]
    fn alpha_mask_cuts_holes_inside_intersection() {
        // Vertex alpha 0 at x = -1 rising to 1 at x = +1: the left half is cut away at cutoff 0.5.
        let colors = [-1.0f32, 1.0, 1.0, -1.0]
            .map(|x| Vec4::new(1.0, 1.0, 1.0, (x + 1.0) * 0.5))
            .to_vec();
        let m = quad()
            .with_colors(colors)
            .unwrap()
            .with_alpha_mask(AlphaMask {
                stochastic: false,
                cutoff: 0.5,
                factor: 1.0,
                map: None,
            })
            .unwrap();
        let hit = |x: f64| {
            let r = Ray::new(DVec3::new(x, 0.1, 1.0), -DVec3::Z);
            (0..2).any(|t| m.intersect(t, &r, f64::INFINITY, false).is_some())
        };
        assert!(!hit(-0.5));
        assert!(hit(0.5));
        let dim = quad().with_alpha_mask(AlphaMask {
            stochastic: false,
            cutoff: 0.5,
            factor: 0.4,
            map: None,
        });
        let dim = dim.unwrap();
        let r = Ray::new(DVec3::new(0.5, 0.1, 1.0), -DVec3::Z);
        assert!(dim.intersect(0, &r, f64::INFINITY, false).is_none());
        assert!(
            quad()
                .with_alpha_mask(AlphaMask {
                    stochastic: false,
                    cutoff: 1.5,
                    factor: 1.0,
                    map: None
                })
                .is_err()
        );
    }
}
