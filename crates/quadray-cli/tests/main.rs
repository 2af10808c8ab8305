//! The command line end to end: every module runs the real `quadray` binary (one test binary for the crate, as ripgrep has: each integration-test binary links the whole workspace).

mod adaptive;
mod antialias;
mod cli;
mod common;
mod distributed;
mod farm;
mod hostile;
mod import;
mod kill;
mod outputs;
mod passes;
mod tools;
