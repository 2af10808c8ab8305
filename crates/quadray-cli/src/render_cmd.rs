//! `quadray render`: load, validate, render in parallel, write, report.

use crate::args::RenderArgs;
use crate::exr_file::{ExrCamera, ExrFrame, ExrPart, write_exr, write_exr_parts};
use crate::output::{Format, check_writable, write_film};
use crate::passes::{Pass, selection_of, write_png_pass};
use crate::progress::RowBar;
use crate::tiles::{Piece, piece_bands};
use crate::{StatusError, usage_ensure};
use anyhow::{Context, Result};
use quadray::{
    AovSelection, Aovs, PixelWindow, RayCounts, RenderSettings, Rendered, SamplingStats, Scene,
};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// EXR attribute describing a piece of a frame in three lines: `I/N` (which piece of how many),
/// `scene: HASH` (a hash of the scene's inputs) and `settings: TEXT` (the render settings every
/// piece of a frame shares). One attribute, because the EXR writer stores a header's custom
/// attributes in hash-map order, which would make two renders of a piece differ in bytes.
pub const PIECE: &str = "quadray.piece";

/// The [`PIECE`] attribute's value.
pub fn piece_attribute(piece: Piece, scene: &str, settings: &str) -> String {
    format!("{piece}\nscene: {scene}\nsettings: {settings}")
}

/// Everything decided before rendering.
struct Job {
    settings: RenderSettings,
    output: PathBuf,
    format: Format,
    selection: AovSelection,
    loaded_in: Duration,
    /// How the scene's BVH is built (the scene's choice, or `--compact-meshes`).
    build_options: quadray::BuildOptions,
    /// The files the scene read (its own first), which a piece's scene hash covers.
    inputs: Vec<PathBuf>,
}

/// Runs the render subcommand.
pub fn run(args: &RenderArgs) -> Result<()> {
    let (loaded, job) = prepare(args)?;
    let settings = job.settings;
    // A piece renders its bands of rows; anything else the settings' window.
    let windows = match args.tile {
        Some(piece) => piece_bands(piece, settings.width, settings.height),
        None => vec![settings.window()],
    };
    check_memory(args, &settings, job.selection, &windows)?;
    let pool = crate::args::thread_pool(args.threads)?;
    let build_start = Instant::now();
    let scene = pool
        .install(|| Scene::build(loaded.description, job.build_options))
        .with_context(|| format!("invalid scene {}", args.scene.display()))?;
    crate::check::log_built(&scene, build_start);
    let built_in = build_start.elapsed();
    if !args.quiet {
        let names = &loaded.material_names;
        crate::warnings::print(&args.scene, &scene, names, settings.width, settings.height);
    }
    let render_start = Instant::now();
    let cpu_start = cpu_time::ProcessTime::try_now().ok();
    let parts = render_windows(args, &pool, &scene, &settings, &windows, job.selection)?;
    let render_time = render_start.elapsed();
    let render_cpu = cpu_start.and_then(|t| t.try_elapsed().ok());
    let rows: u32 = windows.iter().map(|w| w.height()).sum();
    log::info!(
        "rendered {} of {} spp on {} in {:.3} s",
        crate::counted(rows, "row"),
        settings.spp,
        crate::counted(pool.current_num_threads(), "thread"),
        render_time.as_secs_f64()
    );
    let write_start = Instant::now();
    write_output(args, &job, &scene, &parts)?;
    log::info!(
        "wrote {} in {:.3} s",
        job.output.display(),
        write_start.elapsed().as_secs_f64()
    );
    if !args.quiet {
        if args.stats {
            let cpu =
                render_cpu.map_or("unknown".to_string(), |d| format!("{:.3}", d.as_secs_f64()));
            errln!(
                "load {:.3} s, BVH build {:.3} s ({} bounded primitives, {:.1} MB), traversal {}, \
                 kernels {}, threads {}, render CPU {cpu} s",
                job.loaded_in.as_secs_f64(),
                built_in.as_secs_f64(),
                scene.accel().bounded_count(),
                scene.accel().memory_bytes() as f64 / 1e6,
                scene.accel().traversal_path(),
                // The four-ray quadric test and the sample points take this path whatever the
                // BVH's (analytic scenes traverse on the baseline).
                quadray::simd::simd_path(),
                pool.current_num_threads(),
            );
            errln!("{}", crate::check::structure_line(&scene));
        }
        let mut counts = RayCounts::default();
        for (rendered, _) in &parts {
            counts += rendered.counts;
        }
        let windows: Vec<(SamplingStats, u64)> = parts
            .iter()
            .map(|(r, _)| (r.sampling, r.film.pixels().len() as u64))
            .collect();
        let sampling = SamplingStats::merged(&windows).context("nothing was rendered")?;
        errln!(
            "{}",
            stats_line(
                args,
                &settings,
                rows,
                counts,
                &sampling,
                render_time,
                &job.output
            )
        );
    }
    Ok(())
}

