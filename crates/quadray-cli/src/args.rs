//! Command-line arguments (clap derive), parsed first and validated where they are used.

use clap::{Args, Parser, Subcommand};
use quadray::render::{MAX_DEPTH, MAX_SPP};
use std::path::{Path, PathBuf};

/// The exit statuses and the environment variables, as `--help` lists them (and the README).
pub const EXIT_STATUS: &str = "\
Exit status:
  0  success; for compare, the images match
  1  the scene, an image or a file cannot be used (the message says which and where);
     for compare, the images differ
  2  a usage error: an unknown option or a value out of range; for compare, an image
     cannot be read

Environment:
  QUADRAY_CONFINE=DIR              as --confine DIR when the flag is not given
  QUADRAY_AVAILABLE_MEMORY=BYTES   the memory free for a render, in place of what the system
                                   reports (a render that needs more is refused before it starts)
  QUADRAY_SIMD=baseline            the baseline code (SSE2 on x86-64) where AVX2 code would run:
                                   the traversal, camera rays, sample points (same images);
                                   `auto`, or unset: the fastest path the CPU has";

/// Most worker threads `-t` accepts.
pub const MAX_THREADS: usize = 1024;

/// quadray: a ray tracer with clipped quadric surfaces, spheres, planes and meshes.
#[derive(Parser, Debug)]
#[command(name = "quadray", version, about, after_help = EXIT_STATUS, allow_negative_numbers = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
    /// Log what is loaded and each phase's time on stderr (-v phases, -vv every file read).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,
    /// Refuse to read or write any file outside DIR (after resolving links): for scenes from
    /// strangers. Default: the QUADRAY_CONFINE environment variable, else no confinement.
    #[arg(long, value_name = "DIR", global = true)]
    pub confine: Option<PathBuf>,
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
    #[cfg(feature = "bench")]
    Bench(crate::bench::BenchCommand),
    /// Render one quadric under the orbit camera (the seed's explorer).
    Quadric(crate::quadric_cmd::QuadricArgs),
    /// Render every quadric kind into one labelled contact sheet.
    Gallery(crate::gallery::GalleryArgs),
    /// Compare two images (PNG or EXR): RMSE, largest difference, share over a threshold, FLIP.
    Compare(crate::compare_cmd::CompareArgs),
    /// Assemble the pieces of `render --tile I/N` into one image, checking they belong together.
    Merge(crate::merge_cmd::MergeArgs),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(crate::shell::CompletionsArgs),
    /// Print the man page (roff), e.g. `quadray man > quadray.1`.
    Man,
}

/// Arguments of `quadray render`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Output image; the extension picks the format (.png or .exr). Default: the scene's
    /// `[output]` file, else the scene's name with .png, beside the scene.
    #[arg(short, long, value_name = "OUT", value_parser = parse_image_output)]
    pub output: Option<PathBuf>,
    /// Samples per pixel (overrides the scene).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Option<u32>,
    /// Adaptive sampling (overrides the scene's `[render]` choice).
    #[command(flatten)]
    pub sampling: crate::sampling_args::SamplingArgs,
    /// Resolution as WIDTHxHEIGHT (overrides the scene).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Most rays in one reflection chain, camera ray included (overrides the scene).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    pub max_depth: Option<u32>,
    /// How the checker and contour bands are sampled: `box` averages them over each sample's
    /// share of its pixel (carried through mirrors by ray cones); `none` point samples them, as
    /// POV-Ray does.
    #[arg(long, value_name = "FILTER", default_value = "box")]
    pub texture_filter: TextureFilterArg,
    /// Worker threads (default: all cores).
    #[arg(short = 't', long, value_name = "THREADS", value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Print load and BVH build times besides the final stats line.
    #[arg(long)]
    pub stats: bool,
    /// Keep the meshes' BVH compact: its leaves name their triangles instead of copying their
    /// vertices (about 30 bytes a triangle with the mesh instead of 70), for the same image
    /// traced more slowly (as the scene's `render.compact_meshes`).
    #[arg(long)]
    pub compact_meshes: bool,
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
    /// Sample set: 0 (the default) renders the same image every time; another value jitters every
    /// pixel with an unrelated pattern, for independent renders of one scene. At 1 spp every
    /// pixel is sampled at its centre, whatever the seed.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u32,
    /// Override a value of a .toml scene, as if the file said so (repeatable): `--set
    /// render.spp=64 --set camera.vfov=30 --set sphere[0].radius=0.5`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<quadray_loader::Override>,
    /// Render only a window of the image, in fractions of its width and height from the top-left
    /// corner (pbrt's --cropwindow): `--crop 0.25,0.75,0,0.5` is the middle half of the top half.
    /// Its pixels equal the whole render's; a PNG holds just the window, an EXR places it in the
    /// full frame (data window inside the display window).
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = parse_crop)]
    pub crop: Option<[f64; 4]>,
    /// Render piece I of N of the frame (I from 0) into an .exr, for `quadray merge`: one task of
    /// a job array on a render farm (docs/distributed.md).
    #[arg(long, value_name = "I/N", value_parser = crate::tiles::parse_piece, conflicts_with = "crop")]
    pub tile: Option<crate::tiles::Piece>,
    /// A turntable of N frames: frame `--frame I` turns the camera 360·I/N degrees about the
    /// vertical axis through its target; a run of # in the output becomes the frame number
    /// (`-o turn-###.png`, Blender's convention), so one task per frame writes its own file.
    #[arg(long, value_name = "N", requires = "frame", value_parser = clap::value_parser!(u32).range(1..))]
    pub orbit_frames: Option<u32>,
    /// The frame of `--orbit-frames` to render, from 0.
    #[arg(long, value_name = "I", requires = "orbit_frames")]
    pub frame: Option<u32>,
}

