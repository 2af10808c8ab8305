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

/// The Render button's file follows the kind (`renders/quadric-KIND.png`, where git ignores
/// it) until the user types one; from then on it stays.
#[test]
fn the_output_name_follows_the_kind_until_edited() {
    let mut harness = harness(Viewer::new(None, 2).unwrap());
    harness.step();
    assert_eq!(harness.state().output(), "renders/quadric-hyperboloid1.png");
    harness.get_by_label("cone").click();
    harness.step();
    assert_eq!(harness.state().output(), "renders/quadric-cone.png");
    let field = harness.get_by_role_and_label(Role::TextInput, "output");
    field.focus();
    field.type_text("x");
    harness.step();
    let typed = harness.state().output().to_string();
    assert_ne!(typed, "renders/quadric-cone.png");
    harness.get_by_label("ellipsoid").click();
    harness.step();
    assert_eq!(harness.state().output(), typed, "a typed name stays");
}

/// At the default 1000x600 window the most used controls (the kind, its parameters, the camera
/// sliders and the pass menu) are in sight, and the image is centred in the space it has.
#[test]
fn the_panel_fits_the_window_and_the_image_is_centred() {
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1000.0, 600.0))
        .build_ui_state(
            |ui, viewer: &mut Viewer| viewer.ui(ui),
            Viewer::new(None, 2).unwrap(),
        );
    harness.step();
    harness.step();
    for (role, label) in [
        (Role::RadioButton, "cone"),
        (Role::Slider, "a"),
        (Role::Slider, "yaw"),
        (Role::Slider, "distance"),
    ] {
        let rect = harness.get_by_role_and_label(role, label).rect();
        assert!(rect.max.y <= 600.0, "{label} at {rect:?}, below the window");
    }
    let pass = harness.get_by_label("pass").rect();
    assert!(pass.max.y <= 600.0, "pass menu at {pass:?}");
    // The image: 16:9, as wide as the area left of the panel, with equal bands above and below.
    let image = harness.state().image_rect().unwrap();
    let status_top = 600.0 - 30.0;
    let (above, below) = (image.min.y, status_top - image.max.y);
    assert!(image.width() > 650.0, "{image:?}");
    assert!(
        (above - below).abs() < 16.0,
        "{above} above, {below} below: {image:?}"
    );
}

/// A file dropped on the window, as the Open window does.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

fn bundled(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

/// Open: the window's file field opens a scene; Explorer goes back; a dropped file opens too,
/// and a file of another kind is refused with a message. A glTF file's camera is orbited about
/// the scene, not a point one unit in front of the lens.
#[test]
fn scenes_open_from_the_window_and_by_dropping() {
    let mut harness = harness(Viewer::new(None, 2).unwrap());
    harness.step();
    harness.get_by_label("Open…").click();
    harness.run();
    let gltf = bundled("gltf-quadrics.gltf");
    let field = harness.get_by_role_and_label(Role::TextInput, "file");
    field.focus();
    field.type_text(gltf.to_str().unwrap());
    harness.step();
    harness.get_by_label("Open file").click();
    harness.step();
    assert_eq!(harness.state().file(), Some(gltf.as_path()));
    assert_eq!(harness.state().output(), "renders/gltf-quadrics.png");
    step_until(&mut harness, "the glTF scene", refined);
    // The panel keeps its place beside the image: its buttons lie right of the image.
    let image = harness.state().image_rect().unwrap();
    for button in ["Open…", "Explorer", "Render", "Quit"] {
        let rect = harness.get_by_label(button).rect();
        assert!(
            rect.min.x >= image.max.x,
            "{button} at {rect:?} under the image {image:?}"
        );
    }
    let orbit = *harness.state().orbit();
    assert!(orbit.distance > 2.0, "orbits about the scene: {orbit:?}");

    harness.get_by_label("Explorer").click();
    harness.step();
    assert!(harness.state().explorer().is_some());
    assert_eq!(harness.state().output(), "renders/quadric-hyperboloid1.png");

    let toml = bundled("defense.toml");
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(toml.clone())));
    harness.step();
    assert_eq!(harness.state().file(), Some(toml.as_path()));
    step_until(&mut harness, "the dropped scene", |v| v.shown().is_some());
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(bundled("README.md"))));
    harness.step();
    assert_eq!(harness.state().file(), Some(toml.as_path()), "still shown");
    let message = harness.state().message().unwrap();
    assert!(message.contains("is not a scene file"), "{message}");
}

/// A view the renderer refuses (zoomed out beyond the coordinate limit) shows the render's
/// error in the window, not only in the log.
#[test]
fn a_render_error_shows_in_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("far.toml");
    std::fs::write(
        &path,
        "version = 1\n[camera]\nfrom = [0, -4e29, 0]\nto = [0, 0, 0]\nup = [0, 0, 1]\nvfov = 40\n\
         [[material]]\nname = \"white\"\n\
         [[sphere]]\ncenter = [0, 0, 0]\nradius = 1e29\nmaterial = \"white\"\n\
         [render]\nresolution = [320, 180]\nspp = 1\n",
    )
    .unwrap();
    let mut harness = harness(Viewer::new(Some(path), 2).unwrap());
    step_until(&mut harness, "the scene", refined);
    assert!(harness.state().error().is_none());
    harness
        .get_by_role_and_label(Role::Slider, "distance")
        .set_value_accesskit(7e30);
    harness.step();
    step_until(&mut harness, "the render's error", |v| v.error().is_some());
    let error = harness.state().error().unwrap().to_string();
    assert!(error.contains("rendering the view"), "{error}");
    assert!(error.contains("1e30"), "says the limit: {error}");
    assert!(
        harness
            .query_by_label_contains("rendering the view")
            .is_some()
    );
}

/// A pass is one sample of each pixel's first hit: the status line says so, with its real ray
/// rate, not "1/16 spp, 0.0 Mrays/s".
#[test]
fn the_status_line_of_a_pass_says_what_it_is() {
    let mut harness = harness(Viewer::new(None, 2).unwrap());
    step_until(&mut harness, "the first refined frame", refined);
    harness.get_by_label("pass").click();
    harness.run();
    harness.get_by_label("normal").click();
    harness.step();
    step_until(&mut harness, "the normal pass", |v| {
        refined(v)
            && v.last_request()
                .is_some_and(|r| r.pass == quadray_app::passes::Pass::Normal)
    });
    assert!(
        harness
            .query_by_label_contains("normal pass: each pixel's first hit")
            .is_some(),
        "the status line names the pass"
    );
    assert!(harness.query_by_label_contains("/16 spp").is_none());
    assert!(harness.query_by_label_contains(" 0.0 Mrays/s").is_none());
}
