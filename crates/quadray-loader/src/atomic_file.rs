//! Replacing a file only once its new contents are complete and on disk: the one
//! temporary-file-and-rename mechanism behind every output quadray writes (images, reports, glTF).
//!
//! The new contents go to a hidden temporary file beside the target, named
//! `.NAME.pPID.XXXXXX.quadray-tmp.EXT` (recognisable, and keeping the extension), where NAME is
//! the target's name cut short enough that the whole temporary name fits the 255-byte limit of
//! common file systems, so every legal output name can be written. The writer fills it through a
//! buffered writer that this module flushes and checks (a buffered writer dropped unflushed loses
//! its last error: a full disk then left an empty file), then the file is `fsync`ed, renamed over
//! the target, and the folder is `fsync`ed so the rename itself survives a power cut.
//!
//! The file gets the target's permission bits when the target exists (as an editor keeps them),
//! else `0666` less the process's umask, as `cp` or `touch` would create it.
//!
//! A target that is a symbolic link is written through: the file its chain of links ends at is
//! replaced (beside itself, in its own folder), and the link stays a link, as `cp` and a shell's
//! `>` treat one.
//!
//! On any error the temporary file is deleted (the `tempfile` crate deletes it when dropped), and
//! an older target survives untouched. A process ending on a signal it can handle deletes the
//! temporary files being written through [`remove_pending`] (the CLI's handler of SIGINT, SIGTERM
//! and SIGHUP). A process killed outright (SIGKILL) cannot delete it; the
//! next write of the same target removes such leftovers, but only those whose process (the PID in
//! the name) is gone, so a render still running into the same file is never disturbed.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The buffered writer a [`replace_with`] writer fills; it is flushed, checked and synced after.
pub type Writer<'a> = BufWriter<&'a mut File>;

/// The longest file name the temporary file may have: the limit of ext4, XFS, btrfs, tmpfs and
/// NTFS (in bytes, or UTF-16 units on NTFS, which are never more than UTF-8 bytes).
const NAME_MAX: usize = 255;

/// What a temporary name adds to the cut target name: `.`, `.p`, a PID of up to 10 digits, `.`,
/// six random characters and the suffix (whose extension is counted separately).
const NAME_OVERHEAD: usize = 1 + 2 + 10 + 1 + 6;

/// Writes through `write`, which fills the temporary file through the buffered writer it is
/// given, then flushes, syncs and renames that file to `path`. `write`'s error (or the flush's,
/// the sync's, the rename's) is returned; the temporary file is then gone and an older `path`
/// is as it was.
pub fn replace_with<E: From<std::io::Error>>(
    path: &Path,
    write: impl FnOnce(&mut Writer<'_>) -> Result<(), E>,
) -> Result<(), E> {
    Ok(Written::new(path, write)?.commit()?)
}

/// [`replace_with`] for contents already in memory.
pub fn replace(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    replace_with(path, |w| w.write_all(contents))
}

/// Replaces several files that belong together (a `.gltf` and its `.bin`) only once all their
/// new contents are complete and on disk: a failure before the renames (a full disk, a target
/// that is a folder) leaves every older file as it was. The renames then run in order; one that
/// fails after another succeeded (the folder's permissions changed meanwhile) leaves the files
/// renamed before it replaced. The error comes with the file it concerns.
pub fn replace_all(files: &[(&Path, &[u8])]) -> Result<(), (PathBuf, std::io::Error)> {
    // A folder in a target's place fails only at its rename: refused before any file is replaced.
    for &(path, _) in files {
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.is_dir()) {
            let e = std::io::Error::new(std::io::ErrorKind::IsADirectory, "a folder is there");
            return Err((path.to_path_buf(), e));
        }
    }
    let written = (files.iter())
        .map(|&(path, contents)| {
            Written::new(path, |w| w.write_all(contents)).map_err(|e| (path.to_path_buf(), e))
        })
        .collect::<Result<Vec<_>, _>>()?;
    for w in written {
        let path = w.path.clone();
        w.commit().map_err(|e| (path, e))?;
    }
    Ok(())
}

