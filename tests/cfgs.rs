// Shared by the build scripts of the crates whose tests need something a machine may lack
// (`include!`d: build scripts cannot share a library). Each test that needs it carries
// `#[cfg_attr(not(CFG), ignore = "why")]`: where the thing is missing it is counted as ignored,
// not passed; under CI (`CI` set), where `.ci/run` provides everything, the cfg is always set, so
// a missing thing fails the test.

/// Sets the cfg `name` for the crate's tests if `available`, or always under CI.
fn enable(name: &str, available: bool) {
    println!("cargo::rustc-check-cfg=cfg({name})");
    println!("cargo::rerun-if-env-changed=CI");
    if available || std::env::var_os("CI").is_some() {
        println!("cargo::rustc-cfg={name}");
    }
}

/// Whether `../shared/assets` (real third-party files, never copied into the repository) is
/// beside the repository, whose root is `up` folders above the crate's manifest.
#[allow(dead_code)]
fn shared_assets(up: &str) -> bool {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    // The folder holding the repository and `shared/`: its entries change when `shared` appears.
    let parent = std::path::Path::new(&manifest).join(up).join("..");
    println!("cargo::rerun-if-changed={}", parent.display());
    parent.join("shared/assets").is_dir()
}

/// Whether the build runs as root (the effective user, from /proc: Linux only, where the tests
/// that need root mount file systems).
#[allow(dead_code)]
fn running_as_root() -> bool {
    std::fs::read_to_string("/proc/self/status").is_ok_and(|status| {
        status
            .lines()
            .find_map(|l| l.strip_prefix("Uid:"))
            .and_then(|ids| ids.split_whitespace().nth(1))
            == Some("0")
    })
}

/// Whether `tool` is an executable file in a folder of the PATH.
#[allow(dead_code)]
fn on_path(tool: &str) -> bool {
    println!("cargo::rerun-if-env-changed=PATH");
    std::env::var_os("PATH")
        .is_some_and(|path| std::env::split_paths(&path).any(|d| d.join(tool).is_file()))
}
