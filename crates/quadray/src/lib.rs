//! quadray: a Whitted ray tracer in which clipped quadric surfaces are first-class primitives beside
//! spheres, infinite planes and triangle meshes.
//!
//! # Brief overview
//! - [`Scene`] is built from a [`SceneDescription`]: a [`Camera`], [`Material`]s, [`Light`]s and the
//!   [`Geometry`] ([`Sphere`], [`Plane`], [`Mesh`], [`Quadric`], and [`Prototype`]s: shapes stored
//!   once and placed by [`Instance`]s, which nest). Building validates every value and builds the
//!   multi-level acceleration structure ([`accel`]): per level, 8-wide BVHs over meshes and a BVH
//!   over the analytic shapes, under a top over them and the level's instances.
//! - [`Scene::intersect`] and [`Scene::occluded`] (and their slice forms) cast rays without the
//!   renderer.
//! - [`render()`] traces the scene with the [`Whitted`] integrator into a linear [`Film`], in parallel
//!   over rows, bit-identically for any thread count.
//! - Intersection is two-phase (pbrt-v4): inside BVH traversal each primitive returns only a ray
//!   parameter; the full [`SurfaceGeometry`] is built once, for the nearest hit.
//!
//! # Conventions
//! - World space is **right-handed with +z up**; quadrics' canonical equations use z as the height axis.
//! - Units are arbitrary but consistent; nothing depends on an absolute epsilon: spawned rays are
//!   offset by a per-hit bound on the hit point's error, so scenes behave the same at any scale.
//! - Colours are **linear RGB** (Rec. 709 primaries) everywhere; only 8-bit outputs are sRGB-encoded.
//! - Angles in scene descriptions are degrees; geometry is f64, films are f32.
//! - Transforms map object space to world space; rotations are applied about x, then y, then z.
//!
//! # Example
//! ```
//! use quadray::*;
//! use glam::{DVec3, Vec3};
//!
//! let quadric = Quadric::new(
//!     QuadricSurface::Canonical { kind: QuadricKind::Hyperboloid1, a: 0.5, b: 0.5, c: 0.7 },
//!     ClipBox::cube(1.0),
//!     Transform::IDENTITY,
//!     0,
//! ).unwrap();
//! let scene = Scene::new(SceneDescription {
//!     camera: Camera::orbit(DVec3::ZERO, 30.0, 20.0, 6.0, 40.0),
//!     background: Vec3::splat(0.1),
//!     environment: None,
//!     materials: vec![Material { texture: Texture::HeightRamp, ..Material::default() }],
//!     lights: vec![Light::Directional { direction: DVec3::new(-1.0, -1.0, -1.0).normalize(), irradiance: Vec3::ONE }],
//!     geometry: Geometry { quadrics: vec![quadric], ..Geometry::default() },
//! }).unwrap();
//! let settings = RenderSettings { width: 32, height: 24, ..RenderSettings::default() };
//! let out = render(&scene, &settings, &NoProgress).unwrap();
//! assert_eq!(out.counts.camera, 32 * 24);
//! assert!(out.film.pixels().iter().any(|p| p.x != out.film.pixels()[0].x));
//! ```

pub mod accel;
pub mod aov;
pub mod camera;
pub mod coincident;
pub mod colour;
pub mod dielectric;
pub mod film;
pub mod footprint;
pub mod geometry;
// Placements live under the geometry they place; the old paths stay.
pub use geometry::instance;
pub mod integrator;
pub mod light;
pub mod limits;
pub mod material;
pub mod math;
pub mod mesh;
pub mod microfacet;
pub mod plane;
pub mod quadric;
pub mod render;
// The samplers keep the paths their users know.
pub use render::{adaptive, progressive};
pub mod sampler;
pub mod scene;
pub mod shape;
pub mod simd;
pub mod sphere;
pub mod texture;
pub use texture::image as image_texture;
#[cfg(test)]
mod test_rng;
pub mod triangle;

pub use accel::{AccelStats, BuildOptions, MAX_OVERLAP};
pub use adaptive::{Adaptive, AdaptiveError, SamplingStats};
pub use aov::{AovSample, AovSelection, Aovs};
pub use camera::{Camera, CameraError, CameraFrame, Projection};
pub use dielectric::{Attenuation, Transmission};
pub use film::Film;
pub use footprint::{HitFootprint, RayCone};
pub use geometry::{Geometry, Level, Prototype};
pub use image_texture::{ColorEncoding, Filter, Image, ImageError, ImageMap, Wrap};
pub use instance::{
    Instance, InstancePath, MAX_NESTING, MAX_PLACEMENTS, PlacementError, Placements,
};
pub use integrator::{RayCounts, Whitted};
pub use light::Light;
pub use material::{Material, MaterialId, SpecularModel};
pub use math::{Ray, Transform};
pub use mesh::{AlphaMask, Mesh, MeshError, NormalMap};
pub use plane::Plane;
pub use progressive::ProgressiveFilm;
pub use quadric::{
    ClipBox, Coefficients, Quadric, QuadricClass, QuadricError, QuadricKind, QuadricSurface,
};
pub use render::{
    Antialias, AntialiasError, DEFAULT_ANTIALIAS_SPP, NoProgress, PixelMemory, PixelWindow,
    Progress, RenderError, RenderSettings, Rendered, pixel_memory, render, render_with_aovs,
};
pub use scene::{MAX_COORDINATE, Scene, SceneDescription, SceneError};
pub use shape::{LocalPrim, PrimRef, SurfaceGeometry, SurfaceHit};
pub use simd::{SimdPath, simd_path};
pub use sphere::Sphere;
pub use texture::{ImageTexture, Texture, TexturePoint, VertexAttributes};
