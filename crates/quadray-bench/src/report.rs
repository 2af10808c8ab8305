//! The speed-against-error report: every variant on every hard-case family, as a markdown table
//! and a log–log SVG plot of time per ray against error with the Pareto frontier marked.

use crate::hardcases::{self, Family, SuiteSize};
use crate::metrics::{self, Tally, Tier};
use crate::oracle::Reference;
use crate::plot::{LogLogSpec, log_log_svg};
use crate::variants::{Variant, VariantQuadric};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// How much work the report does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    /// Rays per family and kind, and the seed.
    pub size: SuiteSize,
    /// Timed runs per variant and family (the median is reported).
    pub runs: usize,
    /// Hit points per quadric of each family from which rays are spawned for the acne protocol.
    pub acne_hits: usize,
    /// Rays spawned per hit point (pbrt's protocol uses 10⁴).
    pub acne_dirs: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            size: SuiteSize::REPORT,
            runs: 7,
            acne_hits: 1,
            acne_dirs: 10_000,
        }
    }
}

/// One variant on one family (or on all of them).
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Family name, or "all".
    pub family: String,
    /// The variant.
    pub variant: Variant,
    /// Median nanoseconds per ray.
    pub ns_per_ray: f64,
    /// Rays scored (primary rays; spawned rays are counted in `spawned`).
    pub rays: usize,
    /// Spawned rays of the acne protocol.
    pub spawned: usize,
    /// Unambiguous agreeing hits' relative t errors.
    pub errors: Vec<f64>,
    /// Holes: primary misses plus missed re-hits of spawned rays (concave second hits).
    pub holes: usize,
    /// Phantoms and wrong roots of primary rays.
    pub phantoms: usize,
    /// Spawned rays that hit where the oracle has nothing, took a wrong root, or started behind the surface.
    pub acne: usize,
    /// Rays within the margin δ of a decision (primary and spawned).
    pub ambiguous: usize,
}

impl Row {
    /// Median relative t error.
    pub fn median(&self) -> f64 {
        metrics::quantile(&self.errors, 0.5)
    }
    /// 99th percentile relative t error.
    pub fn p99(&self) -> f64 {
        metrics::quantile(&self.errors, 0.99)
    }
    /// Largest relative t error.
    pub fn max(&self) -> f64 {
        metrics::quantile(&self.errors, 1.0)
    }
}

/// The whole report.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// What was run.
    pub settings: Settings,
    /// Variant × family rows, families in catalogue order.
    pub rows: Vec<Row>,
    /// One row per variant over every family, time weighted by rays.
    pub totals: Vec<Row>,
}

fn row_of(family: &str, variant: Variant, ns: f64, primary: &Tally, spawned: &Tally) -> Row {
    Row {
        family: family.to_string(),
        variant,
        ns_per_ray: ns,
        rays: primary.rays,
        spawned: spawned.rays,
        errors: primary.errors.clone(),
        holes: primary.holes + spawned.holes,
        phantoms: primary.phantoms + primary.wrong_roots,
        acne: spawned.phantoms + spawned.wrong_roots + spawned.offset_failures,
        ambiguous: primary.ambiguous + spawned.ambiguous,
    }
}

/// Scores and times every variant on one family; the variants are timed interleaved, run by run,
/// on the same rays, so their ratios are side by side.
pub fn family_rows(family: &Family, settings: &Settings) -> Vec<Row> {
    let quadrics: Vec<VariantQuadric> = metrics::variant_quadrics(family);
    let refs: Vec<Reference> = metrics::references(family, Tier::Exact);
    let spawned = hardcases::spawned(
        family,
        settings.acne_hits,
        settings.acne_dirs,
        settings.size.seed,
    );
    let spawned_refs = metrics::references(&spawned, Tier::Checked);
    let mut times = vec![Vec::new(); Variant::ALL.len()];
    for _ in 0..settings.runs {
        for (i, &v) in Variant::ALL.iter().enumerate() {
            times[i].push(metrics::time_per_ray(family, &quadrics, v, 1));
        }
    }
    Variant::ALL
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let primary = metrics::score(family, &refs, &quadrics, v);
            let sp = metrics::score(&spawned, &spawned_refs, &quadrics, v);
            row_of(
                family.name,
                v,
                metrics::quantile(&times[i], 0.5),
                &primary,
                &sp,
            )
        })
        .collect()
}

