//! Renders as OpenEXR files: the beauty image and its passes in one part (a whole frame or a crop
//! placed in it) under Blender's channel names (dotted names in one part, which compositors key
//! on), several rectangles of one frame as the parts of a multi-part file (a piece of a
//! distributed render), and reading such files back into a film and passes.

use anyhow::{Context, Result, bail};
use exr::meta::attribute::Chromaticities;
use exr::prelude::*;
use quadray::{AovSample, AovSelection, Aovs, Film, PixelWindow};
use std::collections::HashMap;
use std::path::Path;

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
/// Channel names of the albedo pass (Blender's "Diffuse Color" pass).
pub const ALBEDO: [&str; 3] = [
    "ViewLayer.DiffCol.R",
    "ViewLayer.DiffCol.G",
    "ViewLayer.DiffCol.B",
];
/// Channel name of the object-index pass.
pub const INDEX_OB: &str = "ViewLayer.IndexOB.X";
/// Channel name of the per-pixel sample count (Cycles' "Debug Sample Count" pass).
pub const SAMPLE_COUNT: &str = "ViewLayer.Debug Sample Count.X";
/// Channel names of the samples' variance (pbrt-v4's `Variance` channels, in the view layer).
pub const VARIANCE: [&str; 3] = [
    "ViewLayer.Variance.R",
    "ViewLayer.Variance.G",
    "ViewLayer.Variance.B",
];

/// Channel names of the beauty image in a file without passes.
pub const RGBA: [&str; 4] = ["R", "G", "B", "A"];

/// The beauty image's colour channels among the channels `present` reports: Blender's
/// `ViewLayer.Combined.R/G/B` in a file with passes, else plain `R, G, B`.
pub fn beauty_channels(present: impl Fn(&str) -> bool) -> Option<[&'static str; 3]> {
    [COMBINED, RGBA]
        .into_iter()
        .map(|names| [names[0], names[1], names[2]])
        .find(|names| names.iter().all(|n| present(n)))
}

/// Writes an EXR image to `path` through a temporary file beside it, renamed once complete
/// ([`quadray_loader::atomic_file`]): a failed write leaves an older `path` as it was.
fn write_image(
    path: &Path,
    write: impl FnOnce(&mut quadray_loader::atomic_file::Writer<'_>) -> exr::error::UnitResult,
) -> Result<()> {
    crate::output::write_atomically(path, |out| write(out).map_err(write_error))
}

/// An EXR writer's error as one cause: its I/O errors print their cause in their own message and
/// again as their source, so a full disk read "No space left on device" twice.
fn write_error(e: exr::error::Error) -> anyhow::Error {
    match e {
        exr::error::Error::Io(io) => io.into(),
        other => other.into(),
    }
}

/// Name of the attribute holding the camera's position in world space (a v3f).
pub const CAMERA_POSITION: &str = "cameraPosition";

/// The camera of a render, as an EXR stores it: OpenEXR's standard `worldToCamera` and
/// `worldToNDC` matrices (the field of view is in the latter) and quadray's `cameraPosition`.
/// The exr crate's `fieldOfViewHorizontal` and `fieldOfViewVertical` are not written: they are
/// not OpenEXR standard attributes, and no reader we know of (OpenImageIO, Nuke, Blender) uses
/// them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExrCamera {
    /// `worldToCamera`, in the file's order: Imath's row-vector matrix, row by row.
    pub world_to_camera: [f32; 16],
    /// `worldToNDC`, in the file's order.
    pub world_to_ndc: [f32; 16],
    /// The eye (the image plane's centre for an orthographic camera), world space.
    pub position: [f32; 3],
}

impl ExrCamera {
    /// The camera of a `width` × `height` render seen through `camera`.
    pub fn of(camera: &quadray::Camera, width: u32, height: u32) -> Result<ExrCamera> {
        let frame = camera
            .prepare(width as f64 / height as f64)
            .context("the camera")?;
        // Imath multiplies row vectors (p · M): its matrix is the transpose of glam's
        // column-vector one, so its rows, stored in order, are glam's columns.
        let imath = |m: glam::DMat4| m.to_cols_array().map(|x| x as f32);
        Ok(ExrCamera {
            world_to_camera: imath(frame.world_to_camera()),
            world_to_ndc: imath(frame.world_to_ndc()),
            position: camera.from.as_vec3().to_array(),
        })
    }

    /// Puts the camera into a part's attributes.
    fn write(&self, attributes: &mut LayerAttributes) {
        attributes.world_to_camera = Some(self.world_to_camera);
        attributes.world_to_normalized_device = Some(self.world_to_ndc);
        // The only custom attribute of a part: the writer stores custom attributes in hash-map
        // order, which changes from run to run, so two of them would change the file's bytes.
        let [x, y, z] = self.position;
        attributes.other.insert(
            Text::new_or_panic(CAMERA_POSITION),
            AttributeValue::FloatVec3((x, y, z)),
        );
    }

