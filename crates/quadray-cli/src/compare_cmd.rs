//! `quadray compare A B`: measure how a test image differs from a reference, and fail over the
//! thresholds (the regression suite's rule by default).

use crate::compare::{Thresholds, compare, read_image};
use crate::output::{Format, check_writable, write_rgb8_png};
use anyhow::{Result, ensure};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `quadray compare`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct CompareArgs {
    /// The reference image (.png or .exr).
    pub reference: PathBuf,
    /// The image to test against it (.png or .exr).
    pub test: PathBuf,
    /// Write the FLIP error heat map here (.png; black: equal, yellow: very different).
    #[arg(long, value_name = "OUT.png", value_parser = crate::args::parse_png_output)]
    pub diff: Option<PathBuf>,
    /// A pixel counts as different when a channel differs by more than this many 8-bit display
    /// steps (1 = 1/255).
    #[arg(long, value_name = "STEPS", default_value_t = 2.0)]
    pub threshold: f32,
    /// Fail when more than this percentage of pixels differ.
    #[arg(long, value_name = "PERCENT", default_value_t = 0.1)]
    pub max_percent: f64,
    /// Fail when any channel differs by more than this many 8-bit display steps.
    #[arg(long, value_name = "STEPS", default_value_t = 32.0)]
    pub max_diff: f32,
    /// Fail when the mean FLIP error exceeds this (not judged unless given).
    #[arg(long, value_name = "FLIP")]
    pub max_flip: Option<f32>,
}

/// Runs the compare subcommand: the measures on stdout, an error (exit 1) over the thresholds.
pub fn run(args: &CompareArgs) -> Result<()> {
    for (name, v) in [
        ("--threshold", args.threshold),
        ("--max-diff", args.max_diff),
    ] {
        ensure!(
            v.is_finite() && v >= 0.0,
            "{name} must be a non-negative number of 8-bit steps, got {v:?}"
        );
    }
    ensure!(
        (0.0..=100.0).contains(&args.max_percent),
        "--max-percent must be in [0, 100], got {:?}",
        args.max_percent
    );
    if let Some(f) = args.max_flip {
        ensure!(
            (0.0..=1.0).contains(&f),
            "--max-flip must be in [0, 1], got {f:?}"
        );
    }
    if let Some(diff) = &args.diff {
        ensure!(
            check_writable(diff)? == Format::Png,
            "--diff {} must be a .png",
            diff.display()
        );
        let images = [args.reference.clone(), args.test.clone()];
        crate::overwrite::refuse_replacing_an_input(
            "--diff",
            diff,
            &images,
            "one of the images compared",
        )?;
    }
    let thresholds = Thresholds {
        pixel: args.threshold,
        max_share: args.max_percent / 100.0,
        max_diff: args.max_diff,
        max_flip: args.max_flip,
    };
    let reference = read_image(&args.reference)?;
    let test = read_image(&args.test)?;
    let c = compare(&reference, &test, &thresholds)?;
    if let Some(diff) = &args.diff {
        write_rgb8_png(c.width, c.height, &c.heat_map(), diff)?;
    }
    // A closed pipe must not turn images that differ into a success.
    crate::unless_pipe_closed(outln!("{}", c.summary(&thresholds)))?;
    let failures = c.failures(&thresholds);
    if !failures.is_empty() {
        return Err(crate::StatusError::images_differ(format!(
            "{} and {} differ: {}",
            args.reference.display(),
            args.test.display(),
            failures.join("; ")
        ))
        .into());
    }
    Ok(())
}
