//! `quadray bench images`: render time against image error. A scene (by default
//! `scenes/defense.toml`) is rendered at every power of two of uniform samples up to the largest
//! asked, at image-error targets, per-pixel error targets, time limits, previews (the
//! per-pixel rule from a first round of [`PREVIEW_MIN_SPP`] samples) and anti-aliasing by
//! contrast (from one sample a pixel, as POV-Ray's first pass), and compared with a
//! high-sample reference by [`crate::compare`] (RMSE in linear space and of the 8-bit display
//! image, FLIP on the display images); with `--povray`, the same scene's POV-Ray file is
//! rendered at several anti-aliasing settings and compared with POV-Ray's own converged image,
//! each renderer against its own reference since their shading differs slightly. The report is a
//! markdown table and a log–log SVG plot of CPU time against display RMSE. The race between them
//! interpolates nothing: the time to reach an error is that of the cheapest measured render at
//! or below it.
//!
//! The reference is rendered with another sample set ([`REFERENCE_SEED`]): the renderer's
//! per-pixel patterns are deterministic, so with the same seed its samples could share structure
//! with the test renders' and hide part of their error. Its own error is estimated from a second,
//! independent reference ([`CHECK_SEED`]): for two independent estimates of the same image the
//! RMSE between them is √2 times the RMSE of either against the truth.

