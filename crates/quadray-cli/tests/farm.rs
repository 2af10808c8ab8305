//! The Slurm recipe of docs/distributed.md, run on a real Slurm: `scripts/farm/check.sh` submits
//! the documented job array (`sbatch --array`), drops a finished piece so that the `merge
//! --missing` retry has work, merges, and compares the frame byte for byte with a one-process
//! render. The scheduler is the one `scripts/farm/slurm-up.sh` starts (`.ci/run` runs it): under
//! CI a Slurm that does not answer fails the test with the reason; elsewhere the test says it
//! skipped.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Whether a Slurm controller answers (`scontrol ping` fails at once where none does).
fn slurm_answers() -> bool {
    Command::new("scontrol")
        .arg("ping")
        .output()
        .is_ok_and(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).contains("UP"))
}

#[test]
fn slurm_job_array_is_the_one_process_render() {
    if !slurm_answers() {
        if std::env::var_os("CI").is_none() {
            println!(
                "skipped: no Slurm answers here; scripts/farm/slurm-up.sh starts one (as root)"
            );
            return;
        }
        // Under CI: start it, or fail with why it cannot start (bounded: an install that hangs
        // fails the test instead of the run).
        let up = Command::new("timeout")
            .arg("1200")
            .arg(root().join("scripts/farm/slurm-up.sh"))
            .output()
            .expect("scripts/farm/slurm-up.sh runs");
        assert!(
            up.status.success(),
            "Slurm cannot start: {}{}",
            String::from_utf8_lossy(&up.stdout),
            String::from_utf8_lossy(&up.stderr)
        );
    }
    let check = Command::new(root().join("scripts/farm/check.sh"))
        .env("QUADRAY", env!("CARGO_BIN_EXE_quadray"))
        .env("DROP_PIECE", "1")
        .env("TIMEOUT", "300")
        .output()
        .expect("scripts/farm/check.sh runs");
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );
    assert!(check.status.success(), "{said}");
    assert!(said.contains("dropped piece 1"), "{said}");
    assert!(said.contains("byte for byte"), "{said}");
}
