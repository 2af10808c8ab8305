//! Logic tests of the viewer's window in egui_kittest's harness: no display, no GPU. Widgets are
//! found and driven through their accessibility names, as a screen reader would; the renders
//! they start run on the real worker thread.

use eframe::egui::{self, accesskit::Role};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use quadray::{QuadricClass, QuadricKind};
use quadray_viewer::Viewer;
use std::path::Path;
use std::time::{Duration, Instant};

fn harness(viewer: Viewer) -> Harness<'static, Viewer> {
    Harness::builder()
        .with_size(egui::vec2(1000.0, 640.0))
        .build_ui_state(|ui, viewer: &mut Viewer| viewer.ui(ui), viewer)
}

/// Steps the UI until `done` holds (the renders and loads run on other threads).
fn step_until(harness: &mut Harness<'_, Viewer>, what: &str, done: impl Fn(&Viewer) -> bool) {
    let start = Instant::now();
    while !done(harness.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "timed out waiting for {what} (error shown: {:?})",
            harness.state().error()
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    harness.step();
}

/// Whether the newest request's refined frame is on screen.
fn refined(viewer: &Viewer) -> bool {
    viewer.frame().is_some_and(|f| {
        f.frame.done
            && viewer.last_request().is_some_and(|r| {
                (r.settings.width, r.settings.height) == (f.frame.width, f.frame.height)
            })
    })
}

/// The class of the one quadric the newest request renders.
fn requested_class(viewer: &Viewer) -> QuadricClass {
    viewer.last_request().unwrap().scene.geometry().quadrics[0].class()
}

#[test]
fn moving_a_slider_requests_a_preview_with_the_new_value() {
    let mut harness = harness(Viewer::new(None, 2).unwrap());
    step_until(&mut harness, "the first refined frame", refined);
    let before = harness.state().last_request().unwrap().settings.camera;
    harness
        .get_by_role_and_label(Role::Slider, "yaw")
        .set_value_accesskit(75.0);
    harness.step();
    let viewer = harness.state();
    assert!((viewer.orbit().yaw - 75.0).abs() < 1e-9);
    let request = viewer.last_request().unwrap();
    assert!(request.preview, "a change starts with a quick preview");
    assert_ne!(request.settings.camera, before);
    let camera = request.settings.camera.unwrap();
    let eye = camera.from - camera.to;
    assert!(
        (eye.y.atan2(eye.x).to_degrees() - 75.0).abs() < 1e-6,
        "{eye}"
    );
    // A surface parameter rebuilds the quadric with it.
    harness
        .get_by_role_and_label(Role::Slider, "a")
        .set_value_accesskit(0.8);
    harness.step();
    let request = harness.state().last_request().unwrap();
    match request.scene.geometry().quadrics[0].surface_description() {
        quadray::QuadricSurface::Canonical { a, .. } => assert!((a - 0.8).abs() < 1e-9, "{a}"),
        other => panic!("{other:?}"),
    }
    step_until(&mut harness, "the new view refined", refined);
    assert!(harness.state().frame().unwrap().frame.error.is_some());
}

#[test]
fn the_kind_radio_buttons_change_the_shape() {
    let mut harness = harness(Viewer::new(None, 2).unwrap());
    harness.step();
    assert_eq!(
        requested_class(harness.state()),
        QuadricClass::Proper(QuadricKind::Hyperboloid1)
    );
    harness.get_by_label("cone").click();
    harness.step();
    assert_eq!(
        requested_class(harness.state()),
        QuadricClass::Proper(QuadricKind::Cone)
    );
    harness.get_by_label("ellipsoid").click();
    harness.step();
    assert_eq!(
        requested_class(harness.state()),
        QuadricClass::Proper(QuadricKind::Ellipsoid)
    );
    // Sample: the kind's textbook picture, as the gallery's tile.
    harness
        .get_by_role_and_label(Role::Slider, "yaw")
        .set_value_accesskit(10.0);
    harness.step();
    harness.get_by_label("Sample").click();
    harness.step();
    let view = harness.state().explorer().unwrap().textbook_view();
    assert_eq!(*harness.state().orbit(), view);
}

#[test]
fn render_writes_the_current_view_to_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("view.png");
    let mut viewer = Viewer::new(None, 2).unwrap();
    viewer.set_output(output.to_str().unwrap());
    let mut harness = harness(viewer);
    harness.step();
    harness.get_by_label("Render").click();
    harness.step();
    step_until(&mut harness, "the render", |v| !v.rendering());
    let message = harness.state().message().unwrap().to_string();
    assert!(message.starts_with("wrote"), "{message}");
    let image = image_size(&output);
    assert_eq!(image, (1280, 720), "the explorer's output resolution");
    // A bad output name is an error in the window, and no file.
    let bad = dir.path().join("view.gif");
    harness.state_mut().set_output(bad.to_str().unwrap());
    harness.get_by_label("Render").click();
    harness.step();
    let message = harness.state().message().unwrap();
    assert!(message.contains("must end in .png or .exr"), "{message}");
    assert!(!bad.exists());
}

/// Width and height from a PNG's header.
fn image_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn a_broken_scene_on_reload_shows_the_error_and_keeps_the_old_frame() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    let good = "version = 1\n[camera]\norbit = { yaw = 30, pitch = 20, distance = 6 }\nvfov = 40\n\
                [[material]]\nname = \"white\"\n\
                [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"white\"\n\
                [[light]]\ntype = \"point\"\nposition = [4, -4, 6]\nintensity = 40\n\
                [render]\nresolution = [320, 180]\nspp = 4\n";
    std::fs::write(&path, good).unwrap();
    let mut harness = harness(Viewer::new(Some(path.clone()), 2).unwrap());
    step_until(&mut harness, "the scene and its frame", refined);
    let scene = harness.state().shown().unwrap().scene.clone();
    let frame = harness.state().frame().unwrap().frame.rgba.clone();
    // Line 8 breaks: the radius is a string.
    std::fs::write(&path, good.replace("radius = 1", "radius = \"big\"")).unwrap();
    harness.state_mut().reload();
    step_until(&mut harness, "the reload's error", |v| v.error().is_some());
    let error = harness.state().error().unwrap().to_string();
    assert!(
        error.contains("scene.toml:9:10"),
        "names the place: {error}"
    );
    assert!(
        error.contains("radius = \"big\""),
        "shows the line: {error}"
    );
    assert!(
        harness.query_by_label_contains("radius").is_some(),
        "the error is shown in the window"
    );
    let viewer = harness.state();
    assert!(std::sync::Arc::ptr_eq(
        &viewer.shown().unwrap().scene,
        &scene
    ));
    assert_eq!(
        viewer.frame().unwrap().frame.rgba,
        frame,
        "the old frame stays"
    );
    // Fixing the file on disk reloads it by itself (the watcher), and the error goes.
    std::fs::write(&path, good.replace("radius = 1", "radius = 1.2")).unwrap();
    step_until(&mut harness, "the fixed scene", |v| {
        v.error().is_none() && !std::sync::Arc::ptr_eq(&v.shown().unwrap().scene, &scene)
    });
}
