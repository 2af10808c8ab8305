//! The viewer window: the image on the left, settings on the right, a status line below. The UI
//! thread keeps the state and posts render requests; the [`Worker`] renders. The panels are
//! drawn in `panels`; opening a file or going back to the explorer is `switch`.

use crate::explorer::Explorer;
use crate::final_render::FinalRender;
use crate::open_dialog::OpenDialog;
use crate::orbit::Orbit;
use crate::pick::Picked;
use crate::source::{FileSource, LoadedFile};
use crate::worker::{Frame, Request, Worker};
use eframe::egui;
use quadray::{Camera, RenderSettings, Scene};
use quadray_app::passes::Pass;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

mod panels;
mod switch;

use switch::file_output;

/// Resolution the explorer's Render button writes, and so the aspect of its view.
const EXPLORER_RESOLUTION: (u32, u32) = (1280, 720);
/// Samples per pixel the explorer's view refines to.
const EXPLORER_SPP: u32 = 16;
/// Samples per pixel the view refines to for a scene sampled adaptively.
const ADAPTIVE_VIEW_SPP: u32 = 16;
/// Width of the settings panel, points.
const PANEL_WIDTH: f32 = 300.0;
/// The folder the viewer's default outputs go to, relative to where it runs (git ignores it).
pub const OUTPUT_FOLDER: &str = "renders";

/// The passes the view can show, as the CLI's `--pass` names them.
const PASSES: [(Pass, &str); 5] = [
    (Pass::Combined, "combined"),
    (Pass::Depth, "depth"),
    (Pass::Normal, "normal"),
    (Pass::Albedo, "albedo"),
    (Pass::ObjectId, "object id"),
];

/// Wakes the UI from other threads, once the UI has run (and so has a context) at least once.
#[derive(Clone, Default)]
pub struct Waker(Arc<OnceLock<egui::Context>>);

impl Waker {
    /// Asks for a repaint of the viewer's window.
    pub fn wake(&self) {
        if let Some(ctx) = self.0.get() {
            ctx.request_repaint();
        }
    }
}

/// An error as the CLI prints it: the whole chain on one line (file, line and column first), and
/// under it the scene line with a caret where the error has a place in a file.
fn located(error: &anyhow::Error) -> String {
    let mut text = format!("error: {error:#}");
    if let Some(snippet) = quadray_app::snippet::for_error(error) {
        text += "\n";
        text += &snippet;
    }
    text
}

/// What the viewer shows: the quadric explorer, or a scene file.
pub enum Source {
    /// The explorer's panel and its one quadric.
    Explorer(Explorer),
    /// A scene file, reloaded when it changes.
    File(FileSource),
}

/// The scene on screen: the last one that loaded (or built) without error.
pub struct Shown {
    /// The built scene.
    pub scene: Arc<Scene>,
    /// Its render settings (resolution, samples, depth).
    pub settings: RenderSettings,
    /// The scene's own camera, which Home restores.
    pub camera: Camera,
    /// Material names by index.
    pub material_names: Vec<String>,
}

/// What the image area shows and how it was made.
#[derive(Clone, Debug)]
pub struct ShownFrame {
    /// The frame's numbers (size, samples, rate, error).
    pub frame: Frame,
    /// The full resolution of the view it belongs to.
    pub view: (u32, u32),
}

/// The viewer's state.
pub struct Viewer {
    source: Source,
    shown: Option<Shown>,
    orbit: Orbit,
    pass: Pass,
    worker: Worker,
    waker: Waker,
    texture: Option<egui::TextureHandle>,
    frame: Option<ShownFrame>,
    /// The request last posted, to post again only on a change.
    requested: Option<Request>,
    /// Its number: frames of other requests are stale.
    generation: u64,
    /// Size of the view in pixels, from the last layout.
    view_size: (u32, u32),
    error: Option<String>,
    picked: Option<Option<Picked>>,
    output: String,
    /// Whether the user typed the output name: until then it follows the kind or the file.
    output_edited: bool,
    /// The Open window, while it is open.
    open_dialog: Option<OpenDialog>,
    /// Where the image was drawn at the last layout, in points.
    image_rect: Option<egui::Rect>,
    /// The window title last set.
    title: String,
    final_render: Option<FinalRender>,
    message: Option<String>,
    saved_view: Option<String>,
    /// The generation whose refined frame was logged.
    logged: u64,
}

