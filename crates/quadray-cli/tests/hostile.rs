//! The hostile-input corpus (`tests/hostile/cases.toml`) through the `quadray` binary: every bad
//! file given to `quadray check`, and every bad command line, must exit with the stated status
//! (0 success, 1 a scene or file error, 2 a usage error; `compare`: 0 same, 1 different,
//! 2 trouble), print one error line that names the file (and the place) and the problem, never
//! panic, and leave no file behind. `tests/hostile.rs` at the top level checks the same files' error
//! classes through the library.

mod common;

use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
struct Manifest {
    case: Vec<FileCase>,
    command: Vec<CommandCase>,
}

/// The fields of a file case this test needs; the library test reads the rest.
#[derive(Deserialize)]
struct FileCase {
    file: String,
    expect: String,
    #[serde(default)]
    says: String,
    at: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandCase {
    name: String,
    args: Vec<String>,
    exit: i32,
    #[serde(default)]
    says: String,
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/hostile")
}

fn manifest() -> Manifest {
    let text = std::fs::read_to_string(corpus().join("cases.toml")).expect("cases.toml");
    toml::from_str(&text).expect("cases.toml parses")
}

/// What is wrong with one run's stderr, given that it failed: it must hold exactly one `error:`
/// line, which contains every piece of `wanted`.
fn error_line_problem(stderr: &str, wanted: &[&str]) -> Option<String> {
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    if errors.len() != 1 {
        return Some(format!("{} error lines: {stderr}", errors.len()));
    }
    let missing: Vec<&&str> = wanted.iter().filter(|w| !errors[0].contains(**w)).collect();
    (!missing.is_empty()).then(|| format!("the error does not say {missing:?}: {}", errors[0]))
}

#[test]
fn check_gives_each_file_its_exit_status_and_one_clear_error() {
    let mut failures = Vec::new();
    for case in manifest().case {
        let path = corpus().join(&case.file);
        let out = common::quadray(&["check", &path.to_string_lossy()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let code = out.status.code();
        let loads = matches!(case.expect.as_str(), "loads" | "warns");
        let problem = if stderr.contains("panicked") {
            Some(format!("panicked: {stderr}"))
        } else if code != Some(if loads { 0 } else { 1 }) {
            Some(format!("exit {code:?}: {stderr}"))
        } else if case.expect == "warns" {
            (!stderr.contains(&case.says)).then(|| format!("no warning says {:?}", case.says))
        } else if loads {
            None
        } else {
            let name = case.file.rsplit('/').next().unwrap();
            let place = case
                .at
                .as_ref()
                .map(|at| format!("{name}:{at}"))
                .unwrap_or_else(|| name.to_string());
            error_line_problem(&stderr, &[&place, &case.says])
        };
        if let Some(p) = problem {
            failures.push(format!("{}: {p}", case.file));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn bad_command_lines_exit_with_their_status_and_leave_nothing_behind() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut failures = Vec::new();
    let commands = manifest().command;
    assert!(commands.len() >= 30, "{} command lines", commands.len());
    for case in commands {
        let out_dir = tempfile::tempdir().unwrap();
        let args: Vec<String> = case
            .args
            .iter()
            .map(|a| {
                a.replace("{scenes}", &scenes.to_string_lossy())
                    .replace("{corpus}", &corpus().to_string_lossy())
                    .replace("{out}", &out_dir.path().to_string_lossy())
            })
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = common::quadray(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let left: Vec<_> = std::fs::read_dir(out_dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        let problem = if stderr.contains("panicked") {
            Some(format!("panicked: {stderr}"))
        } else if out.status.code() != Some(case.exit) {
            Some(format!("exit {:?}: {stderr}", out.status.code()))
        } else if !left.is_empty() {
            Some(format!("left {left:?} behind"))
        } else if case.exit != 1 {
            // Success (its report on stdout), or a usage error (clap's: the message, a usage line
            // and a hint).
            let stdout = String::from_utf8_lossy(&out.stdout);
            let said = stdout.contains(&case.says) || stderr.contains(&case.says);
            (!said).then(|| format!("does not say {:?}: {stdout} {stderr}", case.says))
        } else {
            error_line_problem(&stderr, &[&case.says])
        };
        if let Some(p) = problem {
            failures.push(format!("{}: {p}", case.name));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
