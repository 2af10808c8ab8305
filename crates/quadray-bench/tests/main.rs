//! The accuracy oracle, the hard cases and the holes census (one test binary for the crate).

mod hardcases;
mod holes;
mod properties;