impl Viewer {
    /// A viewer of `scene` (a file), or of the quadric explorer when `None`, rendering with
    /// `threads` threads (0: one per core).
    pub fn new(scene: Option<PathBuf>, threads: usize) -> std::io::Result<Viewer> {
        let waker = Waker::default();
        let worker = {
            let waker = waker.clone();
            Worker::spawn(threads, move || waker.wake())?
        };
        let explorer = Explorer::default();
        let orbit = explorer.textbook_view();
        let (source, output) = match scene {
            Some(path) => {
                let waker = waker.clone();
                let output = file_output(&path);
                (
                    Source::File(FileSource::open(path, move || waker.wake())),
                    output,
                )
            }
            None => (
                Source::Explorer(explorer.clone()),
                PathBuf::from(explorer.output_name()),
            ),
        };
        let mut viewer = Viewer {
            source,
            shown: None,
            orbit,
            pass: Pass::Combined,
            worker,
            waker,
            texture: None,
            frame: None,
            requested: None,
            generation: 0,
            view_size: (0, 0),
            error: None,
            picked: None,
            output: output.display().to_string(),
            output_edited: false,
            open_dialog: None,
            image_rect: None,
            title: String::new(),
            final_render: None,
            message: None,
            saved_view: None,
            logged: 0,
        };
        if let Source::Explorer(_) = viewer.source {
            viewer.rebuild_explorer();
        }
        Ok(viewer)
    }

    /// The scene on screen, if one loaded.
    pub fn shown(&self) -> Option<&Shown> {
        self.shown.as_ref()
    }

    /// The frame on screen, if any.
    pub fn frame(&self) -> Option<&ShownFrame> {
        self.frame.as_ref()
    }

    /// The request last posted to the worker.
    pub fn last_request(&self) -> Option<&Request> {
        self.requested.as_ref()
    }

    /// The error shown (a scene that failed to load or build), if any.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// The last message of the Render button (written file or error).
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    /// Whether the Render button's render is under way.
    pub fn rendering(&self) -> bool {
        self.final_render.is_some()
    }

    /// The orbit camera.
    pub fn orbit(&self) -> &Orbit {
        &self.orbit
    }

    /// The explorer's settings, when the explorer is shown.
    pub fn explorer(&self) -> Option<&Explorer> {
        match &self.source {
            Source::Explorer(e) => Some(e),
            Source::File(_) => None,
        }
    }

    /// Sets the file the Render button writes, as typing it in the output field does.
    pub fn set_output(&mut self, output: &str) {
        self.output = output.to_string();
        self.output_edited = true;
    }

    /// The file the Render button writes.
    pub fn output(&self) -> &str {
        &self.output
    }

    /// Where the image was drawn at the last layout, in points.
    pub fn image_rect(&self) -> Option<egui::Rect> {
        self.image_rect
    }

    /// The scene file shown, if any (none in the explorer).
    pub fn file(&self) -> Option<&std::path::Path> {
        match &self.source {
            Source::File(file) => Some(file.path()),
            Source::Explorer(_) => None,
        }
    }

