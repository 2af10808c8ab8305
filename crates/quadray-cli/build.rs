//! Which of this crate's tests can run here. The full-disk test mounts a small tmpfs, which needs
//! root: it gets the cfg `quadray_root` when the build runs as root, and always under CI. Those that read `../shared/assets` (real third-party
//! files, never copied into the repository) get the cfg `quadray_shared` where the folder is
//! present, and always under CI (`CI` set), where its absence must fail them; elsewhere they are
//! `#[ignore]`d with the reason, so `cargo test` counts them as not run instead of passing them.

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    // The folder holding the repository and `shared/`: its entries change when `shared` appears.
    let parent = std::path::Path::new(&manifest).join("../../..");
    println!("cargo::rustc-check-cfg=cfg(quadray_shared)");
    println!("cargo::rerun-if-env-changed=CI");
    println!("cargo::rerun-if-changed={}", parent.display());
    if parent.join("shared/assets").is_dir() || std::env::var_os("CI").is_some() {
        println!("cargo::rustc-cfg=quadray_shared");
    }
    println!("cargo::rustc-check-cfg=cfg(quadray_root)");
    // The effective user from /proc (Linux); elsewhere the test cannot mount a tmpfs anyway.
    let root = std::fs::read_to_string("/proc/self/status").is_ok_and(|status| {
        status
            .lines()
            .find_map(|l| l.strip_prefix("Uid:"))
            .and_then(|ids| ids.split_whitespace().nth(1))
            == Some("0")
    });
    if root || std::env::var_os("CI").is_some() {
        println!("cargo::rustc-cfg=quadray_root");
    }
}