    /// The camera a part's attributes hold, if they hold both matrices and the position.
    fn read(attributes: &LayerAttributes) -> Option<ExrCamera> {
        let position = match attributes.other.get(&Text::new_or_panic(CAMERA_POSITION)) {
            Some(AttributeValue::FloatVec3((x, y, z))) => [*x, *y, *z],
            _ => return None,
        };
        Some(ExrCamera {
            world_to_camera: attributes.world_to_camera?,
            world_to_ndc: attributes.world_to_normalized_device?,
            position,
        })
    }
}

/// Where an EXR's pixels lie in the full image, and the camera that saw them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExrFrame {
    /// Full image width (the display window).
    pub width: u32,
    /// Full image height.
    pub height: u32,
    /// The rendered pixels (the data window).
    pub window: PixelWindow,
    /// The camera, written as attributes when known.
    pub camera: Option<ExrCamera>,
}

impl ExrFrame {
    /// The frame of a render with `settings` through `camera`: its full size, its window and the
    /// camera's matrices.
    pub fn of(settings: &quadray::RenderSettings, camera: &quadray::Camera) -> Result<ExrFrame> {
        Ok(ExrFrame {
            width: settings.width,
            height: settings.height,
            window: settings.window(),
            camera: Some(ExrCamera::of(camera, settings.width, settings.height)?),
        })
    }

    /// The whole of a `width` × `height` image, without a camera.
    pub fn full(width: u32, height: u32) -> ExrFrame {
        ExrFrame {
            width,
            height,
            window: PixelWindow::full(width, height),
            camera: None,
        }
    }
}

/// One rectangle of a render: its pixels, its passes, and where it lies in the frame.
#[derive(Clone, Copy, Debug)]
pub struct ExrPart<'a> {
    /// The beauty image of the rectangle.
    pub film: &'a Film,
    /// Its passes, if any were rendered.
    pub aovs: Option<&'a Aovs>,
    /// Its place in the full frame.
    pub window: PixelWindow,
}

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
    let part = ExrPart {
        film,
        aovs,
        window: frame.window,
    };
    let layer = layer(&part, half, frame, None)?;
    let image = Image::new(display_attributes(frame, &[]), layer);
    write_image(path, |out| image.write().to_buffered(out))
}

