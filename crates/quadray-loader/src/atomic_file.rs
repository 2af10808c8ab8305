//! Replacing a file only once its new contents are complete: the one temporary-file-and-rename
//! mechanism behind every output quadray writes (images, reports, glTF).
//!
//! The new contents go to a hidden temporary file beside the target, named
//! `.NAME.pPID.XXXXXX.quadray-tmp.EXT` (recognisable, and keeping the extension, since image
//! writers pick their format from it), which is renamed over the target when complete. On any
//! error it is deleted (the `tempfile` crate deletes it when dropped), and an older target
//! survives untouched. A process killed outright (SIGKILL) cannot delete it; the next write of the
//! same target removes such leftovers, but only those whose process (the PID in the name) is gone,
//! so a render still running into the same file is never disturbed.

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
    let prefix = format!(".{name}.p");
    remove_leftovers(&dir, &prefix, &suffix);
    let tmp = tempfile::Builder::new()
        .prefix(&format!("{prefix}{}.", std::process::id()))
        .suffix(&suffix)
        .tempfile_in(&dir)?;
    write(tmp.path())?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Deletes the temporary files of earlier writes to the same target (`prefix` PID `.` random
/// `suffix`) whose process no longer runs. Best effort: where processes cannot be looked up
/// (no `/proc`), or a file cannot be removed, it stays.
fn remove_leftovers(dir: &Path, prefix: &str, suffix: &str) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(name) = file_name.to_str() else {
            continue;
        };
        // PID `.` RANDOM SUFFIX exactly, RANDOM without dots: another target whose name merely
        // starts like this one's (`out.png.p3.png`) never matches.
        let Some(pid) = name
            .strip_prefix(prefix)
            .and_then(|rest| rest.split_once('.'))
            .filter(|(_, tail)| {
                tail.strip_suffix(suffix)
                    .is_some_and(|random| !random.is_empty() && !random.contains('.'))
            })
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if !proc.join(pid.to_string()).exists() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
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

    /// Leftovers of a dead process writing the same target go; those of a live process (PID 1
    /// always runs), of other targets and of other programs stay.
    #[test]
    fn leftovers_of_dead_processes_are_removed() {
        if !Path::new("/proc/self").exists() {
            eprintln!("skipped: no /proc on this system");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.png");
        let keep = [
            ".out.png.p1.abcdef.quadray-tmp.png",
            ".out.png.p3.png.p999999999.abcdef.quadray-tmp.png",
            ".other.png.p999999999.abcdef.quadray-tmp.png",
            ".out.png.p999999999.abcdef.png",
            "notes.txt",
        ];
        for name in keep {
            std::fs::write(dir.path().join(name), b"x").unwrap();
        }
        std::fs::write(
            dir.path()
                .join(".out.png.p999999999.abcdef.quadray-tmp.png"),
            b"x",
        )
        .unwrap();
        replace(&target, b"new").unwrap();
        let mut expected: Vec<&str> = keep.to_vec();
        expected.push("out.png");
        expected.sort();
        assert_eq!(entries(dir.path()), expected);
    }
}