use crate::args::parse_resolution;
use crate::compare::{Comparison, LinearImage, Thresholds, compare};
use crate::output::{write_bytes_atomically, write_rgb8_png};
use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use quadray::adaptive::ErrorRule;
use quadray::{
    Adaptive, Antialias, Film, NoProgress, RayCounts, RenderSettings, SamplingStats, Scene, render,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod povray;
mod report;

/// First-round samples of the preview rows.
pub const PREVIEW_MIN_SPP: u32 = 2;

/// POV-Ray's reference is rendered at this many times the resolution on each side and averaged
/// down: with `+R4`, 16 × 16 jittered samples in every pixel. POV-Ray's `+R8` at the resolution
/// itself (8 × 8) measured 4.4e-3 display RMSE from a converged image on the reflective scene,
/// above most of the errors it is meant to judge.
pub const POV_REFERENCE_SCALE: u32 = 4;
/// The second POV-Ray reference, at this many times the resolution: its samples fall elsewhere
/// in every pixel, so the RMSE between the two, over √2, estimates their own error.
pub const POV_CHECK_SCALE: u32 = 5;

/// Sample set of the test renders: the renderer's default.
pub const TEST_SEED: u32 = 0;
/// Sample set of the reference render.
pub const REFERENCE_SEED: u32 = 1;
/// Sample set of the second reference that estimates the first one's own error.
pub const CHECK_SEED: u32 = 2;

/// Arguments of `quadray bench images`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct ImagesArgs {
    /// The scene to render.
    #[arg(long, value_name = "FILE", default_value = "scenes/defense.toml")]
    pub scene: PathBuf,
    /// Directory for image-error.md, image-error.svg and image-error-reference.png; created if missing.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// Resolution of every render (default: a quarter of 1280x720 per side, so the reference fits
    /// in minutes on two cores).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, default_value = "480x270")]
    pub res: (u32, u32),
    /// Sample counts of the test renders, comma-separated, increasing.
    #[arg(
        long,
        value_name = "N,N,...",
        value_delimiter = ',',
        default_value = "1,2,4,8,16,32,64"
    )]
    pub spp: Vec<u32>,
    /// Image-error targets of the test renders (`--target-error`), comma-separated (none:
    /// `--adaptive` with no value).
    #[arg(
        long,
        value_name = "E,E,...",
        value_delimiter = ',',
        num_args = 0..,
        default_value = "0.016,0.008,0.004,0.002,0.001,0.0005"
    )]
    pub adaptive: Vec<f64>,
    /// Per-pixel error targets of the test renders (`--pixel-error`), comma-separated (none:
    /// `--pixel` with no value).
    #[arg(
        long,
        value_name = "E,E,...",
        value_delimiter = ',',
        num_args = 0..,
        default_value = "0.16,0.08,0.04,0.02,0.01"
    )]
    pub pixel: Vec<f64>,
    /// Time limits of the test renders in seconds (`--time-limit`, no target), comma-separated
    /// (none: `--time-limit` with no value).
    #[arg(
        long,
        value_name = "S,S,...",
        value_delimiter = ',',
        num_args = 0..,
        default_value = "0.1,0.2,0.4,0.8,1.6"
    )]
    pub time_limit: Vec<f64>,
    /// Per-pixel error targets rendered as previews, from a first round of 2 samples
    /// (`--pixel-error E --min-spp 2`), comma-separated (none: `--preview` with no
    /// value).
    #[arg(
        long,
        value_name = "E,E,...",
        value_delimiter = ',',
        num_args = 0..,
        default_value = "0.08,0.04,0.02"
    )]
    pub preview: Vec<f64>,
    /// Renders anti-aliased by contrast from one sample a pixel (`--spp 1 --aa-threshold T
    /// --aa-spp N`), as THRESHOLD:SAMPLES pairs, comma-separated (none: `--antialias` with
    /// no value).
    #[arg(
        long,
        value_name = "T:N,T:N,...",
        value_delimiter = ',',
        num_args = 0..,
        value_parser = parse_antialias,
        default_value = "0.2:8,0.1:16,0.1:32,0.05:64,0.02:128"
    )]
    pub antialias: Vec<Antialias>,
    /// Largest samples per pixel of the adaptive renders.
    #[arg(long, value_name = "N", default_value_t = quadray::adaptive::DEFAULT_MAX_SPP)]
    pub max_spp: u32,
    /// First-round samples per pixel of the adaptive renders (a power of two, at least 2;
    /// default: the renderer's, lowered to `--max-spp`).
    #[arg(long, value_name = "N")]
    pub min_spp: Option<u32>,
    /// The scene as a POV-Ray 3.7 file, to race POV-Ray on it (e.g. from scenes/pov/toml2pov.py).
    #[arg(long, value_name = "FILE.pov")]
    pub povray: Option<PathBuf>,
    /// POV-Ray anti-aliasing settings to time, separated by `;`.
    #[arg(
        long,
        value_name = "OPTIONS;...",
        value_delimiter = ';',
        default_value = "-A;+A0.3 +AM1 +R3;+A0.1 +AM1 +R3;+A0.3 +AM2 +R3;+A0.1 +AM2 +R3;+A0.05 +AM2 +R4"
    )]
    pub pov_aa: Vec<String>,
    /// POV-Ray's converged image: supersampling every pixel (threshold 0) on a jittered grid, at
    /// [`POV_REFERENCE_SCALE`] times the resolution and box-filtered down (a second one at
    /// [`POV_CHECK_SCALE`] times estimates its own error).
    #[arg(long, value_name = "OPTIONS", default_value = "+A0.0 +AM1 +R4 +J")]
    pub pov_reference: String,
    /// File name stem of the outputs (STEM.md, STEM.svg, STEM-reference.png).
    #[arg(long, value_name = "STEM", default_value = "image-error")]
    pub name: String,
    /// Samples per pixel of the reference (more than any test render).
    #[arg(long, value_name = "N", default_value_t = 1024)]
    pub reference_spp: u32,
    /// Timed runs of each test render (the median is reported).
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub runs: usize,
    /// Skip the second reference that estimates the reference's own error (halves the time).
    #[arg(long)]
    pub no_reference_check: bool,
    /// Worker threads (default: all cores).
    #[arg(short = 't', long, value_name = "THREADS")]
    pub threads: Option<usize>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// How a test image was made.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// quadray, this many samples in every pixel.
    Uniform(u32),
    /// quadray, adaptive sampling to this image error (`--target-error`).
    Adaptive(f64),
    /// quadray, adaptive sampling to this per-pixel error (`--pixel-error`).
    Pixel(f64),
    /// quadray, adaptive sampling for this many seconds (`--time-limit`).
    TimeLimit(f64),
    /// quadray, adaptive sampling to this per-pixel error from [`PREVIEW_MIN_SPP`] samples.
    Preview(f64),
    /// quadray, anti-aliased by contrast from one sample a pixel.
    Antialias(Antialias),
    /// POV-Ray with these anti-aliasing options.
    PovRay(String),
}

impl Method {
    /// Whether quadray sampled adaptively (to a target, a time limit or as a preview).
    pub fn is_adaptive(&self) -> bool {
        matches!(
            self,
            Method::Adaptive(_) | Method::Pixel(_) | Method::TimeLimit(_) | Method::Preview(_)
        )
    }

