//! The hostile-input corpus (`tests/hostile/cases.toml`) through the `quadray` binary: every bad
//! file given to `quadray check`, and every bad command line, must exit with the stated status
//! (0 success, 1 a scene or file error, 2 a usage error; `compare`: 0 same, 1 different,
//! 2 trouble), print one error line that names the file (and the place) and the problem, never
//! panic, and leave no file behind. `tests/hostile.rs` at the top level checks the same files' error
//! classes through the library.

use crate::common;

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

/// `--confine DIR` (or `QUADRAY_CONFINE`): a scene from a stranger reads and writes nothing
/// outside DIR, however the path is spelt (`../`, absolute, `file:` URI, `%2e%2e`, a link out),
/// and `check` lists the files a scene reads and the one it would write.
#[test]
fn confinement_keeps_reads_and_writes_inside_the_folder() {
    use std::fs;
    let base = tempfile::tempdir().unwrap();
    let jail = base.path().join("jail");
    fs::create_dir(&jail).unwrap();
    let outside = base.path().join("secret.obj");
    fs::copy(corpus().join("obj/triangle.obj"), &outside).unwrap();
    // The triangle's 44 buffer bytes, outside, for glTF files that reach for them.
    let gltf: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(corpus().join("gltf/triangle.gltf")).unwrap())
            .unwrap();
    let uri = gltf["buffers"][0]["uri"].as_str().unwrap().to_string();
    let encoded = uri.split_once(',').unwrap().1;
    let bytes =
        base64::Engine::decode(&base64::engine::general_purpose::STANDARD, encoded).unwrap();
    fs::write(base.path().join("secret.bin"), &bytes).unwrap();
    let header = "version = 1\n[camera]\nfrom = [0, -5, 1]\nto = [0, 0, 0]\n";
    let secret_bin = base.path().join("secret.bin");
    let mut cases: Vec<(String, String)> = vec![
        (
            "mesh-up.toml".into(),
            format!("{header}[[mesh]]\npath = \"../secret.obj\"\n"),
        ),
        (
            "mesh-absolute.toml".into(),
            format!("{header}[[mesh]]\npath = \"{}\"\n", outside.display()),
        ),
        (
            "include-up.toml".into(),
            format!("{header}[[include]]\npath = \"../secret.obj\"\n"),
        ),
        (
            "output-out.toml".into(),
            format!(
                "{header}[[material]]\nname = \"m\"\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n\
                 material = \"m\"\n[output]\nfile = \"../stolen.png\"\n"
            ),
        ),
    ];
    for (name, reference) in [
        ("buffer-up.gltf", "../secret.bin".to_string()),
        (
            "buffer-file-uri.gltf",
            format!("file://{}", secret_bin.display()),
        ),
        ("buffer-percent.gltf", "%2e%2e/secret.bin".to_string()),
    ] {
        let mut g = gltf.clone();
        g["buffers"][0]["uri"] = serde_json::Value::String(reference);
        cases.push((name.into(), g.to_string()));
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&outside, jail.join("link.obj")).unwrap();
        cases.push((
            "link.toml".into(),
            format!("{header}[[mesh]]\npath = \"link.obj\"\n"),
        ));
    }
    let jail_arg = jail.to_string_lossy().into_owned();
    for (name, text) in &cases {
        let scene = jail.join(name);
        fs::write(&scene, text).unwrap();
        let scene = scene.to_string_lossy().into_owned();
        // Without confinement the outside files load (the cases are real reaches, not typos)...
        let free = common::quadray(&["check", &scene]);
        if !name.starts_with("output") {
            assert!(
                free.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&free.stderr)
            );
        }
        // ...with it, the read or the write is refused, by flag and by environment variable.
        let out = jail.join("o.png").to_string_lossy().into_owned();
        let flagged = common::quadray(&[
            "--confine",
            &jail_arg,
            "render",
            &scene,
            "-o",
            &out,
            "--res",
            "8x6",
        ]);
        let envd = std::process::Command::new(env!("CARGO_BIN_EXE_quadray"))
            .env("QUADRAY_CONFINE", &jail)
            .args(["render", &scene, "--res", "8x6"])
            .output()
            .unwrap();
        for (how, o) in [("--confine", &flagged), ("QUADRAY_CONFINE", &envd)] {
            let stderr = String::from_utf8_lossy(&o.stderr);
            if name.starts_with("output") && how == "--confine" {
                // -o inside the folder replaces the scene's own output: allowed.
                assert!(o.status.success(), "{name} {how}: {stderr}");
                continue;
            }
            assert_eq!(o.status.code(), Some(1), "{name} {how}: {stderr}");
            assert!(
                error_line_problem(&stderr, &["outside the confinement folder"]).is_none(),
                "{name} {how}: {stderr}"
            );
        }
    }
    assert!(!base.path().join("stolen.png").exists());
    // `convert` does not copy outside bytes into its output either.
    let glb = jail.join("copy.glb").to_string_lossy().into_owned();
    let scene = jail.join("buffer-up.gltf").to_string_lossy().into_owned();
    let o = common::quadray(&["--confine", &jail_arg, "convert", &scene, "-o", &glb]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!jail.join("copy.glb").exists());
    // An output outside, and a folder that does not exist.
    let o = common::quadray(&[
        "--confine",
        &jail_arg,
        "quadric",
        "cone",
        "-o",
        &base.path().join("q.png").to_string_lossy(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // A folder inside that is a link to one outside: the write goes where the link points.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(base.path(), jail.join("out-link")).unwrap();
        let through = jail.join("out-link/q.png").to_string_lossy().into_owned();
        let o = common::quadray(&["--confine", &jail_arg, "quadric", "cone", "-o", &through]);
        assert_eq!(
            o.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(!base.path().join("q.png").exists());
    }
    let o = common::quadray(&["--confine", "/no/such/folder", "check", &scene]);
    assert_eq!(o.status.code(), Some(2));
    // check lists what a scene reads and where it would write.
    let listed = common::quadray(&["check", &jail.join("buffer-up.gltf").to_string_lossy()]);
    let stdout = String::from_utf8_lossy(&listed.stdout);
    assert!(
        stdout.contains("reads: ") && stdout.contains("secret.bin"),
        "{stdout}"
    );
    assert!(
        stdout.contains("writes: ") && stdout.contains("buffer-up.png"),
        "{stdout}"
    );
}

/// A render whose pixels need more memory than is free is refused before it starts, with one
/// error line naming the scene, what it needs and what to do, exit status 1 and no file left
/// (the free memory set by `QUADRAY_AVAILABLE_MEMORY`, as a machine's own cannot be relied on);
/// a render that fits runs, a piece of the refused one (the way out the error gives) fits, an
/// empty setting is no setting, and a malformed one is a usage error, as a bad
/// `QUADRAY_CONFINE` is.
#[test]
fn renders_larger_than_free_memory_are_refused_before_they_start() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene("defense.toml");
    let render = |free: &str, extra: &[&str], out: &str| {
        let mut args = vec!["render", scene.as_str(), "--res", "200x100", "-o", out];
        args.extend_from_slice(extra);
        std::process::Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args(&args)
            .env("QUADRAY_AVAILABLE_MEMORY", free)
            .output()
            .unwrap()
    };
    let out = common::tmp(&dir, "a.exr");
    let out = out.to_string_lossy();
    // 20 000 pixels adaptively: about 226 bytes each and the pilot, 4.5 MB, against 2 MB free.
    let adaptive = ["--target-error", "0.01"];
    let refused = render("2000000", &adaptive, &out);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    let wanted = [
        "defense.toml",
        "adaptive render of 20000 pixels",
        "2 MB is free",
        "--tile",
    ];
    assert_eq!(error_line_problem(&stderr, &wanted), None);
    assert!(!std::path::Path::new(&*out).exists());
    // A quarter of it as a piece: its bands one at a time, about 0.9 MB.
    let piece = render(
        "2000000",
        &[&adaptive[..], &["--tile", "1/4"]].concat(),
        &out,
    );
    assert!(
        piece.status.success(),
        "{}",
        String::from_utf8_lossy(&piece.stderr)
    );
    // Uniformly, 32 bytes a pixel: 640 kB fits.
    let fits = render("2000000", &["--spp", "1"], &out);
    assert!(
        fits.status.success(),
        "{}",
        String::from_utf8_lossy(&fits.stderr)
    );
    let unset = render("", &adaptive, &out);
    assert!(
        unset.status.success(),
        "{}",
        String::from_utf8_lossy(&unset.stderr)
    );
    let bad = render("plenty", &[], &out);
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(2), "{stderr}");
    let wanted = ["QUADRAY_AVAILABLE_MEMORY=\"plenty\" is not a whole number of bytes"];
    assert_eq!(error_line_problem(&stderr, &wanted), None);
}
