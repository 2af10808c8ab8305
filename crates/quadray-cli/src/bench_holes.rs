//! `quadray bench holes`: hole maps of hard quadric scenes, one primary ray per pixel, every
//! intersector variant against the exact oracle ([`quadray_bench::holes`]). Writes `holes.md`
//! (the counts) and, per scene, `holes-<scene>-oracle.png` and `holes-<scene>-<variant>.png`.

use crate::args::parse_resolution;
use crate::output::{write_bytes_atomically, write_rgb8_png};
use anyhow::{Context, Result};
use clap::Args;
use quadray::Scene;
use quadray_bench::holes::{self, HoleScene, SceneHoles};
use quadray_bench::variants::Variant;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Resolution of the built-in scenes (their row of quadrics is three times wider than tall).
pub const BUILTIN_RES: (u32, u32) = (540, 180);

/// The scenes mapped when none is named.
pub const DEFAULT_SCENES: [&str; 4] = [
    "far-1e7",
    "moved-1e6",
    "scenes/paraboloid-grazing.toml",
    "scenes/cone-apex.toml",
];

/// Arguments of `quadray bench holes`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct HolesArgs {
    /// Directory for holes.md and the PNGs; created if missing.
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// Scenes, comma-separated: the built-in far-1e7 and moved-1e6, or scene files (.toml) made
    /// of quadrics only (default: both built-ins, scenes/paraboloid-grazing.toml and
    /// scenes/cone-apex.toml).
    #[arg(long = "scene", value_name = "NAME|FILE", value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Resolution of every scene (default: 540x180 for the built-ins, a scene file's own).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Worker threads (default: all cores).
    #[arg(short = 't', long, value_name = "THREADS")]
    pub threads: Option<usize>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// A built-in scene by name, or a scene file, at `res` if given.
pub fn hole_scene(name: &str, res: Option<(u32, u32)>) -> Result<HoleScene> {
    let (w, h) = res.unwrap_or(BUILTIN_RES);
    match name {
        "far-1e7" => Ok(holes::far(w, h)),
        "moved-1e6" => Ok(holes::moved(w, h)),
        _ => {
            let path = Path::new(name);
            let loaded = quadray_loader::load_any(path).with_context(|| {
                format!("\"{name}\" is neither a built-in scene (far-1e7, moved-1e6) nor a readable scene file")
            })?;
            let (w, h) = res.unwrap_or((loaded.settings.width, loaded.settings.height));
            let scene = Scene::new(loaded.description)
                .with_context(|| format!("invalid scene {}", path.display()))?;
            let stem = path
                .file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
            Ok(HoleScene {
                name: stem,
                about: format!("scene file {}", path.display()),
                scene,
                width: w,
                height: h,
            })
        }
    }
}

/// File-name form of a variant's name (`production+newton` → `production-newton`).
pub fn file_name(variant: Variant) -> String {
    variant.name().replace('+', "-")
}

/// The report: what was mapped, the colour key, the table and the images.
pub fn markdown(scenes: &[SceneHoles]) -> String {
    let mut s = String::new();
    s.push_str("One primary ray through each pixel centre; the oracle decides every quadric exactly. Colours: ");
    s.push_str("red = hole (the oracle hits, the variant misses), blue = phantom (the variant hits, the oracle misses), ");
    s.push_str("orange = wrong object, cyan = ambiguous (a decision within the oracle's margin δ; not a failure either way), ");
    s.push_str("grey tones = the right object, dark = both miss. *Differing* counts unambiguous pixels only.\n\n");
    for sc in scenes {
        let _ = writeln!(
            s,
            "- `{}` ({}x{}): {}",
            sc.name, sc.width, sc.height, sc.about
        );
    }
    s.push('\n');
    s.push_str(&holes::markdown(scenes));
    for sc in scenes {
        let _ = writeln!(s, "\n**{}**: oracle, then each variant\n", sc.name);
        let _ = writeln!(s, "![{} oracle](holes-{}-oracle.png)", sc.name, sc.name);
        for (v, _, _) in &sc.variants {
            let _ = writeln!(
                s,
                "![{} {}](holes-{}-{}.png)",
                sc.name,
                v.name(),
                sc.name,
                file_name(*v)
            );
        }
    }
    s
}

