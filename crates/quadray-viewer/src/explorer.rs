//! The quadric explorer: the original program's panel. One clipped quadric of a chosen kind (or a
//! general one), its parameters, clip box, texture, lighting and reflectivity, in the studio
//! `quadray quadric` and `quadray gallery` use.

use crate::orbit::Orbit;
use anyhow::{Result, anyhow, ensure};
use eframe::egui;
use glam::DVec3;
use quadray::{
    ClipBox, Coefficients, QuadricKind, QuadricSurface, SceneDescription, Texture, Transform,
};
use quadray_app::showcase::{CHECKER_EVEN, CHECKER_ODD, TextureChoice};
use quadray_app::showcase::{GENERAL, Showcase};

/// The surface kinds the explorer offers: the nine named ones and the general quadric.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A canonical kind with parameters a, b, c.
    Named(QuadricKind),
    /// The 10-coefficient general quadric.
    General,
}

impl Kind {
    /// Every kind, in the seed's order.
    pub fn all() -> impl Iterator<Item = Kind> {
        QuadricKind::ALL
            .into_iter()
            .map(Kind::Named)
            .chain([Kind::General])
    }

    /// The kind's name as the CLI spells it.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Named(kind) => kind.name(),
            Kind::General => "general",
        }
    }
}

/// The surface textures, with the parameter each one has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureKind {
    /// The height ramp blue → green → yellow.
    Ramp,
    /// The ramp in flat contour bands.
    Bands,
    /// A 3-D checkerboard.
    Checker,
    /// One plain colour.
    Constant,
}

/// Everything the explorer's panel sets (the camera is the viewer's [`Orbit`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Explorer {
    /// The surface kind.
    pub kind: Kind,
    /// Semi-axis parameters of the named kinds.
    pub abc: [f64; 3],
    /// Coefficients A..J of the general kind (POV-Ray's order).
    pub coefficients: [f64; 10],
    /// Half-size R of the clip cube.
    pub clip_radius: f64,
    /// Clip with the box [`Explorer::box_min`]..[`Explorer::box_max`] instead of the cube.
    pub min_max_box: bool,
    /// Lower corner of the clip box.
    pub box_min: [f64; 3],
    /// Upper corner of the clip box.
    pub box_max: [f64; 3],
    /// The texture.
    pub texture: TextureKind,
    /// Number of bands of [`TextureKind::Bands`].
    pub bands: u32,
    /// Cube size of [`TextureKind::Checker`].
    pub checker_size: f64,
    /// Lit and shaded, or flat texture colours.
    pub lighting: bool,
    /// Mirror reflectivity of the surface.
    pub reflectivity: f32,
}

impl Default for Explorer {
    fn default() -> Self {
        let mut explorer = Explorer {
            kind: Kind::Named(QuadricKind::Hyperboloid1),
            abc: [1.0; 3],
            coefficients: GENERAL.0,
            clip_radius: 1.0,
            min_max_box: false,
            box_min: [-1.0; 3],
            box_max: [1.0; 3],
            texture: TextureKind::Ramp,
            bands: 8,
            checker_size: 0.25,
            lighting: true,
            reflectivity: 0.0,
        };
        explorer.textbook_parameters();
        explorer
    }
}

impl Explorer {
    /// The textbook showcase of the current kind (parameters and view as `quadray gallery`
    /// draws it).
    pub fn textbook(&self) -> Showcase {
        match self.kind {
            Kind::Named(kind) => Showcase::of(kind),
            Kind::General => Showcase::general(GENERAL),
        }
    }

    /// Resets the surface parameters and clip cube to the kind's textbook ones.
    pub fn textbook_parameters(&mut self) {
        let show = self.textbook();
        match show.surface {
            QuadricSurface::Canonical { a, b, c, .. } => self.abc = [a, b, c],
            QuadricSurface::General(k) => self.coefficients = k.0,
        }
        self.clip_radius = show.clip;
        self.min_max_box = false;
    }

