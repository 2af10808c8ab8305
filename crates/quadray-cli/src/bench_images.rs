//! `quadray bench images`: render time against image error. A scene (by default
//! `scenes/defense.toml`) is rendered at several sample counts and compared with a high-sample
//! reference by [`crate::compare`] (RMSE in linear space, FLIP on the clamped 8-bit display
//! images); the report is a markdown table and a log–log SVG plot.
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
use quadray::{Film, NoProgress, RayCounts, RenderSettings, Scene, render};
use quadray_bench::plot::{LogLogSpec, log_log_svg};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Sample set of the test renders: the renderer's default.
pub const TEST_SEED: u32 = 0;
/// Sample set of the reference render.
pub const REFERENCE_SEED: u32 = 1;
/// Sample set of the second reference that estimates the first one's own error.
pub const CHECK_SEED: u32 = 2;

/// Arguments of `quadray bench images`.
#[derive(Args, Debug)]
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
        default_value = "1,4,16,64"
    )]
    pub spp: Vec<u32>,
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

/// One sample count's measurements.
#[derive(Clone, Debug)]
pub struct SppRow {
    /// Samples per pixel.
    pub spp: u32,
    /// Wall-clock render times of every run, seconds, in run order.
    pub wall: Vec<f64>,
    /// Process CPU times of every run, seconds (empty where the platform does not tell).
    pub cpu: Vec<f64>,
    /// Rays traced by one render.
    pub rays: RayCounts,
    /// The render against the reference.
    pub error: Comparison,
}

impl SppRow {
    /// Median wall-clock render time, seconds.
    pub fn wall_median(&self) -> f64 {
        median(&self.wall)
    }
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
    /// One row per test sample count, increasing.
    pub rows: Vec<SppRow>,
    /// The reference image.
    pub reference: LinearImage,
}