/// `path` with its last run of `#` replaced by `frame`, zero-padded to the run's length; `None`
/// when the file name has no `#`.
pub fn numbered_output(path: &Path, frame: u32) -> Option<PathBuf> {
    let name = path.file_name()?.to_str()?;
    let end = name.rfind('#')? + 1;
    let start = name[..end].trim_end_matches('#').len();
    let numbered = format!(
        "{}{frame:0width$}{}",
        &name[..start],
        &name[end..],
        width = end - start
    );
    Some(path.with_file_name(numbered))
}

/// Arguments of `quadray convert`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct ConvertArgs {
    /// The scene file (.toml, .obj, .gltf or .glb).
    pub scene: PathBuf,
    /// Output file: .gltf (with a .bin beside it) or .glb.
    #[arg(short, long, value_name = "OUT", value_parser = parse_gltf_output)]
    pub output: PathBuf,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Arguments of `quadray check`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct CheckArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Override a value of a .toml scene, as `render --set` does (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<quadray_loader::Override>,
    /// For a glTF file: the scene to check, as `render --gltf-scene` chooses it.
    #[arg(long, value_name = "INDEX|NAME", value_parser = parse_selector)]
    pub gltf_scene: Option<quadray_loader::Selector>,
    /// For a glTF file: the camera to check with, as `render --camera` chooses it.
    #[arg(long, value_name = "INDEX|NAME", value_parser = parse_selector)]
    pub camera: Option<quadray_loader::Selector>,
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
        parse_threads(&t.to_string()).map_err(crate::StatusError::usage)?;
        pool = pool.num_threads(t);
    }
    pool.build().context("starting the thread pool")
}

/// Parses a worker thread count, 1 to [`MAX_THREADS`].
pub fn parse_threads(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(t) if (1..=MAX_THREADS).contains(&t) => Ok(t),
        _ => Err(format!(
            "the thread count must be a whole number from 1 to {MAX_THREADS}, got \"{s}\""
        )),
    }
}

/// Parses WIDTHxHEIGHT within the renderer's limits (sides, pixel count, aspect ratio).
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got \"{s}\""))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("\"{v}\" is not a pixel count"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    quadray::render::check_resolution(w, h).map_err(|e| e.to_string())?;
    Ok((w, h))
}

/// Parses a normalised crop window `X0,X1,Y0,Y1`: fractions of the image with `0 <= X0 < X1 <= 1`
/// and the same for Y.
pub fn parse_crop(s: &str) -> Result<[f64; 4], String> {
    let values: Vec<f64> = s
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected four numbers X0,X1,Y0,Y1, got \"{s}\""))?;
    let [x0, x1, y0, y1] = <[f64; 4]>::try_from(values)
        .map_err(|_| format!("expected four numbers X0,X1,Y0,Y1, got \"{s}\""))?;
    let ordered = |a: f64, b: f64| (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) && a < b;
    if !(ordered(x0, x1) && ordered(y0, y1)) {
        return Err(format!(
            "the window must satisfy 0 <= X0 < X1 <= 1 and 0 <= Y0 < Y1 <= 1, got \"{s}\""
        ));
    }
    Ok([x0, x1, y0, y1])
}

