//! Triangle approximations of analytic shapes: the fallback meshes written beside
//! `QUADRAY_quadrics` shapes so that other glTF viewers show something.
//!
//! Clipped quadrics are tessellated by marching tetrahedra over a grid filling the clip box:
//! one method for all nine kinds and the general form, clipped by the box for free, and free of
//! the ambiguous cases of marching cubes. Each grid cube is split into six tetrahedra around its
//! main diagonal (the Freudenthal split, which neighbouring cubes share consistently), and vertices
//! on shared grid edges are shared, so the surface is one connected mesh with smooth normals taken
//! from the quadric's gradient.

use glam::{DVec3, Vec3};
use quadray::{ClipBox, Coefficients};
use std::collections::HashMap;

/// An indexed triangle mesh in a shape's own frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Triangles, counter-clockwise seen from the side the normals point to.
    pub indices: Vec<[u32; 3]>,
}

/// A latitude–longitude sphere of `radius` about the origin, z the polar axis.
pub fn sphere(radius: f64, segments: u32, rings: u32) -> TriMesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut m = TriMesh::default();
    for r in 0..=rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..=segments {
            let phi = std::f64::consts::TAU * s as f64 / segments as f64;
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            m.positions.push((n * radius).as_vec3());
            m.normals.push(n.as_vec3());
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            // Rings run from the north pole down; (a, b, b+1) is counter-clockwise seen from outside.
            if r > 0 {
                m.indices.push([a, b, a + 1]);
            }
            if r + 1 < rings {
                m.indices.push([a + 1, b, b + 1]);
            }
        }
    }
    m
}