    /// The kind's textbook view.
    pub fn textbook_view(&self) -> Orbit {
        Orbit::from_camera(&self.textbook().camera())
    }

    /// The showcase of the current settings seen from `orbit`.
    pub fn showcase(&self, orbit: &Orbit) -> Showcase {
        let [a, b, c] = self.abc;
        Showcase {
            surface: match self.kind {
                Kind::Named(kind) => QuadricSurface::Canonical { kind, a, b, c },
                Kind::General => QuadricSurface::General(Coefficients(self.coefficients)),
            },
            clip: self.clip_radius,
            yaw: orbit.yaw,
            pitch: orbit.pitch,
            distance: orbit.distance,
        }
    }

    /// The core texture of the current choice.
    pub fn core_texture(&self) -> Texture {
        match self.texture {
            TextureKind::Ramp => Texture::HeightRamp,
            TextureKind::Bands => Texture::Bands { steps: self.bands },
            TextureKind::Checker => Texture::Checker {
                size: self.checker_size,
                even: CHECKER_EVEN,
                odd: CHECKER_ODD,
            },
            TextureKind::Constant => TextureChoice::None.texture(),
        }
    }

    /// The scene: the quadric with the chosen texture and box, lit by the studio lights turned
    /// with the view, seen from `orbit`.
    pub fn scene(&self, orbit: &Orbit) -> Result<SceneDescription> {
        let show = self.showcase(orbit);
        let mut scene = show.scene(self.core_texture(), self.lighting)?;
        if self.min_max_box {
            let (min, max) = (DVec3::from(self.box_min), DVec3::from(self.box_max));
            ensure!(
                min.cmplt(max).all(),
                "the clip box's min {min} must be below its max {max} on every axis"
            );
            let quadric =
                quadray::Quadric::new(show.surface, ClipBox { min, max }, Transform::IDENTITY, 0)
                    .map_err(|e| anyhow!("{} quadric: {e}", show.name()))?;
            ensure!(
                quadric.is_visible(),
                "the {} quadric does not reach into the clip box {min}..{max}: nothing would show",
                show.name()
            );
            scene.geometry.quadrics = vec![quadric];
        }
        scene.materials[0].reflectivity = self.reflectivity;
        scene.camera = orbit.camera();
        Ok(scene)
    }

    /// The output file the Render button suggests: `quadric-KIND.png` in the viewer's outputs
    /// folder, `renders/` (which git ignores).
    pub fn output_name(&self) -> String {
        format!(
            "{}/quadric-{}.png",
            crate::app::OUTPUT_FOLDER,
            self.kind.name()
        )
    }

    /// The upper half of the panel, what is changed most: the kind (two columns of radio
    /// buttons), its equation and parameters; returns whether anything changed (a new kind also
    /// resets the parameters to its textbook ones).
    pub fn surface_ui(&mut self, ui: &mut egui::Ui) -> bool {
        let before = self.clone();
        ui.heading("Quadric");
        let mut kind = self.kind;
        egui::Grid::new("kinds").num_columns(2).show(ui, |ui| {
            for (i, k) in Kind::all().enumerate() {
                ui.radio_value(&mut kind, k, k.name());
                if i % 2 == 1 {
                    ui.end_row();
                }
            }
        });
        if kind != self.kind {
            self.kind = kind;
            self.textbook_parameters();
        }
        ui.label(egui::RichText::new(self.textbook().equation()).monospace());
        ui.separator();
        match self.kind {
            Kind::Named(_) => {
                for (name, value) in ["a", "b", "c"].iter().zip(&mut self.abc) {
                    ui.add(
                        egui::Slider::new(value, 0.05..=3.0)
                            .logarithmic(true)
                            .text(*name),
                    );
                }
            }
            Kind::General => {
                ui.label(quadray_app::showcase::GENERAL_EQUATION);
                egui::Grid::new("coefficients")
                    .num_columns(2)
                    .show(ui, |ui| {
                        for (i, k) in self.coefficients.iter_mut().enumerate() {
                            let name = format!("{} ", (b'A' + i as u8) as char);
                            ui.add(egui::DragValue::new(k).speed(0.01).prefix(name));
                            if i % 2 == 1 {
                                ui.end_row();
                            }
                        }
                    });
            }
        }
        *self != before
    }