/// Writes rectangles of one `width` × `height` frame as the parts of one multi-part EXR (named
/// `rows Y0-Y1`), atomically, with `attributes` as text attributes of every part.
pub fn write_exr_parts(
    parts: &[ExrPart<'_>],
    half: bool,
    (width, height, camera): (u32, u32, Option<ExrCamera>),
    attributes: &[(&str, String)],
    path: &Path,
) -> Result<()> {
    let Some(first) = parts.first() else {
        bail!("cannot write a file without pixels");
    };
    let frame = |part: &ExrPart| ExrFrame {
        width,
        height,
        window: part.window,
        camera,
    };
    let name = |part: &ExrPart| format!("rows {}-{}", part.window.y0, part.window.y1);
    let mut layers = SmallVec::new();
    for part in parts {
        layers.push(layer(part, half, &frame(part), Some(&name(part)))?);
    }
    let image = Image::new(display_attributes(&frame(first), attributes), layers);
    write_image(path, |out| image.write().to_buffered(out))
}

/// The colour space of quadray's colour channels (`R, G, B` and `ViewLayer.Combined`,
/// `ViewLayer.DiffCol`): linear Rec. 709 / sRGB primaries with a D65 white, as OpenEXR's
/// `chromaticities` attribute gives them (CIE 1931 xy), so that OpenImageIO, Nuke and Blender
/// read the space instead of assuming one.
pub const REC709_D65: Chromaticities = Chromaticities {
    red: Vec2(0.64, 0.33),
    green: Vec2(0.30, 0.60),
    blue: Vec2(0.15, 0.06),
    white: Vec2(0.3127, 0.3290),
};

/// The attributes every part shares: the display window, the colour space and `attributes` as
/// text.
fn display_attributes(frame: &ExrFrame, attributes: &[(&str, String)]) -> ImageAttributes {
    let display = IntegerBounds::from_dimensions((frame.width as usize, frame.height as usize));
    let mut shared = ImageAttributes::new(display);
    shared.chromaticities = Some(REC709_D65);
    for (key, value) in attributes {
        shared.other.insert(
            Text::new_or_panic(*key),
            AttributeValue::Text(Text::new_or_panic(value)),
        );
    }
    shared
}

/// The channels of one rectangle, placed at its window, optionally named (multi-part files).
fn layer(
    part: &ExrPart<'_>,
    half: bool,
    frame: &ExrFrame,
    name: Option<&str>,
) -> Result<Layer<AnyChannels<FlatSamples>>> {
    let (film, aovs) = (part.film, part.aovs);
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
    let beauty_names = if aovs.is_some() { COMBINED } else { RGBA };
    let mut channels: Vec<AnyChannel<FlatSamples>> = (0..4)
        .map(|c| AnyChannel::new(beauty_names[c], beauty(c)))
        .collect();
    if let Some(a) = aovs {
        channels.extend(pass_channels(a));
    }
    // pLinear 0 on every channel, as Blender and OpenEXR's own writer store them: pLinear marks
    // perceptually linear values for lossy compression, which linear light is not.
    for channel in &mut channels {
        channel.quantize_linearly = false;
    }
    let mut attributes = LayerAttributes {
        layer_name: name.map(Text::new_or_panic),
        layer_position: Vec2(frame.window.x0 as i32, frame.window.y0 as i32),
        ..LayerAttributes::default()
    };
    if let Some(camera) = &frame.camera {
        camera.write(&mut attributes);
    }
    // Increasing line order makes the writer put compressed blocks in file order whatever order
    // its threads finish them in: the same image gives the same bytes on every run.
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    Ok(Layer::new(
        Vec2(w, h),
        attributes,
        encoding,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    ))
}

/// The channels of the passes `aovs` holds, under Blender's names, all f32.
fn pass_channels(a: &Aovs) -> Vec<AnyChannel<FlatSamples>> {
    let mut channels = Vec::new();
    let sel = a.selection();
    let samples = a.samples();
    let f32s = |f: &dyn Fn(&AovSample) -> f32| FlatSamples::F32(samples.iter().map(f).collect());
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
    if sel.sample_count {
        // As a float, like Blender's; counts up to MAX_SPP are exact.
        channels.push(AnyChannel::new(
            SAMPLE_COUNT,
            f32s(&|s| s.sample_count as f32),
        ));
    }
    if sel.variance {
        for (c, name) in VARIANCE.iter().enumerate() {
            channels.push(AnyChannel::new(*name, f32s(&|s| s.variance[c])));
        }
    }
    channels
}

/// An EXR file read back: its full frame, its text attributes, and each part's rectangle with
/// its channels by name.
#[derive(Clone, Debug)]
pub struct ReadExr {
    /// Width and height of the display window.
    pub size: (u32, u32),
    /// Text attributes shared by the parts.
    pub attributes: HashMap<String, String>,
    /// Every part: its place in the frame and its channels, sorted by name.
    pub parts: Vec<(PixelWindow, Vec<(String, FlatSamples)>)>,
    /// The camera the first part's attributes hold, if any.
    pub camera: Option<ExrCamera>,
}

/// Reads every part of the EXR at `path` (all channels, full resolution).
pub fn read_exr(path: &Path) -> Result<ReadExr> {
    quadray_loader::read_limited::regular_file(path)
        .with_context(|| format!("reading {}", path.display()))?;
    let image = exr::prelude::read_all_flat_layers_from_file(path)
        .with_context(|| format!("reading {}", path.display()))?;
    let display = image.attributes.display_window;
    if display.position != Vec2(0, 0) {
        bail!(
            "{}: the display window does not start at (0, 0)",
            path.display()
        );
    }
    let size = (display.size.0 as u32, display.size.1 as u32);
    let text = |v: &AttributeValue| match v {
        AttributeValue::Text(t) => Some(t.to_string()),
        _ => None,
    };
    // Custom attributes written as shared come back as the first part's own.
    let own = image
        .layer_data
        .iter()
        .flat_map(|l| l.attributes.other.iter());
    let attributes = image
        .attributes
        .other
        .iter()
        .chain(own)
        .filter_map(|(k, v)| Some((k.to_string(), text(v)?)))
        .collect();
    let mut parts = Vec::new();
    for layer in image.layer_data.iter() {
        let Vec2(x0, y0) = layer.attributes.layer_position;
        let (x0, y0) = (u32::try_from(x0)?, u32::try_from(y0)?);
        let window = PixelWindow {
            x0,
            y0,
            x1: x0 + layer.size.0 as u32,
            y1: y0 + layer.size.1 as u32,
        };
        if !window.fits(size.0, size.1) {
            bail!("{}: a part lies outside the frame", path.display());
        }
        let channels = layer
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.clone()))
            .collect();
        parts.push((window, channels));
    }
    let camera = image
        .layer_data
        .first()
        .and_then(|layer| ExrCamera::read(&layer.attributes));
    Ok(ReadExr {
        size,
        attributes,
        parts,
        camera,
    })
}

