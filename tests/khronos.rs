//! The twenty Khronos glTF sample models of `../shared/assets/gltf/khronos`, each rendered on its
//! own at 160x120 with 4 samples per pixel (as `quadray render FILE --res 160x120` does: the
//! file's camera, or one framing it, and the default lighting when it brings none), compared with
//! `tests/khronos/<name>.png` under the rule of `quadray compare`, plus the analytic facts that
//! single out what each feature must do: a rough red metal reflects no green or blue, a culled
//! face shows no red failure mark, emission only adds light.
//!
//! Each reference was checked by eye against the sample's own description before it was accepted
//! (`tests/khronos/README.md`). The assets are not part of the repository: without them the tests
//! say so and pass. `QUADRAY_UPDATE_REFS=1` rewrites the references (check them again first).

use quadray::{Film, Scene};
use quadray_app::compare::{LinearImage, Thresholds, compare, read_image};
use quadray_app::output::write_rgb8_png;
use quadray_loader::{ImportOptions, LoadedScene};
use quadray_tests::repo_root;
use std::path::PathBuf;

/// The samples, by folder name.
const SAMPLES: [&str; 20] = [
    "2CylinderEngine",
    "Box",
    "BoxInterleaved",
    "BoxTextured",
    "Cameras",
    "CesiumMilkTruck",
    "Duck",
    "MeshPrimitiveModes",
    "MetalRoughSpheresNoTextures",
    "MultiUVTest",
    "MultipleScenes",
    "NegativeScaleTest",
    "OrientationTest",
    "SimpleMeshes",
    "SimpleSparseAccessor",
    "Suzanne",
    "TextureCoordinateTest",
    "TextureSettingsTest",
    "TriangleWithoutIndices",
    "VertexColorTest",
];

/// The size every sample is rendered at.
const SIZE: [u32; 2] = [160, 120];

/// The samples' folder. Tests that call it are ignored where `../shared` is absent (see
/// `build.rs`); where they run, its absence is a failure.
fn khronos() -> PathBuf {
    let dir = repo_root().join("../shared/assets/gltf/khronos");
    assert!(
        dir.is_dir(),
        "{} is absent (the Khronos samples are not part of the repository)",
        dir.display()
    );
    dir
}

/// The sample's glTF file: its `glTF` variant, else `glTF-Binary`, else `glTF-Embedded`.
fn sample_file(root: &std::path::Path, name: &str) -> PathBuf {
    for (variant, ext) in [
        ("glTF", "gltf"),
        ("glTF-Binary", "glb"),
        ("glTF-Embedded", "gltf"),
    ] {
        let path = root.join(name).join(variant).join(format!("{name}.{ext}"));
        if path.is_file() {
            return path;
        }
    }
    panic!("{name}: no glTF file under {}", root.join(name).display());
}

