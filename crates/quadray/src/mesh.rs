//! Indexed triangle meshes with optional per-vertex normals, intersected in f64.

use crate::material::MaterialId;
use crate::math::{Ray, gamma};
use crate::shape::{SurfaceGeometry, normal_or};
use crate::texture::TexturePoint;
use glam::{DVec3, Vec3};

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
}

/// A triangle mesh in world space (loaders bake the object's transform into the vertices).
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    indices: Vec<[u32; 3]>,
    material: MaterialId,
    z_range: (f64, f64),
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
        })
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

    /// Material index.
    pub fn material(&self) -> MaterialId {
        self.material
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

    /// Möller–Trumbore in f64: parameter t in (0, `t_max`) where the ray meets triangle `tri`.
    /// A ray spawned on a triangle cannot meet that (planar) triangle again.
    #[inline]
    pub fn intersect(&self, tri: u32, ray: &Ray, t_max: f64, from_self: bool) -> Option<f64> {
        if from_self {
            return None;
        }
        let [v0, v1, v2] = self.vertices(tri);
        let e1 = v1 - v0;
        let e2 = v2 - v0;
        let pvec = ray.dir.cross(e2);
        let det = e1.dot(pvec);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let tvec = ray.origin - v0;
        let u = tvec.dot(pvec) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let qvec = tvec.cross(e1);
        let v = ray.dir.dot(qvec) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = e2.dot(qvec) * inv;
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// Surface geometry where `ray` meets triangle `tri` at parameter `t`.
    pub fn surface(&self, tri: u32, ray: &Ray, t: f64) -> SurfaceGeometry {
        let [v0, v1, v2] = self.vertices(tri);
        let e1 = v1 - v0;
        let e2 = v2 - v0;
        let geometric_normal = normal_or(e1.cross(e2), -ray.dir);
        // Barycentrics of the ray point, then the point rebuilt from them: it lies in the triangle's
        // plane up to a few roundings of the vertex magnitudes, whatever t's error.
        let p = ray.at(t) - v0;
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (p1, p2) = (p.dot(e1), p.dot(e2));
        let denom = d11 * d22 - d12 * d12;
        let b1 = ((d22 * p1 - d12 * p2) / denom).clamp(0.0, 1.0);
        let b2 = ((d11 * p2 - d12 * p1) / denom).clamp(0.0, 1.0 - b1);
        let b0 = 1.0 - b1 - b2;
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
