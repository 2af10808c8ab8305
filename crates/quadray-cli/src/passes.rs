//! Render passes on output: the beauty image and AOVs as one Blender-style EXR (dotted channel
//! names in a single part, which compositors key on), or one pass at a time as an 8-bit PNG.

use crate::output::{write_atomically, write_rgb8_png};
use anyhow::{Result, anyhow, bail};
use exr::prelude::*;
use quadray::{AovSelection, Aovs, Film, PixelWindow, film::encode_srgb8};
use std::ops::RangeInclusive;
use std::path::Path;

/// The passes a render can write, as named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Pass {
    /// The beauty image.
    Combined,
    /// Planar depth along the camera's viewing axis.
    Depth,
    /// World-space shading normal facing the camera.
    Normal,
    /// Base colour of the surface.
    Albedo,
    /// 1-based object index, 0 for the background.
    ObjectId,
}

impl Pass {
    /// The selection that computes exactly this pass, as an EXR stores it (none for the beauty
    /// image).
    pub fn channels(self) -> AovSelection {
        let mut s = AovSelection::NONE;
        match self {
            Pass::Combined => {}
            Pass::Depth => s.depth = true,
            Pass::Normal => s.normal = true,
            Pass::Albedo => s.albedo = true,
            Pass::ObjectId => s.object_id = true,
        }
        s
    }

    /// The selection that computes this pass as a PNG shows it: the depth PNG also needs the
    /// object ids, to tell plane pixels apart for its display range.
    pub fn selection(self) -> AovSelection {
        let mut s = self.channels();
        s.object_id |= self == Pass::Depth;
        s
    }
}

/// The union of the channels of `passes`.
pub fn selection_of(passes: &[Pass]) -> AovSelection {
    passes
        .iter()
        .map(|p| p.channels())
        .fold(AovSelection::NONE, |a, b| AovSelection {
            depth: a.depth || b.depth,
            normal: a.normal || b.normal,
            albedo: a.albedo || b.albedo,
            object_id: a.object_id || b.object_id,
        })
}

/// Channel names of the beauty image in a file with passes (Blender's view-layer naming).
pub const COMBINED: [&str; 4] = [
    "ViewLayer.Combined.R",
    "ViewLayer.Combined.G",
    "ViewLayer.Combined.B",
    "ViewLayer.Combined.A",
];
/// Channel name of the depth pass.
pub const DEPTH: &str = "ViewLayer.Depth.Z";
/// Channel names of the normal pass.
pub const NORMAL: [&str; 3] = [
    "ViewLayer.Normal.X",
    "ViewLayer.Normal.Y",
    "ViewLayer.Normal.Z",
];
/// Channel names of the albedo pass.
pub const ALBEDO: [&str; 3] = [
    "ViewLayer.Albedo.R",
    "ViewLayer.Albedo.G",
    "ViewLayer.Albedo.B",
];
/// Channel name of the object-index pass.
pub const INDEX_OB: &str = "ViewLayer.IndexOB.X";

/// Writes the beauty image (half floats when `half`) and the passes `aovs` holds into one EXR,
/// atomically. Without passes the channels are plain `R, G, B, A`, as any viewer expects; with
/// passes they are Blender's `ViewLayer.*` names. Depth, normals, albedo and ids are always f32:
/// half's 11-bit mantissa visibly steps depth. `frame` places the pixels in the full image: its
/// size is the file's display window and its window the data window, as OpenEXR stores a crop.
pub fn write_exr(
    film: &Film,
    aovs: Option<&Aovs>,
    half: bool,
    frame: &ExrFrame,
    path: &Path,
) -> Result<()> {
    let (w, h) = (film.width() as usize, film.height() as usize);
    if w == 0 || h == 0 {
        bail!("cannot write an empty image");
    }
    if (frame.window.width(), frame.window.height()) != (film.width(), film.height())
        || !frame.window.fits(frame.width, frame.height)
    {
        bail!("the image does not fit its place in the frame");
    }
    if let Some(a) = aovs
        && (a.width() as usize, a.height() as usize) != (w, h)
    {
        bail!("passes and image differ in size");
    }
    let px = film.pixels();
    let beauty = |c: usize| -> FlatSamples {
        if c == 3 {
            // The background is part of the image (a colour, not a hole): fully opaque.
            return if half {
                FlatSamples::F16(vec![f16::ONE; w * h])
            } else {
                FlatSamples::F32(vec![1.0; w * h])
            };
        }
        if half {
            FlatSamples::F16(px.iter().map(|p| f16::from_f32(p[c])).collect())
        } else {
            FlatSamples::F32(px.iter().map(|p| p[c]).collect())
        }
    };
    let beauty_names: [&str; 4] = if aovs.is_some() {
        COMBINED
    } else {
        ["R", "G", "B", "A"]
    };
    let mut channels: Vec<AnyChannel<FlatSamples>> = (0..4)
        .map(|c| AnyChannel::new(beauty_names[c], beauty(c)))
        .collect();
    if let Some(a) = aovs {
        let sel = a.selection();
        let samples = a.samples();
        let f32s = |f: &dyn Fn(&quadray::AovSample) -> f32| {
            FlatSamples::F32(samples.iter().map(f).collect())
        };
        if sel.depth {
            channels.push(AnyChannel::new(DEPTH, f32s(&|s| s.depth)));
        }
        if sel.normal {
            for (c, name) in NORMAL.iter().enumerate() {
                channels.push(AnyChannel::new(*name, f32s(&|s| s.normal[c])));
            }
        }
        if sel.albedo {
            for (c, name) in ALBEDO.iter().enumerate() {
                channels.push(AnyChannel::new(*name, f32s(&|s| s.albedo[c])));
            }
        }
        if sel.object_id {
            // Blender stores the index as a float; ids below 2^24 are exact.
            channels.push(AnyChannel::new(INDEX_OB, f32s(&|s| s.object_id as f32)));
        }
    }
    let attributes = LayerAttributes {
        layer_position: Vec2(frame.window.x0 as i32, frame.window.y0 as i32),
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        Vec2(w, h),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    let display = IntegerBounds::from_dimensions((frame.width as usize, frame.height as usize));
    let image = Image::new(ImageAttributes::new(display), layer);
    write_atomically(path, |tmp| {
        image.write().to_file(tmp)?;
        Ok(())
    })
}

/// Where an EXR's pixels lie in the full image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExrFrame {
    /// Full image width (the display window).
    pub width: u32,
    /// Full image height.
    pub height: u32,
    /// The rendered pixels (the data window).
    pub window: PixelWindow,
}

