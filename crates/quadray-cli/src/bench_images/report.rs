//! The image-error report as markdown tables and a log–log SVG plot: CPU time against the
//! display RMSE, for quadray's uniform, adaptive and anti-aliased renders and POV-Ray's
//! anti-aliasing settings, and the race between them (time to reach each POV-Ray setting's
//! error; error within its time), from measured points only.

use super::{
    CHECK_SEED, ImageReport, Method, POV_CHECK_SCALE, POV_REFERENCE_SCALE, REFERENCE_SEED, Row,
    TEST_SEED,
};
use anyhow::{Context, Result, bail};
use quadray_bench::plot::{LogLogSpec, log_log_svg};
use std::fmt::Write as _;

/// A plotted series: legend name, colour, (time, error, label) points.
type Series = (
    &'static str,
    plotters::style::RGBAColor,
    Vec<(f64, f64, String)>,
);

/// Where a curve of (CPU time, error) points reaches an error: the CPU time of its cheapest
/// measured point at or below it, if any. Nothing is interpolated, so the time is an upper
/// bound (an unmeasured setting might get there sooner) and a speed-up from it a lower bound:
/// between 1 and 4 spp a 2-spp render lay well above the log–log line (reflective: 2.31e-2
/// against 2.45e-2 at 1 spp), so interpolating across gaps flattered whichever side it helped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// A measured point at or below the error, at this many seconds.
    Within(f64),
    /// No measured point gets down to it.
    Never,
}

impl Reach {
    fn cell(self) -> String {
        match self {
            Reach::Within(t) => format!("{t:.3}"),
            Reach::Never => "not reached".into(),
        }
    }

    fn ratio(self, peer: f64) -> String {
        match self {
            Reach::Within(t) => format!("{:.1}×", peer / t),
            Reach::Never => "–".into(),
        }
    }
}

/// The time a curve of `(time, error)` points (any order) needs to reach `error`: that of the
/// cheapest point at or below it.
pub fn time_to_reach(points: &[(f64, f64)], error: f64) -> Reach {
    points
        .iter()
        .filter(|&&(_, e)| e <= error)
        .map(|&(t, _)| t)
        .reduce(f64::min)
        .map_or(Reach::Never, Reach::Within)
}

/// A curve's least error among its points that take at most `time`; `None` when every point
/// takes longer.
pub fn error_at(points: &[(f64, f64)], time: f64) -> Option<f64> {
    points
        .iter()
        .filter(|&&(t, _)| t <= time)
        .map(|&(_, e)| e)
        .reduce(f64::min)
}

