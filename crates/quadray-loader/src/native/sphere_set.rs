//! `[[spheres]]`: one sphere a vertex of a PLY file (`crate::ply`), for particle and molecular
//! data sets too large for `[[sphere]]` tables.
//!
//! Each sphere is placed as a `[[sphere]]` with the same `transform` and `material` would be (a
//! uniform scale scales the radii; a non-uniform one makes ellipsoids). A vertex colour makes
//! the material's copy with that constant colour, one per distinct colour and material: a million
//! spheres in eight colours add eight materials.

use super::groups::GraphState;
use super::objects::push_sphere;
use super::*;
use crate::import::{PlacedShape, placed_sphere};
use crate::ply::SphereFile;
use quadray::Prototype;

impl Builder<'_> {
    /// The spheres of the `[[spheres]]` table `spec` into `out`, their colours' materials into
    /// `st`.
    pub(super) fn sphere_set(
        &self,
        st: &mut GraphState<'_>,
        names: &HashMap<String, u32>,
        spec: &Spanned<SphereSetSpec>,
        key: &str,
        out: &mut Prototype,
    ) -> Result<(), LoadError> {
        let s = spec.get_ref();
        let material = self.material_id(names, &s.material, &format!("{key}.material"))?;
        let default_radius = s
            .radius
            .as_ref()
            .map(|r| self.positive(r, &format!("{key}.radius")))
            .transpose()?;
        let to_world = match &s.transform {
            Some(_) => Some(
                self.transform(&s.transform, &format!("{key}.transform"))?
                    .to_world,
            ),
            None => None,
        };
        let path = include::resolve(self.path, s.path.get_ref());
        let path_key = format!("{key}.path");
        let file = SphereFile::read(&path, default_radius)
            .map_err(|e| self.include_err(Some(&s.path), &path_key, e))?;
        if file.has_radius() && s.radius.is_some() {
            st.notes.push(format!(
                "{key}: every vertex of {} has its own radius; `radius` is not used",
                s.path.get_ref()
            ));
        }
        // Room for the spheres, unless the transform makes ellipsoids of them.
        let stays_sphere = to_world
            .is_none_or(|t| matches!(placed_sphere(t, 1.0, material), Ok(PlacedShape::Sphere(_))));
        if stays_sphere {
            out.spheres.reserve(file.capacity());
        }
        let base_name = st.material_names[material as usize].clone();
        let (materials, material_names, tinted) =
            (&mut st.materials, &mut st.material_names, &mut st.tinted);
        file.for_each(|_, v| {
            let material = match v.colour {
                None => material,
                Some(colour) => *tinted
                    .entry((material, colour.to_array().map(f32::to_bits)))
                    .or_insert_with(|| {
                        let mut m = materials[material as usize].clone();
                        m.texture = quadray::Texture::Constant(colour);
                        materials.push(m);
                        material_names.push(format!(
                            "{base_name} rgb({}, {}, {})",
                            colour.x, colour.y, colour.z
                        ));
                        (materials.len() - 1) as u32
                    }),
            };
            push_sphere(out, to_world, v.center, v.radius, material)
        })
        .map_err(|e| self.include_err(Some(&s.path), &path_key, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = r#"
version = 1
[camera]
from = [0, -5, 1]
to = [0, 0, 0]
[[material]]
name = "shiny"
color = [0.5, 0.5, 0.5]
specular = 0.7
reflectivity = 0.25
"#;

    /// An ASCII PLY with `rows` of "x y z red green blue" (8-bit colours).
    fn coloured_ply(rows: &[[i32; 6]]) -> String {
        let mut s = format!(
            "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
             property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
            rows.len()
        );
        for r in rows {
            s.push_str(&format!(
                "{} {} {} {} {} {}\n",
                r[0], r[1], r[2], r[3], r[4], r[5]
            ));
        }
        s
    }

    /// Loads `body` after the common head as `scene.toml` in a folder holding `files`.
    fn load(body: &str, files: &[(&str, &str)]) -> Result<LoadedScene, LoadError> {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).unwrap();
        }
        let path = dir.path().join("scene.toml");
        parse_scene(&format!("{HEAD}{body}"), &path)
    }

    fn error(body: &str, files: &[(&str, &str)]) -> String {
        let e = load(body, files).expect_err("an error").to_string();
        assert!(e.contains("scene.toml"), "names the scene: {e}");
        e
    }

    #[test]
    fn vertices_become_spheres_and_colours_become_one_material_each() {
        let ply = coloured_ply(&[
            [0, 0, 0, 255, 0, 0],
            [1, 0, 0, 0, 255, 0],
            [2, 0, 0, 255, 0, 0],
            [3, 0, 0, 188, 188, 188],
        ]);
        let s = load(
            "[[spheres]]\npath = \"a.ply\"\nradius = 0.25\nmaterial = \"shiny\"\n\
             [[spheres]]\npath = \"a.ply\"\nradius = 0.5\nmaterial = \"shiny\"\n",
            &[("a.ply", &ply)],
        )
        .unwrap();
        let spheres = &s.description.geometry.spheres;
        assert_eq!(spheres.len(), 8);
        assert_eq!(spheres[1].center, DVec3::new(1.0, 0.0, 0.0));
        assert_eq!((spheres[1].radius, spheres[5].radius), (0.25, 0.5));
        // Three colours across both tables: three materials after the scene's one.
        assert_eq!(s.description.materials.len(), 4);
        assert_eq!(spheres[0].material, spheres[2].material);
        assert_eq!(spheres[0].material, spheres[4].material);
        let grey = &s.description.materials[spheres[3].material as usize];
        let g = quadray::colour::decode_srgb8(188);
        assert_eq!(grey.texture, quadray::Texture::Constant(Vec3::splat(g)));
        assert_eq!((grey.specular, grey.reflectivity), (0.7, 0.25));
        assert_eq!(
            s.material_names[spheres[0].material as usize],
            "shiny rgb(1, 0, 0)"
        );
        assert!(s.notes.is_empty(), "{:?}", s.notes);
    }

    #[test]
    fn a_transform_places_the_spheres_as_it_places_a_sphere() {
        let ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n\
                   property double z\nproperty double radius\nend_header\n1 2 3 0.5\n0 0 0 1\n";
        let s = load(
            "[[spheres]]\npath = \"r.ply\"\nmaterial = \"shiny\"\nradius = 9\n\
             transform = { translate = [10, 0, 0], scale = 2 }\n",
            &[("r.ply", ply)],
        )
        .unwrap();
        let spheres = &s.description.geometry.spheres;
        assert_eq!(spheres[0].center, DVec3::new(12.0, 4.0, 6.0));
        assert_eq!((spheres[0].radius, spheres[1].radius), (1.0, 2.0));
        assert_eq!(s.description.materials.len(), 1);
        assert!(
            s.notes.iter().any(|n| n.contains("`radius` is not used")),
            "{:?}",
            s.notes
        );
        // A non-uniform scale makes ellipsoids, as for [[sphere]].
        let s = load(
            "[[spheres]]\npath = \"r.ply\"\nmaterial = \"shiny\"\n\
             transform = { scale = [1, 1, 3] }\n",
            &[("r.ply", ply)],
        )
        .unwrap();
        assert!(s.description.geometry.spheres.is_empty());
        assert_eq!(s.description.geometry.quadrics.len(), 2);
    }

    #[test]
    fn sphere_sets_in_groups_go_into_the_group_prototype() {
        let ply = coloured_ply(&[[0, 0, 0, 0, 0, 255], [1, 1, 1, 0, 0, 255]]);
        let s = load(
            "[[group]]\nname = \"g\"\ntransform = { translate = [0, 0, 5] }\n\
             [[group.spheres]]\npath = \"c.ply\"\nradius = 0.1\nmaterial = \"shiny\"\n",
            &[("c.ply", &ply)],
        )
        .unwrap();
        let g = &s.description.geometry;
        assert!(g.spheres.is_empty());
        assert_eq!(g.prototypes.len(), 1);
        assert_eq!(g.prototypes[0].spheres.len(), 2);
        assert_eq!(g.instances.len(), 1);
        assert_eq!(s.description.materials.len(), 2);
        let e = error(
            "[[group]]\nname = \"g\"\n[[group.spheres]]\npath = \"c.ply\"\nmaterial = \"shiny\"\n",
            &[("c.ply", &ply)],
        );
        assert!(
            e.contains("`group[0].spheres[0].path`") && e.contains("no `radius` property"),
            "{e}"
        );
    }

    #[test]
    fn errors_name_the_scene_key_the_file_and_the_vertex() {
        let ply = coloured_ply(&[[0, 0, 0, 1, 2, 3]]);
        let files = [("a.ply", ply.as_str())];
        let e = error(
            "[[spheres]]\npath = \"a.ply\"\nradius = 1\nmaterial = \"matte\"\n",
            &files,
        );
        assert!(
            e.contains("`spheres[0].material`: unknown material \"matte\""),
            "{e}"
        );
        let e = error(
            "[[spheres]]\npath = \"a.ply\"\nradius = -1\nmaterial = \"shiny\"\n",
            &files,
        );
        assert!(
            e.contains("`spheres[0].radius`: must be positive, got -1"),
            "{e}"
        );
        let e = error(
            "[[spheres]]\npath = \"none.ply\"\nradius = 1\nmaterial = \"shiny\"\n",
            &files,
        );
        assert!(
            e.contains(":12:8: `spheres[0].path`") && e.contains("none.ply: cannot read the file"),
            "{e}"
        );
        let bad = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                   property float z\nproperty float radius\nend_header\n0 0 0 1\n0 0 0 0\n";
        let e = error(
            "[[spheres]]\npath = \"bad.ply\"\nmaterial = \"shiny\"\n",
            &[("bad.ply", bad)],
        );
        assert!(
            e.contains("`spheres[0].path`: ")
                && e.contains("bad.ply:10:1: `vertex[1].radius`: must be positive, got 0"),
            "{e}"
        );
        let e = error(
            "[[spheres]]\npath = \"a.ply\"\nradius = 1\nmaterial = \"shiny\"\ncolor = [1, 0, 0]\n",
            &files,
        );
        assert!(e.contains("unknown field `color`"), "{e}");
    }
}
