//! POV-Ray 3.7 as the peer of `quadray bench images`: one render of a `.pov` file with given
//! anti-aliasing options, its image and the CPU time of its trace phase, and the measurement of
//! every anti-aliasing setting against POV-Ray's own converged image.

use super::{ImagesArgs, Method, PovReport, Row};
use crate::compare::{LinearImage, Thresholds, compare, read_image};
use anyhow::{Context, Result, bail};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// One POV-Ray render.
pub struct PovRender {
    /// The 8-bit sRGB image it wrote.
    pub image: LinearImage,
    /// CPU seconds of its "Trace Time" (parsing and bounding excluded, like quadray's BVH build).
    pub trace_cpu: f64,
}

/// POV-Ray's converged image, then each anti-aliasing setting `runs` times against it.
pub fn measure(a: &ImagesArgs, pov: &Path, progress: &mut dyn FnMut(&str)) -> Result<PovReport> {
    let scratch = a
        .out
        .join(format!(".{}-povray-{}.png", a.name, std::process::id()));
    progress(&format!("POV-Ray reference: {}", a.pov_reference));
    let reference = render(pov, a.res, &a.pov_reference, &scratch)?;
    let mut rows = Vec::new();
    for options in &a.pov_aa {
        progress(&format!("POV-Ray {options}, {} runs", a.runs));
        let (mut wall, mut cpu, mut last) = (Vec::new(), Vec::new(), None);
        for _ in 0..a.runs {
            let start = Instant::now();
            let run = render(pov, a.res, options, &scratch)?;
            wall.push(start.elapsed().as_secs_f64());
            cpu.push(run.trace_cpu);
            last = Some(run.image);
        }
        let image = last.context("no POV-Ray run")?;
        rows.push(Row {
            method: Method::PovRay(options.clone()),
            wall,
            cpu,
            rays: None,
            sampling: None,
            error: compare(&reference.image, &image, &Thresholds::default())?,
        });
    }
    Ok(PovReport {
        file: pov.to_path_buf(),
        reference_options: a.pov_reference.clone(),
        reference_cpu: reference.trace_cpu,
        rows,
    })
}

/// Renders `pov` at `width` × `height` on one thread with `options` (e.g. `+A0.1 +AM2 +R3`, or
/// `-A`), writing its PNG to `scratch` (removed afterwards).
pub fn render(
    pov: &Path,
    (width, height): (u32, u32),
    options: &str,
    scratch: &Path,
) -> Result<PovRender> {
    let dir = pov
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let file = pov.file_name().context("the .pov path names no file")?;
    let scratch = std::path::absolute(scratch)?;
    let output = Command::new("povray")
        .current_dir(dir)
        .arg(format!("+I{}", file.to_string_lossy()))
        .arg(format!("+O{}", scratch.display()))
        .args([format!("+W{width}"), format!("+H{height}")])
        // Headless, quiet, PNG with the sRGB curve, one render thread.
        .args(["-D", "-V", "+FN", "File_Gamma=sRGB", "+WT1"])
        .args(options.split_whitespace())
        .output()
        .context("running povray (apt-get install povray)")?;
    let log = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        bail!(
            "povray {} {options} failed ({}): {}",
            pov.display(),
            output.status,
            log.lines().rev().take(5).collect::<Vec<_>>().join(" / ")
        );
    }
    let trace_cpu = trace_cpu_seconds(&log)
        .with_context(|| format!("no trace time in povray's statistics for {}", pov.display()))?;
    let image = read_image(&scratch);
    let _ = std::fs::remove_file(&scratch);
    Ok(PovRender {
        image: image?,
        trace_cpu,
    })
}

/// The CPU seconds on the line after "Trace Time:" in POV-Ray's statistics
/// (`using 1 thread(s) with 0.341 CPU-seconds total`).
fn trace_cpu_seconds(log: &str) -> Option<f64> {
    let mut lines = log
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("Trace Time:"));
    lines.next()?;
    let usage = lines.next()?;
    let before = usage.split("CPU-seconds").next()?;
    before.split_whitespace().last()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_trace_cpu_time_is_read_from_the_statistics() {
        let log = "Render Time:\n  Photon Time:      No photons\n  Trace Time:       0 hours  0 minutes  0 seconds (0.342 seconds)\n              using 1 thread(s) with 0.341 CPU-seconds total\n";
        assert_eq!(trace_cpu_seconds(log), Some(0.341));
        assert_eq!(
            trace_cpu_seconds("Parse Time: 1\nusing 1 thread(s) with 2.0 CPU-seconds total"),
            None
        );
    }
}
