//! `quadray bench`: the speed-against-error reports (see docs/numerics.md). `accuracy` runs the
//! quadric intersector variants against the exact oracle on the hard-case families; `images` and
//! `holes` are its image-level companions ([`crate::bench_images`], [`crate::bench_holes`]); `rays`
//! measures ray-casting throughput on the peers' ray sets ([`crate::bench_rays`]).

use crate::output::write_bytes_atomically;
use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use quadray_bench::hardcases::SuiteSize;
use quadray_bench::report::{self, Settings};
use std::path::PathBuf;

/// The benchmarks.
#[derive(Subcommand, Debug)]
// The arguments are parsed once per process: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
pub enum BenchCommand {
    /// Every intersector variant on every hard-case family: ns/ray, relative t error, holes,
    /// phantoms and acne against the exact oracle; writes accuracy.md and accuracy.svg.
    Accuracy(AccuracyArgs),
    /// Render time against image error: a scene at several sample counts against a high-sample
    /// reference (RMSE in linear space, FLIP); writes image-error.md, image-error.svg and
    /// image-error-reference.png.
    Images(crate::bench_images::ImagesArgs),
    /// Hole maps: one primary ray per pixel of hard quadric scenes, every intersector variant
    /// against the exact oracle; writes holes.md and one PNG per scene and variant.
    Holes(crate::bench_holes::HolesArgs),
    /// Ray-casting throughput: casts ray files (the `RAYS` format of ../shared/peers/speed, the
    /// same rays Embree and obvhs cast there) at a mesh through the core's intersect and occluded
    /// queries; prints Mrays per CPU-second and per wall second, hits and a t checksum.
    Rays(crate::bench_rays::RaysArgs),
}

/// Arguments of `quadray bench accuracy`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct AccuracyArgs {
    /// Directory for accuracy.md (the table) and accuracy.svg (the plot); created if missing.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// Rays per hard-case family and quadric kind.
    #[arg(long, value_name = "N", default_value_t = SuiteSize::REPORT.rays)]
    pub rays: usize,
    /// Timed runs per variant and family (the median is reported).
    #[arg(long, value_name = "N", default_value_t = 7)]
    pub runs: usize,
    /// Rays spawned per hit point for the acne protocol (pbrt uses 10⁴).
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub acne_rays: usize,
    /// Random seed of the ray generators.
    #[arg(long, default_value_t = SuiteSize::REPORT.seed)]
    pub seed: u64,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs a bench subcommand.
pub fn run(command: &BenchCommand) -> Result<()> {
    match command {
        BenchCommand::Accuracy(a) => accuracy(a),
        BenchCommand::Images(a) => crate::bench_images::run(a),
        BenchCommand::Holes(a) => crate::bench_holes::run(a),
        BenchCommand::Rays(a) => crate::bench_rays::run(a),
    }
}

fn accuracy(a: &AccuracyArgs) -> Result<()> {
    if a.rays == 0 || a.runs == 0 || a.acne_rays == 0 {
        bail!("--rays, --runs and --acne-rays must be at least 1");
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create output directory {}", a.out.display()))?;
    let settings = Settings {
        size: SuiteSize {
            rays: a.rays,
            seed: a.seed,
        },
        runs: a.runs,
        acne_hits: 1,
        acne_dirs: a.acne_rays,
    };
    let quiet = a.quiet;
    let report = report::run(&settings, &mut |family| {
        if !quiet {
            errln!("bench accuracy: {family}");
        }
    });
    let table = report.markdown();
    if !quiet {
        crate::unless_pipe_closed(outln!("{table}"))?;
    }
    let md = a.out.join("accuracy.md");
    let svg = a.out.join("accuracy.svg");
    write_bytes_atomically(&md, table.as_bytes())?;
    let plot = report
        .svg()
        .map_err(|e| anyhow::anyhow!("{e}"))
        .context("drawing the plot")?;
    write_bytes_atomically(&svg, plot.as_bytes())?;
    if !quiet {
        errln!("wrote {} and {}", md.display(), svg.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn small_accuracy_run_writes_table_and_plot() {
        let dir = tempfile::tempdir().unwrap();
        crate::run_args([
            "bench",
            "accuracy",
            "--out",
            dir.path().to_str().unwrap(),
            "--rays",
            "4",
            "--runs",
            "1",
            "--acne-rays",
            "20",
            "--quiet",
        ])
        .unwrap();
        let md = std::fs::read_to_string(dir.path().join("accuracy.md")).unwrap();
        assert!(md.contains("| all | production |"), "{md}");
        let svg = std::fs::read_to_string(dir.path().join("accuracy.svg")).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("Pareto"),
            "{}",
            &svg[..200.min(svg.len())]
        );
        assert!(crate::run_args(["bench", "accuracy", "--rays", "0"]).is_err());
    }
}
