//! The loaders on real and hostile files, through the public API (one test binary for the crate).

mod bad_input;
mod common;
mod doc_examples;
mod gltf_materials;
mod gltf_quadrics_doc;
mod real_assets;
mod real_obj;