/// Writes one scene's PNGs into `out`.
fn write_maps(sc: &SceneHoles, out: &Path) -> Result<()> {
    let png = |suffix: &str, bytes: Vec<u8>| {
        write_rgb8_png(
            sc.width,
            sc.height,
            &bytes,
            &out.join(format!("holes-{}-{suffix}.png", sc.name)),
        )
    };
    png("oracle", holes::hole_map_rgb8(&sc.oracle, None))?;
    for (v, got, _) in &sc.variants {
        png(&file_name(*v), holes::hole_map_rgb8(&sc.oracle, Some(got)))?;
    }
    Ok(())
}

/// Runs `quadray bench holes`.
pub fn run(a: &HolesArgs) -> Result<()> {
    let names: Vec<String> = if a.scenes.is_empty() {
        DEFAULT_SCENES.iter().map(|s| s.to_string()).collect()
    } else {
        a.scenes.clone()
    };
    // Every scene is loaded and checked before any work is done.
    let scenes = names
        .iter()
        .map(|n| hole_scene(n, a.res))
        .collect::<Result<Vec<_>>>()?;
    for s in &scenes {
        holes::check(&s.scene, s.width, s.height).with_context(|| format!("scene {}", s.name))?;
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create output directory {}", a.out.display()))?;
    let pool = crate::args::thread_pool(a.threads)?;
    let mut mapped = Vec::new();
    for s in &scenes {
        if !a.quiet {
            errln!("bench holes: {} ({}x{})", s.name, s.width, s.height);
        }
        let sc = pool
            .install(|| holes::scene_holes(s))
            .with_context(|| format!("scene {}", s.name))?;
        write_maps(&sc, &a.out)?;
        mapped.push(sc);
    }
    let md = markdown(&mapped);
    if !a.quiet {
        crate::unless_pipe_closed(outln!("{}", holes::markdown(&mapped)))?;
    }
    let path = a.out.join("holes.md");
    write_bytes_atomically(&path, md.as_bytes())?;
    if !a.quiet {
        errln!("wrote {} and the hole maps beside it", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holes_of_a_small_far_scene_are_written_and_counted() {
        let dir = tempfile::tempdir().unwrap();
        crate::run_args([
            "bench",
            "holes",
            "--scene",
            "far-1e7",
            "--res",
            "90x30",
            "--out",
            dir.path().to_str().unwrap(),
            "--quiet",
        ])
        .unwrap();
        let md = std::fs::read_to_string(dir.path().join("holes.md")).unwrap();
        assert!(
            md.contains("| far-1e7 (90x30) | production | 2700 |"),
            "{md}"
        );
        for v in Variant::ALL {
            let png = image::open(
                dir.path()
                    .join(format!("holes-far-1e7-{}.png", file_name(v))),
            )
            .unwrap();
            assert_eq!((png.width(), png.height()), (90, 30));
        }
        // holes.md, the oracle's map and one per variant; no temporary files.
        let files = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(files, 2 + Variant::ALL.len());
    }

    #[test]
    fn scenes_the_oracle_cannot_judge_are_refused() {
        let defense = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/defense.toml");
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().to_str().unwrap();
        let err =
            crate::run_args(["bench", "holes", "--scene", defense, "--out", out]).unwrap_err();
        assert!(format!("{err:#}").contains("quadrics only"), "{err:#}");
        let err =
            crate::run_args(["bench", "holes", "--scene", "nowhere", "--out", out]).unwrap_err();
        assert!(format!("{err:#}").contains("nowhere"), "{err:#}");
        // Refused before anything was written.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
