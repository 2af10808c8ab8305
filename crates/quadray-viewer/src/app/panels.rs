//! The viewer's panels: the image with its mouse controls, the settings, the status line, the
//! keys, and the Save view window.

use super::{PASSES, Source, Viewer};
use crate::pick::pick;
use eframe::egui;
use quadray_app::passes::Pass;
use std::time::Duration;

/// The name the pass menu gives `pass`.
fn pass_name(pass: Pass) -> &'static str {
    PASSES
        .iter()
        .find(|(p, _)| *p == pass)
        .map_or("", |(_, n)| n)
}

/// Aspect of the view when no scene is shown.
const DEFAULT_ASPECT: f32 = 16.0 / 9.0;

impl Viewer {
    /// Ctrl+Q quits, Home restores the scene's camera, F5 reloads the file.
    pub(super) fn keys(&mut self, ctx: &egui::Context) {
        let (quit, home, reload) = ctx.input(|i| {
            (
                i.modifiers.command && i.key_pressed(egui::Key::Q),
                i.key_pressed(egui::Key::Home),
                i.key_pressed(egui::Key::F5),
            )
        });
        if quit {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        if home {
            self.restore_camera();
        }
        if reload {
            self.reload();
        }
    }

    /// The image, as large as fits at the scene's aspect, centred (letterboxed): drag to orbit,
    /// Shift+drag or the right button to pan, the wheel to zoom, a click to name the object
    /// under the cursor.
    pub(super) fn image_area(&mut self, ui: &mut egui::Ui) {
        let ppp = ui.ctx().pixels_per_point();
        let aspect = self.shown.as_ref().map_or(DEFAULT_ASPECT, |s| {
            s.settings.width as f32 / s.settings.height as f32
        });
        let available = ui.available_size();
        let points = if available.x / available.y.max(1.0) > aspect {
            egui::vec2(available.y * aspect, available.y)
        } else {
            egui::vec2(available.x, available.x / aspect)
        };
        // Whole pixels, so a refined frame is shown pixel for pixel; rounding down must not take
        // a scene at the renderer's widest aspect past it (640x10 shown 700x10 was refused).
        let (width, height) = (
            (points.x * ppp).floor().max(1.0) as u32,
            (points.y * ppp).floor().max(1.0) as u32,
        );
        let limit = quadray::render::MAX_ASPECT;
        let height = height.max((width as f64 / limit).ceil() as u32);
        let width = width.max((height as f64 / limit).ceil() as u32);
        self.view_size = (width, height);
        let size = egui::vec2(width as f32, height as f32) / ppp;
        let area = ui.available_rect_before_wrap();
        // Centred, and on whole pixels so a refined frame is shown pixel for pixel.
        let corner = ((area.center() - size * 0.5) * ppp).round() / ppp;
        let rect = egui::Rect::from_min_size(corner, size);
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        self.image_rect = Some(rect);
        let painter = ui.painter_at(rect);
        match &self.texture {
            Some(texture) => {
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                painter.image(texture.id(), rect, uv, egui::Color32::WHITE);
            }
            None => {
                painter.rect_filled(rect, 0.0, egui::Color32::from_gray(24));
            }
        }
        let before = self.orbit;
        if response.dragged() {
            let delta = response.drag_delta();
            let pan = ui.input(|i| i.modifiers.shift)
                || response.dragged_by(egui::PointerButton::Secondary)
                || response.dragged_by(egui::PointerButton::Middle);
            if pan {
                self.orbit
                    .pan(delta.x as f64, delta.y as f64, size.y as f64);
            } else {
                self.orbit.drag(delta.x as f64, delta.y as f64);
            }
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.orbit.zoom(scroll as f64);
            }
        }
        if self.orbit != before {
            self.rebuild_explorer();
        }
        if response.clicked()
            && let (Some(position), Some(shown)) = (response.interact_pointer_pos(), &self.shown)
        {
            let pixel = (position - rect.min) * ppp;
            self.picked = Some(pick(
                &shown.scene,
                &self.orbit.camera(),
                (width, height),
                (pixel.x.max(0.0) as u32, pixel.y.max(0.0) as u32),
                &shown.material_names,
            ));
        }
        self.log_refined(ui.ctx(), rect);
    }

    /// Logs, once per view, that its frame is refined and where it is on screen (in pixels):
    /// what an end-to-end check needs to find the image in a screenshot.
    fn log_refined(&mut self, ctx: &egui::Context, rect: egui::Rect) {
        let Some(shown) = &self.frame else { return };
        let f = &shown.frame;
        if !f.done || f.preview || f.generation == self.logged {
            return;
        }
        self.logged = f.generation;
        let ppp = ctx.pixels_per_point();
        let window = ctx
            .input(|i| i.viewport().inner_rect)
            .map_or(egui::Pos2::ZERO, |r| r.min);
        log::info!(
            "refined {}x{} at {} spp in {:.3} s; image at ({}, {}) px in the window, window at ({}, {}) px",
            f.width,
            f.height,
            f.spp,
            f.latency.as_secs_f64(),
            (rect.min.x * ppp).round(),
            (rect.min.y * ppp).round(),
            (window.x * ppp).round(),
            (window.y * ppp).round()
        );
    }