/// The square [−half, half]² in the plane z = 0, facing +z.
pub fn square(half: f64) -> TriMesh {
    let h = half as f32;
    TriMesh {
        positions: vec![
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, -h, 0.0),
            Vec3::new(h, h, 0.0),
            Vec3::new(-h, h, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// The surface f = 0 of `k` inside `clip`, by marching tetrahedra on a grid of about `cells`
/// cubes along the box's longest side. Normals point along ∇f (outwards where f > 0 is outside).
pub fn quadric(k: &Coefficients, clip: ClipBox, cells: u32) -> TriMesh {
    let extent = clip.max - clip.min;
    let longest = extent.max_element();
    let n = (extent / longest * cells.max(2) as f64)
        .ceil()
        .max(DVec3::splat(2.0))
        .as_uvec3();
    let step = extent / n.as_dvec3();
    let node = |i: u32, j: u32, l: u32| clip.min + DVec3::new(i as f64, j as f64, l as f64) * step;
    let id = |i: u32, j: u32, l: u32| (l * (n.y + 1) + j) * (n.x + 1) + i;
    let mut values = Vec::with_capacity(((n.x + 1) * (n.y + 1) * (n.z + 1)) as usize);
    for l in 0..=n.z {
        for j in 0..=n.y {
            for i in 0..=n.x {
                values.push(k.eval(node(i, j, l)));
            }
        }
    }
    let (a, b, _) = k.to_matrix_form();
    let gradient = |p: DVec3| (a * p + b) * 2.0;
    let mut mesh = TriMesh::default();
    let mut on_edge: HashMap<(u32, u32), u32> = HashMap::new();
    // Cube corners by bit (x = 1, y = 2, z = 4); the six tetrahedra run from corner 0 to corner 7
    // through one permutation of the axes each.
    const TETS: [[usize; 4]; 6] = [
        [0, 1, 3, 7],
        [0, 1, 5, 7],
        [0, 2, 3, 7],
        [0, 2, 6, 7],
        [0, 4, 5, 7],
        [0, 4, 6, 7],
    ];
    for l in 0..n.z {
        for j in 0..n.y {
            for i in 0..n.x {
                let corner = |c: usize| {
                    let (ci, cj, cl) = (
                        i + (c & 1) as u32,
                        j + ((c >> 1) & 1) as u32,
                        l + ((c >> 2) & 1) as u32,
                    );
                    (id(ci, cj, cl), node(ci, cj, cl))
                };
                for tet in TETS {
                    let v = tet.map(corner);
                    let f = v.map(|(idx, _)| values[idx as usize]);
                    let inside: Vec<usize> = (0..4).filter(|&t| f[t] < 0.0).collect();
                    let outside: Vec<usize> = (0..4).filter(|&t| f[t] >= 0.0).collect();
                    let mut vertex = |p: usize, q: usize, mesh: &mut TriMesh| -> u32 {
                        let (ip, iq) = (v[p].0, v[q].0);
                        let key = (ip.min(iq), ip.max(iq));
                        *on_edge.entry(key).or_insert_with(|| {
                            let s = f[p] / (f[p] - f[q]);
                            let pos = v[p].1 + (v[q].1 - v[p].1) * s;
                            mesh.positions.push(pos.as_vec3());
                            mesh.normals
                                .push(gradient(pos).normalize_or_zero().as_vec3());
                            (mesh.positions.len() - 1) as u32
                        })
                    };
                    let tris: Vec<[u32; 3]> = match (inside.len(), outside.len()) {
                        (1, 3) | (3, 1) => {
                            let (lone, others) = if inside.len() == 1 {
                                (inside[0], &outside)
                            } else {
                                (outside[0], &inside)
                            };
                            vec![[
                                vertex(lone, others[0], &mut mesh),
                                vertex(lone, others[1], &mut mesh),
                                vertex(lone, others[2], &mut mesh),
                            ]]
                        }
                        (2, 2) => {
                            let (p0, p1, q0, q1) = (inside[0], inside[1], outside[0], outside[1]);
                            let quad = [
                                vertex(p0, q0, &mut mesh),
                                vertex(p0, q1, &mut mesh),
                                vertex(p1, q1, &mut mesh),
                                vertex(p1, q0, &mut mesh),
                            ];
                            vec![[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]]
                        }
                        _ => Vec::new(),
                    };
                    for t in tris {
                        orient_and_push(&mut mesh, t, &gradient);
                    }
                }
            }
        }
    }
    fill_vanishing_normals(&mut mesh);
    mesh
}

/// Where the gradient vanishes (a cone's apex) a vertex has no normal of its own; it gets the
/// normalised sum of its triangles' normals instead, so every normal written is unit length.
fn fill_vanishing_normals(mesh: &mut TriMesh) {
    if mesh.normals.iter().all(|n| n.length_squared() > 0.0) {
        return;
    }
    let mut sums = vec![DVec3::ZERO; mesh.positions.len()];
    for t in &mesh.indices {
        let p = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let face = (p[1] - p[0]).cross(p[2] - p[0]);
        for &i in t {
            sums[i as usize] += face;
        }
    }
    for (n, sum) in mesh.normals.iter_mut().zip(sums) {
        if n.length_squared() == 0.0 {
            *n = sum.try_normalize().unwrap_or(DVec3::Z).as_vec3();
        }
    }
}

/// Adds triangle `t`, turned so that its winding agrees with ∇f. A triangle of zero area (the
/// surface passing exactly through a grid node) is kept: dropping it would open the mesh.
fn orient_and_push(mesh: &mut TriMesh, t: [u32; 3], gradient: &impl Fn(DVec3) -> DVec3) {
    let p = t.map(|i| mesh.positions[i as usize].as_dvec3());
    let face = (p[1] - p[0]).cross(p[2] - p[0]);
    let centroid = (p[0] + p[1] + p[2]) / 3.0;
    if face.dot(gradient(centroid)) < 0.0 {
        mesh.indices.push([t[0], t[2], t[1]]);
    } else {
        mesh.indices.push(t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadray::QuadricKind;

    #[test]
    fn sphere_vertices_lie_on_the_sphere_and_faces_point_out() {
        let m = sphere(2.0, 24, 12);
        assert!(m.positions.iter().all(|p| (p.length() - 2.0).abs() < 1e-5));
        for t in &m.indices {
            let p = t.map(|i| m.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(n.dot(p[0] + p[1] + p[2]) > 0.0, "inward face {t:?}");
        }
        // 24 segments × (2 pole rows of 1 triangle + 10 rows of 2).
        assert_eq!(m.indices.len(), 24 * (2 + 2 * 10));
    }

    #[test]
    fn quadric_tessellation_lies_on_the_surface_inside_the_box() {
        let k = QuadricKind::Hyperboloid1.coefficients(0.5, 0.5, 0.7);
        let clip = ClipBox::cube(1.0);
        let m = quadric(&k, clip, 24);
        assert!(m.indices.len() > 1000);
        for p in &m.positions {
            let p = p.as_dvec3();
            assert!(p.cmpge(clip.min - 1e-9).all() && p.cmple(clip.max + 1e-9).all());
            // Linear interpolation along grid edges: the residual is second order in the cell size.
            let r = k.eval(p).abs();
            assert!(r < 0.05, "residual {r} at {p}");
        }
        // Faces wind with the gradient (outwards from the axis for a hyperboloid of one sheet).
        for t in &m.indices {
            let p = t.map(|i| m.positions[i as usize].as_dvec3());
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let c = (p[0] + p[1] + p[2]) / 3.0;
            assert!(n.dot(DVec3::new(c.x, c.y, 0.0)) >= 0.0);
        }
        // A closed ellipsoid inside the box: every edge is shared by exactly two triangles.
        let e = quadric(
            &QuadricKind::Ellipsoid.coefficients(0.8, 0.6, 0.5),
            clip,
            16,
        );
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &e.indices {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(
            edges.values().all(|&c| c == 2),
            "the ellipsoid mesh has holes"
        );
    }
}
