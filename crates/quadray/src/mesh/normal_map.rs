//! Tangent-space normal maps (glTF `normalTexture`): each vertex carries a tangent (along
//! increasing u) and the sign of its bitangent, and the map's texel bends the interpolated normal
//! within that frame.

use super::{Mesh, MeshError};
use crate::shape::normal_or;
use crate::texture::image::ImageMap;
use glam::{DVec3, Vec4};

/// A tangent-space normal map.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The image, read linearly: texel (r, g, b) is the normal (2r − 1, 2g − 1, 2b − 1) in the
    /// frame (tangent, bitangent, normal), glTF's and OpenGL's convention (+y towards the top of
    /// the image).
    pub map: ImageMap,
    /// Scale of the normal's tangent-plane part (glTF `normalTexture.scale`).
    pub scale: f32,
}

impl Mesh {
    /// Adds per-vertex tangents: xyz along increasing u, w = ±1 the sign of the bitangent, which
    /// is w · (normal × tangent) and points towards the top of the image (glTF's TANGENT).
    pub fn with_tangents(mut self, tangents: Vec<Vec4>) -> Result<Mesh, MeshError> {
        self.check_attribute("tangents", tangents.len())?;
        if let Some(vertex) = tangents.iter().position(|t| !t.is_finite()) {
            return Err(MeshError::AttributeNotFinite {
                what: "tangent",
                vertex,
            });
        }
        self.tangents = Some(tangents);
        Ok(self)
    }

    /// Adds a normal map. It needs the mesh's normals, tangents and the map's coordinate set.
    pub fn with_normal_map(mut self, map: NormalMap) -> Result<Mesh, MeshError> {
        let set = map.map.set as usize;
        let missing = if self.normals.is_none() {
            Some("normals")
        } else if self.tangents.is_none() {
            Some("tangents")
        } else if self.texcoords.get(set).is_none_or(Option::is_none) {
            Some("the texture coordinates it reads")
        } else {
            None
        };
        if let Some(what) = missing {
            return Err(MeshError::NormalMapNeeds(what));
        }
        if !map.scale.is_finite() {
            return Err(MeshError::NormalMapNeeds("a finite scale"));
        }
        self.normal_map = Some(map);
        Ok(self)
    }

    /// Per-vertex tangents, if any.
    pub fn tangents(&self) -> Option<&[Vec4]> {
        self.tangents.as_deref()
    }

    /// The normal map, if any.
    pub fn normal_map(&self) -> Option<&NormalMap> {
        self.normal_map.as_ref()
    }

    /// The unit normal `n`, interpolated at barycentrics `b` of triangle `tri`, bent by the
    /// normal map: n' = normalize(T·x + B·y + n·z) with (x, y, z) the texel's normal (x and y
    /// scaled), T the tangent made orthogonal to n and B = w·(n × T). A degenerate frame leaves
    /// `n` as it is.
    pub(super) fn bend(&self, map: &NormalMap, tri: u32, b: [f64; 3], n: DVec3) -> DVec3 {
        let Some(tangents) = &self.tangents else {
            return n;
        };
        let idx = self.indices[tri as usize].map(|i| i as usize);
        let t4 = tangents[idx[0]] * b[0] as f32
            + tangents[idx[1]] * b[1] as f32
            + tangents[idx[2]] * b[2] as f32;
        let t = t4.truncate().as_dvec3();
        let Some(tangent) = (t - n * n.dot(t)).try_normalize() else {
            return n;
        };
        let sign = if t4.w < 0.0 { -1.0 } else { 1.0 };
        let bitangent = n.cross(tangent) * sign;
        let attributes = self.attributes_at(tri, b.map(|x| x as f32));
        let texel = map.map.sample(&attributes);
        let scale = map.scale as f64;
        let x = (2.0 * texel.x as f64 - 1.0) * scale;
        let y = (2.0 * texel.y as f64 - 1.0) * scale;
        let z = 2.0 * texel.z as f64 - 1.0;
        normal_or(tangent * x + bitangent * y + n * z, n)
    }
}
