//! `quadray-view [SCENE]`: opens a scene file in the viewer, or the quadric explorer.

use anyhow::{Context, Result};
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

/// The interactive quadray viewer.
#[derive(Parser, Debug)]
#[command(name = "quadray-view", version, about)]
struct Args {
    /// A scene file (.toml, .obj, .gltf, .glb); without one, the quadric explorer opens.
    scene: Option<PathBuf>,
    /// Render threads (default: one per core).
    #[arg(short, long, value_name = "N", default_value_t = 0)]
    threads: usize,
    /// Log what the viewer does (-vv: more).
    #[arg(short, long, action = clap::ArgAction::Count)]
    verbose: u8,
}

fn run(args: Args) -> Result<()> {
    if let Some(scene) = &args.scene {
        // A missing file is an error before any window opens; a broken one shows in the window.
        anyhow::ensure!(scene.is_file(), "no scene file at {}", scene.display());
    }
    let viewer = quadray_viewer::Viewer::new(args.scene.clone(), args.threads)
        .context("starting the render thread")?;
    // The viewer sets the title to what it shows.
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_title("quadray-view")
            .with_inner_size([1000.0, 600.0]),
        ..Default::default()
    };
    eframe::run_native(
        "quadray-view",
        options,
        Box::new(|_| Ok(Box::new(App(viewer)))),
    )
    .map_err(|e| anyhow::anyhow!("the window could not open: {e}"))
}

/// The viewer as an eframe application.
struct App(quadray_viewer::Viewer);

impl eframe::App for App {
    fn ui(&mut self, ui: &mut eframe::egui::Ui, _frame: &mut eframe::Frame) {
        self.0.ui(ui);
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    quadray_app::logging::init(quadray_app::logging::level(args.verbose));
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
