//! `quadray check`: load and validate a scene without rendering it.

use crate::args::CheckArgs;
use crate::counted;
use anyhow::{Context, Result};
use quadray::Scene;
use std::time::Instant;

/// How a scene's `[render]` table samples its pixels, in a few words.
fn sampling_text(settings: &quadray_loader::SceneSettings) -> String {
    match (&settings.adaptive, &settings.antialias) {
        (Some(a), _) => {
            let goal = match (a.rule, a.target_error > 0.0) {
                (_, false) => "adaptive".to_string(),
                (quadray::adaptive::ErrorRule::Image, true) => {
                    format!("adaptive to image error {}", a.target_error)
                }
                (quadray::adaptive::ErrorRule::Pixel, true) => {
                    format!("adaptive to pixel error {}", a.target_error)
                }
            };
            format!("{goal}, {}..{} spp", a.min_spp, a.max_spp)
        }
        (None, Some(aa)) => format!(
            "{} spp, {} where a pixel differs from a neighbour by more than {}",
            settings.spp,
            aa.samples(settings.spp),
            aa.threshold
        ),
        (None, None) => format!("{} spp", settings.spp),
    }
}

/// Runs the check subcommand: exit status 0 when the scene is valid, with a summary on stdout.
pub fn run(args: &CheckArgs) -> Result<()> {
    let start = Instant::now();
    quadray_loader::confine::record_reads();
    let options = quadray_loader::ImportOptions {
        scene: args.gltf_scene.clone(),
        ..Default::default()
    };
    let camera = args.camera.as_ref();
    let loaded = quadray_app::scene_file::load(&args.scene, &args.set, &options, camera, None)?;
    let reads = quadray_loader::confine::take_reads();
    log::info!(
        "loaded {} in {:.3} s",
        args.scene.display(),
        start.elapsed().as_secs_f64()
    );
    for note in &loaded.notes {
        errln!("{}", crate::warnings::note_line(note));
    }
    let settings = loaded.settings;
    let loaded_output = loaded.output;
    let built_at = Instant::now();
    let scene = Scene::build(loaded.description, settings.build_options())
        .with_context(|| format!("invalid scene {}", args.scene.display()))?;
    log_built(&scene, built_at);
    crate::warnings::print(
        &args.scene,
        &scene,
        &loaded.material_names,
        settings.width,
        settings.height,
    );
    outln!(
        "{}: ok: {}; {}x{}, {}, max depth {}",
        args.scene.display(),
        contents_line(&scene),
        settings.width,
        settings.height,
        sampling_text(&settings),
        settings.max_depth
    )?;
    outln!("{}", structure_line(&scene))?;
    for file in reads {
        outln!("reads: {}", file.display())?;
    }
    let output =
        loaded_output.unwrap_or_else(|| quadray_app::scene_file::default_output(&args.scene));
    match quadray_loader::confine::check_write(&output) {
        Ok(()) => outln!(
            "writes: {} (unless -o names another file)",
            output.display()
        )?,
        Err(e) => outln!("writes: {} (refused: {e})", output.display())?,
    }
    Ok(())
}

/// What a scene holds, counted: shapes by kind, lights, materials.
pub(crate) fn contents_line(scene: &Scene) -> String {
    let g = scene.geometry();
    let triangles: usize = g.meshes.iter().map(|m| m.triangle_count()).sum();
    format!(
        "{}, {}, {}, {} ({}), {}, {}",
        counted(g.spheres.len(), "sphere"),
        counted(g.planes.len(), "plane"),
        counted(g.quadrics.len(), "quadric"),
        counted(g.meshes.len(), "mesh"),
        counted(triangles, "triangle"),
        counted(scene.lights().len(), "light"),
        counted(scene.materials().len(), "material"),
    )
}

/// Logs (at `-v`) that the scene was built, since `since`, with what it holds.
pub(crate) fn log_built(scene: &Scene, since: Instant) {
    log::info!(
        "built the scene and its BVH in {:.3} s: {}",
        since.elapsed().as_secs_f64(),
        contents_line(scene)
    );
    log::info!("{}", structure_line(scene));
}

/// What the scene stores against what it stands for once instances are expanded, and the
/// acceleration structure's memory per level: for `check` and `render --stats`.
pub(crate) fn structure_line(scene: &Scene) -> String {
    let s = scene.accel().stats(scene.geometry());
    format!(
        "structure: {}, {} ({}); {} stored ({}), {} instanced; BVH bottom level {:.1} MB, top level {:.3} MB",
        counted(s.prototypes, "prototype"),
        counted(s.instances, "instance"),
        counted(s.placements, "placement"),
        counted(s.primitives_stored, "shape"),
        counted(s.triangles_stored, "triangle"),
        counted(s.triangles_instanced, "triangle"),
        s.bottom_bytes as f64 / 1e6,
        s.top_bytes as f64 / 1e6,
    )
}
