//! `quadray render`: load, validate, render in parallel, write, report.

use crate::args::RenderArgs;
use crate::output::{Format, check_writable, write_film};
use crate::passes::{ExrFrame, Pass, selection_of, write_exr, write_png_pass};
use crate::progress::RowBar;
use crate::{StatusError, usage_ensure};
use anyhow::{Context, Result};
use quadray::{PixelWindow, Scene};
use std::time::Instant;

/// Runs the render subcommand.
pub fn run(args: &RenderArgs) -> Result<()> {
    // An output given on the command line is checked before the (possibly long) load.
    if let Some(output) = &args.output {
        pass_selection(args, check_writable(output)?)?;
    }
    let start = Instant::now();
    let options = quadray_loader::ImportOptions {
        scene: args.gltf_scene.clone(),
        ..Default::default()
    };
    let loaded = crate::args::load_scene_for(
        &args.scene,
        &args.set,
        &options,
        args.camera.as_ref(),
        args.res,
    )?;
    log::info!(
        "loaded {} in {:.3} s",
        args.scene.display(),
        start.elapsed().as_secs_f64()
    );
    // -o, else the scene's [output], else the scene's name with .png beside it.
    let output = args
        .output
        .clone()
        .or_else(|| loaded.output.clone())
        .unwrap_or_else(|| crate::args::default_output(&args.scene));
    let format = check_writable(&output)?;
    let selection = pass_selection(args, format)?;
    for note in &loaded.notes {
        if !args.quiet {
            eprintln!("{}", crate::warnings::note_line(note));
        }
    }
    let mut s = loaded.settings;
    if let Some((w, h)) = args.res {
        (s.width, s.height) = (w, h);
    }
    s.spp = args.spp.unwrap_or(s.spp);
    s.max_depth = args.max_depth.unwrap_or(s.max_depth);
    let mut settings = s.render_settings();
    settings.seed = args.seed;
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
    settings.validate()?;
    let loaded_at = Instant::now();

    let pool = crate::args::thread_pool(args.threads)?;
    let scene = pool
        .install(|| Scene::new(loaded.description))
        .with_context(|| format!("invalid scene {}", args.scene.display()))?;
    crate::check::log_built(&scene, loaded_at);
    let built_at = Instant::now();
    if !args.quiet {
        crate::warnings::print(
            &args.scene,
            &scene,
            &loaded.material_names,
            settings.width,
            settings.height,
        );
    }

    let bar = RowBar::new(settings.window().height(), args.quiet);
    let cpu_start = cpu_time::ProcessTime::try_now().ok();
    let (rendered, aovs) =
        pool.install(|| quadray::render_with_aovs(&scene, &settings, selection, &bar))?;
    bar.finish();
    let render_time = built_at.elapsed();
    let render_cpu = cpu_start.and_then(|t| t.try_elapsed().ok());
    log::info!(
        "rendered {} rows of {} spp on {} threads in {:.3} s",
        settings.window().height(),
        settings.spp,
        pool.current_num_threads(),
        render_time.as_secs_f64()
    );
    let write_start = Instant::now();
    match format {
        Format::Exr => write_exr(
            &rendered.film,
            aovs.as_ref(),
            args.half,
            &ExrFrame::of(&settings),
            &output,
        )?,
        Format::Png if args.pass != Pass::Combined => {
            let planes = scene.geometry().plane_object_indices();
            write_png_pass(args.pass, &rendered.film, aovs.as_ref(), &planes, &output)?;
            if args.pass == Pass::Depth
                && !args.quiet
                && let Some((near, far)) = aovs
                    .as_ref()
                    .and_then(|a| crate::passes::depth_display_range(a.samples(), &planes))
            {
                eprintln!(
                    "depth shown from {near:.4} (white, the nearest hit) to {far:.4} (dark grey, \
                     the farthest hit on anything but a plane; farther plane pixels clamp), \
                     misses black"
                );
            }
        }
        _ => write_film(&rendered.film, &output)?,
    }
    log::info!(
        "wrote {} in {:.3} s",
        output.display(),
        write_start.elapsed().as_secs_f64()
    );

    if !args.quiet {
        let c = rendered.counts;
        let secs = render_time.as_secs_f64();
        if args.stats {
            let cpu =
                render_cpu.map_or("unknown".to_string(), |d| format!("{:.3}", d.as_secs_f64()));
            eprintln!(
                "load {:.3} s, BVH build {:.3} s ({} bounded primitives, {:.1} MB), traversal {}, \
                 threads {}, render CPU {cpu} s",
                (loaded_at - start).as_secs_f64(),
                (built_at - loaded_at).as_secs_f64(),
                scene.accel().bounded_count(),
                scene.accel().memory_bytes() as f64 / 1e6,
                scene.accel().traversal_path(),
                pool.current_num_threads(),
            );
            eprintln!("{}", crate::check::structure_line(&scene));
        }
        let window = settings.window();
        let size = match settings.crop {
            Some(_) => format!(
                "{}x{} window at ({}, {}) of {}x{}",
                window.width(),
                window.height(),
                window.x0,
                window.y0,
                settings.width,
                settings.height
            ),
            None => format!("{}x{}", settings.width, settings.height),
        };
        eprintln!(
            "{size}, {} spp: {} camera + {} shadow + {} reflection rays in {:.3} s ({:.2} Mrays/s) -> {}",
            settings.spp,
            c.camera,
            c.shadow,
            c.reflection,
            secs,
            c.total() as f64 / secs.max(1e-9) / 1e6,
            output.display()
        );
    }
    Ok(())
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