/// Runs the report, calling `progress` with each family's name as it starts.
pub fn run(settings: &Settings, progress: &mut dyn FnMut(&str)) -> Report {
    let mut rows = Vec::new();
    for family in hardcases::all(settings.size) {
        progress(family.name);
        rows.extend(family_rows(&family, settings));
    }
    let totals = Variant::ALL
        .iter()
        .map(|&v| {
            let mine: Vec<&Row> = rows.iter().filter(|r| r.variant == v).collect();
            let rays: usize = mine.iter().map(|r| r.rays).sum();
            let ns = mine
                .iter()
                .map(|r| r.ns_per_ray * r.rays as f64)
                .sum::<f64>()
                / rays as f64;
            Row {
                family: "all".into(),
                variant: v,
                ns_per_ray: ns,
                rays,
                spawned: mine.iter().map(|r| r.spawned).sum(),
                errors: mine.iter().flat_map(|r| r.errors.iter().copied()).collect(),
                holes: mine.iter().map(|r| r.holes).sum(),
                phantoms: mine.iter().map(|r| r.phantoms).sum(),
                acne: mine.iter().map(|r| r.acne).sum(),
                ambiguous: mine.iter().map(|r| r.ambiguous).sum(),
            }
        })
        .collect();
    Report {
        settings: *settings,
        rows,
        totals,
    }
}

impl Report {
    /// The total row of `variant`.
    pub fn total(&self, variant: Variant) -> &Row {
        self.totals
            .iter()
            .find(|r| r.variant == variant)
            .expect("every variant has a total")
    }

    /// Production's time per ray over naive f64's, on the same rays, all families.
    pub fn production_ratio(&self) -> f64 {
        self.total(Variant::Production).ns_per_ray / self.total(Variant::NaiveF64).ns_per_ray
    }

    /// The same ratio on the ordinary scene families only (`scene-*`: every kind seen from five
    /// object sizes away, at every scale), the rays a render mostly sends.
    pub fn production_ratio_scenes(&self) -> f64 {
        let sum = |v: Variant| -> (f64, f64) {
            self.rows
                .iter()
                .filter(|r| r.variant == v && r.family.starts_with("scene-"))
                .fold((0.0, 0.0), |(t, n), r| {
                    (t + r.ns_per_ray * r.rays as f64, n + r.rays as f64)
                })
        };
        let (tp, np) = sum(Variant::Production);
        let (tn, nn) = sum(Variant::NaiveF64);
        (tp / np) / (tn / nn)
    }

