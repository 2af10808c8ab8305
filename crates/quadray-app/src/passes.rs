//! Render passes on output: which passes a command line asks for, and one pass at a time as an
//! 8-bit PNG ([`crate::exr_file`] writes them all into an EXR).

use crate::output::write_rgb8_png;
use anyhow::{Result, anyhow};
use quadray::{AovSelection, Aovs, Film, film::encode_srgb8};
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
    /// Samples taken in each pixel (varies when sampling is adaptive).
    SampleCount,
    /// Sample variance of each pixel's linear RGB samples.
    Variance,
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
            Pass::SampleCount => s.sample_count = true,
            Pass::Variance => s.variance = true,
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
        .fold(AovSelection::NONE, union)
}

/// The passes either selection computes.
fn union(a: AovSelection, b: AovSelection) -> AovSelection {
    AovSelection {
        depth: a.depth || b.depth,
        normal: a.normal || b.normal,
        albedo: a.albedo || b.albedo,
        object_id: a.object_id || b.object_id,
        sample_count: a.sample_count || b.sample_count,
        variance: a.variance || b.variance,
    }
}

/// The passes `selection` holds, by their command-line names, comma-separated (`none` if none):
/// the inverse of [`selection_of`].
pub fn names_of(selection: AovSelection) -> String {
    use clap::ValueEnum;
    let names: Vec<String> = Pass::value_variants()
        .iter()
        .filter(|p| **p != Pass::Combined && union(selection, p.channels()) == selection)
        .filter_map(|p| p.to_possible_value().map(|v| v.get_name().to_string()))
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(",")
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
/// (background black); sample counts as grey on a log2 scale up to the largest count; variance as
/// its square root (the samples' standard deviation), sRGB-encoded.
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
        Pass::SampleCount => {
            let s = samples()?;
            let most = s.iter().map(|p| p.sample_count).max().unwrap_or(1).max(2);
            s.iter()
                .flat_map(|p| [sample_count_grey(p.sample_count, most); 3])
                .collect()
        }
        Pass::Variance => samples()?
            .iter()
            .flat_map(|p| {
                p.variance
                    .to_array()
                    .map(|v| encode_srgb8(v.max(0.0).sqrt()))
            })
            .collect(),
    };
    Ok(bytes)
}

/// The grey showing a pixel's sample count: black at one sample, white at `most`, on a log2
/// scale (each doubling, one adaptive round, is an equal step).
fn sample_count_grey(count: u32, most: u32) -> u8 {
    let t = (count.max(1) as f64).log2() / (most as f64).log2();
    (255.0 * t.clamp(0.0, 1.0)).round() as u8
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_names_invert_the_selection() {
        assert_eq!(names_of(AovSelection::NONE), "none");
        let s = selection_of(&[Pass::ObjectId, Pass::Depth]);
        assert_eq!(names_of(s), "depth,object-id");
        assert_eq!(selection_of(&[Pass::Normal]), Pass::Normal.channels());
    }
}
