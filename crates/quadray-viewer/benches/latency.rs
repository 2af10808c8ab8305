//! The viewer's targets, measured on its worker thread (what the window waits for):
//! - preview latency: from a view change (a yaw step, as a drag makes) to the preview frame, on
//!   the defense scene at 640x360 with 2 threads;
//! - refinement: from a change to the 16-spp frame of the explorer's quadric at 640x360.
//!
//! `cargo bench -p quadray-viewer --bench latency`; medians and maxima over the runs.

use quadray::{RenderSettings, Scene};
use quadray_app::passes::Pass;
use quadray_viewer::explorer::Explorer;
use quadray_viewer::orbit::Orbit;
use quadray_viewer::worker::{Request, Worker};
use std::sync::Arc;
use std::time::{Duration, Instant};

const THREADS: usize = 2;
const SIZE: (u32, u32) = (640, 360);

/// Posts `request` and waits for its first frame matching `wanted`; returns the time taken.
fn time_to(
    worker: &Worker,
    request: Request,
    wanted: impl Fn(&quadray_viewer::worker::Frame) -> bool,
) -> Duration {
    let start = Instant::now();
    let generation = worker.request(request);
    loop {
        if let Some(frame) = worker.latest_frame()
            && frame.generation == generation
            && wanted(&frame)
        {
            return start.elapsed();
        }
        std::thread::sleep(Duration::from_micros(200));
    }
}

fn summary(name: &str, mut times: Vec<Duration>) {
    times.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    println!(
        "{name}: median {:.1} ms, max {:.1} ms over {} runs",
        ms(times[times.len() / 2]),
        ms(*times.last().unwrap()),
        times.len()
    );
}

fn main() {
    let worker = Worker::spawn(THREADS, || {}).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let loaded = quadray_viewer::source::load(&root.join("scenes/defense.toml")).unwrap();
    let mut orbit = Orbit::from_camera(loaded.scene.camera());
    let request = |scene: &Arc<Scene>, orbit: &Orbit, spp: u32, settings: RenderSettings| Request {
        scene: scene.clone(),
        settings: RenderSettings {
            width: SIZE.0,
            height: SIZE.1,
            spp,
            camera: Some(orbit.camera()),
            ..settings
        },
        pass: Pass::Combined,
        preview: true,
    };
    // A drag: 60 yaw steps, each answered by a preview before the next (warm-up: the first 10).
    let mut previews = Vec::new();
    for step in 0..70 {
        orbit.drag(4.0, 0.0);
        let r = request(&loaded.scene, &orbit, loaded.settings.spp, loaded.settings);
        let t = time_to(&worker, r, |f| f.preview);
        if step >= 10 {
            previews.push(t);
        }
    }
    summary("defense 640x360, preview after a view change", previews);

    let explorer = Explorer::default();
    let mut orbit = explorer.textbook_view();
    let mut refined = Vec::new();
    for step in 0..12 {
        orbit.drag(10.0, 0.0);
        let scene = Arc::new(Scene::new(explorer.scene(&orbit).unwrap()).unwrap());
        let settings = RenderSettings {
            spp: 16,
            ..RenderSettings::default()
        };
        let t = time_to(&worker, request(&scene, &orbit, 16, settings), |f| f.done);
        if step >= 2 {
            refined.push(t);
        }
    }
    summary(
        "explorer quadric 640x360, refined to 16 spp after a change",
        refined,
    );
}