/// Loads the scene and settles the settings, the output and the passes, refusing what cannot
/// work before any rendering.
fn prepare(args: &RenderArgs) -> Result<(quadray_loader::LoadedScene, Job)> {
    // An output given on the command line is checked before the (possibly long) load.
    if let Some(output) = &args.output {
        pass_selection(args, check_writable(output)?)?;
    }
    let start = Instant::now();
    let options = quadray_loader::ImportOptions {
        scene: args.gltf_scene.clone(),
        ..Default::default()
    };
    // The files the scene reads (its own, includes, meshes, textures), which the output must
    // not replace.
    quadray_loader::confine::record_reads();
    let loaded = quadray_app::scene_file::load(
        &args.scene,
        &args.set,
        &options,
        args.camera.as_ref(),
        args.res,
    );
    let inputs = quadray_loader::confine::take_reads();
    let mut loaded = loaded?;
    let loaded_in = start.elapsed();
    log::info!(
        "loaded {} in {:.3} s",
        args.scene.display(),
        loaded_in.as_secs_f64()
    );
    // -o, else the scene's [output], else the scene's name with .png beside it.
    let named_by_scene = args.output.is_none() && loaded.output.is_some();
    let mut output = args
        .output
        .clone()
        .or_else(|| loaded.output.clone())
        .unwrap_or_else(|| quadray_app::scene_file::default_output(&args.scene));
    if let (Some(frames), Some(frame)) = (args.orbit_frames, args.frame) {
        usage_ensure(
            frame < frames,
            &format!(
                "--frame {frame}: a turntable of {frames} frames has frames 0 to {}",
                frames - 1
            ),
        )?;
        output = crate::args::numbered_output(&output, frame).ok_or_else(|| {
            StatusError::usage(format!(
                "--orbit-frames: the output {} needs a run of # for the frame number \
                 (e.g. turn-###.png), or every frame would overwrite the last",
                output.display()
            ))
        })?;
        let camera = &mut loaded.description.camera;
        *camera = camera.orbited(360.0 * frame as f64 / frames as f64);
    }
    // An output the scene names ([output] file) is checked only now: say where it came from.
    let format = check_writable(&output).with_context(|| {
        if named_by_scene {
            format!(
                "the output {} that {}'s [output] file names",
                output.display(),
                args.scene.display()
            )
        } else {
            format!("the output {}", output.display())
        }
    })?;
    crate::overwrite::refuse_replacing_an_input(
        "the output",
        &output,
        &inputs,
        "one of the files the scene reads",
    )?;
    let selection = pass_selection(args, format)?;
    if !args.quiet {
        for note in &loaded.notes {
            errln!("{}", crate::warnings::note_line(note));
        }
    }
    // --res is already in the loaded settings: the loader needed it to frame a camera-less scene.
    let mut s = loaded.settings;
    s.spp = args.spp.unwrap_or(s.spp);
    s.max_depth = args.max_depth.unwrap_or(s.max_depth);
    s.adaptive = args.sampling.resolve(args.spp, s.adaptive)?;
    s.antialias = (args.sampling).resolve_antialias(s.spp, &mut s.adaptive, s.antialias)?;
    let mut settings = s.render_settings();
    s.compact_meshes |= args.compact_meshes;
    let build_options = s.build_options();
    settings.seed = args.seed;
    settings.texture_filter = args.texture_filter == crate::args::TextureFilterArg::Box;
    if let Some(crop) = args.crop {
        let window = PixelWindow::from_normalized(crop, settings.width, settings.height)
            .ok_or_else(|| {
                StatusError::usage(format!(
                    "--crop {}: the window holds the top-left corner of no pixel of the {}x{} image \
                     (the pixels a window covers)",
                    crop.map(|v| v.to_string()).join(","),
                    settings.width,
                    settings.height
                ))
            })?;
        settings.crop = Some(window);
    }
    if let Some(piece) = args.tile {
        check_piece(piece, format, &settings)?;
    }
    settings.validate()?;
    let job = Job {
        settings,
        output,
        format,
        selection,
        loaded_in,
        build_options,
        inputs,
    };
    Ok((loaded, job))
}

