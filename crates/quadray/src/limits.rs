//! The documented limits of a render, in one module that every other may import (the scene checks
//! its camera against the aspect limit, the loaders and the command line their values).

/// Largest image side in pixels.
pub const MAX_SIDE: u32 = 16384;
/// Largest pixel count (about 134 megapixels, 1.6 GB of f32 RGB).
pub const MAX_PIXELS: u64 = 1 << 27;
/// Largest samples per pixel.
pub const MAX_SPP: u32 = 65536;
/// Largest ray chain length.
pub const MAX_DEPTH: u32 = 64;
/// Largest image aspect ratio (either way).
pub const MAX_ASPECT: f64 = 64.0;
