//! Reading the files a scene names within documented sizes: only regular files are read (never a
//! device such as `/dev/zero` or a pipe, which would never end), and none larger than the limit
//! for its kind, checked before anything is allocated.

use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// Largest native scene (TOML) file read: 64 MiB.
pub const MAX_SCENE_BYTES: u64 = 64 << 20;
/// Largest OBJ, glTF, GLB or glTF buffer file read: 4 GiB.
pub const MAX_MESH_BYTES: u64 = 4 << 30;
/// Largest MTL material library read: 64 MiB.
pub const MAX_MATERIAL_BYTES: u64 = 64 << 20;
/// Largest encoded image (PNG, JPEG) read: 512 MiB.
pub const MAX_IMAGE_BYTES: u64 = 512 << 20;
/// Largest decoded image side, in pixels (as the render resolution's).
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most memory one image decode may allocate: 1 GiB.
pub const MAX_IMAGE_ALLOC: u64 = 1 << 30;

/// The metadata of `path` if it is a regular file (after following links); an error for a
/// device, a pipe (whose read would block or never end) or a folder.
/// A file outside the confinement folder ([`crate::confine`]) is refused the same way.
pub fn regular_file(path: &Path) -> std::io::Result<std::fs::Metadata> {
    crate::confine::check_read(path)?;
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (devices, pipes and folders are not read)",
        ));
    }
    Ok(meta)
}

/// The bytes of the regular file at `path`, if it holds at most `limit` of them.
pub fn read(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let meta = regular_file(path)?;
    let too_large = |size: u64| {
        Error::new(
            ErrorKind::InvalidData,
            format!("the file is {size} bytes; at most {limit} are read for this kind of file"),
        )
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    // The file may grow while it is read: never take more than the limit.
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64));
    }
    log::debug!("read {} ({} bytes)", path.display(), bytes.len());
    crate::confine::note_read(path);
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_and_oversized_files_are_refused() {
        if Path::new("/dev/zero").exists() {
            let e = read(Path::new("/dev/zero"), 1 << 20).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let dir = tempfile::tempdir().unwrap();
        assert!(read(dir.path(), 10).is_err());
        let file = dir.path().join("f");
        std::fs::write(&file, [0u8; 100]).unwrap();
        let e = read(&file, 99).unwrap_err();
        assert!(e.to_string().contains("100 bytes; at most 99"), "{e}");
        assert_eq!(read(&file, 100).unwrap().len(), 100);
    }
}