/// Refuses a `--tile` that cannot make a piece: a PNG output, or more pieces than rows.
fn check_piece(piece: Piece, format: Format, settings: &RenderSettings) -> Result<()> {
    usage_ensure(
        format == Format::Exr,
        "--tile writes a piece as an .exr file (`quadray merge` assembles the pieces into a PNG or EXR)",
    )?;
    if piece.count > settings.height {
        return Err(StatusError::usage(format!(
            "--tile {piece}: the {}-row image cannot be cut into {} pieces",
            settings.height, piece.count
        ))
        .into());
    }
    Ok(())
}

/// Renders each window of the frame in turn (each in parallel over its rows).
fn render_windows(
    args: &RenderArgs,
    pool: &rayon::ThreadPool,
    scene: &Scene,
    settings: &RenderSettings,
    windows: &[PixelWindow],
    selection: AovSelection,
) -> Result<Vec<(Rendered, Option<Aovs>)>> {
    // Anti-aliasing by contrast reports each row twice: its first samples, then its refinement.
    let passes = if settings.antialias.is_some() { 2 } else { 1 };
    let rows: u32 = windows.iter().map(|w| w.height()).sum();
    let bar = RowBar::new(passes * rows, args.quiet);
    let mut parts = Vec::with_capacity(windows.len());
    for window in windows {
        let settings = RenderSettings {
            crop: Some(*window),
            ..*settings
        };
        parts.push(pool.install(|| quadray::render_with_aovs(scene, &settings, selection, &bar))?);
    }
    bar.finish();
    Ok(parts)
}

