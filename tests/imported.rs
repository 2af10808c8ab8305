//! End-to-end checks of what the OBJ and glTF importers rely on in the renderer (image textures,
//! vertex colours, alpha cut-outs, spot lights, tinted reflections), each against a value worked
//! out by hand, and of the committed glTF scene against the native scene it was converted from.

use glam::{DVec3, Vec2, Vec3, Vec4};
use quadray::{
    AlphaMask, Camera, ColorEncoding, Filter, Geometry, Image, ImageMap, ImageTexture, Light,
    Material, Mesh, Plane, Projection, Scene, SceneDescription, Sphere, Texture, Wrap,
};
use quadray_tests::{render_with_threads, repo_root};
use std::sync::Arc;

/// A camera looking straight down at the unit square around the origin.
fn top_down(height: f64) -> Camera {
    Camera {
        from: DVec3::new(0.0, 0.0, 5.0),
        to: DVec3::ZERO,
        up: DVec3::Y,
        projection: Projection::Orthographic { height },
    }
}

/// The square [-1, 1]² at height `z`, texture coordinates (0, 0) at its top-left corner (−1, 1).
fn square(z: f32, material: u32) -> Mesh {
    let p = vec![
        Vec3::new(-1.0, 1.0, z),
        Vec3::new(1.0, 1.0, z),
        Vec3::new(1.0, -1.0, z),
        Vec3::new(-1.0, -1.0, z),
    ];
    Mesh::new(p, vec![[0, 1, 2], [0, 2, 3]], None, material)
        .unwrap()
        .with_texcoords(
            0,
            vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ],
        )
        .unwrap()
}

/// An unlit material: the pixel shows the base colour exactly.
fn unlit(texture: Texture) -> Material {
    Material {
        texture,
        ambient: 1.0,
        diffuse: 0.0,
        ..Material::default()
    }
}

fn render(d: SceneDescription, w: u32, h: u32) -> quadray::Film {
    let settings = quadray::RenderSettings {
        width: w,
        height: h,
        ..quadray::RenderSettings::default()
    };
    render_with_threads(&Scene::new(d).unwrap(), &settings, 2).film
}

/// A 2×2 linear image: red, green / blue, white (alpha 255, 0 / 255, 0 from left to right).
fn quad_image() -> Arc<Image> {
    Arc::new(
        Image::from_rgba8(
            2,
            2,
            vec![
                255, 0, 0, 255, 0, 255, 0, 0, 0, 0, 255, 255, 255, 255, 255, 0,
            ],
            ColorEncoding::Linear,
        )
        .unwrap(),
    )
}

#[test]
fn image_texture_and_vertex_colours_reach_the_pixels() {
    let map = ImageMap {
        image: quad_image(),
        wrap: [Wrap::ClampToEdge; 2],
        filter: Filter::Nearest,
        set: 0,
    };
    let mesh = square(0.0, 0)
        .with_colors(vec![Vec4::new(1.0, 1.0, 0.5, 1.0); 4])
        .unwrap();
    let film = render(
        SceneDescription {
            camera: top_down(2.0),
            background: Vec3::ZERO,
            environment: None,
            materials: vec![unlit(Texture::Image(ImageTexture {
                map,
                factor: Vec3::new(1.0, 0.5, 1.0),
            }))],
            lights: vec![],
            geometry: Geometry {
                meshes: vec![mesh],
                ..Geometry::default()
            },
        },
        4,
        4,
    );
    // Pixel (x, y) of a 4×4 image over the square lies in texel (x / 2, y / 2); the colour is
    // texel × factor (1, 0.5, 1) × vertex colour (1, 1, 0.5).
    let expect = |texel: Vec3| texel * Vec3::new(1.0, 0.5, 0.5);
    assert_eq!(film.get(0, 0), expect(Vec3::X));
    assert_eq!(film.get(3, 0), expect(Vec3::Y));
    assert_eq!(film.get(0, 3), expect(Vec3::Z));
    assert_eq!(film.get(3, 3), expect(Vec3::ONE));
}

