//! Tangents for normal-mapped meshes whose file gives none: glTF asks for MikkTSpace's, computed
//! from the positions, normals and the normal map's texture coordinates
//! ([bevy_mikktspace](https://crates.io/crates/bevy_mikktspace)).

use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};
use glam::{Vec2, Vec3, Vec4};
use quadray::Mesh;

/// Per-vertex tangents of `mesh` for texture coordinate set `set` (xyz along increasing u, w the
/// bitangent's sign, bitangent = w · normal × tangent towards the top of the image), or `None`
/// when the mesh lacks normals or that set.
///
/// MikkTSpace works in OpenGL's texture convention, v growing upwards; glTF's (and quadray's) v
/// grows downwards, so it is given 1 − v, and its bitangents point to the top of the image, as
/// glTF's normal maps expect (+y up).
pub fn generate(mesh: &Mesh, set: usize) -> Option<Vec<Vec4>> {
    let mut input = MikkMesh {
        positions: mesh.positions(),
        normals: mesh.normals()?,
        texcoords: mesh.texcoords(set)?,
        indices: mesh.indices(),
        // Vertices of faces MikkTSpace cannot give a frame keep this default: +u, no flip.
        tangents: vec![Vec4::new(1.0, 0.0, 0.0, 1.0); mesh.positions().len()],
    };
    generate_tangents(&mut input).ok()?;
    Some(input.tangents)
}

/// A mesh as MikkTSpace reads it, with the tangents it writes.
struct MikkMesh<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    texcoords: &'a [Vec2],
    indices: &'a [[u32; 3]],
    tangents: Vec<Vec4>,
}

impl MikkMesh<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face][vert] as usize
    }
}

impl Geometry for MikkMesh<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.texcoords[self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent(&mut self, tangent_space: Option<TangentSpace>, face: usize, vert: usize) {
        if let Some(space) = tangent_space {
            let index = self.vertex(face, vert);
            self.tangents[index] = Vec4::from_array(space.tangent_encoded());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square at z = 0, normals +z, texture coordinates (0, 0) at its top-left corner
    /// (−1, 1): u grows along +x and the top of the image is +y, so the tangent is +x and the
    /// bitangent w · (z × x) = w · y must be +y: w = +1. Mirrored in x (u growing along −x), the
    /// tangent is −x and the bitangent still +y: w = −1.
    #[test]
    fn tangents_follow_u_and_bitangents_the_top_of_the_image() {
        let positions = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let uv = |mirror: bool| {
            let u = |x: f32| if mirror { 1.0 - x } else { x };
            vec![
                Vec2::new(u(0.0), 1.0),
                Vec2::new(u(1.0), 1.0),
                Vec2::new(u(1.0), 0.0),
                Vec2::new(u(0.0), 0.0),
            ]
        };
        for (mirror, tangent) in [
            (false, Vec4::new(1.0, 0.0, 0.0, 1.0)),
            (true, Vec4::new(-1.0, 0.0, 0.0, -1.0)),
        ] {
            let mesh = Mesh::new(
                positions.clone(),
                vec![[0, 1, 2], [0, 2, 3]],
                Some(vec![Vec3::Z; 4]),
                0,
            )
            .unwrap()
            .with_texcoords(0, uv(mirror))
            .unwrap();
            let tangents = generate(&mesh, 0).unwrap();
            for t in tangents {
                assert!((t - tangent).length() < 1e-5, "mirror {mirror}: {t}");
            }
        }
        let bare = Mesh::new(positions, vec![[0, 1, 2]], None, 0).unwrap();
        assert_eq!(generate(&bare, 0), None);
    }
}
