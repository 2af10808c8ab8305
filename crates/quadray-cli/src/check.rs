//! `quadray check`: load and validate a scene without rendering it.

use crate::args::CheckArgs;
use anyhow::{Context, Result};
use quadray::Scene;

/// Runs the check subcommand: exit status 0 when the scene is valid, with a summary on stdout.
pub fn run(args: &CheckArgs) -> Result<()> {
    let loaded = crate::args::load_scene_for(&args.scene, &args.set, &Default::default(), None)?;
    for note in &loaded.notes {
        eprintln!("note: {note}");
    }
    let settings = loaded.settings;
    for (i, q) in loaded.description.geometry.quadrics.iter().enumerate() {
        if !q.is_visible() {
            eprintln!(
                "warning: {}: quadric[{i}] ({}) does not reach into its clip box: nothing of it will show",
                args.scene.display(),
                q.class()
            );
        }
    }
    let scene = Scene::new(loaded.description)
        .with_context(|| format!("invalid scene {}", args.scene.display()))?;
    for warning in
        crate::warnings::scene_warnings(&args.scene, &scene, settings.width, settings.height)
    {
        eprintln!("warning: {warning}");
    }
    let g = scene.geometry();
    let triangles: usize = g.meshes.iter().map(|m| m.triangle_count()).sum();
    println!(
        "{}: ok: {} spheres, {} planes, {} quadrics, {} meshes ({} triangles), {} lights, {} materials; {}x{}, {} spp, max depth {}",
        args.scene.display(),
        g.spheres.len(),
        g.planes.len(),
        g.quadrics.len(),
        g.meshes.len(),
        triangles,
        scene.lights().len(),
        scene.materials().len(),
        settings.width,
        settings.height,
        settings.spp,
        settings.max_depth
    );
    println!("{}", structure_line(&scene));
    Ok(())
}

/// What the scene stores against what it stands for once instances are expanded, and the
/// acceleration structure's memory per level: for `check` and `render --stats`.
pub(crate) fn structure_line(scene: &Scene) -> String {
    let s = scene.accel().stats(scene.geometry());
    format!(
        "structure: {} prototypes, {} instances ({} placements); {} shapes stored ({} triangles), {} triangles instanced; BVH bottom level {:.1} MB, top level {:.3} MB",
        s.prototypes,
        s.instances,
        s.placements,
        s.primitives_stored,
        s.triangles_stored,
        s.triangles_instanced,
        s.bottom_bytes as f64 / 1e6,
        s.top_bytes as f64 / 1e6,
    )
}
