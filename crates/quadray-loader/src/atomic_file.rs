//! Replacing a file only once its new contents are complete: the one temporary-file-and-rename
//! mechanism behind every output quadray writes (images, reports, glTF).
//!
//! The new contents go to a hidden temporary file beside the target, named
//! `.NAME.XXXXXX.quadray-tmp.EXT` (recognisable, and keeping the extension, since image writers
//! pick their format from it), which is renamed over the target when complete. On any error it
//! is deleted (the `tempfile` crate deletes it when dropped), and an older target survives
//! untouched. A process killed outright (SIGKILL) cannot delete it: such a leftover is safe to
//! remove, and the target is never half-written either way.

use std::path::{Path, PathBuf};

/// Writes through `write`, which fills the temporary file at the path it is given, then renames
/// that file to `path`. `write`'s error (or the rename's) is returned; the temporary file is gone.
pub fn replace_with<E: From<std::io::Error>>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("output");
    let suffix = match path.extension().and_then(|e| e.to_str()) {
        Some(ext) => format!(".quadray-tmp.{ext}"),
        None => ".quadray-tmp".to_string(),
    };
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(&suffix)
        .tempfile_in(&dir)?;
    write(tmp.path())?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// [`replace_with`] for contents already in memory.
pub fn replace(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    replace_with(path, |tmp| std::fs::write(tmp, contents))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn failures_leave_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.png");
        std::fs::write(&target, b"old").unwrap();
        let failed: std::io::Result<()> = replace_with(&target, |tmp| {
            assert!(
                tmp.file_name()
                    .unwrap()
                    .to_str()
                    .unwrap()
                    .ends_with(".quadray-tmp.png")
            );
            std::fs::write(tmp, b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(entries(dir.path()), vec!["out.png"]);
        replace(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(entries(dir.path()), vec!["out.png"]);
    }
}
