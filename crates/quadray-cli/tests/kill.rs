//! Outputs survive a killed render (SIGKILL, which no handler sees, at many moments) and a full
//! disk, and keep the permissions a user expects.

use crate::common;
use common::{quadray, render_to, scene, tmp};
use std::process::Command;

/// A render of scenes/defense.toml into `out` on one thread with `args`, started and not waited
/// for (its messages dropped).
fn start_render(out: &std::path::Path, args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args([
            "render",
            &scene("defense.toml"),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["-t", "1", "-q"])
        .args(args)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// A render killed outright (SIGKILL, which no handler sees) at several moments never damages the
/// previous output: it stays byte for byte and decodes; any leftover is a recognisable hidden
/// temporary file; and the next render succeeds, replaces the output and removes the leftovers.
#[test]
fn killed_renders_leave_the_previous_output_intact() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["png", "exr"] {
        let out = tmp(&dir, &format!("kill.{ext}"));
        assert!(render_to("defense.toml", &out, "64x48").status.success());
        let mut before = std::fs::read(&out).unwrap();
        let first = before.clone();
        // Kills while rendering (a long render), then at moments spread over short renders, so
        // some land while the image is being written.
        let long = [0u64, 30, 120, 400].map(|d| (d, "1600x1200"));
        let short = (0..24u64).map(|i| (i * 4, "480x360"));
        for (delay_ms, res) in long.into_iter().chain(short) {
            let mut child = start_render(&out, &["--res", res, "--spp", "4"]);
            std::thread::sleep(std::time::Duration::from_millis(delay_ms));
            let _ = child.kill(); // SIGKILL on Unix; the render may have finished already
            let finished = child.wait().unwrap().success();
            let now = std::fs::read(&out).unwrap();
            if finished {
                before = now; // a complete render replaced it: that one must decode too
            } else {
                assert_eq!(now, before, "{ext}, killed after {delay_ms} ms");
            }
            let decodes = match ext {
                "png" => image::open(&out).map(|_| ()).map_err(|e| e.to_string()),
                _ => exr::prelude::read_first_flat_layer_from_file(&out)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
            };
            decodes.unwrap_or_else(|e| panic!("{ext}: the old output decodes: {e}"));
        }
        for entry in std::fs::read_dir(dir.path()).unwrap() {
            let name = entry.unwrap().file_name().to_string_lossy().into_owned();
            assert!(
                name.starts_with("kill.")
                    || name.starts_with(".kill.") && name.contains(".quadray-tmp."),
                "unexpected file {name}"
            );
        }
        let o = quadray(&[
            "render",
            &scene("quadrics.toml"),
            "-o",
            out.to_str().unwrap(),
            "--res",
            "64x48",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".quadray-tmp."))
            .collect();
        assert!(
            leftovers.is_empty() || !std::path::Path::new("/proc/self").exists(),
            "the next render removes what killed renders left: {leftovers:?}"
        );
        assert_ne!(
            std::fs::read(&out).unwrap(),
            first,
            "the next render replaced it"
        );
    }
}

/// A render ended by SIGINT (Ctrl-C), SIGTERM (`kill`, `timeout`) or SIGHUP at moments spread
/// over its run, its image and passes being written at some of them: it exits with 128 + the
/// signal's number, leaves the previous output byte for byte, and, unlike a SIGKILL, leaves no
/// temporary file at all.
#[cfg(unix)]
#[test]
fn interrupted_renders_leave_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = tmp(&dir, "stop.exr");
    assert!(render_to("defense.toml", &out, "32x24").status.success());
    let mut before = std::fs::read(&out).unwrap();
    let mut stopped = 0;
    for (k, (signal, number)) in [("INT", 2), ("TERM", 15), ("HUP", 1)]
        .iter()
        .cycle()
        .take(24)
        .enumerate()
    {
        let passes = ["--res", "400x300", "--aov", "depth,normal,albedo,variance"];
        let mut child = start_render(&out, &passes);
        std::thread::sleep(std::time::Duration::from_millis(10 * k as u64));
        let sent = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
        let status = child.wait().unwrap();
        let now = std::fs::read(&out).unwrap();
        if status.success() {
            before = now; // finished before the signal
        } else {
            // A signal that lands before `main` sets its handler (at once after the spawn, on a
            // loaded host) ends the process itself, before any output was begun.
            use std::os::unix::process::ExitStatusExt;
            if status.signal() != Some(*number) {
                let code = status.code();
                assert_eq!(code, Some(128 + number), "SIG{signal} after {} ms", 10 * k);
                stopped += 1;
            }
            assert_eq!(now, before, "SIG{signal} after {} ms", 10 * k);
        }
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["stop.exr"], "SIG{signal} after {} ms", 10 * k);
    }
    assert!(stopped > 6, "{stopped} renders stopped by a signal");
}

/// A 64 KiB tmpfs mounted on a temporary folder, unmounted when dropped: a disk that fills up.
struct SmallDisk {
    dir: tempfile::TempDir,
}

impl SmallDisk {
    /// Mounts the disk (root on Linux only). Where that is impossible the reason is returned;
    /// under CI (`CI` set), where `.ci/run` runs as root, that fails the test instead.
    fn mount() -> Result<SmallDisk, String> {
        let dir = tempfile::tempdir().unwrap();
        let mounted = Command::new("mount")
            .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"])
            .arg(dir.path())
            .output();
        match mounted {
            Ok(o) if o.status.success() => Ok(SmallDisk { dir }),
            Ok(o) => Err(format!(
                "mount -t tmpfs failed: {}",
                String::from_utf8_lossy(&o.stderr).trim()
            )),
            Err(e) => Err(format!("no mount command: {e}")),
        }
    }