/// Rebuilds a film, its passes and whether the beauty image was half floats from full-frame
/// channels by name (as [`write_exr`] writes them); the inverse of the writer.
pub fn film_and_aovs(
    (width, height): (u32, u32),
    channels: &HashMap<String, FlatSamples>,
) -> Result<(Film, Option<Aovs>, bool)> {
    let n = width as usize * height as usize;
    let values = |name: &str| -> Option<Vec<f32>> {
        channels.get(name).map(|s| s.values_as_f32().collect())
    };
    let names = beauty_channels(|name| channels.contains_key(name))
        .context("no colour channels (ViewLayer.Combined.R/G/B or R/G/B)")?;
    let rgb: Vec<Vec<f32>> = names.iter().filter_map(|name| values(name)).collect();
    let half = matches!(channels.get(names[0]), Some(FlatSamples::F16(_)));
    let pixels = (0..n)
        .map(|i| glam::Vec3::new(rgb[0][i], rgb[1][i], rgb[2][i]))
        .collect();
    let film = Film::from_pixels(width, height, pixels).context("channel sizes differ")?;
    let selection = AovSelection {
        depth: channels.contains_key(DEPTH),
        normal: channels.contains_key(NORMAL[0]),
        albedo: channels.contains_key(ALBEDO[0]),
        object_id: channels.contains_key(INDEX_OB),
        sample_count: channels.contains_key(SAMPLE_COUNT),
        variance: channels.contains_key(VARIANCE[0]),
    };
    if !selection.any() {
        return Ok((film, None, half));
    }
    let triple = |names: [&str; 3], on: bool| -> Result<Option<[Vec<f32>; 3]>> {
        if !on {
            return Ok(None);
        }
        let [a, b, c] = names.map(values);
        Ok(Some([
            a.context("incomplete pass")?,
            b.context("incomplete pass")?,
            c.context("incomplete pass")?,
        ]))
    };
    let (depth, ids, counts) = (values(DEPTH), values(INDEX_OB), values(SAMPLE_COUNT));
    let (normal, albedo, variance) = (
        triple(NORMAL, selection.normal)?,
        triple(ALBEDO, selection.albedo)?,
        triple(VARIANCE, selection.variance)?,
    );
    let v3 = |t: &Option<[Vec<f32>; 3]>, i: usize| {
        t.as_ref().map_or(glam::Vec3::ZERO, |[a, b, c]| {
            glam::Vec3::new(a[i], b[i], c[i])
        })
    };
    let samples = (0..n)
        .map(|i| AovSample {
            depth: depth.as_ref().map_or(quadray::aov::NO_HIT_DEPTH, |d| d[i]),
            normal: v3(&normal, i),
            albedo: v3(&albedo, i),
            object_id: ids
                .as_ref()
                .map_or(quadray::aov::NO_HIT_OBJECT, |d| d[i] as u32),
            sample_count: counts.as_ref().map_or(0, |d| d[i] as u32),
            variance: v3(&variance, i),
        })
        .collect();
    let aovs = Aovs::new(width, height, selection, samples).context("channel sizes differ")?;
    Ok((film, Some(aovs), half))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every channel is written with pLinear 0, and the camera attributes read back as written,
    /// from a single-part file and from a multi-part piece.
    #[test]
    fn channels_are_not_perceptually_linear_and_the_camera_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let camera = quadray::Camera {
            from: glam::DVec3::new(1.0, -4.0, 2.0),
            to: glam::DVec3::ZERO,
            up: glam::DVec3::Z,
            projection: quadray::Projection::Perspective { vfov_deg: 35.0 },
        };
        let exr_camera = ExrCamera::of(&camera, 4, 2).unwrap();
        let film = Film::new(4, 2);
        let selection = AovSelection {
            depth: true,
            albedo: true,
            ..AovSelection::NONE
        };
        let aovs = Aovs::new(4, 2, selection, vec![AovSample::MISS; 8]).unwrap();
        let frame = ExrFrame {
            camera: Some(exr_camera),
            ..ExrFrame::full(4, 2)
        };
        let single = dir.path().join("single.exr");
        write_exr(&film, Some(&aovs), false, &frame, &single).unwrap();
        let part = ExrPart {
            film: &film,
            aovs: Some(&aovs),
            window: PixelWindow::full(4, 2),
        };
        let piece = dir.path().join("piece.exr");
        write_exr_parts(&[part], true, (4, 2, Some(exr_camera)), &[], &piece).unwrap();
        for path in [&single, &piece] {
            let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
            assert_eq!(image.attributes.chromaticities, Some(REC709_D65));
            let channels = &image.layer_data[0].channel_data.list;
            assert_eq!(channels.len(), 8);
            assert!(channels.iter().all(|c| !c.quantize_linearly));
            assert_eq!(read_exr(path).unwrap().camera, Some(exr_camera));
        }
        assert_eq!(exr_camera.position, [1.0, -4.0, 2.0]);
    }
}