/// Parses an output path whose extension is one of `extensions` (any case).
fn output_with(s: &str, extensions: &[&str]) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if extensions.iter().any(|e| ext.eq_ignore_ascii_case(e)) {
        Ok(path)
    } else {
        let listed: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        Err(format!("the output must end in {}", listed.join(" or ")))
    }
}

/// Parses an image output path: .png or .exr.
pub fn parse_image_output(s: &str) -> Result<PathBuf, String> {
    output_with(s, &["png", "exr"])
}

/// Parses a PNG output path.
pub fn parse_png_output(s: &str) -> Result<PathBuf, String> {
    output_with(s, &["png"])
}

/// Parses a glTF output path: .gltf or .glb.
pub fn parse_gltf_output(s: &str) -> Result<PathBuf, String> {
    output_with(s, &["gltf", "glb"])
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
        assert!(parse_resolution("0x0").is_err());
        assert!(parse_resolution("16384x1").is_err(), "aspect");
        assert!(parse_resolution("16384x16384").is_err(), "pixels");
    }

    #[test]
    fn crop_windows_parse_in_pbrt_order() {
        assert_eq!(parse_crop("0.25,0.75, 0,0.5"), Ok([0.25, 0.75, 0.0, 0.5]));
        for bad in [
            "0,1,0",
            "0,1,0,1,0",
            "0.5,0.5,0,1",
            "0,1,1,0",
            "-1,1,0,1",
            "a,b,c,d",
            "0,1,0,NaN",
        ] {
            assert!(parse_crop(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn frame_numbers_fill_the_hashes() {
        let at = |p: &str, f| numbered_output(Path::new(p), f);
        assert_eq!(
            at("out/turn-###.png", 7),
            Some(PathBuf::from("out/turn-007.png"))
        );
        assert_eq!(at("t#.exr", 1234), Some(PathBuf::from("t1234.exr")));
        assert_eq!(at("#a/turn.png", 1), None, "only the file name counts");
    }

    /// Every option that takes a value, of every subcommand, reads `-1` as a value: the error is
    /// the option's own (its range or its parse), never clap's "unexpected argument '-1'", whose
    /// tip (`-- -1`) fails too.
    #[test]
    fn negative_numbers_reach_every_options_own_check() {
        use clap::CommandFactory;
        fn walk(command: &clap::Command, path: &mut Vec<String>, checked: &mut usize) {
            for sub in command.get_subcommands() {
                path.push(sub.get_name().to_string());
                walk(sub, path, checked);
                path.pop();
            }
            for arg in command.get_arguments() {
                let Some(long) = arg.get_long() else { continue };
                if !arg.get_action().takes_values() || long == "help" {
                    continue;
                }
                let mut argv = vec!["quadray".to_string()];
                argv.extend(path.iter().cloned());
                argv.extend([format!("--{long}"), "-1".to_string()]);
                let message = match Cli::try_parse_from(&argv) {
                    Ok(_) => continue,
                    Err(e) => e.to_string(),
                };
                assert!(
                    !message.contains("unexpected argument '-1'"),
                    "{}: {message}",
                    argv.join(" ")
                );
                *checked += 1;
            }
        }
        let mut checked = 0;
        walk(&Cli::command(), &mut Vec::new(), &mut checked);
        assert!(checked > 20, "only {checked} options checked");
        let spp = Cli::try_parse_from(["quadray", "render", "s.toml", "--spp", "-1"]).unwrap_err();
        assert!(spp.to_string().contains("not in 1..="), "{spp}");
    }

    #[test]
    fn thread_counts_are_checked() {
        assert_eq!(thread_pool(Some(2)).unwrap().current_num_threads(), 2);
        assert!(thread_pool(Some(0)).is_err());
        assert!(thread_pool(Some(5000)).is_err());
    }
}

/// `--texture-filter`: how procedural textures with hard edges are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TextureFilterArg {
    /// Averaged over each sample's footprint.
    Box,
    /// Point sampled.
    None,
}
