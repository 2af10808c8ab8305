//! The files and images a glTF file refers to: URIs (base64 `data:`, `file:`, or paths relative
//! to the file, percent-decoded), and images in a URI or a buffer view, decoded as sRGB.

use super::document::GltfFile;
use crate::image_file::{decode_image, resolve_reference};
use base64::Engine;
use quadray::{ColorEncoding, Image};
use std::path::{Path, PathBuf};

/// Why a URI could not be read.
pub enum UriError {
    /// The file it names could not be read.
    Io(PathBuf, std::io::Error),
    /// The URI itself is malformed or of a kind quadray does not fetch.
    Invalid(String),
}

/// The bytes a URI refers to: a base64 data URI, a `file:` URI, or a path relative to `base`
/// (percent-decoded, Windows separators accepted).
pub fn read_uri(base: &Path, uri: &str) -> Result<Vec<u8>, UriError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or_else(|| UriError::Invalid("a data URI must be base64 (`;base64,`)".into()))?;
        return base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| UriError::Invalid(format!("bad base64 in data URI: {e}")));
    }
    let local = if let Some(rest) = uri.strip_prefix("file://") {
        rest
    } else if let Some(rest) = uri.strip_prefix("file:") {
        rest
    } else if let Some((scheme, _)) = uri.split_once("://") {
        return Err(UriError::Invalid(format!(
            "`{scheme}://` URIs are not fetched; only relative paths, file: and data: URIs are read"
        )));
    } else {
        uri
    };
    let decoded = percent_encoding::percent_decode_str(local)
        .decode_utf8()
        .map_err(|_| UriError::Invalid(format!("`{uri}` is not valid percent-encoded UTF-8")))?;
    let file = resolve_reference(base, &decoded);
    crate::read_limited::read(&file, crate::read_limited::MAX_MESH_BYTES)
        .map_err(|e| UriError::Io(file, e))
}

/// Decodes image `image` of the document as sRGB, or says why it cannot be.
pub fn read_image(
    file: &GltfFile,
    image: &gltf::Image<'_>,
    budget: &crate::image_file::TextureBudget,
) -> Result<Image, String> {
    // The gltf crate's `source` unwraps: an image with a bufferView needs a mimeType, and one
    // without needs a uri (the spec says so; hostile files do not). Checked here first.
    let json = file.document.as_json();
    let raw = json
        .images
        .get(image.index())
        .ok_or_else(|| format!("image {} does not exist", image.index()))?;
    match (&raw.buffer_view, &raw.mime_type, &raw.uri) {
        (Some(_), None, _) => {
            return Err(format!(
                "image {} reads a bufferView but has no mimeType (glTF requires one)",
                image.index()
            ));
        }
        (None, _, None) => {
            return Err(format!(
                "image {} has neither a uri nor a bufferView",
                image.index()
            ));
        }
        _ => {}
    }
    let bytes = match image.source() {
        gltf::image::Source::Uri { uri, .. } => {
            let bytes = read_uri(&file.base, uri).map_err(|e| match e {
                UriError::Io(p, e) => format!("cannot read `{}`: {e}", p.display()),
                UriError::Invalid(m) => m,
            })?;
            // Name the file: a decoder's message alone ("format could not be determined") does
            // not say which of a model's images it is about.
            let shown = if uri.starts_with("data:") {
                "data URI"
            } else {
                uri
            };
            return decode_image(&bytes, ColorEncoding::Srgb, budget)
                .map_err(|e| format!("cannot decode `{shown}`: {e}"));
        }
        gltf::image::Source::View { view, .. } => {
            let buffer = file
                .buffers
                .get(view.buffer().index())
                .ok_or_else(|| format!("buffer {} is missing", view.buffer().index()))?;
            buffer
                .get(view.offset()..)
                .and_then(|b| b.get(..view.length()))
                .ok_or_else(|| format!("buffer view {} lies outside its buffer", view.index()))?
                .to_vec()
        }
    };
    decode_image(&bytes, ColorEncoding::Srgb, budget)
}