    /// A short label for tables and plots.
    pub fn label(&self) -> String {
        match self {
            Method::Uniform(spp) => format!("{spp} spp"),
            Method::Adaptive(e) => format!("target {e}"),
            Method::Pixel(e) => format!("pixel {e}"),
            Method::TimeLimit(t) => format!("time {t} s"),
            Method::Preview(e) => format!("preview {e}"),
            Method::Antialias(aa) => format!("aa {} ({} spp)", aa.threshold, aa.samples(1)),
            Method::PovRay(o) => o.clone(),
        }
    }
}

/// One test image's measurements.
#[derive(Clone, Debug)]
pub struct Row {
    /// How it was made.
    pub method: Method,
    /// Wall-clock render times of every run, seconds, in run order.
    pub wall: Vec<f64>,
    /// CPU times of every run, seconds (quadray: the process during the render; POV-Ray: its
    /// trace phase); empty where the platform does not tell.
    pub cpu: Vec<f64>,
    /// Rays traced by one render (quadray only).
    pub rays: Option<RayCounts>,
    /// Samples per pixel taken (quadray only).
    pub sampling: Option<SamplingStats>,
    /// The image against its renderer's reference.
    pub error: Comparison,
}

impl Row {
    /// Median wall-clock render time, seconds.
    pub fn wall_median(&self) -> f64 {
        median(&self.wall)
    }

    /// Median CPU time, seconds (the wall time where CPU time is unknown).
    pub fn cpu_median(&self) -> f64 {
        if self.cpu.is_empty() {
            self.wall_median()
        } else {
            median(&self.cpu)
        }
    }
}

/// POV-Ray's part of a report.
#[derive(Clone, Debug)]
pub struct PovReport {
    /// The .pov file.
    pub file: PathBuf,
    /// Options of its converged image.
    pub reference_options: String,
    /// CPU seconds of the converged image's trace.
    pub reference_cpu: f64,
    /// The display RMSE between the reference and a second one with other sample positions, if
    /// it was rendered ([`POV_CHECK_SCALE`]).
    pub reference_check: Option<f64>,
    /// One row per anti-aliasing setting.
    pub rows: Vec<Row>,
}

