//! The viewer's camera: an orbit (yaw, pitch, distance) around a target, turned by mouse drags and
//! the wheel, starting from (and restorable to) the scene's own camera.

use glam::DVec3;
use quadray::{Camera, Projection};

/// Closest the orbit gets to the poles, degrees: at ±90 the view's up vector is undefined.
const PITCH_LIMIT: f64 = 89.5;
/// Degrees turned per point of mouse drag.
const DEGREES_PER_POINT: f64 = 0.4;
/// Distance factor per point of wheel scroll: 1.1 per notch of 50 points.
const ZOOM_PER_POINT: f64 = 0.0019;

/// An orbit camera around `target` in world space (+z up; see the core crate's conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// The point looked at and orbited.
    pub target: DVec3,
    /// Azimuth of the eye about +z from +x, degrees.
    pub yaw: f64,
    /// Elevation of the eye above the target's horizontal plane, degrees.
    pub pitch: f64,
    /// Distance from the target to the eye.
    pub distance: f64,
    /// The projection (field of view, or orthographic height) kept from the scene's camera.
    pub projection: Projection,
}

impl Orbit {
    /// The orbit whose eye, target and projection are the camera's: the camera's target is
    /// orbited, so the first view is the scene's own (up to the roll, which an orbit keeps at 0).
    pub fn from_camera(camera: &Camera) -> Orbit {
        let offset = camera.from - camera.to;
        let distance = offset.length();
        let (yaw, pitch) = if distance > 0.0 {
            (
                offset.y.atan2(offset.x).to_degrees(),
                (offset.z / distance).clamp(-1.0, 1.0).asin().to_degrees(),
            )
        } else {
            (0.0, 0.0)
        };
        Orbit {
            target: camera.to,
            yaw,
            pitch: pitch.clamp(-PITCH_LIMIT, PITCH_LIMIT),
            distance: if distance > 0.0 { distance } else { 1.0 },
            projection: camera.projection,
        }
    }

    /// The camera of this orbit.
    pub fn camera(&self) -> Camera {
        let vfov = match self.projection {
            Projection::Perspective { vfov_deg } => vfov_deg,
            Projection::Orthographic { .. } => 40.0,
        };
        Camera {
            projection: self.projection,
            ..Camera::orbit(self.target, self.yaw, self.pitch, self.distance, vfov)
        }
    }

    /// Turns the orbit by a mouse drag of `(dx, dy)` points: right turns the scene right, down
    /// raises the eye.
    pub fn drag(&mut self, dx: f64, dy: f64) {
        self.yaw = (self.yaw - dx * DEGREES_PER_POINT + 180.0).rem_euclid(360.0) - 180.0;
        self.pitch = (self.pitch + dy * DEGREES_PER_POINT).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Moves the eye towards the target for a positive wheel scroll of `points`, away for a
    /// negative one, by a constant factor per point (so zooming is the same at any scale).
    pub fn zoom(&mut self, points: f64) {
        self.distance *= (-points * ZOOM_PER_POINT).exp();
    }

    /// Pans the target across the view by a drag of `(dx, dy)` points on an image `height` points
    /// tall, so the point under the cursor at the target's depth follows the cursor.
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) {
        let camera = self.camera();
        let forward = (camera.to - camera.from).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let visible_height = match self.projection {
            Projection::Perspective { vfov_deg } => {
                2.0 * self.distance * (vfov_deg.to_radians() / 2.0).tan()
            }
            Projection::Orthographic { height } => height,
        };
        let per_point = visible_height / height.max(1.0);
        self.target += (-right * dx + up * dy) * per_point;
    }

