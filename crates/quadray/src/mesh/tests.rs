//! Tests of meshes: validation, intersection, attributes and coverage.

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
    let m = textured_quad()
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

/// The unit square at z = 0 with normals +z and texture coordinates (0, 0) at its top-left
/// corner (−1, 1): u grows along +x, v along −y, so the top of the image is +y.
fn textured_quad() -> Mesh {
    quad()
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
}

/// A one-texel linear normal map.
fn normal_map(rgb: [u8; 3], scale: f32) -> NormalMap {
    let image = crate::Image::from_rgba8(
        1,
        1,
        vec![rgb[0], rgb[1], rgb[2], 255],
        crate::ColorEncoding::Linear,
    )
    .unwrap();
    NormalMap {
        map: crate::ImageMap {
            image: std::sync::Arc::new(image),
            wrap: [crate::Wrap::Repeat; 2],
            filter: crate::Filter::Nearest,
            set: 0,
        },
        scale,
    }
}

/// The texel's normal lands in the frame (tangent +x, bitangent +y, normal +z): a texel
/// (200, 90, 230) is the normal (2·200/255 − 1, 2·90/255 − 1, 2·230/255 − 1), normalised; the
/// scale multiplies its x and y; a mesh without tangents cannot take a map.
#[test]
fn normal_maps_bend_the_shading_normal_in_the_tangent_frame() {
    let normals = vec![Vec3::Z; 4];
    let quad = textured_quad();
    let with_normals = Mesh::new(
        quad.positions().to_vec(),
        quad.indices().to_vec(),
        Some(normals),
        0,
    )
    .unwrap()
    .with_texcoords(0, quad.texcoords(0).unwrap().to_vec())
    .unwrap();
    assert_eq!(
        with_normals
            .clone()
            .with_normal_map(normal_map([128, 128, 255], 1.0))
            .unwrap_err(),
        MeshError::NormalMapNeeds("tangents")
    );
    let tangent = Vec4::new(1.0, 0.0, 0.0, 1.0);
    let mapped = |rgb, scale| {
        with_normals
            .clone()
            .with_tangents(vec![tangent; 4])
            .unwrap()
            .with_normal_map(normal_map(rgb, scale))
            .unwrap()
    };
    let ray = Ray::new(DVec3::new(0.2, 0.3, 1.0), -DVec3::Z);
    let code = |c: u8| 2.0 * c as f64 / 255.0 - 1.0;
    for scale in [1.0, 0.5] {
        let g = mapped([200, 90, 230], scale).surface(0, &ray, 1.0);
        let expected =
            DVec3::new(code(200) * scale as f64, code(90) * scale as f64, code(230)).normalize();
        assert!(
            (g.shading_normal - expected).length() < 1e-6,
            "{} vs {expected}",
            g.shading_normal
        );
        assert_eq!(g.geometric_normal, DVec3::Z);
    }
    // A flipped bitangent sign mirrors y.
    let flipped = with_normals
        .with_tangents(vec![Vec4::new(1.0, 0.0, 0.0, -1.0); 4])
        .unwrap()
        .with_normal_map(normal_map([200, 90, 230], 1.0))
        .unwrap();
    assert!(flipped.surface(0, &ray, 1.0).shading_normal.y > 0.0);
}