#[test]
fn alpha_cut_outs_let_camera_and_shadow_rays_through() {
    // A cut-out square (the image's right column has alpha 0) at z = 1 over a white floor, lit
    // straight from above. Looking down: the left half shows the square (red/blue), the right half
    // the floor. The floor is in shadow under the left half only.
    let mask = AlphaMask {
        stochastic: false,
        cutoff: 0.5,
        factor: 1.0,
        map: Some(ImageMap {
            image: quad_image(),
            wrap: [Wrap::ClampToEdge; 2],
            filter: Filter::Nearest,
            set: 0,
        }),
    };
    let card = square(1.0, 0).with_alpha_mask(mask).unwrap();
    let floor = Material {
        texture: Texture::Constant(Vec3::ONE),
        ambient: 0.0,
        diffuse: 1.0,
        ..Material::default()
    };
    let description = |camera: Camera| SceneDescription {
        camera,
        background: Vec3::ZERO,
        environment: None,
        materials: vec![
            unlit(Texture::Constant(Vec3::new(0.5, 0.0, 0.0))),
            floor.clone(),
        ],
        lights: vec![Light::Directional {
            direction: -DVec3::Z,
            irradiance: Vec3::ONE,
        }],
        geometry: Geometry {
            meshes: vec![card.clone()],
            planes: vec![Plane {
                point: DVec3::ZERO,
                normal: DVec3::Z,
                material: 1,
            }],
            ..Geometry::default()
        },
    };
    let film = render(description(top_down(2.0)), 4, 4);
    assert_eq!(
        film.get(0, 1),
        Vec3::new(0.5, 0.0, 0.0),
        "the card's kept half"
    );
    assert_eq!(
        film.get(3, 1),
        Vec3::ONE,
        "the lit floor through the cut-out half"
    );
    // The same view with the camera's image plane moved under the card (z = 0.5): the floor.
    let mut under = top_down(2.0);
    under.from.z = 0.5;
    let film = render(description(under), 4, 4);
    assert_eq!(film.get(0, 1), Vec3::ZERO, "the floor in the card's shadow");
    assert_eq!(
        film.get(3, 1),
        Vec3::ONE,
        "the floor lit through the cut-out"
    );
}

#[test]
fn spot_light_lights_its_cone_with_the_inverse_square_law() {
    // A spot 4 units above a white floor pointing down, cone half-angles 10° and 20°.
    let (inner, outer) = (10f64.to_radians(), 20f64.to_radians());
    let film = render(
        SceneDescription {
            camera: top_down(8.0),
            background: Vec3::ZERO,
            environment: None,
            materials: vec![Material {
                texture: Texture::Constant(Vec3::ONE),
                ambient: 0.0,
                diffuse: 1.0,
                ..Material::default()
            }],
            lights: vec![Light::Spot {
                position: DVec3::new(0.0, 0.0, 4.0),
                direction: -DVec3::Z,
                intensity: Vec3::splat(16.0),
                cos_inner: inner.cos(),
                cos_outer: outer.cos(),
            }],
            geometry: Geometry {
                planes: vec![Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                    material: 0,
                }],
                ..Geometry::default()
            },
        },
        65,
        65,
    );
    // The centre pixel is on the axis: 16 / 4² = 1.
    assert!(
        (film.get(32, 32).x - 1.0).abs() < 1e-6,
        "{}",
        film.get(32, 32)
    );
    // A corner pixel, 4·√2 off axis, is far outside the 20° cone: dark.
    assert_eq!(film.get(0, 0), Vec3::ZERO);
}

#[test]
fn metals_reflect_in_their_base_colour() {
    // A mirror square facing up, under a white sky (the background): the pixel is the reflection,
    // white × reflectivity for a coating, the base colour × reflectivity for a metal.
    let scene = |tint: f32| SceneDescription {
        camera: top_down(2.0),
        background: Vec3::ONE,
        environment: None,
        materials: vec![Material {
            texture: Texture::Constant(Vec3::new(1.0, 0.5, 0.25)),
            ambient: 0.0,
            diffuse: 0.0,
            reflectivity: 0.8,
            reflection_tint: tint,
            ..Material::default()
        }],
        lights: vec![],
        geometry: Geometry {
            meshes: vec![square(0.0, 0)],
            ..Geometry::default()
        },
    };
    assert_eq!(render(scene(0.0), 2, 2).get(0, 0), Vec3::splat(0.8));
    assert_eq!(render(scene(1.0), 2, 2).get(0, 0), Vec3::new(0.8, 0.4, 0.2));
}

