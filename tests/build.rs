//! Which of this crate's tests can run here: those reading `../shared/assets` get the cfg
//! `quadray_shared` (see `cfgs.rs`).

include!("cfgs.rs");

fn main() {
    enable("quadray_shared", shared_assets(".."));
}
