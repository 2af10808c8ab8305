//! The render worker: one thread that turns the latest view request into frames, first a quick
//! low-resolution preview, then full-resolution frames refined sample by sample, and drops work
//! the moment a newer request arrives. The UI thread only posts requests and picks up frames.

use quadray::{Progress, ProgressiveFilm, RenderError, RenderSettings, Scene};
use quadray_app::passes::{Pass, pass_rgb8};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Time a preview should take: short enough that the view follows a drag within a display frame
/// or two.
const PREVIEW_BUDGET: Duration = Duration::from_millis(20);
/// Largest preview reduction per axis.
const MAX_PREVIEW_SCALE: u32 = 8;

/// What to show: a scene through a camera at a resolution, refined to a sample count.
#[derive(Clone)]
pub struct Request {
    /// The scene (shared with the UI, which picks objects in it).
    pub scene: Arc<Scene>,
    /// The view: its full resolution, its camera ([`RenderSettings::camera`]), the samples per
    /// pixel to refine to, and the scene's recursion limits. Crop and adaptive sampling are not
    /// used.
    pub settings: RenderSettings,
    /// The pass shown.
    pub pass: Pass,
    /// Whether the view is moving: show a reduced 1-sample preview before refining.
    pub preview: bool,
}

/// One image of a request, ready for the screen.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Which request it belongs to ([`Worker::request`]'s number).
    pub generation: u64,
    /// Width in pixels (smaller than the request's for a preview).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// 8-bit sRGB RGBA pixels, row by row from the top.
    pub rgba: Vec<u8>,
    /// Samples per pixel reached.
    pub spp: u32,
    /// Whether this is the last frame of its request.
    pub done: bool,
    /// Whether this is a reduced preview.
    pub preview: bool,
    /// Millions of rays per second over the request's full-resolution steps so far.
    pub mrays_per_s: f64,
    /// The estimated RMSE of the image's display values ([`ProgressiveFilm::estimated_error`]), from
    /// 8 spp.
    pub error: Option<f64>,
    /// Time from the worker taking up the request to this frame.
    pub latency: Duration,
}

/// State shared by the UI side and the worker thread.
struct Shared {
    /// The newest request not yet taken, with its number.
    pending: Mutex<Option<(u64, Request)>>,
    wake: Condvar,
    /// The number of the newest request: work on any other is stale.
    generation: AtomicU64,
    /// Whether the request being worked on has frames still to come.
    busy: AtomicBool,
    /// The newest request that failed, with why, for the window to show.
    failure: Mutex<Option<(u64, String)>>,
    quit: AtomicBool,
}

/// The worker thread and the frames it sends.
pub struct Worker {
    shared: Arc<Shared>,
    frames: Receiver<Frame>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the worker with a rayon pool of `threads` threads (0: one per core); `notify` is
    /// called after every frame sent (to wake the UI).
    pub fn spawn(threads: usize, notify: impl Fn() + Send + 'static) -> std::io::Result<Worker> {
        let shared = Arc::new(Shared {
            pending: Mutex::new(None),
            wake: Condvar::new(),
            generation: AtomicU64::new(0),
            busy: AtomicBool::new(false),
            failure: Mutex::new(None),
            quit: AtomicBool::new(false),
        });
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("quadray-view render {i}"))
            .build()
            .map_err(std::io::Error::other)?;
        let (send, frames) = channel();
        let thread = {
            let shared = shared.clone();
            std::thread::Builder::new()
                .name("quadray-view worker".into())
                .spawn(move || {
                    let looper = Looper {
                        shared,
                        send,
                        notify: Box::new(notify),
                        preview_scale: Cell::new(2),
                    };
                    pool.install(move || looper.run());
                })?
        };
        Ok(Worker {
            shared,
            frames,
            thread: Some(thread),
        })
    }

    /// Replaces whatever is being rendered with `request`; returns its number.
    pub fn request(&self, request: Request) -> u64 {
        let generation = self.shared.generation.fetch_add(1, Ordering::SeqCst) + 1;
        self.shared.busy.store(true, Ordering::SeqCst);
        *lock(&self.shared.pending) = Some((generation, request));
        self.shared.wake.notify_one();
        generation
    }

    /// The newest frame sent since the last call, if any (older ones are dropped).
    pub fn latest_frame(&self) -> Option<Frame> {
        self.frames.try_iter().last()
    }

    /// Makes every request so far stale without posting a new one (the scene shown is being
    /// replaced): their frames and failures are not shown. Returns the new number.
    pub fn cancel(&self) -> u64 {
        let generation = self.shared.generation.fetch_add(1, Ordering::SeqCst) + 1;
        *lock(&self.shared.pending) = None;
        generation
    }

    /// Why a request failed, with its number, once (the window shows it; `quadray render`
    /// would have printed the same).
    pub fn failure(&self) -> Option<(u64, String)> {
        lock(&self.shared.failure).take()
    }

    /// Whether frames of the newest request are still to come.
    pub fn busy(&self) -> bool {
        self.shared.busy.load(Ordering::SeqCst)
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.shared.quit.store(true, Ordering::SeqCst);
        self.shared.generation.fetch_add(1, Ordering::SeqCst);
        self.shared.wake.notify_one();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// Locks a mutex, carrying on with the data if another thread panicked while holding it.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

/// Cancels a render as soon as a newer request exists or the worker quits.
struct Staleness<'a> {
    shared: &'a Shared,
    generation: u64,
}

impl Progress for Staleness<'_> {
    fn row_done(&self) {}

    fn cancelled(&self) -> bool {
        self.shared.generation.load(Ordering::Relaxed) != self.generation
            || self.shared.quit.load(Ordering::Relaxed)
    }
}