/// The whole image report.
#[derive(Clone, Debug)]
pub struct ImageReport {
    /// The scene file.
    pub scene: PathBuf,
    /// Width and height of every render.
    pub resolution: (u32, u32),
    /// Reference samples per pixel.
    pub reference_spp: u32,
    /// Wall-clock time of the reference render, seconds.
    pub reference_wall: f64,
    /// Rays traced by the reference.
    pub reference_rays: RayCounts,
    /// The second reference against the first, if it was rendered.
    pub reference_check: Option<Comparison>,
    /// Worker threads used.
    pub threads: usize,
    /// Timed runs per test render.
    pub runs: usize,
    /// One row per uniform sample count, increasing, then one per adaptive target, then one per
    /// preview target.
    pub rows: Vec<Row>,
    /// POV-Ray's renders, when asked for.
    pub povray: Option<PovReport>,
    /// The reference image.
    pub reference: LinearImage,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// One timed render: the film, its rays and sampling, wall and CPU seconds.
fn timed_render(
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<(Film, RayCounts, SamplingStats, f64, Option<f64>)> {
    let cpu_start = cpu_time::ProcessTime::try_now().ok();
    let start = Instant::now();
    let rendered = render(scene, settings, &NoProgress)?;
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_start
        .and_then(|t| t.try_elapsed().ok())
        .map(|d| d.as_secs_f64());
    Ok((rendered.film, rendered.counts, rendered.sampling, wall, cpu))
}

/// A THRESHOLD:SAMPLES pair of `--antialias`.
fn parse_antialias(s: &str) -> Result<Antialias, String> {
    let (threshold, spp) =
        (s.split_once(':')).ok_or_else(|| format!("expected THRESHOLD:SAMPLES, got \"{s}\""))?;
    let antialias = Antialias {
        threshold: (threshold.trim().parse())
            .map_err(|_| format!("expected a threshold from 0 to 1, got \"{threshold}\""))?,
        spp: Some(
            (spp.trim().parse()).map_err(|_| format!("expected a sample count, got \"{spp}\""))?,
        ),
    };
    antialias.validate(1).map_err(|e| e.to_string())?;
    Ok(antialias)
}

/// Checks the arguments before any work is done.
fn validate(a: &ImagesArgs) -> Result<()> {
    ensure!(a.runs >= 1, "--runs must be at least 1");
    ensure!(!a.spp.is_empty(), "--spp needs at least one sample count");
    ensure!(
        a.spp.windows(2).all(|w| w[0] < w[1]),
        "--spp must be increasing, got {:?}",
        a.spp
    );
    for (flag, targets) in [
        ("--adaptive", &a.adaptive),
        ("--pixel", &a.pixel),
        ("--time-limit", &a.time_limit),
        ("--preview", &a.preview),
    ] {
        for &target in targets {
            ensure!(
                target.is_finite() && target > 0.0,
                "{flag} targets must be numbers above 0, got {target}"
            );
        }
    }
    if let Some(pov) = &a.povray {
        ensure!(pov.is_file(), "POV-Ray scene {} not found", pov.display());
    }
    ensure!(
        !a.name.is_empty() && !a.name.contains(['/', '\\']),
        "--name must be a plain file name stem, got \"{}\"",
        a.name
    );
    let most = *a.spp.last().unwrap_or(&0);
    ensure!(
        a.reference_spp > most,
        "--reference-spp {} must be more than every test render's ({most})",
        a.reference_spp
    );
    for &spp in a.spp.iter().chain([&a.reference_spp]) {
        RenderSettings {
            width: a.res.0,
            height: a.res.1,
            spp,
            ..RenderSettings::default()
        }
        .validate()?;
    }
    if !a.adaptive.is_empty() {
        adaptive(a, a.adaptive[0]).validate()?;
    }
    if !a.preview.is_empty() {
        pixel(a, a.preview[0])
            .with_min_spp(PREVIEW_MIN_SPP)
            .validate()?;
    }
    for &t in &a.time_limit {
        timed(a, t)?.validate()?;
    }
    Ok(())
}

/// The adaptive settings of a test render with per-pixel `target`.
fn pixel(a: &ImagesArgs, target: f64) -> Adaptive {
    Adaptive {
        rule: ErrorRule::Pixel,
        ..adaptive(a, target)
    }
}

/// The adaptive settings of a test render limited to `seconds`, with no target.
fn timed(a: &ImagesArgs, seconds: f64) -> Result<Adaptive> {
    Ok(Adaptive {
        time_limit: Some(quadray::adaptive::time_limit_from_secs(seconds)?),
        ..adaptive(a, 0.0)
    })
}

/// The adaptive settings of a test render with `target`.
fn adaptive(a: &ImagesArgs, target: f64) -> Adaptive {
    let settings = Adaptive {
        target_error: target,
        ..Adaptive::default()
    }
    .with_max_spp(a.max_spp);
    match a.min_spp {
        Some(min_spp) => settings.with_min_spp(min_spp),
        None => settings,
    }
}

/// Renders one test image `runs` times and compares the last with the reference.
fn test_row(
    scene: &Scene,
    settings: &RenderSettings,
    method: Method,
    runs: usize,
    reference: &LinearImage,
) -> Result<Row> {
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..runs {
        let (film, rays, sampling, w, c) = timed_render(scene, settings)?;
        wall.push(w);
        cpu.extend(c);
        last = Some((film, rays, sampling));
    }
    let Some((film, rays, sampling)) = last else {
        bail!("no run of {}", method.label());
    };
    let error = compare(
        reference,
        &LinearImage::from_film(&film),
        &Thresholds::default(),
    )?;
    Ok(Row {
        method,
        wall,
        cpu,
        rays: Some(rays),
        sampling: Some(sampling),
        error,
    })
}

/// Renders the reference(s) and every test sample count, and compares them.
pub fn measure(a: &ImagesArgs, progress: &mut dyn FnMut(&str)) -> Result<ImageReport> {
    validate(a)?;
    let loaded = quadray_loader::load_any(&a.scene)?;
    let mut base = loaded.settings.render_settings();
    (base.width, base.height) = a.res;
    let scene = Scene::build(loaded.description, loaded.settings.build_options())
        .with_context(|| format!("invalid scene {}", a.scene.display()))?;
    let settings = |spp: u32, seed: u32| RenderSettings { spp, seed, ..base };

    progress(&format!("reference: {} spp", a.reference_spp));
    let (reference, reference_rays, _, reference_wall, _) =
        timed_render(&scene, &settings(a.reference_spp, REFERENCE_SEED))?;
    let reference = LinearImage::from_film(&reference);
    let reference_check = if a.no_reference_check {
        None
    } else {
        progress(&format!(
            "second reference: {} spp, independent samples",
            a.reference_spp
        ));
        let (check, ..) = timed_render(&scene, &settings(a.reference_spp, CHECK_SEED))?;
        Some(compare(
            &reference,
            &LinearImage::from_film(&check),
            &Thresholds::default(),
        )?)
    };
    // The test renders: uniform counts, then adaptive targets, previews and anti-aliasing.
    let uniform = a
        .spp
        .iter()
        .map(|&spp| (Method::Uniform(spp), settings(spp, TEST_SEED)));
    let targets = a
        .adaptive
        .iter()
        .map(|&t| (Method::Adaptive(t), adaptive(a, t)));
    let pixels = a.pixel.iter().map(|&t| (Method::Pixel(t), pixel(a, t)));
    let limits = (a.time_limit.iter())
        .map(|&t| Ok((Method::TimeLimit(t), timed(a, t)?)))
        .collect::<Result<Vec<_>>>()?;
    let previews = a.preview.iter().map(|&t| {
        let preview = pixel(a, t).with_min_spp(PREVIEW_MIN_SPP);
        (Method::Preview(t), preview)
    });
    let adaptive_renders =
        (targets.chain(pixels).chain(limits).chain(previews)).map(|(method, adaptive)| {
            let s = RenderSettings {
                adaptive: Some(adaptive),
                ..settings(1, TEST_SEED)
            };
            (method, s)
        });
    let antialiased = a.antialias.iter().map(|&antialias| {
        let s = RenderSettings {
            antialias: Some(antialias),
            ..settings(1, TEST_SEED)
        };
        (Method::Antialias(antialias), s)
    });
    let mut rows = Vec::new();
    for (method, s) in uniform.chain(adaptive_renders).chain(antialiased) {
        progress(&format!("{}, {} runs", method.label(), a.runs));
        rows.push(test_row(&scene, &s, method, a.runs, &reference)?);
    }
    let povray = match &a.povray {
        Some(pov) => Some(povray::measure(a, pov, progress)?),
        None => None,
    };
    Ok(ImageReport {
        scene: a.scene.clone(),
        resolution: a.res,
        reference_spp: a.reference_spp,
        reference_wall,
        reference_rays,
        reference_check,
        threads: rayon::current_num_threads(),
        runs: a.runs,
        rows,
        povray,
        reference,
    })
}

/// Runs `quadray bench images`: measures, prints the table, writes the files.
pub fn run(a: &ImagesArgs) -> Result<()> {
    validate(a)?;
    if !a.scene.is_file() {
        bail!(
            "scene {} not found (run from the repository root, or pass --scene FILE)",
            a.scene.display()
        );
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create output directory {}", a.out.display()))?;
    let pool = crate::args::thread_pool(a.threads)?;
    let quiet = a.quiet;
    let report = pool.install(|| {
        measure(a, &mut |what| {
            if !quiet {
                errln!("bench images: {what}");
            }
        })
    })?;
    let table = report.markdown();
    if !quiet {
        crate::unless_pipe_closed(outln!("{table}"))?;
    }
    write_outputs(&report, &a.out, &a.name, &table)?;
    if !quiet {
        errln!(
            "wrote {}.md, {0}.svg and {0}-reference.png",
            a.out.join(&a.name).display(),
        );
    }
    Ok(())
}

fn write_outputs(report: &ImageReport, out: &Path, name: &str, table: &str) -> Result<()> {
    let svg = report.svg()?;
    write_bytes_atomically(&out.join(format!("{name}.md")), table.as_bytes())?;
    write_bytes_atomically(&out.join(format!("{name}.svg")), svg.as_bytes())?;
    let r = &report.reference;
    write_rgb8_png(
        r.width,
        r.height,
        &r.to_srgb8(),
        &out.join(format!("{name}-reference.png")),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests;
