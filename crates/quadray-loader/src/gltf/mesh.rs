//! glTF mesh primitives as quadray meshes, baked into world space by their node's transform.
//!
//! - Modes TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN become triangles (strip and fan orders
//!   as in the glTF spec §3.7.2.1, which keep every triangle's winding); degenerate triangles
//!   (a repeated index, as strips use to restart) are dropped. POINTS and LINES* yield nothing and
//!   the caller notes them.
//! - Indexed or not; sparse accessors are read through the gltf crate's reader after
//!   [`crate::gltf::accessor::check`] has bounded every access.
//! - POSITION, NORMAL (transformed by the inverse transpose, so non-uniform scales keep them
//!   perpendicular), TEXCOORD_0/1 (normalised integers become [0, 1]) and COLOR_0 (linear RGBA).
//! - A node whose transform mirrors (negative determinant) flips every triangle's winding, so
//!   front faces stay front faces (the spec's rule for negative scales).

use crate::gltf::accessor::{Expect, check};
use crate::gltf::document::GltfFile;
use crate::gltf::material::MaterialUse;
use glam::{DAffine3, DVec3, Vec2, Vec3, Vec4};
use gltf::Semantic;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use quadray::{MAX_COORDINATE, Mesh};

const POSITIONS: Expect = Expect {
    dimensions: &[Dimensions::Vec3],
    types: &[DataType::F32],
};
const NORMALS: Expect = POSITIONS;
const INDICES: Expect = Expect {
    dimensions: &[Dimensions::Scalar],
    types: &[DataType::U8, DataType::U16, DataType::U32],
};
const TEXCOORDS: Expect = Expect {
    dimensions: &[Dimensions::Vec2],
    types: &[DataType::F32, DataType::U8, DataType::U16],
};
const TANGENTS: Expect = Expect {
    dimensions: &[Dimensions::Vec4],
    types: &[DataType::F32],
};
const COLORS: Expect = Expect {
    dimensions: &[Dimensions::Vec3, Dimensions::Vec4],
    types: &[DataType::F32, DataType::U8, DataType::U16],
};