/// Refuses a render whose pixels need more memory than the machine has free
/// ([`quadray::pixel_memory`] against [`quadray_app::memory::available_bytes`]): the process
/// would be killed, or aborted by a failed allocation, part way instead. A malformed
/// `QUADRAY_AVAILABLE_MEMORY` is a usage error, as a bad `QUADRAY_CONFINE` is.
fn check_memory(
    args: &RenderArgs,
    settings: &RenderSettings,
    selection: AovSelection,
    windows: &[PixelWindow],
) -> Result<()> {
    use quadray_app::memory::{AVAILABLE_MEMORY_VAR, available_bytes, human_bytes};
    let available = available_bytes().map_err(|e| StatusError::usage(e.to_string()))?;
    let Some(available) = available else {
        return Ok(());
    };
    // The windows render one after another and are written together: every window's film and
    // passes, and the largest window's working memory.
    let memory: Vec<_> = (windows.iter())
        .map(|&w| quadray::pixel_memory(settings, selection, w))
        .collect();
    let kept: u64 = memory.iter().map(|m| m.kept).sum();
    let needed = kept.saturating_add(memory.iter().map(|m| m.working).max().unwrap_or(0));
    if needed <= available {
        return Ok(());
    }
    let pixels: u64 = (windows.iter())
        .map(|w| u64::from(w.width()) * u64::from(w.height()))
        .sum();
    let (kind, uniformly) = match settings.adaptive {
        Some(_) => ("an adaptive render", ", or sample it uniformly (`--spp`)"),
        None => ("a render", ""),
    };
    Err(anyhow::anyhow!(
        "{kind} of {pixels} pixels needs about {} for them ({} bytes a pixel{}), and {} is free \
         ({AVAILABLE_MEMORY_VAR} overrides what the system says): render the image in pieces \
         (`--tile I/N`, then `quadray merge`) or a window (`--crop`), lower the resolution{}",
        human_bytes(needed),
        needed / pixels.max(1),
        if selection.any() {
            ", with its passes"
        } else {
            ""
        },
        human_bytes(available),
        uniformly,
    ))
    .context(format!("cannot render {}", args.scene.display()))
}

/// Writes the rendered windows: one piece's bands, or one image (EXR, PNG, or a PNG pass).
fn write_output(
    args: &RenderArgs,
    job: &Job,
    scene: &Scene,
    parts: &[(Rendered, Option<Aovs>)],
) -> Result<()> {
    let (settings, output) = (&job.settings, &job.output);
    if let Some(piece) = args.tile {
        let exr_parts: Vec<ExrPart> = parts
            .iter()
            .map(|(r, a)| ExrPart {
                film: &r.film,
                aovs: a.as_ref(),
                window: r.window,
            })
            .collect();
        let settings_text = settings_text(settings, job.selection, args.half);
        let attributes = [(
            PIECE,
            piece_attribute(piece, &scene_hash(args, &job.inputs)?, &settings_text),
        )];
        let camera = ExrCamera::of(scene.camera(), settings.width, settings.height)?;
        let frame = (settings.width, settings.height, Some(camera));
        return write_exr_parts(&exr_parts, args.half, frame, &attributes, output);
    }
    let (rendered, aovs) = &parts[0];
    match job.format {
        Format::Exr => write_exr(
            &rendered.film,
            aovs.as_ref(),
            args.half,
            &ExrFrame::of(settings, scene.camera())?,
            output,
        ),
        Format::Png if args.pass != Pass::Combined => {
            let planes = scene.geometry().plane_object_indices();
            write_png_pass(args.pass, &rendered.film, aovs.as_ref(), &planes, output)?;
            if args.pass == Pass::Depth
                && !args.quiet
                && let Some((near, far)) = aovs
                    .as_ref()
                    .and_then(|a| crate::passes::depth_display_range(a.samples(), &planes))
            {
                errln!(
                    "depth shown from {near:.4} (white, the nearest hit) to {far:.4} (dark grey, \
                     the farthest hit on anything but a plane; farther plane pixels clamp), \
                     misses black"
                );
            }
            Ok(())
        }
        Format::Png => write_film(&rendered.film, output),
    }
}

/// Identifies what a piece was rendered from: the bytes of every file the scene read (`inputs`,
/// the scene file first, then its meshes, includes and textures), and every command-line choice
/// that changes the scene (overrides, the glTF scene, the camera, the turntable frame).
fn scene_hash(args: &RenderArgs, inputs: &[PathBuf]) -> Result<String> {
    let mut files = String::new();
    for input in inputs {
        let hash = crate::tiles::fnv1a_file_hex(input)
            .with_context(|| format!("reading {} again to identify it", input.display()))?;
        files.push_str(&hash);
    }
    let choices = format!(
        "{:?} {:?} {:?} {:?} {:?}",
        args.set.iter().map(ToString::to_string).collect::<Vec<_>>(),
        args.gltf_scene,
        args.camera,
        args.orbit_frames,
        args.frame
    );
    Ok(crate::tiles::fnv1a_hex(&[
        files.as_bytes(),
        choices.as_bytes(),
    ]))
}

