//! End-to-end tests on the bundled scene files.

use quadray_tests::{load, render_with_threads, scene_path};

#[test]
fn renders_are_bit_identical_across_thread_counts() {
    let (scene, mut settings) = load("defense.toml");
    (settings.width, settings.height, settings.spp) = (96, 54, 3);
    let one = render_with_threads(&scene, &settings, 1);
    let two = render_with_threads(&scene, &settings, 2);
    let bits = |r: &quadray::Rendered| {
        r.film
            .pixels()
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(one.counts, two.counts);
}

#[test]
fn a_crop_window_renders_exactly_the_whole_image_pixels_it_covers() {
    let (scene, mut settings) = load("defense.toml");
    (settings.width, settings.height, settings.spp) = (80, 45, 2);
    let whole = render_with_threads(&scene, &settings, 2);
    let window = quadray::PixelWindow::from_normalized([0.3, 0.75, 0.1, 0.6], 80, 45).unwrap();
    settings.crop = Some(window);
    let crop = render_with_threads(&scene, &settings, 1);
    assert_eq!(crop.window, window);
    assert_eq!(
        (crop.film.width(), crop.film.height()),
        (window.width(), window.height())
    );
    for y in 0..window.height() {
        for x in 0..window.width() {
            let inside = crop.film.get(x, y).to_array().map(f32::to_bits);
            let full = whole
                .film
                .get(window.x0 + x, window.y0 + y)
                .to_array()
                .map(f32::to_bits);
            assert_eq!(inside, full, "pixel ({x}, {y}) of the window");
        }
    }
    // Work is done only inside the window: one camera ray per sample of its pixels.
    assert_eq!(
        crop.counts.camera,
        (window.width() * window.height() * settings.spp) as u64
    );
}

#[test]
fn exr_output_holds_the_linear_film_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("q.exr");
    let scene_file = scene_path("quadrics.toml");
    quadray_cli::run_args([
        "render",
        scene_file.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--res",
        "64x36",
        "--spp",
        "2",
        "-q",
    ])
    .unwrap();
    let (scene, mut settings) = load("quadrics.toml");
    (settings.width, settings.height, settings.spp) = (64, 36, 2);
    let film = render_with_threads(&scene, &settings, 2).film;
    let img = exr::prelude::read_first_rgba_layer_from_file(
        &out,
        |res, _| vec![[0f32; 3]; res.width() * res.height()],
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * 64 + pos.x()] = [r, g, b]
        },
    )
    .unwrap();
    let read = &img.layer_data.channel_data.pixels;
    assert_eq!(read.len(), film.pixels().len());
    assert!(
        read.iter()
            .zip(film.pixels())
            .all(|(a, b)| *a == b.to_array())
    );
}

#[test]
fn work_follows_the_scene_no_reflections_or_shadows_that_cannot_matter() {
    // quadrics.toml has no reflective material: no reflection ray may be traced.
    let (scene, mut settings) = load("quadrics.toml");
    (settings.width, settings.height) = (80, 45);
    let r = render_with_threads(&scene, &settings, 2);
    assert_eq!(r.counts.reflection, 0);
    assert!(r.counts.shadow > 0);
    // Without lights, no shadow ray is traced.
    let mut description = scene.clone().into_description();
    description.lights.clear();
    let dark = quadray::Scene::new(description).unwrap();
    let r = render_with_threads(&dark, &settings, 2);
    assert_eq!(r.counts.shadow, 0);
    // defense.toml has mirrors: reflections are traced, and at most max_depth - 1 per camera ray.
    let (scene, mut settings) = load("defense.toml");
    (settings.width, settings.height, settings.spp) = (80, 45, 1);
    let r = render_with_threads(&scene, &settings, 2);
    assert!(r.counts.reflection > 0);
    assert!(r.counts.reflection <= r.counts.camera * (settings.whitted.max_depth as u64 - 1));
}

#[test]
fn checked_pixels_of_the_defense_scene() {
    // Facts visible in the image, each following from the scene file:
    // the sky above the horizon is the background colour; the floor is lit and checkered.
    let (scene, mut settings) = load("defense.toml");
    (settings.width, settings.height, settings.spp) = (160, 90, 1);
    let film = render_with_threads(&scene, &settings, 2).film;
    assert_eq!(film.get(80, 2), scene.background(), "top row sees the sky");
    let floor_row = 85;
    let values: Vec<f32> = (0..160).map(|x| film.get(x, floor_row).x).collect();
    let (lo, hi) = values
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert!(
        hi > lo * 1.3,
        "checker squares alternate along a floor row: {lo} .. {hi}"
    );
}

/// A compact mesh BVH, asked for by `--compact-meshes` or by the scene's `render.compact_meshes`,
/// writes the image the default BVH writes, byte for byte (scenes/obj-mesh.toml: two copies of an
/// OBJ mesh beside quadrics, a sphere and a mirror); a value that is not true or false is refused.
#[test]
fn compact_meshes_write_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let scene_file = scene_path("obj-mesh.toml");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["render", scene_file.to_str().unwrap(), "-o"];
        args.push(out.to_str().unwrap());
        args.extend(["--res", "64x40", "--spp", "1", "-q"]);
        args.extend(extra);
        quadray_cli::run_args(args).map(|_| std::fs::read(&out).unwrap())
    };
    let default = render("default.png", &[]).unwrap();
    let flag = render("flag.png", &["--compact-meshes"]).unwrap();
    let key = render("key.png", &["--set", "render.compact_meshes=true"]).unwrap();
    assert!(default == flag && default == key);
    let refused = render("refused.png", &["--set", "render.compact_meshes=1"]).unwrap_err();
    assert!(
        format!("{refused:#}").contains("expected true or false"),
        "{refused:#}"
    );
}
