//! Whether the viewer's window test can run here: it needs Xvfb and ImageMagick's `import` on the
//! PATH. Where they are, and always under CI (`CI` set, where `.ci/run` installs them and their
//! absence must fail the test), it gets the cfg `quadray_xvfb`; elsewhere it is `#[ignore]`d with
//! the reason, so `cargo test` counts it as not run instead of passing it.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(quadray_xvfb)");
    println!("cargo::rerun-if-env-changed=CI");
    println!("cargo::rerun-if-env-changed=PATH");
    let on_path = |tool: &str| {
        std::env::var_os("PATH")
            .is_some_and(|path| std::env::split_paths(&path).any(|d| d.join(tool).is_file()))
    };
    if (on_path("xvfb-run") && on_path("import")) || std::env::var_os("CI").is_some() {
        println!("cargo::rustc-cfg=quadray_xvfb");
    }
}
