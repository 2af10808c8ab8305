//! The image-error report as markdown tables and a log–log SVG plot: CPU time against the
//! display RMSE, for quadray's uniform and adaptive renders and POV-Ray's anti-aliasing settings,
//! and the race between them (time to reach each POV-Ray setting's error; error at its time).

use super::{CHECK_SEED, ImageReport, Method, REFERENCE_SEED, Row, TEST_SEED};
use anyhow::{Context, Result, bail};
use quadray_bench::plot::{LogLogSpec, log_log_svg};
use std::fmt::Write as _;

/// A plotted series: legend name, colour, (time, error, label) points.
type Series = (
    &'static str,
    plotters::style::RGBAColor,
    Vec<(f64, f64, String)>,
);

/// Where a curve of (CPU time, error) points reaches an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Interpolated between two measured points (log–log), in seconds.
    At(f64),
    /// The cheapest measured point is already below: at most this many seconds.
    Within(f64),
    /// No measured point gets down to it.
    Never,
}

impl Reach {
    fn cell(self) -> String {
        match self {
            Reach::At(t) => format!("{t:.3}"),
            Reach::Within(t) => format!("≤ {t:.3}"),
            Reach::Never => "not reached".into(),
        }
    }

    fn ratio(self, peer: f64) -> String {
        match self {
            Reach::At(t) => format!("{:.1}×", peer / t),
            Reach::Within(t) => format!("≥ {:.1}×", peer / t),
            Reach::Never => "–".into(),
        }
    }
}

/// The time a curve of `(time, error)` points (any order) needs to reach `error`, interpolating
/// log–log between the cheapest point at or below it and the point before.
pub fn time_to_reach(points: &[(f64, f64)], error: f64) -> Reach {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let Some(i) = p.iter().position(|&(_, e)| e <= error) else {
        return Reach::Never;
    };
    if i == 0 {
        return Reach::Within(p[0].0);
    }
    let ((t0, e0), (t1, e1)) = (p[i - 1], p[i]);
    let f = (error.ln() - e0.ln()) / (e1.ln() - e0.ln());
    Reach::At((t0.ln() + f * (t1.ln() - t0.ln())).exp())
}

/// The `(time, error)` points that no other point beats in both (at most the time and less
/// error), by increasing time: the best a set of settings offers at each time.
pub fn front(mut points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut best = f64::INFINITY;
    points.retain(|&(_, error)| {
        let kept = error < best;
        best = best.min(error);
        kept
    });
    points
}

/// A curve's error at `time`, interpolated log–log; `None` outside the measured times.
pub fn error_at(points: &[(f64, f64)], time: f64) -> Option<f64> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let i = p.iter().position(|&(t, _)| t >= time)?;
    if i == 0 {
        return (p[0].0 == time).then_some(p[0].1);
    }
    let ((t0, e0), (t1, e1)) = (p[i - 1], p[i]);
    let f = (time.ln() - t0.ln()) / (t1.ln() - t0.ln());
    Some((e0.ln() + f * (e1.ln() - e0.ln())).exp())
}

impl ImageReport {
    /// The reference's own RMSE against the truth, estimated as the RMSE between two independent
    /// references over √2.
    pub fn reference_rmse(&self) -> Option<f64> {
        self.reference_check
            .as_ref()
            .map(|c| c.rmse_linear / std::f64::consts::SQRT_2)
    }

    /// quadray's (CPU time, display RMSE) points of one kind of method (adaptive: targets and
    /// previews together), without the points a cheaper one beats.
    fn curve(&self, adaptive: bool) -> Vec<(f64, f64)> {
        front(
            self.rows
                .iter()
                .filter(|r| r.method.is_adaptive() == adaptive)
                .map(|r| (r.cpu_median(), r.error.rmse_display))
                .collect(),
        )
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
                "\nPOV-Ray 3.7 on `{}`, one thread, against its own converged image (`{}`, {:.2} CPU s): each renderer is measured against its own reference, since their shading differs slightly. CPU time is POV-Ray's trace phase.\n",
                pov.file.display(),
                pov.reference_options,
                pov.reference_cpu
            );
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

    /// CPU seconds quadray needs to reach each POV-Ray setting's display RMSE, and quadray's
    /// error at each setting's CPU time.
    fn race_table(&self, pov: &[Row]) -> String {
        let (uniform, adaptive) = (self.curve(false), self.curve(true));
        let mut s = String::from(
            "\n| POV-Ray options | its RMSE | its CPU s | quadray uniform CPU s to reach it | speed-up | quadray adaptive CPU s to reach it | speed-up | quadray's best RMSE at its CPU s | error ratio |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        );
        for r in pov {
            let (error, time) = (r.error.rmse_display, r.cpu_median());
            let (u, a) = (
                time_to_reach(&uniform, error),
                time_to_reach(&adaptive, error),
            );
            let best = [error_at(&uniform, time), error_at(&adaptive, time)]
                .into_iter()
                .flatten()
                .reduce(f64::min);
            let (at, ratio) = best
                .map_or(("beyond the measured times".into(), "–".into()), |e| {
                    (format!("{e:.2e}"), format!("{:.2}", e / error))
                });
            let _ = writeln!(
                s,
                "| `{}` | {error:.2e} | {time:.3} | {} | {} | {} | {} | {at} | {ratio} |",
                r.method.label(),
                u.cell(),
                u.ratio(time),
                a.cell(),
                a.ratio(time)
            );
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
                "quadray, adaptive",
                RGBColor(44, 160, 44).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Adaptive(_))),
            ),
            (
                "quadray, preview (from 2 spp)",
                RGBColor(148, 103, 189).to_rgba(),
                points(&self.rows, &|m| matches!(m, Method::Preview(_))),
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

    #[test]
    fn reach_and_error_interpolate_log_log() {
        let curve = [(1.0, 0.1), (4.0, 0.025), (16.0, 0.01)];
        // Halfway in log error between 0.1 and 0.025 is 0.05: halfway in log time, 2 s.
        assert!(matches!(time_to_reach(&curve, 0.05), Reach::At(t) if (t - 2.0).abs() < 1e-9));
        assert_eq!(time_to_reach(&curve, 0.2), Reach::Within(1.0));
        assert_eq!(time_to_reach(&curve, 0.001), Reach::Never);
        assert!((error_at(&curve, 2.0).unwrap() - 0.05).abs() < 1e-12);
        assert_eq!(error_at(&curve, 32.0), None);
        assert_eq!(error_at(&curve, 0.5), None);
        assert_eq!(error_at(&curve, 1.0), Some(0.1));
    }

    #[test]
    fn the_front_drops_points_a_cheaper_one_beats() {
        let points = vec![
            (4.0, 0.02),
            (1.0, 0.1),
            (2.0, 0.01),
            (3.0, 0.03),
            (2.0, 0.05),
        ];
        assert_eq!(front(points), [(1.0, 0.1), (2.0, 0.01)]);
        assert_eq!(front(vec![]), []);
    }
}
