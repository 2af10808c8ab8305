//! `quadray check`: load and validate a scene without rendering it.

use crate::args::CheckArgs;
use anyhow::{Context, Result};
use quadray::Scene;

/// Runs the check subcommand: exit status 0 when the scene is valid, with a summary on stdout.
pub fn run(args: &CheckArgs) -> Result<()> {
    let loaded = quadray_loader::load_any(&args.scene)?;
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
    Ok(())
}
