//! The Render button: a full-quality render of the current view at the scene's output resolution
//! and sampling, in the background with its progress, written by the CLI's writer (atomically, to
//! PNG or EXR by the extension).

use anyhow::{Context, Result};
use quadray::{Progress, RenderSettings, Scene};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};

/// A render under way, and its result once written.
pub struct FinalRender {
    rows: Arc<RowCounter>,
    result: Receiver<Result<PathBuf>>,
    output: PathBuf,
}

/// Counts finished rows and wakes the UI each time the percentage moves.
struct RowCounter {
    done: AtomicU32,
    total: u32,
    notify: Box<dyn Fn() + Send + Sync>,
}

impl Progress for RowCounter {
    fn row_done(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if done * 100 / self.total.max(1) != (done - 1) * 100 / self.total.max(1) {
            (self.notify)();
        }
    }
}

impl FinalRender {
    /// Starts rendering `scene` with `settings` (camera included) into `output`. The output is
    /// checked first (a known extension, an existing folder), so a bad name fails at once.
    pub fn start(
        scene: Arc<Scene>,
        settings: RenderSettings,
        output: PathBuf,
        notify: impl Fn() + Send + Sync + Clone + 'static,
    ) -> Result<FinalRender> {
        quadray_app::output::check_writable(&output)?;
        settings.validate()?;
        let rows = Arc::new(RowCounter {
            done: AtomicU32::new(0),
            total: settings.window().height(),
            notify: Box::new(notify.clone()),
        });
        let (send, result) = channel();
        {
            let (rows, output) = (rows.clone(), output.clone());
            std::thread::spawn(move || {
                let written = render_and_write(&scene, &settings, &output, &*rows);
                let _ = send.send(written.map(|()| output));
                notify();
            });
        }
        Ok(FinalRender {
            rows,
            result,
            output,
        })
    }

    /// The file being written.
    pub fn output(&self) -> &Path {
        &self.output
    }

    /// How far the render is, from 0 to 1 (adaptive sampling's later rounds count again).
    pub fn fraction(&self) -> f32 {
        (self.rows.done.load(Ordering::Relaxed) as f32 / self.rows.total.max(1) as f32).min(1.0)
    }

    /// The written file or the error, once finished.
    pub fn finished(&mut self) -> Option<Result<PathBuf>> {
        match self.result.try_recv() {
            Ok(result) => Some(result),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(anyhow::anyhow!(
                "the render of {} stopped without a result",
                self.output.display()
            ))),
        }
    }
}

fn render_and_write(
    scene: &Scene,
    settings: &RenderSettings,
    output: &Path,
    progress: &dyn Progress,
) -> Result<()> {
    let rendered = quadray::render(scene, settings, progress)
        .with_context(|| format!("rendering {}", output.display()))?;
    quadray_app::output::write_film(&rendered.film, output)
}