    /// Resolution, samples, ray rate and error of the frame on screen.
    pub(super) fn status_line(&mut self, ui: &mut egui::Ui) {
        let text = match &self.frame {
            None if self.error.is_some() => "no scene to show".to_string(),
            None => "loading…".to_string(),
            Some(shown) if shown.frame.preview => format!(
                "preview {}x{} of {}x{}, 1 spp",
                shown.frame.width, shown.frame.height, shown.view.0, shown.view.1
            ),
            Some(shown) if self.pass != Pass::Combined => format!(
                "{}x{}, {} pass: each pixel's first hit, {:.1} Mrays/s",
                shown.frame.width,
                shown.frame.height,
                pass_name(self.pass),
                shown.frame.mrays_per_s
            ),
            Some(shown) => {
                let f = &shown.frame;
                let target = self.requested.as_ref().map_or(f.spp, |r| r.settings.spp);
                let mut text = format!(
                    "{}x{}, {}/{} spp, {:.1} Mrays/s",
                    f.width, f.height, f.spp, target, f.mrays_per_s
                );
                if let Some(error) = f.error {
                    text += &format!(", estimated image error {error:.1e} RMSE");
                }
                if !f.done {
                    text += ", refining…";
                }
                text
            }
        };
        ui.label(text);
    }

    /// The settings, most used first: an error, the explorer's kind and parameters (or the
    /// file's name), the camera and the pass, then the explorer's clip box and look, and what
    /// was clicked.
    pub(super) fn settings_panel(&mut self, ui: &mut egui::Ui) {
        if let Some(error) = &self.error {
            let colour = ui.visuals().error_fg_color;
            ui.colored_label(colour, egui::RichText::new(error).monospace());
            ui.separator();
        }
        let surface_changed = match &mut self.source {
            Source::Explorer(explorer) => explorer.surface_ui(ui),
            Source::File(file) => {
                ui.heading("Scene");
                ui.label(file.path().display().to_string());
                if file.loading() {
                    ui.label("loading…");
                }
                false
            }
        };
        if surface_changed {
            self.rebuild_explorer();
        }
        ui.separator();
        self.camera_controls(ui);
        egui::ComboBox::from_label("pass")
            .selected_text(pass_name(self.pass))
            .show_ui(ui, |ui| {
                for (pass, name) in PASSES {
                    ui.selectable_value(&mut self.pass, pass, name);
                }
            });
        if let Source::Explorer(explorer) = &mut self.source {
            ui.separator();
            if explorer.look_ui(ui) {
                self.rebuild_explorer();
            }
        }
        if let Some(picked) = &self.picked {
            ui.separator();
            match picked {
                Some(p) => ui.label(format!(
                    "object {}: {}\nmaterial {}\ndistance {:.4}",
                    p.id, p.kind, p.material, p.distance
                )),
                None => ui.label("background"),
            };
        }
    }

    /// Yaw, pitch and distance sliders, and the scene camera button.
    fn camera_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Camera");
        let before = self.orbit;
        let reference = self
            .shown
            .as_ref()
            .map_or(5.0, |s| s.camera.from.distance(s.camera.to).max(1e-9));
        ui.add(egui::Slider::new(&mut self.orbit.yaw, -180.0..=180.0).text("yaw"));
        ui.add(egui::Slider::new(&mut self.orbit.pitch, -89.5..=89.5).text("pitch"));
        ui.add(
            egui::Slider::new(
                &mut self.orbit.distance,
                reference * 0.05..=reference * 20.0,
            )
            .logarithmic(true)
            .text("distance"),
        );
        if ui.button("Scene camera (Home)").clicked() {
            self.restore_camera();
        } else if self.orbit != before {
            self.rebuild_explorer();
        }
    }

    /// Open and Explorer, Render (with its output and progress), Sample, Save view, Quit.
    pub(super) fn buttons(&mut self, ui: &mut egui::Ui) {
        // Short enough for the panel's width: the drop hint is the button's tooltip.
        ui.horizontal(|ui| {
            let open = ui.button("Open…").on_hover_text(
                "Open a scene file (.toml, .obj, .gltf, .glb), or drop one on the window",
            );
            if open.clicked() {
                self.show_open_dialog();
            }
            if let Source::File(_) = self.source
                && ui.button("Explorer").clicked()
            {
                self.show_explorer();
            }
        });
        ui.horizontal(|ui| {
            let label = ui.label("output");
            let field = ui
                .text_edit_singleline(&mut self.output)
                .labelled_by(label.id);
            if field.changed() {
                self.output_edited = true;
            }
        });
        ui.horizontal(|ui| {
            let idle = self.final_render.is_none();
            if ui.add_enabled(idle, egui::Button::new("Render")).clicked() {
                self.start_final_render();
            }
            if let Source::Explorer(_) = self.source
                && ui.button("Sample").clicked()
            {
                self.sample();
            }
            if ui.button("Save view").clicked() {
                self.saved_view = Some(self.orbit.toml());
            }
            if ui.button("Quit").clicked() {
                ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
            }
        });
        if let Some(render) = &self.final_render {
            ui.add(egui::ProgressBar::new(render.fraction()).show_percentage());
            ui.label(format!("rendering {}", render.output().display()));
            // The bar moves with the render's rows, which wake the UI; this catches the last one.
            ui.ctx().request_repaint_after(Duration::from_millis(250));
        }
        if let Some(message) = &self.message {
            ui.label(message);
        }
    }

    /// The current view as a `[camera]` table to paste into a scene, with a copy button.
    pub(super) fn saved_view_window(&mut self, ctx: &egui::Context, text: String) {
        let mut open = true;
        egui::Window::new("Save view")
            .open(&mut open)
            .show(ctx, |ui| {
                ui.label("Paste into a scene file in place of its [camera] table:");
                ui.code(&text);
                if ui.button("Copy").clicked() {
                    ui.ctx().copy_text(text.clone());
                }
            });
        if !open {
            self.saved_view = None;
        }
    }
}