/// The temporary files being written now, by any thread: what [`remove_pending`] deletes.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Deletes every temporary file being written now. For a process about to end on a signal
/// (Ctrl-C, `kill`, a closed terminal), which runs no destructors: older outputs are untouched,
/// and no half-written temporary file is left. Best effort: a file already renamed over its
/// target, or that cannot be removed, stays.
pub fn remove_pending() {
    let pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
    for path in pending.iter() {
        let _ = std::fs::remove_file(path);
    }
}

/// A temporary file listed in [`PENDING`] while it lives.
struct Listed(PathBuf);

impl Listed {
    fn new(path: &Path) -> Listed {
        PENDING
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(path.to_path_buf());
        Listed(path.to_path_buf())
    }
}

impl Drop for Listed {
    fn drop(&mut self) {
        let mut pending = PENDING.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(k) = pending.iter().position(|p| *p == self.0) {
            pending.swap_remove(k);
        }
    }
}

/// New contents complete and synced in a temporary file beside their target, not yet renamed
/// over it; dropped, the temporary file is deleted.
struct Written {
    tmp: tempfile::NamedTempFile,
    path: PathBuf,
    dir: PathBuf,
    /// Listed for [`remove_pending`] until renamed or deleted.
    _listed: Listed,
}

impl Written {
    /// Fills a temporary file beside `path` through `write`, then flushes and syncs it.
    fn new<E: From<std::io::Error>>(
        path: &Path,
        write: impl FnOnce(&mut Writer<'_>) -> Result<(), E>,
    ) -> Result<Written, E> {
        let target = link_target(path)?;
        let path = target.as_path();
        crate::confine::check_write(path)?;
        let dir = parent_dir(path);
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("output");
        let suffix = match path.extension().and_then(|e| e.to_str()) {
            Some(ext) => format!(".quadray-tmp.{ext}"),
            None => ".quadray-tmp".to_string(),
        };
        // An extension too long for any temporary name leaves none of NAME; the write then
        // fails with the file system's own error.
        let room = NAME_MAX.saturating_sub(NAME_OVERHEAD + suffix.len());
        let prefix = format!(".{}.p", cut_to(name, room));
        remove_leftovers(&dir, &prefix, &suffix);
        let pid_prefix = format!("{prefix}{}.", std::process::id());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&pid_prefix).suffix(&suffix);
        ask_for_default_mode(&mut builder);
        let mut tmp = builder.tempfile_in(&dir)?;
        let listed = Listed::new(tmp.path());
        {
            let mut writer = BufWriter::new(tmp.as_file_mut());
            write(&mut writer)?;
            writer.flush()?;
        }
        keep_existing_mode(path, tmp.as_file())?;
        tmp.as_file().sync_all()?;
        Ok(Written {
            tmp,
            path: path.to_path_buf(),
            dir,
            _listed: listed,
        })
    }

    /// Renames the temporary file over the target, and makes the rename durable.
    fn commit(self) -> std::io::Result<()> {
        self.tmp.persist(&self.path).map_err(|e| e.error)?;
        sync_dir(&self.dir);
        Ok(())
    }
}

/// The most symbolic links followed from one target (Linux's own limit).
const MAX_LINKS: usize = 40;

/// Where `path`'s chain of symbolic links ends (`path` itself when it is no link), whether that
/// file exists or not.
fn link_target(path: &Path) -> std::io::Result<PathBuf> {
    let mut target = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&target) {
            Ok(meta) if meta.file_type().is_symlink() => {
                // A relative link is relative to its own folder; an absolute one replaces it all.
                target = parent_dir(&target).join(std::fs::read_link(&target)?);
            }
            _ => return Ok(target),
        }
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("more than {MAX_LINKS} symbolic links, or a loop of them"),
    ))
}

fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The longest start of `name` of at most `max` bytes that ends on a character boundary.
fn cut_to(name: &str, max: usize) -> &str {
    if name.len() <= max {
        return name;
    }
    let mut end = max;
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name[..end]
}

/// Asks for mode `0666` on creation, which the kernel narrows by the umask: the mode a new file
/// of `cp` gets (the `tempfile` crate's default, `0600`, hid renders from a farm's other users).
/// An existing target's mode is copied after creation by [`keep_existing_mode`], since creation
/// cannot widen past the umask. Elsewhere than Unix a new file's default permissions are right.
fn ask_for_default_mode(builder: &mut tempfile::Builder<'_, '_>) {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    #[cfg(not(unix))]
    let _ = builder;
}

/// Gives the temporary file the permission bits of the file it replaces, if that is a regular
/// file: replacing a shared `0644` render must not make it private. Only the read, write and
/// execute bits are copied, never set-user-ID, set-group-ID or sticky.
fn keep_existing_mode(path: &Path, tmp: &File) -> std::io::Result<()> {
    match std::fs::metadata(path) {
        Ok(old) if old.is_file() => tmp.set_permissions(plain_bits(old.permissions())),
        _ => Ok(()),
    }
}

#[cfg(unix)]
fn plain_bits(p: std::fs::Permissions) -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt;
    std::fs::Permissions::from_mode(p.mode() & 0o777)
}

#[cfg(not(unix))]
fn plain_bits(p: std::fs::Permissions) -> std::fs::Permissions {
    p
}

/// Makes a rename in `dir` durable. Best effort: a folder cannot be opened for syncing on every
/// platform (Windows), and the data itself was synced before the rename.
fn sync_dir(dir: &Path) {
    if let Ok(handle) = File::open(dir) {
        let _ = handle.sync_all();
    }
}

