//! Which of this crate's tests can run here (see `tests/cfgs.rs`): those reading
//! `../shared/assets` get the cfg `quadray_shared`, and the full-disk test, which mounts a small
//! tmpfs, `quadray_root` when the build runs as root.

include!("../../tests/cfgs.rs");

fn main() {
    enable("quadray_shared", shared_assets("../.."));
    enable("quadray_root", running_as_root());
}
