//! What lies under a pixel: the object the camera ray through its centre hits first.

use quadray::{Camera, LocalPrim, QuadricClass, Scene};

/// The object under a pixel, as the viewer describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct Picked {
    /// 1-based object index, as the object-id pass numbers it.
    pub id: u32,
    /// What kind of object it is (sphere, plane, the quadric's kind, mesh), and whether it is a
    /// placed copy.
    pub kind: String,
    /// Its material's name (or index).
    pub material: String,
    /// Distance along the ray from the eye to the hit.
    pub distance: f64,
}

/// The object under pixel `(x, y)` of a `width` × `height` view through `camera`; `None` for the
/// background (or a camera that cannot make rays).
pub fn pick(
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    (x, y): (u32, u32),
    material_names: &[String],
) -> Option<Picked> {
    let frame = camera.prepare(width as f64 / height as f64).ok()?;
    let ray = frame.ray(
        (x as f64 + 0.5) / width as f64,
        (y as f64 + 0.5) / height as f64,
    );
    let hit = scene.intersect(&ray)?;
    let geometry = scene.geometry();
    let mut kind = match hit.prim.local {
        LocalPrim::Sphere(_) => "sphere".to_string(),
        LocalPrim::Plane(_) => "plane".to_string(),
        LocalPrim::Quadric(i) if hit.prim.placement == 0 => {
            match geometry.quadrics[i as usize].class() {
                QuadricClass::Proper(k) => format!("quadric ({})", k.name()),
                other => format!("quadric ({other:?})"),
            }
        }
        LocalPrim::Quadric(_) => "quadric".to_string(),
        LocalPrim::Triangle { .. } => "mesh".to_string(),
    };
    if hit.prim.placement > 0 {
        kind += ", placed copy";
    }
    let material = material_names
        .get(hit.material as usize)
        .cloned()
        .unwrap_or_else(|| format!("#{}", hit.material));
    Some(Picked {
        id: geometry.object_index(hit.prim),
        kind,
        material,
        distance: hit.t * ray.dir.length(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_centre_pixel_shows_the_sphere_in_front_and_corners_the_background() {
        let text = "version = 1\n[camera]\nfrom = [0, -10, 0]\nto = [0, 0, 0]\nup = [0, 0, 1]\nvfov = 30\n\
                    [[material]]\nname = \"chrome\"\nreflectivity = 0.8\n\
                    [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"chrome\"\n";
        let loaded = quadray_loader::parse_scene(text, Path::new("pick.toml")).unwrap();
        let camera = loaded.description.camera;
        let scene = Scene::new(loaded.description).unwrap();
        let names = loaded.material_names;
        let picked = pick(&scene, &camera, (101, 101), (50, 50), &names).unwrap();
        assert_eq!(picked.id, 1);
        assert_eq!(picked.kind, "sphere");
        assert_eq!(picked.material, "chrome");
        // The eye is 10 from the centre of a unit sphere: the front is 9 away.
        assert!((picked.distance - 9.0).abs() < 1e-6, "{}", picked.distance);
        assert_eq!(pick(&scene, &camera, (101, 101), (0, 0), &names), None);
    }
}
