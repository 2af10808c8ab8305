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
                    .replace("{deep_key}", &vec!["a"; 20_000].join("."))
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

/// A reader that closed the pipe ends the command quietly with success, as in ripgrep: no panic,
/// no error line.
#[test]
fn a_closed_pipe_ends_output_quietly() {
    use std::process::{Command, Stdio};
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/defense.toml");
    for args in [
        vec!["check".to_string(), scene.to_string_lossy().into_owned()],
        vec!["quadric".to_string(), "--list".to_string()],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader goes before anything is written
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("panicked") && !stderr.contains("error"),
            "{args:?}: {stderr}"
        );
    }
}

/// Pipes given where a file is read are refused at once instead of blocking forever (the loaders
/// refuse them already: these are the merge and compare inputs).
#[cfg(unix)]
#[test]
fn pipes_are_refused_as_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let mut paths = Vec::new();
    for name in ["pipe.exr", "pipe.png"] {
        let path = dir.path().join(name);
        let made = std::process::Command::new("mkfifo").arg(&path).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("skipped: mkfifo is not available");
            return;
        }
        paths.push(path.to_string_lossy().into_owned());
    }
    let red = corpus()
        .join("texture/red.png")
        .to_string_lossy()
        .into_owned();
    let out = dir.path().join("m.png").to_string_lossy().into_owned();
    for (args, exit) in [
        (vec!["merge", &paths[0], "-o", &out], 1),
        (vec!["compare", &paths[1], &red], 2),
        (vec!["compare", &red, &paths[0]], 2),
    ] {
        // A blocked read would hang the test: the binary runs under a watchdog thread instead.
        let (send, receive) = std::sync::mpsc::channel();
        let args_owned: Vec<String> = args.iter().map(|a| a.to_string()).collect();
        std::thread::spawn(move || {
            let refs: Vec<&str> = args_owned.iter().map(String::as_str).collect();
            let _ = send.send(common::quadray(&refs));
        });
        let o = receive
            .recv_timeout(std::time::Duration::from_secs(60))
            .unwrap_or_else(|_| panic!("{args:?} blocked on a pipe"));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(exit), "{args:?}: {stderr}");
        assert!(
            error_line_problem(&stderr, &["not a regular file"]).is_none(),
            "{stderr}"
        );
    }
}