/// The worker thread's side.
struct Looper {
    shared: Arc<Shared>,
    send: Sender<Frame>,
    notify: Box<dyn Fn() + Send>,
    /// Current preview reduction per axis, tuned so previews fit [`PREVIEW_BUDGET`].
    preview_scale: Cell<u32>,
}

impl Looper {
    fn run(&self) {
        loop {
            let (generation, request) = {
                let mut pending = lock(&self.shared.pending);
                loop {
                    if self.shared.quit.load(Ordering::SeqCst) {
                        return;
                    }
                    if let Some(next) = pending.take() {
                        break next;
                    }
                    pending = self
                        .shared
                        .wake
                        .wait(pending)
                        .unwrap_or_else(|e| e.into_inner());
                }
            };
            let stale = Staleness {
                shared: &self.shared,
                generation,
            };
            let result = self.serve(&request, generation, &stale);
            if !stale.cancelled() {
                if let Err(e) = result {
                    log::error!("rendering the view failed: {e:#}");
                    *lock(&self.shared.failure) =
                        Some((generation, format!("error: rendering the view: {e:#}")));
                }
                self.shared.busy.store(false, Ordering::SeqCst);
                (self.notify)();
            }
        }
    }

    /// Sends the request's frames until it is done or stale.
    fn serve(&self, request: &Request, generation: u64, stale: &Staleness) -> anyhow::Result<()> {
        let started = Instant::now();
        let send = |frame: Frame| {
            let _ = self.send.send(frame);
            (self.notify)();
        };
        let frame = |width: u32, height: u32, rgb: &[u8]| Frame {
            generation,
            width,
            height,
            rgba: rgb
                .chunks_exact(3)
                .flat_map(|p| [p[0], p[1], p[2], 255])
                .collect(),
            spp: 1,
            done: false,
            preview: false,
            mrays_per_s: 0.0,
            error: None,
            latency: started.elapsed(),
        };
        let (width, height, target) = (
            request.settings.width,
            request.settings.height,
            request.settings.spp,
        );
        let settings = RenderSettings {
            adaptive: None,
            antialias: None,
            crop: None,
            spp: 1,
            ..request.settings
        };
        if request.pass != Pass::Combined {
            // Passes come from each pixel's first hit: one sample is the whole pass.
            let pass_start = Instant::now();
            let (rendered, aovs) = quadray::render_with_aovs(
                &request.scene,
                &settings,
                request.pass.selection(),
                stale,
            )?;
            let planes = request.scene.geometry().plane_object_indices();
            let rgb = pass_rgb8(request.pass, &rendered.film, aovs.as_ref(), &planes)?;
            let seconds = pass_start.elapsed().as_secs_f64().max(1e-9);
            send(Frame {
                done: true,
                mrays_per_s: rendered.counts.total() as f64 / seconds / 1e6,
                ..frame(width, height, &rgb)
            });
            return Ok(());
        }
        if request.preview {
            self.preview(&request.scene, &settings, stale, &send, &frame)?;
        }
        let mut film = ProgressiveFilm::new(settings)?;
        let mut rays = 0u64;
        let refine_start = Instant::now();
        for count in refinement_steps(target) {
            rays += film.refine(&request.scene, count, stale)?.total();
            let seconds = refine_start.elapsed().as_secs_f64().max(1e-9);
            send(Frame {
                spp: count,
                done: count == target,
                mrays_per_s: rays as f64 / seconds / 1e6,
                error: film.estimated_error(),
                ..frame(width, height, &film.film().to_srgb8())
            });
        }
        Ok(())
    }

    /// Renders and sends the 1-sample preview at reduced resolution, adjusting the reduction so
    /// the next preview fits the budget.
    fn preview(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        stale: &Staleness,
        send: &dyn Fn(Frame),
        frame: &dyn Fn(u32, u32, &[u8]) -> Frame,
    ) -> Result<(), RenderError> {
        let scale = self.preview_scale.get();
        let (width, height) = (
            settings.width.div_ceil(scale).max(1),
            settings.height.div_ceil(scale).max(1),
        );
        let started = Instant::now();
        let mut film = ProgressiveFilm::new(RenderSettings {
            width,
            height,
            ..*settings
        })?;
        film.refine(scene, 1, stale)?;
        let took = started.elapsed();
        // Halve or double the pixel count (√2 per axis, rounded) to stay inside the budget.
        if took > PREVIEW_BUDGET && scale < MAX_PREVIEW_SCALE {
            self.preview_scale.set(scale + 1);
        } else if took * 3 < PREVIEW_BUDGET && scale > 1 {
            self.preview_scale.set(scale - 1);
        }
        send(Frame {
            preview: true,
            ..frame(width, height, &film.film().to_srgb8())
        });
        Ok(())
    }
}

/// The sample counts a frame is shown at on its way to `spp`: 1, 2, 4, ... and `spp` itself.
pub fn refinement_steps(spp: u32) -> impl Iterator<Item = u32> {
    let spp = spp.max(1);
    std::iter::successors(Some(1u32), move |&n| (n < spp).then(|| (n * 2).min(spp)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refinement_doubles_up_to_the_target() {
        assert_eq!(refinement_steps(1).collect::<Vec<_>>(), [1]);
        assert_eq!(refinement_steps(16).collect::<Vec<_>>(), [1, 2, 4, 8, 16]);
        assert_eq!(refinement_steps(12).collect::<Vec<_>>(), [1, 2, 4, 8, 12]);
    }
}