#[test]
fn committed_gltf_scene_is_the_converted_native_scene() {
    // scenes/gltf-quadrics.gltf is `quadray convert scenes/obj-mesh.toml`: reading both gives the
    // same shapes, materials and lights (this fails when one is edited without the other).
    let native = quadray_loader::load_any(&repo_root().join("scenes/obj-mesh.toml")).unwrap();
    let gltf = quadray_loader::load_any(&repo_root().join("scenes/gltf-quadrics.gltf")).unwrap();
    let (a, b) = (&native.description, &gltf.description);
    assert_eq!(a.geometry.quadrics.len(), b.geometry.quadrics.len());
    for (qa, qb) in a.geometry.quadrics.iter().zip(&b.geometry.quadrics) {
        assert_eq!(qa.surface_description(), qb.surface_description());
        assert_eq!(qa.clip(), qb.clip());
        let d = qa.transform().to_world.translation - qb.transform().to_world.translation;
        assert!(d.length() < 1e-12);
        assert_eq!(
            a.materials[qa.material() as usize],
            b.materials[qb.material() as usize]
        );
    }
    let sphere = |s: &Sphere| (s.center, s.radius);
    assert_eq!(
        a.geometry.spheres.iter().map(sphere).collect::<Vec<_>>(),
        b.geometry.spheres.iter().map(sphere).collect::<Vec<_>>()
    );
    assert_eq!(a.geometry.planes.len(), b.geometry.planes.len());
    let positions = |d: &SceneDescription| {
        d.geometry
            .meshes
            .iter()
            .map(|m| m.positions().to_vec())
            .collect::<Vec<_>>()
    };
    assert_eq!(positions(a), positions(b));
    assert_eq!(a.lights.len(), b.lights.len());
    assert_eq!(a.background, b.background);
    assert_eq!(native.settings, gltf.settings);
    // The OBJ's textured material survived the trip with its texels.
    let image = |d: &SceneDescription| {
        d.materials.iter().find_map(|m| match &m.texture {
            Texture::Image(t) => Some(t.map.image.texels().to_vec()),
            _ => None,
        })
    };
    assert!(image(a).is_some());
    assert_eq!(image(a), image(b));
}

/// Stochastic coverage (glTF BLEND): a white square of alpha 0.3 over a red one. Each ray keeps
/// the white hit with probability 0.3, so over many samples a pixel converges to the blend
/// 0.3·white + 0.7·red, and two renders give the same pixels.
#[test]
fn blended_coverage_converges_to_the_blend() {
    let glass = square(1.0, 0)
        .with_alpha_mask(AlphaMask {
            cutoff: 0.5,
            stochastic: true,
            factor: 0.3,
            map: None,
        })
        .unwrap();
    let description = || SceneDescription {
        camera: top_down(2.0),
        background: Vec3::ZERO,
        environment: None,
        materials: vec![
            unlit(Texture::Constant(Vec3::ONE)),
            unlit(Texture::Constant(Vec3::new(1.0, 0.0, 0.0))),
        ],
        lights: vec![],
        geometry: Geometry {
            meshes: vec![glass.clone(), square(0.0, 1)],
            ..Geometry::default()
        },
    };
    let settings = quadray::RenderSettings {
        width: 4,
        height: 4,
        spp: 256,
        ..quadray::RenderSettings::default()
    };
    let film = render_with_threads(&Scene::new(description()).unwrap(), &settings, 2).film;
    // Green and blue carry the white layer's share alone: 0.3, within 4 standard deviations of a
    // 256-sample share (σ = √(0.3·0.7/256) ≈ 0.029), for every pixel.
    for p in film.pixels() {
        assert_eq!(p.x, 1.0);
        assert!((p.y - 0.3).abs() < 0.12 && p.y == p.z, "{p}");
    }
    let mean = film.pixels().iter().map(|p| p.y).sum::<f32>() / 16.0;
    assert!((mean - 0.3).abs() < 0.03, "{mean}");
    let again = render_with_threads(&Scene::new(description()).unwrap(), &settings, 1).film;
    assert_eq!(film, again);
}