    /// The report as markdown: the totals, then every family.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let st = &self.settings;
        let _ = writeln!(
            s,
            "Rays per family and kind: {}, seed {}; timing: median of {} runs; acne: {} hit points × {} spawned rays per family.\n",
            st.size.rays, st.size.seed, st.runs, st.acne_hits, st.acne_dirs
        );
        let header = "| family | variant | ns/ray | median rel. t error | p99 | max | holes | phantoms | acne | ambiguous |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        s.push_str(header);
        for r in self.totals.iter().chain(&self.rows) {
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} | {:.1e} | {:.1e} | {:.1e} | {} | {} | {} | {} |",
                r.family,
                r.variant.name(),
                r.ns_per_ray,
                r.median(),
                r.p99(),
                r.max(),
                r.holes,
                r.phantoms,
                r.acne,
                r.ambiguous
            );
        }
        let _ = writeln!(
            s,
            "\nproduction / naive-f64 time per ray, same rays, one run: {:.3} over all families, {:.3} over the scene-* families",
            self.production_ratio(),
            self.production_ratio_scenes()
        );
        s
    }

    /// Variants on the Pareto frontier of (ns/ray, p99 error, failures): no other variant is at least
    /// as fast, at least as accurate and has no more holes, phantoms and acne, while better in one.
    pub fn pareto(&self) -> Vec<Variant> {
        let key = |r: &Row| (r.ns_per_ray, r.p99(), r.holes + r.phantoms + r.acne);
        self.totals
            .iter()
            .filter(|r| {
                let (t, e, f) = key(r);
                !self.totals.iter().any(|o| {
                    let (to, eo, fo) = key(o);
                    to <= t && eo <= e && fo <= f && (to < t || eo < e || fo < f)
                })
            })
            .map(|r| r.variant)
            .collect()
    }

    /// The log–log plot of time per ray against p99 relative t error, as SVG (texts placed by
    /// hand, see [`crate::plot`]).
    pub fn svg(&self) -> Result<String, Box<dyn std::error::Error>> {
        const FLOOR: f64 = 1e-18;
        let err = |r: &Row| r.p99().max(FLOOR);
        let all: Vec<&Row> = self.totals.iter().chain(&self.rows).collect();
        let (mut t0, mut t1) = (f64::INFINITY, 0f64);
        let (mut e0, mut e1) = (f64::INFINITY, 0f64);
        for r in &all {
            t0 = t0.min(r.ns_per_ray);
            t1 = t1.max(r.ns_per_ray);
            e0 = e0.min(err(r));
            e1 = e1.max(err(r));
        }
        let spec = LogLogSpec {
            width: 960,
            height: 660,
            title: "quadray quadric intersectors: time per ray against error (log–log)".into(),
            x_label: "ns per ray (median of runs, same rays for every variant)".into(),
            y_label: "p99 relative t error vs the exact oracle".into(),
            x_range: (t0 * 0.8, t1 * 1.25),
            y_range: (e0 * 0.3, e1 * 3.0),
            legend_width: 300,
        };
        let svg = log_log_svg(&spec, |c| {
            let (px1, py1) = c.upper_right;
            let colour = |i: usize| Palette99::pick(i).to_rgba();
            for (i, &v) in Variant::ALL.iter().enumerate() {
                // Families as small dots, the total over all families as a large one.
                c.chart
                    .draw_series(self.rows.iter().filter(|r| r.variant == v).map(|r| {
                        Circle::new((r.ns_per_ray, err(r)), 3, colour(i).mix(0.45).filled())
                    }))?;
                let t = self.total(v);
                c.chart.draw_series(std::iter::once(Circle::new(
                    (t.ns_per_ray, err(t)),
                    8,
                    colour(i).filled(),
                )))?;
                c.legend_dot(
                    py1 + 20 + 44 * i as i32,
                    colour(i),
                    v.name(),
                    Some(&format!(
                        "{:.1} ns, holes {}, phantoms {}, acne {}",
                        t.ns_per_ray, t.holes, t.phantoms, t.acne
                    )),
                )?;
            }
            let mut frontier: Vec<(f64, f64)> = self
                .pareto()
                .into_iter()
                .map(|v| {
                    let t = self.total(v);
                    (t.ns_per_ray, err(t))
                })
                .collect();
            frontier.sort_by(|a, b| a.0.total_cmp(&b.0));
            c.chart
                .draw_series(LineSeries::new(frontier, BLACK.stroke_width(2)))?;
            let ly = py1 + 20 + 44 * Variant::ALL.len() as i32;
            c.legend_line(
                ly,
                BLACK.stroke_width(2),
                "Pareto frontier",
                Some("(time, p99 error, failures)"),
            )?;
            c.text(
                px1 + 16,
                ly + 44,
                "start",
                11,
                "large dots: all families; small: each family",
            );
            Ok(())
        })?;
        Ok(svg)
    }

    /// Writes [`Report::svg`] to `path`.
    pub fn write_svg(&self, path: &Path) -> Result<(), Box<dyn std::error::Error>> {
        std::fs::write(path, self.svg()?)?;
        Ok(())
    }
}
