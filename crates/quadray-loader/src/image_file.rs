//! Texture images: decoding PNG and JPEG with the `image` crate, and finding the files that OBJ
//! material libraries and glTF documents name (relative, absolute or Windows-style paths).

use quadray::{ColorEncoding, Image};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Most bytes the decoded textures of one load may take together (2 GiB, RGBA8 counted): each
/// image is within [`crate::read_limited::MAX_IMAGE_ALLOC`], and without a total a few small
/// files that each claim 16384² pixels would take many GiB.
pub const MAX_TEXTURE_BYTES: u64 = 2 << 30;

/// What one load's textures have taken of [`MAX_TEXTURE_BYTES`]; clones share the count, so a
/// scene and the files it includes draw on one budget.
#[derive(Clone, Debug, Default)]
pub struct TextureBudget {
    used: Arc<AtomicU64>,
}

impl TextureBudget {
    /// Takes `bytes` from the budget, or says why they do not fit (and takes nothing).
    pub fn take(&self, bytes: u64) -> Result<(), String> {
        self.used
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |used| {
                used.checked_add(bytes).filter(|&t| t <= MAX_TEXTURE_BYTES)
            })
            .map(|_| ())
            .map_err(|used| {
                format!(
                    "its {} MiB decoded would bring the textures to more than {} MiB together \
                     ({} MiB taken)",
                    bytes >> 20,
                    MAX_TEXTURE_BYTES >> 20,
                    used >> 20
                )
            })
    }
}

/// Images read so far, by resolved path, so a texture shared by many materials is decoded once;
/// a failure is remembered too, so it is reported once.
#[derive(Default)]
pub struct ImageCache {
    images: HashMap<PathBuf, Option<Arc<Image>>>,
    budget: TextureBudget,
}

impl ImageCache {
    /// An empty cache whose images draw on `budget`.
    pub fn new(budget: TextureBudget) -> ImageCache {
        ImageCache {
            images: HashMap::new(),
            budget,
        }
    }

    /// The image at `path`, decoded as sRGB; on failure `None`, with a note saying what happened
    /// and that the base colour is used instead.
    pub fn get(&mut self, path: &Path, user: &str, notes: &mut Vec<String>) -> Option<Arc<Image>> {
        self.images
            .entry(path.to_path_buf())
            .or_insert_with(
                || match read_image(path, ColorEncoding::Srgb, &self.budget) {
                    Ok(img) => Some(Arc::new(img)),
                    Err(e) => {
                        notes.push(format!(
                            "warning: {user}: texture unavailable ({e}); using the base colour"
                        ));
                        None
                    }
                },
            )
            .clone()
    }
}

/// The limits every image decode runs under, checked from the header before pixels are allocated
/// (a 1 kB PNG can claim to be 100 000 pixels square).
pub fn decode_limits() -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(crate::read_limited::MAX_IMAGE_SIDE);
    limits.max_image_height = Some(crate::read_limited::MAX_IMAGE_SIDE);
    limits.max_alloc = Some(crate::read_limited::MAX_IMAGE_ALLOC);
    limits
}

