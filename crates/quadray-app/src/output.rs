//! Writing films to PNG or EXR, atomically: into a temporary file beside the target, then renamed.

use anyhow::{Context, Result, bail};
use quadray::Film;
use std::path::{Path, PathBuf};

/// Image formats quadray writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB-encoded, clamped.
    Png,
    /// Linear, scene-referred f32 RGBA, not clamped.
    Exr,
}

impl Format {
    /// The format named by `path`'s extension.
    pub fn from_path(path: &Path) -> Result<Format> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(Format::Png),
            Some("exr") => Ok(Format::Exr),
            _ => bail!("output {} must end in .png or .exr", path.display()),
        }
    }
}

/// Checks before rendering that `path` can be written: known format, existing folder, inside
/// the confinement folder if there is one ([`quadray_loader::confine`]).
pub fn check_writable(path: &Path) -> Result<Format> {
    let format = Format::from_path(path)?;
    check_output_folder(path)?;
    Ok(format)
}

/// Checks, before any work, that `path`'s folder exists and that confinement lets it be written,
/// whatever its format.
pub fn check_output_folder(path: &Path) -> Result<()> {
    let dir = parent_dir(path);
    if !dir.is_dir() {
        bail!("output folder {} does not exist", dir.display());
    }
    quadray_loader::confine::check_write(path)
        .with_context(|| format!("writing {}", path.display()))
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes `film` to `path`; an existing file is replaced only once the new one is complete.
pub fn write_film(film: &Film, path: &Path) -> Result<()> {
    match Format::from_path(path)? {
        Format::Png => write_rgb8_png(film.width(), film.height(), &film.to_srgb8(), path),
        Format::Exr => {
            let frame = crate::exr_file::ExrFrame::full(film.width(), film.height());
            crate::exr_file::write_exr(film, None, false, &frame, path)
        }
    }
}

/// Writes through `write` into a temporary file beside `path`, then flushes, syncs and renames it
/// to `path`; on any failure the temporary file is removed and an older `path` survives
/// ([`quadray_loader::atomic_file`]).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut quadray_loader::atomic_file::Writer<'_>) -> Result<()>,
) -> Result<()> {
    quadray_loader::atomic_file::replace_with(path, write)
        .with_context(|| format!("writing {}", path.display()))
}

/// Writes `contents` (a report, a table, an SVG) to `path` through a temporary file beside it,
/// renamed once complete; on failure the temporary file is removed and an older `path` survives.
pub fn write_bytes_atomically(path: &Path, contents: &[u8]) -> Result<()> {
    quadray_loader::atomic_file::replace(path, contents)
        .with_context(|| format!("writing {}", path.display()))
}

/// Writes 8-bit RGB bytes (row-major) as a PNG, atomically.
pub fn write_rgb8_png(width: u32, height: u32, bytes: &[u8], path: &Path) -> Result<()> {
    Format::from_path(path)?;
    write_atomically(path, |out| {
        image::write_buffer_with_format(
            out,
            bytes,
            width,
            height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn film() -> Film {
        let px = vec![Vec3::new(0.0, 0.5, 1.0), Vec3::new(2.5, 0.25, 0.0)];
        Film::from_pixels(2, 1, px).unwrap()
    }

    #[test]
    fn exr_keeps_linear_unclamped_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        write_film(&film(), &path).unwrap();
        let img = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| vec![[0f32; 4]; res.width() * res.height()],
            |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * 2 + pos.x()] = [r, g, b, a]
            },
        )
        .unwrap();
        assert_eq!(img.layer_data.channel_data.pixels[1], [2.5, 0.25, 0.0, 1.0]);
        // No temporary file is left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn png_is_srgb_encoded_and_clamped() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png");
        write_film(&film(), &path).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.get_pixel(0, 0).0, [0, 188, 255]);
        assert_eq!(img.get_pixel(1, 0).0[0], 255);
    }

    #[test]
    fn failed_write_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png");
        std::fs::write(&path, b"old").unwrap();
        let empty = Film::from_pixels(0, 0, vec![]).unwrap();
        assert!(write_film(&empty, &path).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn text_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("table.md");
        write_bytes_atomically(&path, b"| a |").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"| a |");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let missing = dir.path().join("no/such/dir/table.md");
        assert!(write_bytes_atomically(&missing, b"x").is_err());
    }

    #[test]
    fn unknown_extension_is_refused() {
        assert!(Format::from_path(Path::new("a.jpg")).is_err());
        assert!(check_writable(Path::new("/no/such/dir/a.png")).is_err());
    }
}