    /// The orbit as a native scene file's `[camera]` table, to paste into a scene.
    pub fn toml(&self) -> String {
        let t = self.target;
        let mut text = format!(
            "[camera]\norbit = {{ yaw = {:.3}, pitch = {:.3}, distance = {}, target = [{}, {}, {}] }}\n",
            self.yaw,
            self.pitch,
            round6(self.distance),
            round6(t.x),
            round6(t.y),
            round6(t.z)
        );
        match self.projection {
            Projection::Perspective { vfov_deg } => {
                text += &format!("vfov = {}\n", round6(vfov_deg));
            }
            Projection::Orthographic { height } => {
                // An orbit camera is perspective; an orthographic view is written with from/to.
                let camera = self.camera();
                let v = |p: DVec3| format!("[{}, {}, {}]", round6(p.x), round6(p.y), round6(p.z));
                text = format!(
                    "[camera]\nprojection = \"orthographic\"\nfrom = {}\nto = {}\nup = {}\nheight = {}\n",
                    v(camera.from),
                    v(camera.to),
                    v(camera.up),
                    round6(height)
                );
            }
        }
        text
    }
}

/// `v` to six significant decimals, as short as they allow (for pasted scene text).
fn round6(v: f64) -> f64 {
    let scale = 10f64.powi(6 - v.abs().log10().ceil().max(0.0) as i32);
    (v * scale).round() / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_camera_comes_back_as_the_same_orbit() {
        let camera = Camera::orbit(DVec3::new(1.0, 2.0, 0.5), 30.0, 20.0, 8.0, 35.0);
        let orbit = Orbit::from_camera(&camera);
        assert!((orbit.yaw - 30.0).abs() < 1e-9 && (orbit.pitch - 20.0).abs() < 1e-9);
        assert!((orbit.distance - 8.0).abs() < 1e-9);
        let again = orbit.camera();
        assert!(again.from.distance(camera.from) < 1e-9);
        assert!(again.up.distance(camera.up) < 1e-9);
        assert_eq!(again.projection, camera.projection);
    }

    #[test]
    fn drags_turn_and_clamp_and_the_wheel_zooms_by_factors() {
        let mut orbit = Orbit::from_camera(&Camera::orbit(DVec3::ZERO, 0.0, 0.0, 5.0, 40.0));
        orbit.drag(-100.0, 1e6);
        assert!((orbit.yaw - 40.0).abs() < 1e-9, "{}", orbit.yaw);
        assert_eq!(orbit.pitch, PITCH_LIMIT);
        assert!(
            orbit.camera().prepare(1.0).is_ok(),
            "a valid view at the pole limit"
        );
        orbit.zoom(50.0);
        orbit.zoom(-50.0);
        assert!((orbit.distance - 5.0).abs() < 1e-12);
        orbit.zoom(50.0);
        assert!(orbit.distance < 5.0);
    }

    #[test]
    fn panning_moves_the_target_across_the_view_only() {
        let mut orbit = Orbit::from_camera(&Camera::orbit(DVec3::ZERO, 0.0, 0.0, 5.0, 90.0));
        // From +x looking at the origin with +z up, right is +y. A 100-point drag right on a
        // 200-point image at 90° moves the scene right by half the visible height
        // (2 · 5 · tan 45° = 10), so the target moves 5 to the left.
        orbit.pan(100.0, 0.0, 200.0);
        assert!(
            orbit.target.distance(DVec3::new(0.0, -5.0, 0.0)) < 1e-9,
            "{}",
            orbit.target
        );
        orbit.pan(0.0, 100.0, 200.0);
        assert!((orbit.target.z - 5.0).abs() < 1e-9);
    }

    #[test]
    fn saved_views_parse_as_the_same_camera() {
        let orbit = Orbit::from_camera(&Camera::orbit(
            DVec3::new(0.5, -1.0, 2.0),
            -40.0,
            25.0,
            7.5,
            38.0,
        ));
        let text = format!(
            "version = 1\n{}\n[[material]]\nname = \"m\"\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n",
            orbit.toml()
        );
        let loaded = quadray_loader::parse_scene(&text, std::path::Path::new("view.toml")).unwrap();
        let camera = loaded.description.camera;
        assert!(camera.from.distance(orbit.camera().from) < 1e-3, "{text}");
        assert!(camera.to.distance(orbit.target) < 1e-6);
        assert_eq!(camera.projection, orbit.projection);
    }
}