/// Deletes the temporary files of earlier writes to the same target (`prefix` PID `.` random
/// `suffix`) whose process no longer runs. Best effort: where processes cannot be looked up
/// (no `/proc`), or a file cannot be removed, it stays. The PID is looked up on this machine and
/// in this PID namespace: processes of other machines writing into a shared folder (NFS) are not
/// known here, so render farms should give each worker its own output names, as
/// `render --tile` does.
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

    /// A link is written through: the file it ends at gets the contents, beside itself, and the
    /// link stays; a dangling link makes its file; a loop of links is an error.
    #[cfg(unix)]
    #[test]
    fn links_are_written_through() {
        use std::os::unix::fs::symlink;
        let dir = tempfile::tempdir().unwrap();
        let (real, sub) = (dir.path().join("real.png"), dir.path().join("renders"));
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(&real, b"old").unwrap();
        // A relative link, reached through a second link in another folder.
        symlink("real.png", dir.path().join("first.png")).unwrap();
        symlink("../first.png", sub.join("out.png")).unwrap();
        replace(&sub.join("out.png"), b"new").unwrap();
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        assert!(
            sub.join("out.png")
                .symlink_metadata()
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(entries(&sub), vec!["out.png"]);
        assert_eq!(
            entries(dir.path()),
            vec!["first.png", "real.png", "renders"]
        );
        // A dangling link makes the file it names.
        symlink(dir.path().join("made.png"), dir.path().join("dangling.png")).unwrap();
        replace(&dir.path().join("dangling.png"), b"made").unwrap();
        assert_eq!(std::fs::read(dir.path().join("made.png")).unwrap(), b"made");
        // A loop is refused, and nothing is written.
        symlink("b.png", dir.path().join("a.png")).unwrap();
        symlink("a.png", dir.path().join("b.png")).unwrap();
        let error = replace(&dir.path().join("a.png"), b"x").unwrap_err();
        assert!(error.to_string().contains("loop"), "{error}");
    }

    #[test]
    fn failures_leave_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.png");
        std::fs::write(&target, b"old").unwrap();
        let failed: std::io::Result<()> = replace_with(&target, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(entries(dir.path()), vec!["out.png"]);
        replace(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(entries(dir.path()), vec!["out.png"]);
    }

    /// Files replaced together: all or none. A folder in the second's place leaves the first
    /// as it was and no temporary file; with the way clear both are replaced.
    #[test]
    fn files_that_belong_together_are_replaced_together() {
        let dir = tempfile::tempdir().unwrap();
        let (first, second) = (dir.path().join("a.bin"), dir.path().join("a.gltf"));
        std::fs::write(&first, b"old").unwrap();
        std::fs::create_dir(&second).unwrap();
        let files: [(&Path, &[u8]); 2] = [(&first, b"new bin"), (&second, b"new gltf")];
        let (path, e) = replace_all(&files).unwrap_err();
        assert_eq!(
            (path.as_path(), e.kind()),
            (second.as_path(), std::io::ErrorKind::IsADirectory)
        );
        assert_eq!(std::fs::read(&first).unwrap(), b"old");
        assert_eq!(entries(dir.path()), vec!["a.bin", "a.gltf"]);
        std::fs::remove_dir(&second).unwrap();
        replace_all(&files).unwrap();
        assert_eq!(std::fs::read(&first).unwrap(), b"new bin");
        assert_eq!(std::fs::read(&second).unwrap(), b"new gltf");
        assert_eq!(entries(dir.path()), vec!["a.bin", "a.gltf"]);
    }

    /// The temporary file sits beside the target, hidden, with the target's extension.
    #[test]
    fn the_temporary_name_is_hidden_and_keeps_the_extension() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.png");
        let mut seen = Vec::new();
        replace_with(&target, |_| {
            seen = entries(dir.path());
            Ok::<(), std::io::Error>(())
        })
        .unwrap();
        assert_eq!(seen.len(), 1, "{seen:?}");
        assert!(seen[0].starts_with(".out.png.p"), "{seen:?}");
        assert!(seen[0].ends_with(".quadray-tmp.png"), "{seen:?}");
    }

    /// Every name the file system accepts can be written: 255 bytes, also in multi-byte UTF-8.
    #[test]
    fn names_up_to_the_file_system_limit_are_written() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            format!("{}.png", "a".repeat(251)),
            format!("{}.png", "é".repeat(125)),
            "b".repeat(255),
        ] {
            assert!(name.len() <= 255);
            let target = dir.path().join(&name);
            replace(&target, b"x").unwrap_or_else(|e| panic!("{} bytes: {e}", name.len()));
            assert_eq!(std::fs::read(&target).unwrap(), b"x");
            std::fs::remove_file(&target).unwrap();
        }
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn cut_to_ends_on_a_character_boundary() {
        assert_eq!(cut_to("abc", 5), "abc");
        assert_eq!(cut_to("abcdef", 3), "abc");
        assert_eq!(cut_to("éé", 3), "é");
    }

    /// A new file gets 0666 less the umask; a replaced file keeps its own mode.
    #[cfg(unix)]
    #[test]
    fn modes_follow_the_umask_or_the_replaced_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        // What the umask makes of 0666, as plain `File::create` (also 0666) shows it.
        let probe = dir.path().join("probe");
        File::create(&probe).unwrap();
        let fresh = dir.path().join("new.png");
        replace(&fresh, b"x").unwrap();
        assert_eq!(mode(&fresh), mode(&probe));
        let shared = dir.path().join("shared.png");
        std::fs::write(&shared, b"old").unwrap();
        std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o644)).unwrap();
        replace(&shared, b"new").unwrap();
        assert_eq!(mode(&shared), 0o644);
        std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o640)).unwrap();
        replace(&shared, b"newer").unwrap();
        assert_eq!(mode(&shared), 0o640);
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
