//! quadray end to end on scene files: renders checked against analytic facts and references, the
//! hostile-input corpus, imported meshes and scene graphs (one test binary, as ripgrep has).

mod analytic;
mod glass;
mod hostile;
mod imported;
mod instancing;
mod instancing_gltf;
mod khronos;
mod meshes;
mod ply_spheres;
mod regression;
mod scenes;