fn load(root: &std::path::Path, name: &str) -> LoadedScene {
    let options = ImportOptions {
        resolution: Some(SIZE),
        ..ImportOptions::default()
    };
    quadray_loader::load_any_with(&sample_file(root, name), &options, None)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Renders at the file's settings (4 samples per pixel, as `quadray render` does).
fn render(loaded: LoadedScene) -> Film {
    render_with_spp(loaded, None)
}

/// Renders with one sample at each pixel centre: for the facts about surfaces, whose edges would
/// blend with the backdrop at more samples.
fn render_at_centres(loaded: LoadedScene) -> Film {
    render_with_spp(loaded, Some(1))
}

fn render_with_spp(loaded: LoadedScene, spp: Option<u32>) -> Film {
    let defaults = loaded.settings.render_settings();
    let settings = quadray::RenderSettings {
        spp: spp.unwrap_or(defaults.spp),
        ..defaults
    };
    let scene = Scene::new(loaded.description).unwrap();
    quadray::render(&scene, &settings, &quadray::NoProgress)
        .unwrap()
        .film
}

/// Display (8-bit sRGB) values of a film, row by row.
fn srgb8(film: &Film) -> Vec<[u8; 3]> {
    LinearImage::from_film(film)
        .to_srgb8()
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn every_khronos_sample_matches_its_reference() {
    let root = khronos();
    let update = std::env::var("QUADRAY_UPDATE_REFS").is_ok_and(|v| v == "1");
    let refs = repo_root().join("tests/khronos");
    let out_dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("khronos");
    let thresholds = Thresholds::default();
    let mut failed = Vec::new();
    for name in SAMPLES {
        let film = render(load(&root, name));
        assert_eq!([film.width(), film.height()], SIZE, "{name}");
        let new = LinearImage::from_film(&film);
        let bytes = new.to_srgb8();
        let reference = refs.join(format!("{name}.png"));
        if update {
            write_rgb8_png(new.width, new.height, &bytes, &reference).unwrap();
            continue;
        }
        let new = LinearImage::from_srgb8(new.width, new.height, &bytes);
        let old = read_image(&reference).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        let c = compare(&old, &new, &thresholds).unwrap();
        let failures = c.failures(&thresholds);
        if failures.is_empty() {
            println!("{name}: {}", c.summary(&thresholds));
        } else {
            std::fs::create_dir_all(&out_dir).unwrap();
            let new_path = out_dir.join(format!("{name}.new.png"));
            write_rgb8_png(new.width, new.height, &bytes, &new_path).unwrap();
            failed.push(format!(
                "{name}: {} (new image {})",
                failures.join("; "),
                new_path.display()
            ));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// BoxInterleaved's only material is red (0.8, 0, 0) with glTF's default metallic 1 and
/// roughness 1: a rough red metal, whose diffuse term is gone and whose highlight and glossy
/// reflections are tinted by its F₀, its red, with glTF's Fresnel rising to white at grazing
/// views. Every pixel of the box has green equal to blue and at most its red (the backdrop is
/// grey); a coloured highlight, or a diffuse term in another colour, would not. At one sample a
/// pixel whose glossy ray is lost to masking is black, so the red is asked of the box as a
/// whole.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn box_interleaved_is_red_in_every_pixel() {
    let root = khronos();
    let pixels = srgb8(&render_at_centres(load(&root, "BoxInterleaved")));
    let backdrop = pixels[0];
    let boxed: Vec<_> = pixels.iter().filter(|&&p| p != backdrop).collect();
    assert!(boxed.len() > 5000, "{} box pixels", boxed.len());
    // Schlick's Fresnel whitens a metal towards grazing views (F = F₀ + (1 − F₀)(1 − cos)⁵, the
    // same in green and blue since F₀ has 0 in both): a grey sheen over red, never a colour.
    assert!(boxed.iter().all(|p| p[1] == p[2] && p[1] <= p[0]));
    let lit = boxed.iter().filter(|p| p[0] > 0).count();
    assert!(
        lit > boxed.len() / 2,
        "{lit} of {} box pixels red",
        boxed.len()
    );
}

/// NegativeScaleTest and TextureSettingsTest draw a red ✗ on faces that glTF culls (the backs of
/// single-sided materials, also under mirroring node transforms) and a green ✓ where culling
/// shows what lies behind. With back faces culled no strongly red pixel is left; drawn two-sided,
/// the red marks appear.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn culled_faces_hide_their_red_marks() {
    let root = khronos();
    let red = |film: &Film| {
        srgb8(film)
            .iter()
            // The marks' red, lit: about (146, 52, 45) on the display.
            .filter(|p| p[0] > 90 && p[0] as u32 > 2 * p[1] as u32 && p[0] as u32 > 2 * p[2] as u32)
            .count()
    };
    for name in ["NegativeScaleTest", "TextureSettingsTest"] {
        let loaded = load(&root, name);
        let mut two_sided = loaded.clone();
        for mesh in two_sided.description.geometry.meshes.iter_mut().chain(
            two_sided
                .description
                .geometry
                .prototypes
                .iter_mut()
                .flat_map(|p| p.meshes.iter_mut()),
        ) {
            *mesh = mesh.clone().with_single_sided(false);
        }
        let (culled, drawn) = (
            red(&render_at_centres(loaded)),
            red(&render_at_centres(two_sided)),
        );
        assert_eq!(culled, 0, "{name}");
        assert!(drawn > 10, "{name}: the marks show two-sided ({drawn})");
    }
}

/// MultiUVTest's material emits its glTF logo through an emissive texture on the second
/// texture coordinate set. Emission only adds light: without it no pixel is brighter in any
/// channel, and with it the logo's pixels are.
#[cfg_attr(not(quadray_shared), ignore = "needs ../shared/assets, absent here")]
#[test]
fn multi_uv_test_emission_adds_the_logo() {
    let root = khronos();
    let loaded = load(&root, "MultiUVTest");
    let mut dark = loaded.clone();
    for m in &mut dark.description.materials {
        assert!(m.emission.is_some(), "the sample's material emits");
        m.emission = None;
    }
    let (lit, dark) = (render_at_centres(loaded), render_at_centres(dark));
    let mut brighter = 0;
    for (a, b) in lit.pixels().iter().zip(dark.pixels()) {
        let added = *a - *b;
        assert!(added.min_element() >= 0.0, "{a} vs {b}");
        brighter += usize::from(added.max_element() > 0.05);
    }
    assert!(brighter > 50, "{brighter} pixels lit by the logo");
}
