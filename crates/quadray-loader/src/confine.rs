//! Confinement: keeping every file a process reads or writes inside one folder, for scenes from
//! strangers (a render service, a farm's queue). Without it a scene names any file it likes: a
//! glTF buffer `../../etc/passwd` (or `file:` and `%2e%2e` spellings of it) is read, `convert`
//! copies its bytes into a `.glb`, and error messages echo some of them; an `[output] file`
//! writes or replaces any image anywhere.
//!
//! The policy is the process's, like POV-Ray's I/O restrictions: set once (the CLI's `--confine
//! DIR`, or the `QUADRAY_CONFINE` environment variable), it holds for every read through
//! [`crate::read_limited`] and every write through [`crate::atomic_file`], which all of quadray's
//! file access goes through. Paths are compared after resolving symbolic links and `..`, so a
//! link inside the folder that points out of it is outside. The default is no confinement: a
//! user's own scenes may use shared texture folders anywhere.
//!
//! The same choke point can list what was read ([`record_reads`]), which `quadray check` prints.

use std::cell::RefCell;
use std::io::{Error, ErrorKind};
use std::path::{Path, PathBuf};
use std::sync::RwLock;

/// The environment variable that confines a process when no `--confine` is given.
pub const ENV: &str = "QUADRAY_CONFINE";

static ROOT: RwLock<Option<PathBuf>> = RwLock::new(None);
thread_local! {
    /// The files this thread has read since [`record_reads`], when they are being listed: the
    /// loader reads on the thread that asked, so two loads on two threads keep their own lists.
    static READS: RefCell<Option<Vec<PathBuf>>> = const { RefCell::new(None) };
}

/// Confines every later read and write to `dir` (resolved: it must exist and be a folder).
pub fn confine_to(dir: &Path) -> std::io::Result<PathBuf> {
    let root = std::fs::canonicalize(dir).map_err(|e| {
        Error::new(
            e.kind(),
            format!("confinement folder {}: {e}", dir.display()),
        )
    })?;
    if !root.is_dir() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!("confinement folder {} is not a folder", dir.display()),
        ));
    }
    *ROOT.write().unwrap_or_else(|e| e.into_inner()) = Some(root.clone());
    Ok(root)
}

/// The folder reads and writes are confined to, if any.
pub fn root() -> Option<PathBuf> {
    ROOT.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// An error unless the existing file `path` lies inside the confinement folder (or there is
/// none).
pub fn check_read(path: &Path) -> std::io::Result<()> {
    root().map_or(Ok(()), |root| read_within(&root, path))
}

fn read_within(root: &Path, path: &Path) -> std::io::Result<()> {
    match std::fs::canonicalize(path) {
        Ok(resolved) => inside(root, &resolved, path),
        // A file that cannot be resolved (missing) is judged by its spelling, so that "not
        // found" and "outside" do not tell a stranger which files exist outside the folder.
        Err(e) => {
            let spelt = lexical(path);
            inside(root, &spelt, path)?;
            Err(e)
        }
    }
}

/// `path` made absolute and with `.` and `..` taken away by spelling alone (links unresolved).
fn lexical(path: &Path) -> PathBuf {
    use std::path::Component;
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = PathBuf::new();
    for part in absolute.components() {
        match part {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// An error unless the file `path` would be written inside the confinement folder (or there is
/// none). The file need not exist: its folder is resolved, and the name joined to it (a link in
/// that place is replaced, not followed, by the rename that writes it).
pub fn check_write(path: &Path) -> std::io::Result<()> {
    root().map_or(Ok(()), |root| write_within(&root, path))
}

fn write_within(root: &Path, path: &Path) -> std::io::Result<()> {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| Error::new(ErrorKind::InvalidInput, "the output path names no file"))?;
    let resolved = std::fs::canonicalize(folder)?.join(name);
    inside(root, &resolved, path)
}

fn inside(root: &Path, resolved: &Path, asked: &Path) -> std::io::Result<()> {
    if resolved.starts_with(root) {
        return Ok(());
    }
    Err(Error::new(
        ErrorKind::PermissionDenied,
        format!(
            "{} is outside the confinement folder {} (--confine or {ENV})",
            if resolved == asked {
                resolved.display().to_string()
            } else {
                format!("{} (resolved: {})", asked.display(), resolved.display())
            },
            root.display()
        ),
    ))
}

/// Starts listing the files this thread reads from now on, for [`take_reads`].
pub fn record_reads() {
    READS.with_borrow_mut(|reads| *reads = Some(Vec::new()));
}

/// Notes that `path` was read, if reads are being listed.
pub(crate) fn note_read(path: &Path) {
    READS.with_borrow_mut(|reads| {
        if let Some(list) = reads.as_mut() {
            let resolved = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
            if !list.contains(&resolved) {
                list.push(resolved);
            }
        }
    });
}

/// The files this thread read since [`record_reads`] (resolved, each once, in order of first
/// read), and stops listing.
pub fn take_reads() -> Vec<PathBuf> {
    READS.with_borrow_mut(Option::take).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    // The process-wide setting is exercised end to end by the CLI's tests, in their own
    // processes: setting it here would confine the other tests of this binary running beside.
    #[test]
    fn reads_and_writes_outside_the_folder_are_refused() {
        let base = tempfile::tempdir().unwrap();
        let inner = base.path().join("scenes");
        std::fs::create_dir(&inner).unwrap();
        std::fs::write(inner.join("in.txt"), b"x").unwrap();
        std::fs::write(base.path().join("out.txt"), b"x").unwrap();
        let root = std::fs::canonicalize(&inner).unwrap();
        read_within(&root, &inner.join("in.txt")).unwrap();
        write_within(&root, &inner.join("new.png")).unwrap();
        // Outside whether or not the file exists: the answer must not tell which.
        for refused in [
            base.path().join("out.txt"),
            inner.join("../out.txt"),
            inner.join("../missing.txt"),
        ] {
            let e = read_within(&root, &refused).unwrap_err();
            assert_eq!(e.kind(), ErrorKind::PermissionDenied);
            assert!(
                e.to_string().contains("outside the confinement folder"),
                "{e}"
            );
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(base.path().join("out.txt"), inner.join("link.txt"))
                .unwrap();
            assert!(
                read_within(&root, &inner.join("link.txt")).is_err(),
                "a link out"
            );
        }
        assert!(write_within(&root, &base.path().join("new.png")).is_err());
        assert!(write_within(&root, &inner.join("../new.png")).is_err());
    }
}