/// A plotted series: legend name, colour, (time, error) points.
type Series = (&'static str, plotters::style::RGBAColor, Vec<(f64, f64)>);

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// One timed render: the film, its rays, wall and CPU seconds.
fn timed_render(
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<(Film, RayCounts, f64, Option<f64>)> {
    let cpu_start = cpu_time::ProcessTime::try_now().ok();
    let start = Instant::now();
    let rendered = render(scene, settings, &NoProgress)?;
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_start
        .and_then(|t| t.try_elapsed().ok())
        .map(|d| d.as_secs_f64());
    Ok((rendered.film, rendered.counts, wall, cpu))
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
    Ok(())
}

/// Renders the reference(s) and every test sample count, and compares them.
pub fn measure(a: &ImagesArgs, progress: &mut dyn FnMut(&str)) -> Result<ImageReport> {
    validate(a)?;
    let loaded = quadray_loader::load_any(&a.scene)?;
    let mut base = loaded.settings.render_settings();
    (base.width, base.height) = a.res;
    let scene = Scene::new(loaded.description)
        .with_context(|| format!("invalid scene {}", a.scene.display()))?;
    let settings = |spp: u32, seed: u32| RenderSettings { spp, seed, ..base };

    progress(&format!("reference: {} spp", a.reference_spp));
    let (reference, reference_rays, reference_wall, _) =
        timed_render(&scene, &settings(a.reference_spp, REFERENCE_SEED))?;
    let reference = LinearImage::from_film(&reference);
    let thresholds = Thresholds::default();
    let reference_check = if a.no_reference_check {
        None
    } else {
        progress(&format!(
            "second reference: {} spp, independent samples",
            a.reference_spp
        ));
        let (check, _, _, _) = timed_render(&scene, &settings(a.reference_spp, CHECK_SEED))?;
        Some(compare(
            &reference,
            &LinearImage::from_film(&check),
            &thresholds,
        )?)
    };
    let mut rows = Vec::new();
    for &spp in &a.spp {
        progress(&format!("{spp} spp, {} runs", a.runs));
        let (mut wall, mut cpu) = (Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..a.runs {
            let (film, rays, w, c) = timed_render(&scene, &settings(spp, TEST_SEED))?;
            wall.push(w);
            cpu.extend(c);
            last = Some((film, rays));
        }
        let Some((film, rays)) = last else {
            bail!("no run of {spp} spp");
        };
        let error = compare(&reference, &LinearImage::from_film(&film), &thresholds)?;
        rows.push(SppRow {
            spp,
            wall,
            cpu,
            rays,
            error,
        });
    }
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
        reference,
    })
}

impl ImageReport {
    /// The reference's own RMSE against the truth, estimated as the RMSE between two independent
    /// references over √2.
    pub fn reference_rmse(&self) -> Option<f64> {
        self.reference_check
            .as_ref()
            .map(|c| c.rmse_linear / std::f64::consts::SQRT_2)
    }

    /// The report as markdown: what was run, then one row per sample count.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let (w, h) = self.resolution;
        let _ = writeln!(
            s,
            "Scene `{}` at {w}x{h}; reference {} spp (sample set {REFERENCE_SEED}, rendered in {:.2} s, {} rays); test renders: sample set {TEST_SEED}, wall-clock time median of {} runs on {} threads, BVH build excluded.\n",
            self.scene.display(),
            self.reference_spp,
            self.reference_wall,
            self.reference_rays.total(),
            self.runs,
            self.threads
        );
        s.push_str("| spp | render time, median (s) | fastest run (s) | CPU time, median (s) | rays | RMSE (linear) | FLIP mean | FLIP max |\n");
        s.push_str("|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for r in &self.rows {
            let cpu = if r.cpu.is_empty() {
                "unknown".to_string()
            } else {
                format!("{:.3}", median(&r.cpu))
            };
            let fastest = r.wall.iter().copied().fold(f64::INFINITY, f64::min);
            let _ = writeln!(
                s,
                "| {} | {:.3} | {:.3} | {cpu} | {} | {:.2e} | {:.4} | {:.3} |",
                r.spp,
                r.wall_median(),
                fastest,
                r.rays.total(),
                r.error.rmse_linear,
                r.error.flip_mean,
                r.error.flip_max
            );
        }
        if let (Some(rmse), Some(c)) = (self.reference_rmse(), &self.reference_check) {
            let _ = writeln!(
                s,
                "\nThe reference's own error, from a second {}-spp reference with independent samples (set {CHECK_SEED}): RMSE {:.2e} between the two, so about {rmse:.2e} against the converged image (FLIP mean between them {:.4}). Test errors well above this are the test renders' own.",
                self.reference_spp, c.rmse_linear, c.flip_mean
            );
        }
        s
    }

    /// The log–log plot of render time against RMSE and mean FLIP, one mark per sample count.
    pub fn svg(&self) -> Result<String> {
        let times: Vec<f64> = self.rows.iter().map(SppRow::wall_median).collect();
        let mut errors: Vec<f64> = self
            .rows
            .iter()
            .flat_map(|r| [r.error.rmse_linear, r.error.flip_mean as f64])
            .collect();
        errors.extend(self.reference_rmse());
        let positive = |v: &[f64]| v.iter().all(|&x| x > 0.0 && x.is_finite());
        if !positive(&times) || !positive(&errors) {
            bail!(
                "cannot plot on log axes: a render time or error is zero (times {times:?}, errors {errors:?})"
            );
        }
        let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        let (w, h) = self.resolution;
        let spec = LogLogSpec {
            width: 900,
            height: 600,
            title: format!(
                "{}: render time against image error, {w}x{h} (log–log)",
                self.scene
                    .file_name()
                    .map_or("scene".into(), |n| n.to_string_lossy())
            ),
            x_label: "render time, s (median of runs, wall clock)".into(),
            y_label: format!("error against the {}-spp reference", self.reference_spp),
            x_range: (lo(&times) * 0.6, hi(&times) * 1.8),
            y_range: (lo(&errors) * 0.5, hi(&errors) * 2.0),
            legend_width: 260,
        };
        let svg = log_log_svg(&spec, |c| {
            use plotters::prelude::*;
            let series: [Series; 2] = [
                (
                    "RMSE, linear",
                    RGBColor(31, 119, 180).to_rgba(),
                    self.rows
                        .iter()
                        .map(|r| (r.wall_median(), r.error.rmse_linear))
                        .collect(),
                ),
                (
                    "FLIP mean (8-bit display)",
                    RGBColor(214, 39, 40).to_rgba(),
                    self.rows
                        .iter()
                        .map(|r| (r.wall_median(), r.error.flip_mean as f64))
                        .collect(),
                ),
            ];
            let (px1, py1) = c.upper_right;
            for (i, (name, colour, points)) in series.iter().enumerate() {
                c.chart
                    .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?;
                c.chart
                    .draw_series(points.iter().map(|&p| Circle::new(p, 5, colour.filled())))?;
                for (r, &(t, e)) in self.rows.iter().zip(points) {
                    let (px, py) = c.pixel(t, e);
                    c.text(px + 8, py - 8, "start", 11, &format!("{} spp", r.spp));
                }
                c.legend_dot(py1 + 20 + 40 * i as i32, *colour, name, None)?;
            }
            // Independent samples: error ∝ (samples)^−1/2 ∝ time^−1/2, drawn from the first RMSE.
            let first = &self.rows[0];
            let (t1, e1) = (first.wall_median(), first.error.rmse_linear);
            let t_end = spec.x_range.1;
            let slope_colour = RGBColor(31, 119, 180).mix(0.5);
            c.chart.draw_series(DashedLineSeries::new(
                [(t1, e1), (t_end, e1 * (t_end / t1).powf(-0.5))],
                3,
                3,
                slope_colour.stroke_width(1),
            ))?;
            c.legend_line(
                py1 + 20 + 40 * series.len() as i32,
                slope_colour.stroke_width(1),
                "time^−1/2 from 1 spp",
                Some("(independent samples' rate)"),
            )?;
            if let Some(rmse) = self.reference_rmse() {
                let (x0, x1) = spec.x_range;
                let grey = RGBColor(120, 120, 120);
                c.chart.draw_series(DashedLineSeries::new(
                    [(x0, rmse), (x1, rmse)],
                    6,
                    4,
                    grey.stroke_width(1),
                ))?;
                c.legend_line(
                    py1 + 20 + 40 * (series.len() as i32 + 1),
                    grey.stroke_width(1),
                    "reference's own RMSE",
                    Some(&format!("(estimated: {rmse:.1e})")),
                )?;
            }
            c.text(
                px1 + 16,
                py1 + 20 + 40 * (series.len() as i32 + 3),
                "start",
                11,
                &format!(
                    "reference: {} spp, {:.1} s",
                    self.reference_spp, self.reference_wall
                ),
            );
            Ok(())
        })
        .map_err(|e| anyhow::anyhow!("{e}"))
        .context("drawing the plot")?;
        Ok(svg)
    }
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
                eprintln!("bench images: {what}");
            }
        })
    })?;
    let table = report.markdown();
    if !quiet {
        println!("{table}");
    }
    write_outputs(&report, &a.out, &table)?;
    if !quiet {
        eprintln!(
            "wrote {}, {} and {}",
            a.out.join("image-error.md").display(),
            a.out.join("image-error.svg").display(),
            a.out.join("image-error-reference.png").display()
        );
    }
    Ok(())
}

