//! Scoring a variant on a family against the oracle: relative t error, residual, holes, phantoms,
//! wrong roots and acne, and timing.

use crate::hardcases::{Case, Family};
use crate::oracle::{self, Reference};
use crate::variants::{Variant, VariantQuadric};
use std::hint::black_box;
use std::time::Instant;

/// Which oracle tier computes the references.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    /// Exact rationals throughout.
    Exact,
    /// Double-double, with the exact tier wherever double-double is not reliable.
    Checked,
}

/// The bound constant K of the stated error bound: |t − t*| ≤ K·u·κ·|t*| (docs/numerics.md).
pub const K_BOUND: f64 = 64.0;

/// Unit roundoff of f64.
pub const U: f64 = f64::EPSILON * 0.5;

/// A spawned ray "hits the surface again at that point" when the true crossing lies within this
/// many local units (object sizes) ahead of its origin: its offset put it on the wrong side.
pub const SAME_POINT: f64 = 1e-9;

/// The oracle's verdicts for every case of a family.
pub fn references(family: &Family, tier: Tier) -> Vec<Reference> {
    family
        .cases
        .iter()
        .map(|c| {
            let q = &family.quadrics[c.quadric];
            match tier {
                Tier::Exact => oracle::exact(q, &c.ray, c.t_max),
                Tier::Checked => oracle::checked(q, &c.ray, c.t_max),
            }
        })
        .collect()
}

/// One disagreement, kept for diagnostics.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// Index of the case in its family.
    pub case: usize,
    /// What went wrong.
    pub what: &'static str,
    /// The variant's answer.
    pub got: Option<f64>,
    /// The oracle's answer.
    pub want: Option<f64>,
    /// The oracle's margin and δ.
    pub margin: (f64, f64),
}

/// Counts and error samples of one variant on one family.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Rays scored.
    pub rays: usize,
    /// Rays within δ of a decision boundary (not scored for holes or phantoms).
    pub ambiguous: usize,
    /// Hits the oracle has beyond the margin that the variant missed.
    pub holes: usize,
    /// Hits the variant reported where the oracle has none beyond the margin.
    pub phantoms: usize,
    /// Hits on another root of the quadratic than the oracle's.
    pub wrong_roots: usize,
    /// Spawned rays whose true surface crossing lies within [`SAME_POINT`] ahead of their origin.
    pub offset_failures: usize,
    /// Relative t errors |t − t*|/|t*| of agreeing, unambiguous hits.
    pub errors: Vec<f64>,
    /// The same divided by the root's condition number κ (what the bound [`K_BOUND`]·u caps).
    pub scaled_errors: Vec<f64>,
    /// Residuals |f(p)|/|∇f(p)| of agreeing hits, in object sizes.
    pub residuals: Vec<f64>,
    /// The first few failures.
    pub failures: Vec<Failure>,
}

impl Tally {
    /// Holes + phantoms + wrong roots + offset failures.
    pub fn failures_total(&self) -> usize {
        self.holes + self.phantoms + self.wrong_roots + self.offset_failures
    }

    fn fail(&mut self, case: usize, what: &'static str, got: Option<f64>, r: &Reference) {
        if self.failures.len() < 8 {
            self.failures.push(Failure {
                case,
                what,
                got,
                want: r.t(),
                margin: (r.margin, r.delta),
            });
        }
    }