impl ExrFrame {
    /// The frame of a render with `settings`: its full size and its window.
    pub fn of(settings: &quadray::RenderSettings) -> ExrFrame {
        ExrFrame {
            width: settings.width,
            height: settings.height,
            window: settings.window(),
        }
    }
}

/// Share of hit depths the depth PNG spans when only planes are in view: the nearest hit to this
/// quantile (the rest run to the horizon and clamp).
pub const DEPTH_DISPLAY_QUANTILE: f64 = 0.95;

/// The depths the depth PNG maps to white and to its darkest grey: the nearest hit, and the
/// farthest hit on the scene's finite content (anything but `planes`, the ids of
/// [`quadray::Geometry::plane_object_indices`]), so that a floor running
/// to the horizon does not squeeze the objects into one grey; farther plane pixels clamp. With
/// only planes in view, the [`DEPTH_DISPLAY_QUANTILE`] of hit depths. `None` when nothing was hit.
pub fn depth_display_range(
    samples: &[quadray::AovSample],
    planes: &RangeInclusive<u32>,
) -> Option<(f32, f32)> {
    let hit = |p: &&quadray::AovSample| p.depth < quadray::aov::NO_HIT_DEPTH;
    let near = samples
        .iter()
        .filter(hit)
        .map(|p| p.depth)
        .reduce(f32::min)?;
    let finite_far = samples
        .iter()
        .filter(hit)
        .filter(|p| !planes.contains(&p.object_id))
        .map(|p| p.depth)
        .reduce(f32::max);
    let far = finite_far.unwrap_or_else(|| {
        let mut depths: Vec<f32> = samples.iter().filter(hit).map(|p| p.depth).collect();
        depths.sort_unstable_by(f32::total_cmp);
        depths[((depths.len() - 1) as f64 * DEPTH_DISPLAY_QUANTILE).round() as usize]
    });
    Some((near, far))
}

/// The 8-bit RGB bytes showing one pass: the beauty and albedo sRGB-encoded; depth as grey, white
/// at the nearest hit to a dark grey at [`depth_display_range`]'s far end and beyond (misses
/// black); normals as (n + 1)/2 without
/// encoding (the usual normal-map colours; misses black); object ids as distinct colours
/// (background black).
pub fn pass_rgb8(
    pass: Pass,
    film: &Film,
    aovs: Option<&Aovs>,
    planes: &RangeInclusive<u32>,
) -> Result<Vec<u8>> {
    let samples = || match aovs {
        Some(a) => Ok(a.samples()),
        None => Err(anyhow!("the {pass:?} pass was not rendered")),
    };
    let bytes = match pass {
        Pass::Combined => film.to_srgb8(),
        Pass::Albedo => samples()?
            .iter()
            .flat_map(|p| p.albedo.to_array().map(encode_srgb8))
            .collect(),
        Pass::Normal => samples()?
            .iter()
            .flat_map(|p| {
                if p.normal == glam::Vec3::ZERO {
                    [0; 3]
                } else {
                    p.normal
                        .to_array()
                        .map(|c| ((c + 1.0) * 127.5).round() as u8)
                }
            })
            .collect(),
        Pass::Depth => {
            let s = samples()?;
            let (lo, hi) = depth_display_range(s, planes).unwrap_or((0.0, 1.0));
            let span = (hi - lo).max(f32::MIN_POSITIVE);
            s.iter()
                .flat_map(|p| {
                    let v = if p.depth < quadray::aov::NO_HIT_DEPTH {
                        let t = ((p.depth - lo) / span).min(1.0);
                        (255.0 * (1.0 - 0.85 * t)).round() as u8
                    } else {
                        0
                    };
                    [v; 3]
                })
                .collect()
        }
        Pass::ObjectId => samples()?
            .iter()
            .flat_map(|p| id_colour(p.object_id))
            .collect(),
    };
    Ok(bytes)
}

/// A saturated colour for object `id`, far from its neighbours' (golden-angle hues); black for 0.
pub fn id_colour(id: u32) -> [u8; 3] {
    if id == 0 {
        return [0; 3];
    }
    let hue = (id as f32 * 0.618_034).fract() * 6.0;
    let x = 1.0 - (hue % 2.0 - 1.0).abs();
    let (r, g, b) = match hue as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    [r, g, b].map(|c: f32| (55.0 + 200.0 * c) as u8)
}

/// Writes one pass as a PNG, atomically.
pub fn write_png_pass(
    pass: Pass,
    film: &Film,
    aovs: Option<&Aovs>,
    planes: &RangeInclusive<u32>,
    path: &Path,
) -> Result<()> {
    let bytes = pass_rgb8(pass, film, aovs, planes)?;
    write_rgb8_png(film.width(), film.height(), &bytes, path)
}
