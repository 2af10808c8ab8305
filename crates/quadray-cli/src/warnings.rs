//! Warnings about scenes that load but will not look as their author likely meant: shown by
//! `check` and `render` on stderr, never fatal.

use quadray::Scene;
use std::path::Path;

/// Rays per side of the grid `camera_sees_nothing` casts: 32 × 18 camera rays cost well under a
/// millisecond and miss only objects smaller than a grid cell.
const PROBE: (u32, u32) = (32, 18);

/// What looks wrong about `scene` (loaded from `path`, to be rendered at `width` × `height`), one
/// line each, ready to print after `warning: `.
pub fn scene_warnings(path: &Path, scene: &Scene, width: u32, height: u32) -> Vec<String> {
    let mut warnings = Vec::new();
    let name = path.display();
    if scene.lights().is_empty() {
        warnings.push(format!(
            "{name}: the scene has no lights: surfaces show only their ambient term \
             (ambient × colour) and what mirrors reflect of it, so the image will be dark; \
             add a [[light]]"
        ));
    }
    if camera_sees_nothing(scene, width as f64 / height.max(1) as f64) {
        warnings.push(format!(
            "{name}: the camera sees none of the scene's surfaces (a grid of {}x{} camera rays \
             hit nothing): the image will show only the background",
            PROBE.0, PROBE.1
        ));
    }
    warnings
}

/// Whether a coarse grid of camera rays over the image misses every surface.
fn camera_sees_nothing(scene: &Scene, aspect: f64) -> bool {
    let Ok(frame) = scene.camera().prepare(aspect) else {
        return false; // the renderer reports an unusable camera itself
    };
    let (nx, ny) = PROBE;
    !(0..ny).any(|j| {
        (0..nx).any(|i| {
            let (u, v) = ((i as f64 + 0.5) / nx as f64, (j as f64 + 0.5) / ny as f64);
            scene.intersect(&frame.ray(u, v)).is_some()
        })
    })
}