    /// Scores one answer of a variant against its reference.
    pub fn score(&mut self, index: usize, case: &Case, got: Option<f64>, r: &Reference) {
        self.rays += 1;
        // A true crossing just ahead of a spawned ray's origin that the variant does not report means
        // the offset left the origin behind the surface (a variant that finds it is merely right).
        let just_ahead = r
            .roots
            .iter()
            .find(|root| root.t > 0.0 && root.t * r.dir_local < SAME_POINT);
        if let Some(root) = just_ahead.filter(|_| case.from_self)
            && got.is_none_or(|t| (t - root.t).abs() > 1e-3 * root.t)
        {
            self.offset_failures += 1;
            self.fail(index, "spawned ray starts behind its surface", got, r);
            return;
        }
        let ambiguous = if case.from_self {
            r.ambiguous_spawned()
        } else {
            r.ambiguous()
        };
        if ambiguous {
            self.ambiguous += 1;
            return;
        }
        match (got, r.t()) {
            (None, None) => {}
            (None, Some(_)) => {
                self.holes += 1;
                self.fail(index, "hole", got, r);
            }
            (Some(_), None) => {
                self.phantoms += 1;
                self.fail(index, "phantom", got, r);
            }
            (Some(t), Some(_)) => {
                if r.is_wrong_root(t) {
                    self.wrong_roots += 1;
                    self.fail(index, "wrong root", got, r);
                } else {
                    let e = r.relative_error(t).unwrap_or(0.0);
                    self.errors.push(e);
                    self.scaled_errors.push(e / r.condition);
                }
            }
        }
    }
}

/// Scores `variant` on every case of `family`.
pub fn score(
    family: &Family,
    refs: &[Reference],
    quadrics: &[VariantQuadric],
    variant: Variant,
) -> Tally {
    let mut tally = Tally::default();
    for (i, (c, r)) in family.cases.iter().zip(refs).enumerate() {
        let got = quadrics[c.quadric].intersect(variant, &c.ray, c.t_max, c.from_self);
        tally.score(i, c, got, r);
    }
    tally
}

/// Residuals of the variant's agreeing unambiguous hits, with the exact oracle (slow: use on samples).
pub fn residuals(
    family: &Family,
    refs: &[Reference],
    quadrics: &[VariantQuadric],
    variant: Variant,
    every: usize,
) -> Vec<f64> {
    let mut out = Vec::new();
    for (c, r) in family.cases.iter().zip(refs).step_by(every.max(1)) {
        let q = &quadrics[c.quadric];
        let Some(t) = q.intersect(variant, &c.ray, c.t_max, c.from_self) else {
            continue;
        };
        if r.ambiguous() || r.t().is_none() || r.is_wrong_root(t) {
            continue;
        }
        let prepared = oracle::Prepared::<oracle::Dyadic>::new(
            &oracle::OracleInput::of(&q.quadric),
            &c.ray,
            c.t_max,
        );
        out.push(prepared.residual(t));
    }
    out
}

/// The quantile `p` in [0, 1] of `v` (nearest rank), or 0 for an empty slice.
pub fn quantile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((s.len() as f64 - 1.0) * p).round() as usize;
    s[i.min(s.len() - 1)]
}

/// Median wall-clock nanoseconds per ray of `variant` over all of `family`'s cases, over `runs` runs.
pub fn time_per_ray(
    family: &Family,
    quadrics: &[VariantQuadric],
    variant: Variant,
    runs: usize,
) -> f64 {
    let mut samples = Vec::with_capacity(runs);
    // Repeat short families so each timed run lasts long enough to read the clock meaningfully.
    let repeat = (20_000 / family.cases.len().max(1)).max(1);
    for _ in 0..runs {
        let start = Instant::now();
        let mut hits = 0usize;
        for _ in 0..repeat {
            for c in &family.cases {
                let q = &quadrics[c.quadric];
                if black_box(q)
                    .intersect(variant, black_box(&c.ray), c.t_max, c.from_self)
                    .is_some()
                {
                    hits += 1;
                }
            }
        }
        black_box(hits);
        let ns = start.elapsed().as_nanos() as f64;
        samples.push(ns / (repeat * family.cases.len().max(1)) as f64);
    }
    quantile(&samples, 0.5)
}

/// The variant copies of a family's quadrics.
pub fn variant_quadrics(family: &Family) -> Vec<VariantQuadric> {
    family
        .quadrics
        .iter()
        .cloned()
        .map(VariantQuadric::new)
        .collect()
}