    /// The whole window, inside `ui` (eframe's root, or a test harness).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let _ = self.waker.0.set(ui.ctx().clone());
        let title = match self.file() {
            Some(path) => format!("quadray-view: {}", path.display()),
            None => "quadray-view: quadric explorer".to_string(),
        };
        if title != self.title {
            ui.ctx()
                .send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        self.poll();
        self.keys(ui.ctx());
        egui::Panel::bottom("status").show(ui, |ui| self.status_line(ui));
        egui::Panel::right("settings")
            .exact_size(PANEL_WIDTH)
            .show(ui, |ui| {
                // The buttons stay in sight; the settings below them scroll.
                self.buttons(ui);
                ui.separator();
                egui::ScrollArea::vertical().show(ui, |ui| self.settings_panel(ui));
            });
        egui::CentralPanel::default().show(ui, |ui| self.image_area(ui));
        self.post_request();
        if let Some(text) = self.saved_view.clone() {
            self.saved_view_window(ui.ctx(), text);
        }
        self.open_window(ui.ctx());
        self.take_dropped_file(ui.ctx());
    }

    /// Takes in what the background threads finished: a load, frames, a written render.
    fn poll(&mut self) {
        if let Source::File(file) = &mut self.source {
            if file.changed() {
                let waker = self.waker.clone();
                file.reload(move || waker.wake());
            }
            if let Some(result) = file.finished() {
                match result {
                    Ok(loaded) => self.show_file(loaded),
                    Err(e) => self.error = Some(located(&e)),
                }
            }
        }
        if let Some(frame) = self.worker.latest_frame() {
            self.take_frame(frame);
        }
        if let Some((generation, failure)) = self.worker.failure()
            && generation == self.generation
        {
            self.error = Some(failure);
        }
        if let Some(result) = self.final_render.as_mut().and_then(FinalRender::finished) {
            self.message = Some(match result {
                Ok(path) => format!("wrote {}", path.display()),
                Err(e) => format!("error: {e:#}"),
            });
            self.final_render = None;
        }
    }

    /// Shows a newly loaded file; a reload keeps the view unless the scene's camera moved.
    fn show_file(&mut self, loaded: LoadedFile) {
        let camera = *loaded.scene.camera();
        let keep_view = self.shown.as_ref().is_some_and(|s| s.camera == camera);
        if !keep_view {
            self.orbit = Orbit::from_camera(&camera);
        }
        for note in &loaded.notes {
            log::warn!("{note}");
        }
        self.shown = Some(Shown {
            scene: loaded.scene,
            settings: loaded.settings,
            camera,
            material_names: loaded.material_names,
        });
        self.error = None;
    }

    /// Builds the explorer's scene for the current settings and view; an impossible one (a
    /// surface outside its box) shows the error and keeps the last one.
    fn rebuild_explorer(&mut self) {
        let Source::Explorer(explorer) = &self.source else {
            return;
        };
        if !self.output_edited {
            self.output = explorer.output_name();
        }
        let built = explorer.scene(&self.orbit).and_then(|d| Ok(Scene::new(d)?));
        match built {
            Ok(scene) => {
                let (width, height) = EXPLORER_RESOLUTION;
                self.shown = Some(Shown {
                    camera: *scene.camera(),
                    scene: Arc::new(scene),
                    settings: RenderSettings {
                        width,
                        height,
                        spp: EXPLORER_SPP,
                        ..RenderSettings::default()
                    },
                    material_names: vec!["quadric".into()],
                });
                self.error = None;
            }
            Err(e) => self.error = Some(located(&e)),
        }
    }

    /// Puts a frame of the current request on screen (frames of older requests are dropped).
    fn take_frame(&mut self, frame: Frame) {
        if frame.generation != self.generation {
            return;
        }
        let Some(ctx) = self.waker.0.get() else {
            return;
        };
        let image = egui::ColorImage::from_rgba_unmultiplied(
            [frame.width as usize, frame.height as usize],
            &frame.rgba,
        );
        // Full-resolution frames are shown pixel for pixel; previews are smoothed when enlarged.
        let filter = if frame.preview {
            egui::TextureOptions::LINEAR
        } else {
            egui::TextureOptions::NEAREST
        };
        match &mut self.texture {
            Some(texture) => texture.set(image, filter),
            None => self.texture = Some(ctx.load_texture("view", image, filter)),
        }
        let view = self
            .requested
            .as_ref()
            .map_or((frame.width, frame.height), |r| {
                (r.settings.width, r.settings.height)
            });
        self.frame = Some(ShownFrame { frame, view });
    }