/// The settings every piece of one frame must share, as text: every setting that changes a
/// pixel (quadray's version included: two versions may render a pixel differently).
fn settings_text(settings: &RenderSettings, selection: AovSelection, half: bool) -> String {
    let sampling = match (&settings.adaptive, &settings.antialias) {
        (None, None) => format!("spp {}", settings.spp),
        (None, Some(aa)) => format!(
            "spp {}, anti-aliased by contrast above {} with {} spp",
            settings.spp,
            aa.threshold,
            aa.samples(settings.spp)
        ),
        (Some(a), _) => format!(
            "adaptive: {:?} rule, target error {}, spp {}..{}, time limit {:?}, spp budget {:?}",
            a.rule, a.target_error, a.min_spp, a.max_spp, a.time_limit, a.spp_budget
        ),
    };
    format!(
        "quadray {}; {}x{}; {sampling}; max depth {}; min throughput {}; seed {}; \
         texture filter {}; passes {}; half {half}",
        env!("CARGO_PKG_VERSION"),
        settings.width,
        settings.height,
        settings.whitted.max_depth,
        settings.whitted.min_throughput,
        settings.seed,
        if settings.texture_filter { "on" } else { "off" },
        crate::passes::names_of(selection),
    )
}

/// The final line: what was rendered, the rays by kind, the time and the output.
fn stats_line(
    args: &RenderArgs,
    settings: &RenderSettings,
    rows: u32,
    c: RayCounts,
    sampling: &SamplingStats,
    time: Duration,
    output: &std::path::Path,
) -> String {
    let window = settings.window();
    let size = match (args.tile, settings.crop) {
        (Some(piece), _) => format!(
            "piece {piece} ({rows} of {} rows) of {}x{}",
            settings.height, settings.width, settings.height
        ),
        (None, Some(_)) => format!(
            "{}x{} window at ({}, {}) of {}x{}",
            window.width(),
            window.height(),
            window.x0,
            window.y0,
            settings.width,
            settings.height
        ),
        (None, None) => format!("{}x{}", settings.width, settings.height),
    };
    let secs = time.as_secs_f64();
    let refraction = if c.refraction > 0 {
        format!(" + {} refraction", c.refraction)
    } else {
        String::new()
    };
    let untraced = if c.untraced_camera > 0 {
        format!(
            " ({} in tiles seeing nothing, not traced, but counted in the rate)",
            c.untraced_camera
        )
    } else {
        String::new()
    };
    format!(
        "{size}, {}: {} camera{untraced} + {} shadow + {} reflection{refraction} rays in {secs:.3} s ({:.2} Mrays/s) -> {}",
        sampling.summary(),
        c.camera,
        c.shadow,
        c.reflection,
        c.total() as f64 / secs.max(1e-9) / 1e6,
        output.display()
    )
}

/// The passes to compute, checked against the output format before any work is done.
fn pass_selection(args: &RenderArgs, format: Format) -> Result<quadray::AovSelection> {
    match format {
        Format::Exr => {
            usage_ensure(
                args.pass == Pass::Combined,
                "--pass is for PNG output; an EXR takes its passes from --aov",
            )?;
            usage_ensure(
                !args.aov.contains(&Pass::Combined),
                "--aov combined: the beauty image is always written; list only the extra passes",
            )?;
            Ok(selection_of(&args.aov))
        }
        Format::Png => {
            usage_ensure(
                args.aov.is_empty(),
                "--aov needs an .exr output; a PNG shows one pass, chosen with --pass",
            )?;
            usage_ensure(!args.half, "--half is for EXR output")?;
            Ok(args.pass.selection())
        }
    }
}
