//! `quadray quadric KIND`: the seed's explorer on the command line. One quadric in the seed's clip
//! cube under the orbit camera, every option with a sensible default; `--list` prints the kinds.

use crate::output::{check_writable, write_film};
use crate::showcase::{GENERAL, GENERAL_EQUATION, Showcase, TextureChoice};
use crate::{StatusError, usage_ensure};
use anyhow::Result;
use clap::Args;
use quadray::{Coefficients, QuadricKind, QuadricSurface, RenderSettings, Scene};
use std::path::PathBuf;

/// Arguments of `quadray quadric`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct QuadricArgs {
    /// The kind (see --list), or `general` (with --coeffs, else the gallery's general quadric).
    #[arg(required_unless_present = "list")]
    pub kind: Option<String>,
    /// Print the kinds with their canonical equations and exit.
    #[arg(long)]
    pub list: bool,
    /// Parameter a (default: the kind's textbook value).
    #[arg(short = 'a', value_name = "A")]
    pub a: Option<f64>,
    /// Parameter b.
    #[arg(short = 'b', value_name = "B")]
    pub b: Option<f64>,
    /// Parameter c.
    #[arg(short = 'c', value_name = "C")]
    pub c: Option<f64>,
    /// The ten coefficients A..J of a general quadric (POV-Ray's order), comma-separated
    /// (default: the gallery's, a turned and shifted one-sheet hyperboloid using all ten).
    #[arg(long, value_name = "A,B,..,J", value_delimiter = ',')]
    pub coeffs: Vec<f64>,
    /// Half-size R of the clip cube [-R, R]³.
    #[arg(long, value_name = "R", default_value_t = 1.0)]
    pub clip: f64,
    /// Surface texture.
    #[arg(long, value_enum, default_value = "ramp")]
    pub texture: TextureChoice,
    /// Show flat texture colours, without lights or shading.
    #[arg(long)]
    pub no_lighting: bool,
    /// Orbit azimuth about +z from +x, degrees (default: the kind's textbook view).
    #[arg(long, value_name = "DEG")]
    pub yaw: Option<f64>,
    /// Orbit elevation above the xy plane, degrees, in [-90, 90].
    #[arg(long, value_name = "DEG")]
    pub pitch: Option<f64>,
    /// Orbit distance from the centre (default: 5 × the clip size).
    #[arg(long, value_name = "D")]
    pub distance: Option<f64>,
    /// Resolution as WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", value_parser = crate::args::parse_resolution, default_value = "640x480")]
    pub res: (u32, u32),
    /// Samples per pixel.
    #[arg(long, value_name = "N", default_value_t = 4,
          value_parser = clap::value_parser!(u32).range(1..=quadray::render::MAX_SPP as i64))]
    pub spp: u32,
    /// Output image (.png or .exr). Default: `quadric-KIND.png` in the current folder.
    #[arg(
        short,
        long,
        value_name = "OUT",
        value_parser = crate::args::parse_image_output
    )]
    pub output: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The `--list` text: every kind's name and canonical equation, then the general form.
pub fn list() -> String {
    let mut out = String::new();
    for k in QuadricKind::ALL {
        out += &format!("{:<22} {}\n", k.name(), k.equation());
    }
    out += &format!(
        "{:<22} {GENERAL_EQUATION}  (--coeffs A,B,C,D,E,F,G,H,I,J)\n",
        "general"
    );
    out
}

/// The showcase the arguments describe: the kind's textbook one with the given overrides.
pub fn showcase(args: &QuadricArgs) -> Result<Showcase> {
    let name = args.kind.as_deref().unwrap_or_default();
    let mut show = if name == "general" {
        usage_ensure(
            args.a.is_none() && args.b.is_none() && args.c.is_none(),
            "-a, -b and -c belong to the named kinds; a general quadric takes only --coeffs",
        )?;
        if args.coeffs.is_empty() {
            Showcase::general(GENERAL)
        } else {
            usage_ensure(
                args.coeffs.len() == 10,
                &format!(
                    "a general quadric needs --coeffs with exactly 10 numbers A..J, got {}",
                    args.coeffs.len()
                ),
            )?;
            let mut k = [0.0; 10];
            k.copy_from_slice(&args.coeffs);
            Showcase::general(Coefficients(k))
        }
    } else {
        let Some(kind) = QuadricKind::from_name(name) else {
            let names = QuadricKind::ALL.map(|k| k.name());
            return Err(StatusError::usage(format!(
                "unknown quadric kind \"{name}\"{}; the kinds are {} and general",
                quadray_loader::suggest::did_you_mean(name, names.into_iter().chain(["general"])),
                names.join(", ")
            ))
            .into());
        };
        usage_ensure(
            args.coeffs.is_empty(),
            &format!("--coeffs is for `general`; the {name} takes -a, -b, -c"),
        )?;
        for (flag, value) in [("-a", args.a), ("-b", args.b), ("-c", args.c)] {
            if let Some(v) = value {
                usage_ensure(
                    v > 0.0 && v.is_finite(),
                    &format!("{flag} must be a positive number, got {v:?}"),
                )?;
            }
        }
        let mut show = Showcase::of(kind);
        if let QuadricSurface::Canonical { a, b, c, .. } = &mut show.surface {
            *a = args.a.unwrap_or(*a);
            *b = args.b.unwrap_or(*b);
            *c = args.c.unwrap_or(*c);
        }
        show
    };
    usage_ensure(
        args.clip > 0.0 && args.clip.is_finite(),
        &format!("--clip must be a positive number, got {:?}", args.clip),
    )?;
    show.clip = args.clip;
    show.yaw = args.yaw.unwrap_or(show.yaw);
    show.pitch = args.pitch.unwrap_or(show.pitch);
    show.distance = args.distance.unwrap_or(show.distance * args.clip);
    usage_ensure(show.yaw.is_finite(), "--yaw must be a finite angle")?;
    usage_ensure(
        (-90.0..=90.0).contains(&show.pitch),
        &format!("--pitch must be in [-90, 90] degrees, got {:?}", show.pitch),
    )?;
    usage_ensure(
        show.distance > 0.0 && show.distance.is_finite(),
        &match args.distance {
            Some(d) => format!("--distance must be a positive number, got {d:?}"),
            None => format!(
                "--clip {:?} puts the default camera (5 x the clip size away) out of range; give \
                 --distance",
                args.clip
            ),
        },
    )?;
    Ok(show)
}

/// Where `quadray quadric KIND` writes without `-o`: `quadric-KIND.png` in the current folder,
/// as POV-Ray writes a scene's image beside where it runs.
pub fn default_output(kind: &str) -> PathBuf {
    PathBuf::from(format!("quadric-{kind}.png"))
}

/// Runs the explorer.
pub fn run(args: &QuadricArgs) -> Result<()> {
    if args.list {
        outln!("{}", list().trim_end())?;
        return Ok(());
    }
    let show = showcase(args)?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(show.name()));
    let output = &output;
    check_writable(output)?;
    let scene = Scene::new(show.scene(args.texture.texture(), !args.no_lighting)?)?;
    let settings = RenderSettings {
        width: args.res.0,
        height: args.res.1,
        spp: args.spp,
        ..RenderSettings::default()
    };
    let rendered = quadray::render(&scene, &settings, &quadray::NoProgress)?;
    write_film(&rendered.film, output)?;
    if !args.quiet {
        errln!(
            "{} {}: {}x{}, {} spp -> {}",
            show.name(),
            show.equation(),
            settings.width,
            settings.height,
            settings.spp,
            output.display()
        );
    }
    Ok(())
}
