//! `quadray convert`: write a scene (native, OBJ or glTF) as glTF 2.0 with the `QUADRAY_quadrics`
//! extension and tessellated fallbacks, so it opens in other tools and reads back into quadray.

use crate::args::ConvertArgs;
use anyhow::{Context, Result};

/// Runs the convert subcommand.
pub fn run(args: &ConvertArgs) -> Result<()> {
    // Before the (possibly long) load, and before a temporary file's name can reach a message.
    quadray_app::output::check_output_folder(&args.output)?;
    quadray_loader::confine::record_reads();
    let loaded = quadray_loader::load_any(&args.scene);
    let inputs = quadray_loader::confine::take_reads();
    let loaded = loaded?;
    // A .gltf output writes its buffer beside it: neither may replace a file the scene reads.
    let gltf = (args.output.extension()).is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
    let buffer = gltf.then(|| args.output.with_extension("bin"));
    for output in std::iter::once(args.output.clone()).chain(buffer) {
        crate::overwrite::refuse_replacing_an_input(
            "-o",
            &output,
            &inputs,
            "one of the files the scene reads",
        )?;
    }
    for note in &loaded.notes {
        if !args.quiet {
            errln!("{}", crate::warnings::note_line(note));
        }
    }
    // Validate first: a scene quadray would refuse to render is not worth exporting.
    let scene = quadray::Scene::new(loaded.description.clone())
        .with_context(|| format!("invalid scene {}", args.scene.display()))?;
    let notes = quadray_loader::export::export_gltf(&loaded, &args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    if !args.quiet {
        for note in notes {
            errln!("{}", crate::warnings::note_line(&note));
        }
        let g = &loaded.description.geometry;
        // Shapes inside prototypes are placed by instances: the world's own counts alone said
        // "0 spheres" of a scene of 65 536 instanced ones.
        let stats = scene.accel().stats(scene.geometry());
        let instanced = match stats.instances {
            0 => String::new(),
            n => format!(
                " in the world, and {} placed by {} ({})",
                crate::counted(stats.prototypes, "prototype"),
                crate::counted(n, "instance"),
                crate::counted(stats.placements, "placement")
            ),
        };
        errln!(
            "wrote {}: {}, {}, {}, {}{instanced}; {}, {}",
            args.output.display(),
            crate::counted(g.meshes.len(), "mesh"),
            crate::counted(g.quadrics.len(), "quadric"),
            crate::counted(g.spheres.len(), "sphere"),
            crate::counted(g.planes.len(), "plane"),
            crate::counted(loaded.description.lights.len(), "light"),
            crate::counted(loaded.description.materials.len(), "material")
        );
    }
    Ok(())
}
