//! Command-line arguments (clap derive), parsed first and validated where they are used.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// quadray: a ray tracer with clipped quadric surfaces, spheres, planes and meshes.
#[derive(Parser, Debug)]
#[command(version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to PNG (sRGB, clamped) or EXR (linear, scene-referred).
    Render(RenderArgs),
    /// Validate a scene without rendering it.
    Check(CheckArgs),
    /// Write a scene as glTF 2.0 (.gltf + .bin, or .glb), quadrics through the QUADRAY_quadrics extension.
    Convert(ConvertArgs),
    /// Benchmarks: speed against error of the quadric intersector.
    #[command(subcommand)]
    Bench(crate::bench::BenchCommand),
    /// Render one quadric under the orbit camera (the seed's explorer).
    Quadric(crate::quadric_cmd::QuadricArgs),
    /// Render every quadric kind into one labelled contact sheet.
    Gallery(crate::gallery::GalleryArgs),
    /// Compare two images (PNG or EXR): RMSE, largest difference, share over a threshold, FLIP.
    Compare(crate::compare_cmd::CompareArgs),
}

/// Arguments of `quadray render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output image; the extension picks the format (.png or .exr).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Samples per pixel (overrides the scene).
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    /// Resolution as WIDTHxHEIGHT (overrides the scene).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Most rays in one reflection chain, camera ray included (overrides the scene).
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(short = 't', long, value_name = "THREADS")]
    pub threads: Option<usize>,
    /// Print load and BVH build times besides the final stats line.
    #[arg(long)]
    pub stats: bool,
    /// Passes written into an EXR output beside the beauty image, comma-separated (Blender
    /// channel names; from the first hit of each pixel's first sample).
    #[arg(long, value_name = "PASSES", value_delimiter = ',')]
    pub aov: Vec<crate::passes::Pass>,
    /// Write the EXR beauty pass as half floats (passes stay f32).
    #[arg(long)]
    pub half: bool,
    /// The pass a PNG output shows.
    #[arg(long, value_name = "PASS", default_value = "combined")]
    pub pass: crate::passes::Pass,
    /// For a glTF file: the scene to render, by index or name (default: the file's default scene).
    #[arg(long, value_name = "INDEX|NAME", value_parser = parse_selector)]
    pub gltf_scene: Option<quadray_loader::Selector>,
    /// For an OBJ or glTF file: the file's camera to use, by index or name (default: its first).
    #[arg(long, value_name = "INDEX|NAME", value_parser = parse_selector)]
    pub camera: Option<quadray_loader::Selector>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Arguments of `quadray convert`.
#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// The scene file (.toml, .obj, .gltf or .glb).
    pub scene: PathBuf,
    /// Output file: .gltf (with a .bin beside it) or .glb.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Arguments of `quadray check`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// The scene file.
    pub scene: PathBuf,
}

/// Parses a scene or camera choice: a number is an index, anything else a name.
pub fn parse_selector(s: &str) -> Result<quadray_loader::Selector, String> {
    Ok(match s.parse::<usize>() {
        Ok(i) => quadray_loader::Selector::Index(i),
        Err(_) => quadray_loader::Selector::Name(s.to_string()),
    })
}

/// The worker pool a `--threads` argument asks for (all cores when `None`), or why it cannot be made.
pub fn thread_pool(threads: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    use anyhow::Context;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        anyhow::ensure!(
            (1..=1024).contains(&t),
            "thread count must be between 1 and 1024, got {t}"
        );
        pool = pool.num_threads(t);
    }
    pool.build().context("starting the thread pool")
}

/// Parses `640x480`.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got \"{s}\""))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("\"{v}\" is not a pixel count"))
    };
    Ok((parse(w)?, parse(h)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_parses_and_rejects_garbage() {
        assert_eq!(parse_resolution("1280x720"), Ok((1280, 720)));
        assert!(parse_resolution("1280").is_err());
        assert!(parse_resolution("ax2").is_err());
        assert!(parse_resolution("-5x2").is_err());
    }

    #[test]
    fn thread_counts_are_checked() {
        assert_eq!(thread_pool(Some(2)).unwrap().current_num_threads(), 2);
        assert!(thread_pool(Some(0)).is_err());
        assert!(thread_pool(Some(5000)).is_err());
    }
}
