//! quadray-bench: how accurate and how fast quadray's quadric intersector is.
//!
//! - [`oracle`]: a reference intersection from the f64 inputs, exact (dyadic rationals, 320-bit roots)
//!   or double-double, with the margin of each case from its decision boundaries.
//! - [`variants`]: the benchmark-only intersectors (naive f32/f64, stable f64, production, + Newton).
//! - [`hardcases`]: generators for every family of the hard-case catalogue.
//! - [`metrics`]: relative t error, residual, holes, phantoms, wrong roots, acne, timing.
//! - [`report`]: the speed-against-error table and its log–log plot.
//! - [`plot`]: log–log SVG charts with hand-placed text, shared by the reports.
//! - [`holes`]: hole maps: one primary ray per pixel of a quadric scene, each variant against the oracle.
//!
//! This crate is bench and test code; the renderer does not depend on it.

pub mod hardcases;
pub mod holes;
pub mod metrics;
pub mod oracle;
pub mod plot;
pub mod report;
pub mod variants;
