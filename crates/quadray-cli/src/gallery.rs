//! `quadray gallery`: the seed's Sample button. Every kind with its textbook parameters and view,
//! plus the general form, rendered into one contact sheet with each name and equation drawn in.

use crate::label::{Canvas, text_width};
use crate::output::{Format, check_writable, write_rgb8_png};
use crate::showcase::TextureChoice;
use crate::showcase::{BACKGROUND, Showcase};
use anyhow::{Result, ensure};
use clap::Args;
use quadray::film::encode_srgb8;
use quadray::{RenderSettings, Scene};
use std::path::PathBuf;

/// Tiles per row of the sheet.
const COLUMNS: u32 = 5;
/// Height of the title band above the tiles, in pixels per unit of text scale.
const TITLE_BAND: u32 = 22;
/// Height of the caption band under each picture, per unit of text scale.
const CAPTION_BAND: u32 = 30;

/// Arguments of `quadray gallery`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct GalleryArgs {
    /// Output contact sheet (.png).
    #[arg(short, long, value_name = "OUT.png", default_value = "gallery.png",
          value_parser = crate::args::parse_png_output)]
    pub output: PathBuf,
    /// Size of one tile (picture and caption) as WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", value_parser = crate::args::parse_resolution, default_value = "440x400")]
    pub tile: (u32, u32),
    /// Samples per pixel.
    #[arg(long, value_name = "N", default_value_t = 4,
          value_parser = clap::value_parser!(u32).range(1..=quadray::render::MAX_SPP as i64))]
    pub spp: u32,
    /// Surface texture of every tile.
    #[arg(long, value_enum, default_value = "ramp")]
    pub texture: TextureChoice,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The label colours: names in warm white, equations in a quieter blue-grey.
const NAME_COLOUR: [u8; 3] = [240, 236, 226];
const EQUATION_COLOUR: [u8; 3] = [150, 170, 200];
const TITLE_COLOUR: [u8; 3] = [200, 205, 215];

/// Renders the contact sheet as 8-bit sRGB RGB bytes; returns (width, height, bytes).
pub fn render_sheet(args: &GalleryArgs) -> Result<(u32, u32, Vec<u8>)> {
    let (tw, th) = args.tile;
    // Text scale follows the tile size, so small sheets stay legible and large ones balanced.
    let scale = (tw / 220).clamp(1, 4);
    let caption = CAPTION_BAND * scale;
    let title = TITLE_BAND * scale;
    crate::usage_ensure(
        (64..=4096).contains(&tw) && th >= caption + 32 && th <= 4096,
        &format!(
            "--tile must be at least 64 wide and {} tall, and at most 4096x4096, got {tw}x{th}",
            caption + 32
        ),
    )?;
    let shows = Showcase::all();
    let rows = (shows.len() as u32).div_ceil(COLUMNS);
    let (w, h) = (tw * COLUMNS, title + th * rows);
    let background = BACKGROUND.to_array().map(encode_srgb8);
    let mut bytes: Vec<u8> = std::iter::repeat_n(background, (w * h) as usize)
        .flatten()
        .collect();
    let settings = RenderSettings {
        width: tw,
        height: th - caption,
        spp: args.spp,
        ..RenderSettings::default()
    };
    settings.validate()?;
    // One size for every equation: the largest at which the longest fits with a margin.
    let eq_scale = (1..=scale)
        .rev()
        .find(|&s| {
            shows
                .iter()
                .all(|show| text_width(caption_equation(show), s) + 8 * s <= tw)
        })
        .unwrap_or(1);
    for (i, show) in shows.iter().enumerate() {
        let scene = Scene::new(show.scene(args.texture.texture(), true)?)?;
        let film = quadray::render(&scene, &settings, &quadray::NoProgress)?.film;
        let (x0, y0) = ((i as u32 % COLUMNS) * tw, title + (i as u32 / COLUMNS) * th);
        let tile = film.to_srgb8();
        for y in 0..settings.height {
            let src = (y * tw * 3) as usize;
            let dst = (((y0 + y) * w + x0) * 3) as usize;
            bytes[dst..dst + (tw * 3) as usize]
                .copy_from_slice(&tile[src..src + (tw * 3) as usize]);
        }
        let mut canvas = Canvas {
            width: w,
            height: h,
            bytes: &mut bytes,
        };
        let cx = (x0 + tw / 2) as i64;
        let cap_y = (y0 + settings.height) as i64;
        let name = show.name().replace('-', " ");
        canvas.text_centred(cx, cap_y + 2 * scale as i64, &name, scale, NAME_COLOUR);
        // The equation at the name's size when it fits, else the largest size that does.
        let eq = caption_equation(show);
        canvas.text_centred(cx, cap_y + 16 * scale as i64, eq, eq_scale, EQUATION_COLOUR);
        if !args.quiet {
            errln!("rendered {} ({}/{})", show.name(), i + 1, shows.len());
        }
    }
    let mut canvas = Canvas {
        width: w,
        height: h,
        bytes: &mut bytes,
    };
    canvas.text_centred(
        (w / 2) as i64,
        (title as i64 - 8 * (scale as i64 + 1)) / 2,
        "The real quadrics, clipped to a cube",
        scale + 1,
        TITLE_COLOUR,
    );
    Ok((w, h, bytes))
}

/// The equation under a tile: the canonical one, or the general form with its middle terms elided
/// (all ten do not fit a caption).
fn caption_equation(show: &Showcase) -> &'static str {
    match show.surface {
        quadray::QuadricSurface::General(_) => "Ax²+By²+Cz²+...+Iz+J = 0",
        _ => show.equation(),
    }
}

/// Runs the gallery subcommand.
pub fn run(args: &GalleryArgs) -> Result<()> {
    ensure!(
        check_writable(&args.output)? == Format::Png,
        "the gallery is a labelled 8-bit sheet: -o must end in .png"
    );
    let (w, h, bytes) = render_sheet(args)?;
    write_rgb8_png(w, h, &bytes, &args.output)?;
    if !args.quiet {
        errln!("{w}x{h} contact sheet -> {}", args.output.display());
    }
    Ok(())
}