/// Whether quadray renders primitives of this mode (surfaces) or skips them (points, lines).
pub fn is_surface(mode: Mode) -> bool {
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// The glTF name of a primitive mode.
pub fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

/// Triangles of a primitive from its index list (or 0..n), by mode, and how many degenerate ones
/// were dropped; `None` for points and lines.
pub fn assemble(mode: Mode, indices: &[u32]) -> Option<(Vec<[u32; 3]>, usize)> {
    let n = indices.len();
    let tris: Vec<[u32; 3]> = match mode {
        Mode::Triangles => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        // Triangle i of a strip is (i, i+1+i%2, i+2−i%2): odd triangles swap to keep the winding.
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        // Triangle i of a fan is (i+1, i+2, 0).
        Mode::TriangleFan => (0..n.saturating_sub(2))
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => return None,
    };
    let all = tris.len();
    let kept: Vec<[u32; 3]> = tris
        .into_iter()
        .filter(|[a, b, c]| a != b && b != c && a != c)
        .collect();
    let dropped = all - kept.len();
    Some((kept, dropped))
}

/// A primitive converted: its mesh (if any triangle is left) and the degenerate triangles dropped.
pub struct Built {
    /// The mesh, world space.
    pub mesh: Option<Mesh>,
    /// Triangles with a repeated vertex index, dropped (they cannot be hit).
    pub degenerate: usize,
    /// Why the material's normal map was left off, if it was.
    pub normal_map_skipped: Option<&'static str>,
}

/// Why a primitive could not be built.
#[derive(Debug)]
pub enum BuildError {
    /// Its data is invalid; the message says how.
    Data(String),
    /// Its vertices lie within [`MAX_COORDINATE`], but its node's transform places them past it,
    /// as far as `reach`: the transform's fault, not the data's.
    PlacedTooFar {
        /// The largest coordinate magnitude of a placed vertex.
        reach: f64,
    },
}

impl From<String> for BuildError {
    fn from(message: String) -> BuildError {
        BuildError::Data(message)
    }
}

impl From<&str> for BuildError {
    fn from(message: &str) -> BuildError {
        BuildError::Data(message.to_string())
    }
}

/// The quadray mesh of `primitive` placed by `to_world` (none when no triangle is left).
pub fn build(
    primitive: &gltf::Primitive<'_>,
    file: &GltfFile,
    to_world: DAffine3,
    material: &MaterialUse,
) -> Result<Built, BuildError> {
    let buffers = &file.buffers;
    let positions_accessor = primitive
        .get(&Semantic::Positions)
        .ok_or("the primitive has no POSITION attribute")?;
    check(&positions_accessor, &POSITIONS, buffers).map_err(|e| format!("POSITION: {e}"))?;
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let local: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or("POSITION could not be read")?
        .collect();
    let n = local.len();
    if n != positions_accessor.count() {
        return Err(BuildError::Data(format!(
            "POSITION: read {n} of {} vertices",
            positions_accessor.count()
        )));
    }
    let indices: Vec<u32> = match primitive.indices() {
        Some(acc) => {
            check(&acc, &INDICES, buffers).map_err(|e| format!("indices: {e}"))?;
            let read: Vec<u32> = reader
                .read_indices()
                .ok_or("indices could not be read")?
                .into_u32()
                .collect();
            if let Some(bad) = read.iter().find(|&&i| i as usize >= n) {
                return Err(BuildError::Data(format!(
                    "indices: accessor {} holds vertex index {bad}, but the primitive has {n} vertices",
                    acc.index()
                )));
            }
            read
        }
        None => (0..n as u32).collect(),
    };
    let Some((mut triangles, degenerate)) = assemble(primitive.mode(), &indices) else {
        return Ok(Built {
            mesh: None,
            degenerate: 0,
            normal_map_skipped: None,
        });
    };
    if triangles.is_empty() {
        return Ok(Built {
            mesh: None,
            degenerate,
            normal_map_skipped: None,
        });
    }
    if to_world.matrix3.determinant() < 0.0 {
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    // How far the vertices reach before and after the transform (NaN data is left to the
    // mesh's own check), so that a transform placing sound vertices past the limit is named
    // before f32 turns them into infinities (two nested node scales of 1e20 do).
    let (mut data_reach, mut placed_reach) = (0.0f64, 0.0f64);
    let positions: Vec<Vec3> = local
        .iter()
        .map(|&p| {
            let p = DVec3::from(p.map(f64::from));
            let placed = to_world.transform_point3(p);
            data_reach = data_reach.max(p.abs().max_element());
            placed_reach = placed_reach.max(placed.abs().max_element());
            placed.as_vec3()
        })
        .collect();
    if placed_reach > MAX_COORDINATE && data_reach <= MAX_COORDINATE {
        return Err(BuildError::PlacedTooFar {
            reach: placed_reach,
        });
    }
    let normals = baked_normals(primitive, &reader, buffers, &to_world, n)?;
    let mesh = Mesh::new(positions, triangles, normals, material.id).map_err(|e| e.to_string())?;
    let mesh = with_surface_attributes(mesh, primitive, &reader, buffers, material)?;
    let (mesh, normal_map_skipped) =
        with_normal_map(mesh, primitive, &reader, buffers, material, &to_world)?;
    Ok(Built {
        mesh: Some(mesh),
        degenerate,
        normal_map_skipped,
    })
}

/// The primitive's reader of vertex attributes.
type Reader<'a, 's, F> = gltf::mesh::Reader<'a, 's, F>;

/// The primitive's NORMALs baked by `to_world` (by its inverse transpose, renormalised), if it
/// has them.
fn baked_normals<'a, 's, F>(
    primitive: &gltf::Primitive<'_>,
    reader: &Reader<'a, 's, F>,
    buffers: &[Vec<u8>],
    to_world: &DAffine3,
    n: usize,
) -> Result<Option<Vec<Vec3>>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    Ok(match primitive.get(&Semantic::Normals) {
        Some(acc) => {
            check(&acc, &NORMALS, buffers).map_err(|e| format!("NORMAL: {e}"))?;
            let normal_matrix = to_world.matrix3.inverse().transpose();
            let normals: Vec<Vec3> = reader
                .read_normals()
                .ok_or("NORMAL could not be read")?
                .map(|v| {
                    (normal_matrix * DVec3::from(v.map(f64::from)))
                        .normalize_or_zero()
                        .as_vec3()
                })
                .collect();
            same_count("NORMAL", normals.len(), n)?;
            Some(normals)
        }
        None => None,
    })
}

/// `mesh` with the primitive's texture coordinates (the material's KHR_texture_transform
/// applied), vertex colours, and the material's coverage and sides.
fn with_surface_attributes<'a, 's, F>(
    mut mesh: Mesh,
    primitive: &gltf::Primitive<'_>,
    reader: &Reader<'a, 's, F>,
    buffers: &[Vec<u8>],
    material: &MaterialUse,
) -> Result<Mesh, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let n = mesh.positions().len();
    for set in 0..2u32 {
        let Some(acc) = primitive.get(&Semantic::TexCoords(set)) else {
            continue;
        };
        let what = format!("TEXCOORD_{set}");
        check(&acc, &TEXCOORDS, buffers).map_err(|e| format!("{what}: {e}"))?;
        let mut uv: Vec<Vec2> = reader
            .read_tex_coords(set)
            .ok_or_else(|| format!("{what} could not be read"))?
            .into_f32()
            .map(Vec2::from)
            .collect();
        same_count(&what, uv.len(), n)?;
        if let Some(t) = material.uv_transform.filter(|t| t.set == set as usize) {
            uv.iter_mut().for_each(|p| *p = t.apply(*p));
        }
        mesh = mesh
            .with_texcoords(set as usize, uv)
            .map_err(|e| e.to_string())?;
    }
    if let Some(acc) = primitive.get(&Semantic::Colors(0)) {
        check(&acc, &COLORS, buffers).map_err(|e| format!("COLOR_0: {e}"))?;
        let colors: Vec<Vec4> = reader
            .read_colors(0)
            .ok_or("COLOR_0 could not be read")?
            .into_rgba_f32()
            .map(Vec4::from)
            .collect();
        same_count("COLOR_0", colors.len(), n)?;
        mesh = mesh.with_colors(colors).map_err(|e| e.to_string())?;
    }
    if let Some(mask) = &material.mask {
        mesh = mesh
            .with_alpha_mask(mask.clone())
            .map_err(|e| e.to_string())?;
    }
    Ok(mesh.with_single_sided(material.single_sided))
}