fn write_outputs(report: &ImageReport, out: &Path, table: &str) -> Result<()> {
    let svg = report.svg()?;
    write_bytes_atomically(&out.join("image-error.md"), table.as_bytes())?;
    write_bytes_atomically(&out.join("image-error.svg"), svg.as_bytes())?;
    let r = &report.reference;
    write_rgb8_png(
        r.width,
        r.height,
        &r.to_srgb8(),
        &out.join("image-error-reference.png"),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene_path() -> String {
        concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/defense.toml").to_string()
    }

    /// On a tiny render of the defense scene, error against the reference falls with every step
    /// of 4x the samples (stratified sampling: RMSE at least halves per step here) and all files
    /// are written; the reference check is far below the 64-spp error.
    #[test]
    fn error_falls_with_samples_and_the_files_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().to_str().unwrap();
        crate::run_args([
            "bench",
            "images",
            "--scene",
            &scene_path(),
            "--out",
            out,
            "--res",
            "64x36",
            "--reference-spp",
            "256",
            "--runs",
            "1",
            "--quiet",
        ])
        .unwrap();
        let md = std::fs::read_to_string(dir.path().join("image-error.md")).unwrap();
        let rows: Vec<Vec<String>> = md
            .lines()
            .filter(|l| l.starts_with("| ") && l.as_bytes()[2].is_ascii_digit())
            .map(|l| l.split('|').map(|c| c.trim().to_string()).collect())
            .collect();
        let spp: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
        assert_eq!(spp, ["1", "4", "16", "64"], "{md}");
        let rmse: Vec<f64> = rows.iter().map(|r| r[6].parse().unwrap()).collect();
        for w in rmse.windows(2) {
            assert!(
                w[1] < 0.75 * w[0],
                "RMSE must fall with samples: {rmse:?}\n{md}"
            );
        }
        let flip: Vec<f64> = rows.iter().map(|r| r[7].parse().unwrap()).collect();
        assert!(
            flip[3] < flip[0],
            "FLIP must fall from 1 to 64 spp: {flip:?}"
        );
        assert!(md.contains("reference's own error"), "{md}");
        let svg = std::fs::read_to_string(dir.path().join("image-error.svg")).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("64 spp") && svg.contains("FLIP mean"));
        let png = image::open(dir.path().join("image-error-reference.png")).unwrap();
        assert_eq!((png.width(), png.height()), (64, 36));
        // Nothing but the three outputs (no temporary files left behind).
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
    }

    #[test]
    fn bad_arguments_are_refused_before_rendering() {
        let scene = scene_path();
        for bad in [
            vec!["--reference-spp", "64"],
            vec!["--spp", "4,1"],
            vec!["--spp", "0,4"],
            vec!["--runs", "0"],
            vec!["--res", "0x10"],
        ] {
            let mut args = vec!["bench", "images", "--scene", &scene, "--quiet"];
            args.extend(bad.iter().copied());
            let err = crate::run_args(args).unwrap_err();
            assert!(!format!("{err:#}").is_empty());
        }
        let err =
            crate::run_args(["bench", "images", "--scene", "/no/such/scene.toml"]).unwrap_err();
        assert!(
            format!("{err:#}").contains("/no/such/scene.toml"),
            "{err:#}"
        );
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