    /// The request the current state calls for: the scene through the orbit camera at the view's
    /// size, refined to the scene's samples.
    fn wanted_request(&self) -> Option<Request> {
        let shown = self.shown.as_ref()?;
        let (width, height) = self.view_size;
        if width == 0 || height == 0 {
            return None;
        }
        let spp = match (&self.source, shown.settings.adaptive) {
            (Source::Explorer(_), _) => EXPLORER_SPP,
            (Source::File(_), Some(adaptive)) => {
                ADAPTIVE_VIEW_SPP.clamp(adaptive.min_spp, adaptive.max_spp)
            }
            (Source::File(_), None) => shown.settings.spp,
        };
        Some(Request {
            scene: shown.scene.clone(),
            settings: RenderSettings {
                width,
                height,
                spp,
                camera: Some(self.orbit.camera()),
                ..shown.settings
            },
            pass: self.pass,
            preview: true,
        })
    }

    /// Posts the wanted request when it differs from the last one (a new scene, view, size or
    /// pass), which cancels the work on the old one.
    fn post_request(&mut self) {
        let Some(wanted) = self.wanted_request() else {
            return;
        };
        let same = self.requested.as_ref().is_some_and(|r| {
            Arc::ptr_eq(&r.scene, &wanted.scene)
                && r.settings == wanted.settings
                && r.pass == wanted.pass
        });
        if !same {
            self.generation = self.worker.request(wanted.clone());
            self.requested = Some(wanted);
            self.picked = None;
        }
    }

    /// Starts the Render button's full-quality render of the current view.
    pub fn start_final_render(&mut self) {
        let Some(shown) = &self.shown else {
            self.message = Some("error: no scene to render".into());
            return;
        };
        let settings = RenderSettings {
            camera: Some(self.orbit.camera()),
            ..shown.settings
        };
        let waker = self.waker.clone();
        let output = PathBuf::from(&self.output);
        // The default outputs folder is made when first needed; a folder the user typed must exist.
        if !self.output_edited
            && let Some(folder) = output.parent().filter(|f| !f.as_os_str().is_empty())
            && let Err(e) = std::fs::create_dir_all(folder)
        {
            self.message = Some(format!("error: cannot make {}: {e}", folder.display()));
            return;
        }
        match FinalRender::start(shown.scene.clone(), settings, output, move || waker.wake()) {
            Ok(render) => {
                self.message = None;
                self.final_render = Some(render);
            }
            Err(e) => self.message = Some(format!("error: {e:#}")),
        }
    }

    /// The Sample button: the current kind's textbook parameters and view, as the gallery shows
    /// it.
    pub fn sample(&mut self) {
        if let Source::Explorer(explorer) = &mut self.source {
            explorer.textbook_parameters();
            self.orbit = explorer.textbook_view();
            self.rebuild_explorer();
        }
    }

    /// Back to the scene's own camera (the explorer's: the kind's textbook view).
    pub fn restore_camera(&mut self) {
        match (&self.source, &self.shown) {
            (Source::Explorer(explorer), _) => {
                self.orbit = explorer.textbook_view();
                self.rebuild_explorer();
            }
            (Source::File(_), Some(shown)) => self.orbit = Orbit::from_camera(&shown.camera),
            (Source::File(_), None) => {}
        }
    }

    /// Starts loading the scene file again (what an edit on disk does by itself).
    pub fn reload(&mut self) {
        if let Source::File(file) = &mut self.source {
            let waker = self.waker.clone();
            file.reload(move || waker.wake());
        }
    }
}