    fn path(&self, name: &str) -> std::path::PathBuf {
        self.dir.path().join(name)
    }

    /// Fills what is left of the disk with one file.
    fn fill(&self) {
        use std::io::Write;
        let mut filler = std::fs::File::create(self.path("filler")).unwrap();
        let block = [0u8; 1024];
        while filler.write_all(&block).is_ok() {}
        let _ = filler.write_all(&[0]);
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

/// With the output's disk full, every command that writes an image fails with a located error
/// (exit 1, naming the file and the cause), keeps the old file byte for byte and leaves no
/// temporary file. Small images fit a writer's buffer, so this is where a lost flush error used
/// to rename an empty file over the old one.
#[cfg_attr(
    not(quadray_root),
    ignore = "needs root to mount a small tmpfs (.ci/run runs as root)"
)]
#[test]
fn a_full_disk_keeps_the_old_outputs() {
    let disk = SmallDisk::mount().unwrap_or_else(|why| panic!("cannot fill a disk: {why}"));
    let work = tempfile::tempdir().unwrap();
    let w = |name: &str| tmp(&work, name).to_string_lossy().into_owned();
    let ok = |args: &[&str]| {
        let o = quadray(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    // Inputs on a roomy disk: two images to compare and the two pieces of a tiled render.
    ok(&[
        "render",
        &scene("quadrics.toml"),
        "-o",
        &w("a.png"),
        "--res",
        "16x12",
    ]);
    ok(&[
        "render",
        &scene("defense.toml"),
        "-o",
        &w("b.png"),
        "--res",
        "16x12",
    ]);
    for i in 0..2 {
        let piece = w(&format!("piece{i}.exr"));
        let tile = format!("{i}/2");
        ok(&[
            "render",
            &scene("quadrics.toml"),
            "-o",
            &piece,
            "--res",
            "16x12",
            "--tile",
            &tile,
        ]);
    }
    let names = ["o.png", "big.png", "o.exr", "m.png", "h.png", "q.png"];
    for name in names {
        std::fs::write(disk.path(name), format!("old {name}")).unwrap();
    }
    disk.fill();
    let d = |name: &str| disk.path(name).to_string_lossy().into_owned();
    let runs: [Vec<String>; 6] = [
        vec![
            "render".into(),
            scene("quadrics.toml"),
            "-o".into(),
            d("o.png"),
            "--res".into(),
            "16x12".into(),
        ],
        vec![
            "render".into(),
            scene("quadrics.toml"),
            "-o".into(),
            d("big.png"),
            "--res".into(),
            "320x240".into(),
        ],
        vec![
            "render".into(),
            scene("quadrics.toml"),
            "-o".into(),
            d("o.exr"),
            "--res".into(),
            "16x12".into(),
        ],
        vec![
            "merge".into(),
            w("piece0.exr"),
            w("piece1.exr"),
            "-o".into(),
            d("m.png"),
        ],
        vec![
            "compare".into(),
            w("a.png"),
            w("b.png"),
            "--diff".into(),
            d("h.png"),
        ],
        vec![
            "quadric".into(),
            "cone".into(),
            "-o".into(),
            d("q.png"),
            "--res".into(),
            "16x12".into(),
        ],
    ];
    for args in &runs {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = quadray(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        // compare exits 1 for "different" and 2 for trouble; every other command 1 for errors.
        let expected = if args[0] == "compare" { 2 } else { 1 };
        assert_eq!(o.status.code(), Some(expected), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(
            stderr.contains("No space left on device")
                && stderr.contains(&disk.path("").to_string_lossy().into_owned()),
            "{args:?} names the file and the cause: {stderr}"
        );
        assert_eq!(
            stderr.matches("No space left on device").count(),
            1,
            "{args:?} says the cause once: {stderr}"
        );
    }
    for name in names {
        assert_eq!(
            std::fs::read_to_string(disk.path(name)).unwrap(),
            format!("old {name}"),
            "{name} kept"
        );
    }
    let mut left: Vec<String> = std::fs::read_dir(disk.dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    let mut expected: Vec<String> = names.iter().map(|n| n.to_string()).collect();
    expected.push("filler".into());
    expected.sort();
    assert_eq!(left, expected, "no temporary file is left");
}

/// Outputs honour the umask (a farm's merge job, a web server or a colleague must read them), and
/// a replaced output keeps its mode.
#[cfg(unix)]
#[test]
fn outputs_get_the_mode_a_new_file_gets() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let mode = |p: &std::path::Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    let out = tmp(&dir, "o.png");
    // Under a known umask (the tempfile crate's own 0600 would pass a test run with umask 077).
    let render = |umask: &str| {
        let o = Command::new("sh")
            .args(["-c", &format!("umask {umask}; exec \"$0\" \"$@\"")])
            .arg(env!("CARGO_BIN_EXE_quadray"))
            .args([
                "render",
                &scene("quadrics.toml"),
                "-o",
                out.to_str().unwrap(),
            ])
            .args(["--res", "16x12"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    render("022");
    assert_eq!(mode(&out), 0o644, "a new output: 0666 less the umask 022");
    std::fs::remove_file(&out).unwrap();
    render("027");
    assert_eq!(mode(&out), 0o640, "a new output: 0666 less the umask 027");
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o604)).unwrap();
    render("077");
    assert_eq!(mode(&out), 0o604, "a replaced output keeps its mode");
}
