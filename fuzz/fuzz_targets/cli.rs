//! The command line's surface: any arguments (NUL-separated) parsed as `quadray` parses them, and
//! what a render or check does with its numbers before loading, `--set` overrides applied to a
//! bundled scene's text and validated, `--time-limit`/`--target-error`/`--min-spp`/`--max-spp`
//! resolved, `--res` checked: no panic, no runaway allocation.
#![no_main]

use clap::Parser;
use libfuzzer_sys::fuzz_target;
use quadray_cli::args::{Cli, Command};

/// The scene overrides are applied to (the quick-start scene).
const SCENE: &str = include_str!("../../scenes/sphere-on-plane.toml");

fn overrides(set: &[quadray_loader::Override]) {
    let path = std::path::Path::new("fuzz.toml");
    if let Ok(text) = quadray_loader::native::overrides::apply(SCENE, set)
        && let Ok(loaded) = quadray_loader::parse_scene(&text, path)
    {
        let _ = quadray::Scene::new(loaded.description);
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let argv = std::iter::once("quadray").chain(text.split('\0'));
    let Ok(cli) = Cli::try_parse_from(argv) else { return };
    match cli.command {
        Command::Render(r) => {
            let _ = r.sampling.resolve(r.spp, None);
            if let Some((w, h)) = r.res {
                let _ = quadray::render::check_resolution(w, h);
            }
            overrides(&r.set);
        }
        Command::Check(c) => overrides(&c.set),
        _ => {}
    }
});