/// `mesh` with the material's normal map and its tangents (the file's TANGENT baked by
/// `to_world`, else MikkTSpace's), or as it is with the reason the map was left off.
fn with_normal_map<'a, 's, F>(
    mesh: Mesh,
    primitive: &gltf::Primitive<'_>,
    reader: &Reader<'a, 's, F>,
    buffers: &[Vec<u8>],
    material: &MaterialUse,
    to_world: &DAffine3,
) -> Result<(Mesh, Option<&'static str>), String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let Some(map) = &material.normal_map else {
        return Ok((mesh, None));
    };
    let set = map.map.set as usize;
    if mesh.normals().is_none() {
        return Ok((mesh, Some("the primitive has no NORMAL")));
    }
    if mesh.texcoords(set).is_none() {
        return Ok((
            mesh,
            Some("the primitive lacks the texture coordinates it reads"),
        ));
    }
    let tangents = match primitive.get(&Semantic::Tangents) {
        Some(acc) => {
            check(&acc, &TANGENTS, buffers).map_err(|e| format!("TANGENT: {e}"))?;
            let tangents: Vec<Vec4> = reader
                .read_tangents()
                .ok_or("TANGENT could not be read")?
                .map(|t| baked_tangent(t, to_world))
                .collect();
            same_count("TANGENT", tangents.len(), mesh.positions().len())?;
            Some(tangents)
        }
        // Computed on the baked mesh, so in world space already.
        None => crate::tangents::generate(&mesh, set),
    };
    let Some(tangents) = tangents else {
        return Ok((mesh, Some("no tangents could be generated")));
    };
    let mesh = mesh
        .with_tangents(tangents)
        .and_then(|m| m.with_normal_map(map.clone()))
        .map_err(|e| e.to_string())?;
    Ok((mesh, None))
}

/// A file tangent baked into world space: xyz by the node's linear map (a tangent is a direction
/// along the surface), w negated by a mirroring map, so that w · (normal × tangent) is still the
/// image of the bitangent.
fn baked_tangent(t: [f32; 4], to_world: &DAffine3) -> Vec4 {
    let xyz = (to_world.matrix3 * Vec3::new(t[0], t[1], t[2]).as_dvec3())
        .normalize_or_zero()
        .as_vec3();
    let mirror = if to_world.matrix3.determinant() < 0.0 {
        -1.0
    } else {
        1.0
    };
    xyz.extend(if t[3] < 0.0 { -mirror } else { mirror })
}

fn same_count(what: &str, got: usize, vertices: usize) -> Result<(), String> {
    if got == vertices {
        Ok(())
    } else {
        Err(format!(
            "{what} has {got} elements but POSITION has {vertices}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_winding_and_drop_degenerates() {
        // A strip over a 2x3 grid of vertices: 0 2 4 / 1 3 5 zig-zag.
        let strip = assemble(Mode::TriangleStrip, &[0, 1, 2, 3, 4, 5]).unwrap();
        assert_eq!(strip, (vec![[0, 1, 2], [1, 3, 2], [2, 3, 4], [3, 5, 4]], 0));
        // A restart by repeated indices yields no degenerate triangles, and says how many it dropped.
        let (restarted, dropped) =
            assemble(Mode::TriangleStrip, &[0, 1, 2, 2, 5, 5, 6, 7]).unwrap();
        assert!(restarted.iter().all(|[a, b, c]| a != b && b != c && a != c));
        assert_eq!(restarted, vec![[0, 1, 2], [5, 7, 6]]);
        assert_eq!(dropped, 4);
        let fan = assemble(Mode::TriangleFan, &[0, 1, 2, 3]).unwrap();
        assert_eq!(fan, (vec![[1, 2, 0], [2, 3, 0]], 0));
        assert_eq!(
            assemble(Mode::Triangles, &[0, 1, 2, 3, 4]).unwrap(),
            (vec![[0, 1, 2]], 0)
        );
        assert!(assemble(Mode::Lines, &[0, 1]).is_none());
        assert!(assemble(Mode::TriangleFan, &[0, 1]).unwrap().0.is_empty());
    }
}