    /// The lower half of the panel: clip box, texture, lighting, reflectivity; returns whether
    /// anything changed.
    pub fn look_ui(&mut self, ui: &mut egui::Ui) -> bool {
        let before = self.clone();
        ui.heading("Clip box and look");
        ui.add_enabled(
            !self.min_max_box,
            egui::Slider::new(&mut self.clip_radius, 0.1..=5.0)
                .logarithmic(true)
                .text("clip"),
        );
        ui.checkbox(&mut self.min_max_box, "min/max box");
        if self.min_max_box {
            egui::Grid::new("clip box").num_columns(3).show(ui, |ui| {
                for (label, corner) in [("min", &mut self.box_min), ("max", &mut self.box_max)] {
                    for (axis, v) in ["x", "y", "z"].iter().zip(corner.iter_mut()) {
                        let name = format!("{axis} {label} ");
                        ui.add(egui::DragValue::new(v).speed(0.02).prefix(name));
                    }
                    ui.end_row();
                }
            });
        }
        ui.separator();
        ui.horizontal_wrapped(|ui| {
            for (kind, name) in [
                (TextureKind::Ramp, "ramp"),
                (TextureKind::Bands, "bands"),
                (TextureKind::Checker, "checker"),
                (TextureKind::Constant, "constant"),
            ] {
                ui.radio_value(&mut self.texture, kind, name);
            }
        });
        match self.texture {
            TextureKind::Bands => {
                ui.add(egui::Slider::new(&mut self.bands, 2..=32).text("bands"));
            }
            TextureKind::Checker => {
                ui.add(
                    egui::Slider::new(&mut self.checker_size, 0.02..=1.0)
                        .logarithmic(true)
                        .text("checker size"),
                );
            }
            _ => {}
        }
        ui.checkbox(&mut self.lighting, "lighting");
        ui.add(egui::Slider::new(&mut self.reflectivity, 0.0..=1.0).text("reflectivity"));
        *self != before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_textbook_scene_is_the_gallery_tile() {
        for kind in Kind::all() {
            let explorer = Explorer {
                kind,
                ..Explorer::default()
            };
            let mut explorer = explorer;
            explorer.textbook_parameters();
            let view = explorer.textbook_view();
            let scene = explorer.scene(&view).unwrap();
            let tile = explorer
                .textbook()
                .scene(Texture::HeightRamp, true)
                .unwrap();
            assert_eq!(scene.geometry.quadrics, tile.geometry.quadrics, "{kind:?}");
            assert!(
                scene.camera.from.distance(tile.camera.from) < 1e-9,
                "{kind:?}"
            );
        }
    }

    #[test]
    fn a_box_missing_the_surface_or_inside_out_is_an_error() {
        let mut explorer = Explorer {
            min_max_box: true,
            box_min: [5.0, 5.0, 5.0],
            box_max: [6.0, 6.0, 6.0],
            kind: Kind::Named(QuadricKind::Ellipsoid),
            ..Explorer::default()
        };
        let view = explorer.textbook_view();
        let err = explorer.scene(&view).unwrap_err().to_string();
        assert!(err.contains("does not reach into the clip box"), "{err}");
        explorer.box_max = [4.0, 7.0, 7.0];
        let err = explorer.scene(&view).unwrap_err().to_string();
        assert!(err.contains("must be below"), "{err}");
        explorer.box_min = [-0.5; 3];
        explorer.box_max = [0.5, 0.5, 1.0];
        assert!(explorer.scene(&view).is_ok());
    }
}
