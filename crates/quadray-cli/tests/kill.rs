//! Outputs survive a killed render: SIGKILL, which no handler sees, at many moments.

mod common;
use common::{quadray, scene, tmp};
use std::process::Command;

/// A render killed outright (SIGKILL, which no handler sees) at several moments never damages the
/// previous output: it stays byte for byte and decodes; any leftover is a recognisable hidden
/// temporary file; and the next render succeeds, replaces the output and removes the leftovers.
#[test]
fn killed_renders_leave_the_previous_output_intact() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["png", "exr"] {
        let out = tmp(&dir, &format!("kill.{ext}"));
        let o = quadray(&[
            "render",
            &scene("defense.toml"),
            "-o",
            out.to_str().unwrap(),
            "--res",
            "64x48",
        ]);
        assert!(o.status.success());
        let mut before = std::fs::read(&out).unwrap();
        let first = before.clone();
        // Kills while rendering (a long render), then at moments spread over short renders, so
        // some land while the image is being written.
        let long = [0u64, 30, 120, 400].map(|d| (d, "1600x1200"));
        let short = (0..24u64).map(|i| (i * 4, "480x360"));
        for (delay_ms, res) in long.into_iter().chain(short) {
            let mut child = Command::new(env!("CARGO_BIN_EXE_quadray"))
                .args([
                    "render",
                    &scene("defense.toml"),
                    "-o",
                    out.to_str().unwrap(),
                ])
                .args(["--res", res, "--spp", "4", "-t", "1", "-q"])
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap();
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