/// Decodes an encoded PNG or JPEG image (format guessed from its bytes) into 8-bit RGBA, taking
/// its decoded size from `budget` first.
pub fn decode_image(
    bytes: &[u8],
    encoding: ColorEncoding,
    budget: &TextureBudget,
) -> Result<Image, String> {
    let reader = || {
        image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    // The header's size, checked before any pixel is decoded.
    let (width, height) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    budget.take(u64::from(width) * u64::from(height) * 4)?;
    let mut reader = reader()?;
    reader.limits(decode_limits());
    let decoded = reader.decode().map_err(|e| e.to_string())?;
    let rgba = decoded.into_rgba8();
    let (w, h) = rgba.dimensions();
    Image::from_rgba8(w, h, rgba.into_raw(), encoding).map_err(|e| e.to_string())
}

/// Reads and decodes the image file at `path`, drawing on `budget`.
pub fn read_image(
    path: &Path,
    encoding: ColorEncoding,
    budget: &TextureBudget,
) -> Result<Image, String> {
    let bytes = crate::read_limited::read(path, crate::read_limited::MAX_IMAGE_BYTES)
        .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let image = decode_image(&bytes, encoding, budget)
        .map_err(|e| format!("cannot decode `{}`: {e}", path.display()))?;
    log::debug!(
        "decoded {}: {}x{}",
        path.display(),
        image.width(),
        image.height()
    );
    Ok(image)
}

/// Resolves a file reference written in another file against that file's folder `base`.
///
/// References written on Windows use backslashes (`textures\wood.png`) and sometimes drive
/// letters; on other systems the backslashes become separators. When the reference does not exist
/// as written, its last component is tried in `base` (exporters often leave absolute paths of the
/// author's machine), and then the same name with any letter case (files copied through
/// case-insensitive file systems). The first existing candidate wins; if none exists, the plain
/// resolution is returned so that the error names what was expected.
pub fn resolve_reference(base: &Path, reference: &str) -> PathBuf {
    let normalised = reference.trim().replace('\\', "/");
    let written = Path::new(&normalised);
    let plain = if written.is_absolute() {
        written.to_path_buf()
    } else {
        base.join(written)
    };
    if plain.is_file() {
        return plain;
    }
    let Some(name) = normalised.rsplit('/').next().filter(|n| !n.is_empty()) else {
        return plain;
    };
    let beside = base.join(name);
    if beside.is_file() {
        return beside;
    }
    if let Ok(entries) = std::fs::read_dir(base) {
        for entry in entries.flatten() {
            if entry
                .file_name()
                .to_string_lossy()
                .eq_ignore_ascii_case(name)
            {
                return entry.path();
            }
        }
    }
    plain
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_paths_and_stray_folders_resolve() {
        let dir = std::env::temp_dir().join(format!("quadray-imgref-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("tex")).unwrap();
        std::fs::write(dir.join("tex").join("Wood.png"), b"x").unwrap();
        assert_eq!(
            resolve_reference(&dir, "tex\\Wood.png"),
            dir.join("tex/Wood.png")
        );
        // An absolute path from another machine falls back to the name beside the file... which
        // here only exists in tex/, so the plain resolution is returned.
        let far = resolve_reference(&dir, "C:\\Users\\me\\Wood.png");
        assert!(far.ends_with("C:/Users/me/Wood.png"), "{}", far.display());
        std::fs::write(dir.join("wood.png"), b"x").unwrap();
        assert_eq!(
            resolve_reference(&dir, "C:\\Users\\me\\wood.png"),
            dir.join("wood.png")
        );
        // Case-insensitive fallback.
        assert_eq!(
            resolve_reference(&dir.join("tex"), "WOOD.PNG"),
            dir.join("tex").join("Wood.png")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn decodes_png_and_reports_garbage() {
        let mut png = Vec::new();
        image::RgbaImage::from_raw(2, 1, vec![255, 0, 0, 255, 0, 0, 255, 128])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let budget = TextureBudget::default();
        let img = decode_image(&png, ColorEncoding::Srgb, &budget).unwrap();
        assert_eq!((img.width(), img.height()), (2, 1));
        assert_eq!(img.texel(0, 0), glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
        assert!(decode_image(b"not an image", ColorEncoding::Srgb, &budget).is_err());
        // The budget is shared by clones and taken from the header before decoding.
        let shared = budget.clone();
        shared.take(MAX_TEXTURE_BYTES - 8 - 4).unwrap();
        let e = decode_image(&png, ColorEncoding::Srgb, &budget).unwrap_err();
        assert!(e.contains("more than 2048 MiB together"), "{e}");
        assert!(budget.take(4).is_ok() && budget.take(1).is_err());
    }
}