/// A kind of quadray render in the race: its name, and which methods belong to it.
type Racer = (&'static str, fn(&Method) -> bool);

/// The kinds of quadray render the race compares with POV-Ray, each a curve of its own.
const RACERS: [Racer; 5] = [
    ("uniform", |m| matches!(m, Method::Uniform(_))),
    ("image target", |m| matches!(m, Method::Adaptive(_))),
    ("per-pixel", |m| {
        matches!(m, Method::Pixel(_) | Method::Preview(_))
    }),
    ("time limit", |m| matches!(m, Method::TimeLimit(_))),
    ("anti-aliased", |m| matches!(m, Method::Antialias(_))),
];

impl ImageReport {
    /// The reference's own RMSE against the truth, estimated as the RMSE between two independent
    /// references over √2.
    pub fn reference_rmse(&self) -> Option<f64> {
        self.reference_check
            .as_ref()
            .map(|c| c.rmse_linear / std::f64::consts::SQRT_2)
    }

    /// quadray's (CPU time, display RMSE) points of the methods `kind` accepts.
    fn curve(&self, kind: fn(&Method) -> bool) -> Vec<(f64, f64)> {
        self.rows
            .iter()
            .filter(|r| kind(&r.method))
            .map(|r| (r.cpu_median(), r.error.rmse_display))
            .collect()
    }

    /// The report as markdown: what was run, quadray's rows, POV-Ray's rows and the race.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let (w, h) = self.resolution;
        let _ = writeln!(
            s,
            "Scene `{}` at {w}x{h}; reference {} spp (sample set {REFERENCE_SEED}, rendered in {:.2} s, {} rays); test renders: sample set {TEST_SEED}, median of {} runs on {} threads, BVH build excluded. CPU time is the process's during the render. RMSE (display) is over the 8-bit sRGB channels, in [0, 1].\n",
            self.scene.display(),
            self.reference_spp,
            self.reference_wall,
            self.reference_rays.total(),
            self.runs,
            self.threads
        );
        s.push_str("| method | spp mean (min..max) | CPU s, median | wall s, median | rays | RMSE (linear) | RMSE (display) | FLIP mean | FLIP max |\n");
        s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for r in &self.rows {
            let spp = r.sampling.map_or("–".into(), |x| {
                if x.min_spp == x.max_spp {
                    x.min_spp.to_string()
                } else {
                    format!("{:.1} ({}..{})", x.mean_spp, x.min_spp, x.max_spp)
                }
            });
            let _ = writeln!(
                s,
                "| {} | {spp} | {:.3} | {:.3} | {} | {:.2e} | {:.2e} | {:.4} | {:.3} |",
                r.method.label(),
                r.cpu_median(),
                r.wall_median(),
                r.rays.map_or(0, |c| c.total()),
                r.error.rmse_linear,
                r.error.rmse_display,
                r.error.flip_mean,
                r.error.flip_max
            );
        }
        if let (Some(rmse), Some(c)) = (self.reference_rmse(), &self.reference_check) {
            let _ = writeln!(
                s,
                "\nThe reference's own error, from a second {}-spp reference with independent samples (set {CHECK_SEED}): RMSE {:.2e} between the two, so about {rmse:.2e} against the converged image (display RMSE between them {:.2e}, FLIP mean {:.4}). Test errors well above this are the test renders' own.",
                self.reference_spp, c.rmse_linear, c.rmse_display, c.flip_mean
            );
        }
        if let Some(pov) = &self.povray {
            let _ = writeln!(
                s,
                "\nPOV-Ray 3.7 on `{}`, one thread, against its own converged image (`{}` at {POV_REFERENCE_SCALE}x the resolution, box-filtered down; {:.2} CPU s): each renderer is measured against its own reference, since their shading differs slightly. CPU time is POV-Ray's trace phase.",
                pov.file.display(),
                pov.reference_options,
                pov.reference_cpu
            );
            if let Some(between) = pov.reference_check {
                let _ = writeln!(
                    s,
                    "The POV-Ray reference's own error, from a second one at {POV_CHECK_SCALE}x the resolution (other sample positions in every pixel): display RMSE {between:.2e} between the two, so about {:.2e} against the converged image.",
                    between / std::f64::consts::SQRT_2
                );
            }
            s.push('\n');
            s.push_str("| POV-Ray options | CPU s, median | wall s, median | RMSE (display) | FLIP mean | FLIP max |\n");
            s.push_str("|---|---:|---:|---:|---:|---:|\n");
            for r in &pov.rows {
                let _ = writeln!(
                    s,
                    "| `{}` | {:.3} | {:.3} | {:.2e} | {:.4} | {:.3} |",
                    r.method.label(),
                    r.cpu_median(),
                    r.wall_median(),
                    r.error.rmse_display,
                    r.error.flip_mean,
                    r.error.flip_max
                );
            }
            s.push_str(&self.race_table(&pov.rows));
        }
        s
    }

    /// CPU seconds each kind of quadray render needs to reach each POV-Ray setting's display
    /// RMSE (its cheapest measured render at or below it), and quadray's least error among the
    /// renders that take at most that setting's CPU time.
    fn race_table(&self, pov: &[Row]) -> String {
        let curves: Vec<Vec<(f64, f64)>> =
            RACERS.iter().map(|(_, kind)| self.curve(*kind)).collect();
        let mut s = String::from("\n| POV-Ray options | its RMSE | its CPU s |");
        for (name, _) in RACERS {
            let _ = write!(s, " quadray {name}: CPU s to reach it | speed-up |");
        }
        s.push_str(" quadray's least RMSE within its CPU s | error ratio |\n|---|---:|---:|");
        s.push_str(&"---:|---:|".repeat(RACERS.len()));
        s.push_str("---:|---:|\n");
        for r in pov {
            let (error, time) = (r.error.rmse_display, r.cpu_median());
            let _ = write!(s, "| `{}` | {error:.2e} | {time:.3} |", r.method.label());
            for curve in &curves {
                let reach = time_to_reach(curve, error);
                let _ = write!(s, " {} | {} |", reach.cell(), reach.ratio(time));
            }
            let best = curves
                .iter()
                .filter_map(|c| error_at(c, time))
                .reduce(f64::min);
            let (at, ratio) = best.map_or(("none as fast".into(), "–".into()), |e| {
                (format!("{e:.2e}"), format!("{:.2}", e / error))
            });
            let _ = writeln!(s, " {at} | {ratio} |");
        }
        s
    }

    /// The log–log plot of CPU time against display RMSE, one mark per test image.
    pub fn svg(&self) -> Result<String> {
        use plotters::prelude::*;
        let points = |rows: &[Row], kind: &dyn Fn(&Method) -> bool| -> Vec<(f64, f64, String)> {
            rows.iter()
                .filter(|r| kind(&r.method))
                .map(|r| (r.cpu_median(), r.error.rmse_display, r.method.label()))
                .collect()
        };
        let mut series: Vec<Series> = vec![
            (
                "quadray, uniform spp",
                RGBColor(31, 119, 180).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Uniform(_))),
            ),
            (
                "quadray, image target",
                RGBColor(44, 160, 44).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Adaptive(_))),
            ),
            (
                "quadray, per-pixel target",
                RGBColor(255, 127, 14).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Pixel(_))),
            ),
            (
                "quadray, time limit",
                RGBColor(23, 190, 207).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::TimeLimit(_))),
            ),
            (
                "quadray, preview (from 2 spp)",
                RGBColor(148, 103, 189).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Preview(_))),
            ),
            (
                "quadray, anti-aliased by contrast",
                RGBColor(140, 86, 75).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Antialias(_))),
            ),
        ];
        if let Some(pov) = &self.povray {
            series.push((
                "POV-Ray 3.7 (own reference)",
                RGBColor(214, 39, 40).to_rgba(),
                points(&pov.rows, &|_| true),
            ));
        }
        series.retain(|(_, _, p)| !p.is_empty());
        let all: Vec<(f64, f64)> = series
            .iter()
            .flat_map(|(_, _, p)| p.iter().map(|&(t, e, _)| (t, e)))
            .collect();
        if all
            .iter()
            .any(|&(t, e)| !(t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite()))
        {
            bail!("cannot plot on log axes: a time or error is zero ({all:?})");
        }
        let range = |f: &dyn Fn(&(f64, f64)) -> f64| {
            let v: Vec<f64> = all.iter().map(f).collect();
            (
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(0.0, f64::max),
            )
        };
        let ((t0, t1), (e0, e1)) = (range(&|p| p.0), range(&|p| p.1));
        let (w, h) = self.resolution;
        let spec = LogLogSpec {
            width: 900,
            height: 600,
            title: format!(
                "{}: CPU time against image error, {w}x{h} (log–log)",
                self.scene
                    .file_name()
                    .map_or("scene".into(), |n| n.to_string_lossy())
            ),
            x_label: "CPU time, s (median of runs)".into(),
            y_label: "RMSE of the 8-bit display image against the renderer's own reference".into(),
            x_range: (t0 * 0.6, t1 * 1.8),
            y_range: (e0 * 0.5, e1 * 2.0),
            legend_width: 260,
        };
        let svg = log_log_svg(&spec, |c| {
            let (_, py1) = c.upper_right;
            for (i, (name, colour, pts)) in series.iter().enumerate() {
                let xy: Vec<(f64, f64)> = pts.iter().map(|&(t, e, _)| (t, e)).collect();
                c.chart
                    .draw_series(LineSeries::new(xy.clone(), colour.stroke_width(2)))?;
                c.chart
                    .draw_series(xy.iter().map(|&p| Circle::new(p, 5, colour.filled())))?;
                for (t, e, label) in pts {
                    let (px, py) = c.pixel(*t, *e);
                    c.text(px + 8, py - 8, "start", 11, label);
                }
                c.legend_dot(py1 + 20 + 40 * i as i32, *colour, name, None)?;
            }
            Ok(())
        })
        .map_err(|e| anyhow::anyhow!("{e}"))
        .context("drawing the plot")?;
        Ok(svg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only measured points count: the time to reach an error is the cheapest point at or below
    /// it, and the error within a time the least among the points that take no longer.
    #[test]
    fn reach_and_error_take_measured_points_only() {
        let curve = [(4.0, 0.025), (1.0, 0.1), (16.0, 0.01), (8.0, 0.03)];
        assert_eq!(time_to_reach(&curve, 0.05), Reach::Within(4.0));
        assert_eq!(time_to_reach(&curve, 0.2), Reach::Within(1.0));
        assert_eq!(time_to_reach(&curve, 0.01), Reach::Within(16.0));
        assert_eq!(time_to_reach(&curve, 0.001), Reach::Never);
        assert_eq!(error_at(&curve, 2.0), Some(0.1));
        assert_eq!(error_at(&curve, 9.0), Some(0.025));
        assert_eq!(error_at(&curve, 32.0), Some(0.01));
        assert_eq!(error_at(&curve, 0.5), None);
    }
}
