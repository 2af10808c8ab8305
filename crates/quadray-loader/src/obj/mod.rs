//! Wavefront OBJ files, read with tobj: polygons triangulated (fans), positions, normals (smooth
//! shading where the file has them), texture coordinates, vertex colours, and MTL materials.
//!
//! - One quadray mesh per OBJ object/group and material (tobj's models), in world space: the file is
//!   rotated from y-up to z-up unless the caller says it is z-up already (`crate::import`).
//! - Texture coordinates are flipped to the image convention (OBJ's v grows upwards, quadray's
//!   downwards, as in glTF).
//! - Vertex colours (`v x y z r g b`) are read as sRGB-encoded and decoded to linear.
//! - A missing material library is not fatal: real files often name one that was never shipped
//!   (SOURCES.md lists five among the test assets); its faces get a default grey material and a
//!   note names the file that was looked for. A library that exists but cannot be parsed is an error.

mod locate;
pub mod mtl;

pub use locate::MAX_FACE_VERTICES;

use crate::error::{LoadError, LoadErrorKind, Location};
use crate::image_file::{ImageCache, resolve_reference};
use crate::import::{ImportOptions, Imported};
use crate::obj::locate::{
    locate_far_vertex, locate_non_finite, locate_parse_error, locate_zero_index, oversized_face,
    undefined_materials,
};
use crate::obj::mtl::{prepare_mtl_text, whitted_material};
use glam::{DVec3, Vec2, Vec3, Vec4};
use quadray::{Material, Mesh};
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// Reads the OBJ file at `path` (and the material libraries and textures it names).
pub fn import_obj(path: &Path, options: &ImportOptions) -> Result<Imported, LoadError> {
    let bytes = crate::read_limited::read(path, crate::read_limited::MAX_MESH_BYTES)
        .map_err(|e| LoadError::new(path, None, LoadErrorKind::Io(e)))?;
    import_obj_bytes(&bytes, path, options)
}

/// A material library tobj asked for, as this loader found it.
struct Library {
    folder: PathBuf,
    materials: usize,
}

/// Reads OBJ text already in memory; `path` names it in errors and locates the files it refers to.
pub fn import_obj_bytes(
    bytes: &[u8],
    path: &Path,
    options: &ImportOptions,
) -> Result<Imported, LoadError> {
    if let Some((line, count)) = oversized_face(bytes) {
        return Err(LoadError::new(
            path,
            Some(Location { line, column: 1 }),
            LoadErrorKind::Unsupported(format!(
                "a face with {count} vertices; at most {MAX_FACE_VERTICES} are supported (split the polygon)"
            )),
        ));
    }
    let folder = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Parsed {
        models,
        materials,
        libraries,
        mut notes,
    } = parse(bytes, path, &folder)?;
    check_numbers(bytes, path, &models)?;
    // Placed as written (no transform to bring it back within the limit), a vertex past the
    // coordinate limit is the file's error, at its line, not the geometry's or the camera's.
    if options.transform.is_none() {
        check_reach(bytes, path, &models)?;
    }
    let mut out = Imported::default();
    if !options.skip_materials {
        out.materials =
            convert_materials(&materials, &libraries, &folder, path, options, &mut notes)?;
    }
    let default_id = out.materials.len() as u32;
    let mut unmatched = 0;
    for model in &models {
        if model.mesh.indices.is_empty() {
            continue;
        }
        let material = match model.mesh.material_id {
            Some(i) if i < materials.len() && !options.skip_materials => i as u32,
            _ => {
                if !materials.is_empty() && !options.skip_materials {
                    unmatched += 1;
                }
                default_id
            }
        };
        out.geometry
            .meshes
            .push(convert_mesh(model, material, path, options)?);
    }
    if unmatched > 0 {
        let defined: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
        let undefined = undefined_materials(bytes, &defined);
        let named = if undefined.is_empty() {
            String::new()
        } else {
            format!(" (undefined: {})", undefined.join(", "))
        };
        notes.push(format!(
            "warning: {unmatched} object(s) name no material, or one their libraries do not define{named}; they use a default grey"
        ));
    } else if materials.is_empty() && !options.skip_materials {
        // No library read defines a material (none named, none found, or none in them): tobj
        // then drops every `usemtl` without a word, so the names are found here.
        let said = memchr::memmem::find(bytes, b"usemtl").is_some();
        let undefined = if said {
            undefined_materials(bytes, &[])
        } else {
            Vec::new()
        };
        if !undefined.is_empty() {
            notes.push(format!(
                "warning: `usemtl` names {}, which no material library read defines; those faces use a default grey",
                undefined.join(", ")
            ));
        }
    }
    if out
        .geometry
        .meshes
        .iter()
        .any(|m| m.material() == default_id)
        || out.materials.is_empty()
    {
        out.materials.push(("default".into(), Material::default()));
    }
    if out.geometry.meshes.is_empty() {
        // Comments only, binary junk, lines and points, faces of two vertices: nothing renders,
        // which is worth saying rather than drawing an empty image.
        return Err(LoadError::new(
            path,
            None,
            LoadErrorKind::Unsupported(
                "the file has no faces with three or more vertices: nothing to render (is it an OBJ file?)"
                    .into(),
            ),
        ));
    }
    out.notes = notes;
    Ok(out)
}

/// What tobj read: the objects, the materials of every library, where each library lies (in
/// order, with its material count) and the notes about libraries that could not be read.
struct Parsed {
    models: Vec<tobj::Model>,
    materials: Vec<tobj::Material>,
    libraries: Vec<Library>,
    notes: Vec<String>,
}

/// Parses the OBJ text with tobj, reading each MTL library it names beside `folder` (within the
/// size limit; its numbers checked line by line). A library that cannot be read is a note (its
/// materials fall back to grey); one that is malformed is an error naming both files.
fn parse(bytes: &[u8], path: &Path, folder: &Path) -> Result<Parsed, LoadError> {
    let libraries = RefCell::new(Vec::<Library>::new());
    let notes = RefCell::new(Vec::<String>::new());
    let library_error = RefCell::new(None::<LoadError>);
    let load_options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let result = tobj::load_obj_buf(&mut &bytes[..], &load_options, |reference| {
        let mtl_path = resolve_reference(folder, &reference.to_string_lossy());
        let text = match crate::read_limited::read(
            &mtl_path,
            crate::read_limited::MAX_MATERIAL_BYTES,
        ) {
            Ok(b) => String::from_utf8_lossy(&b).into_owned(),
            Err(e) => {
                notes.borrow_mut().push(format!(
                    "warning: material library `{}` not found ({e}); its materials fall back to a default grey",
                    mtl_path.display()
                ));
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        let parsed = prepare_mtl_text(&text)
            .map_err(|(line, message)| {
                LoadError::new(
                    &mtl_path,
                    Some(Location { line, column: 1 }),
                    LoadErrorKind::Syntax(message),
                )
            })
            .and_then(|text| {
                tobj::load_mtl_buf(&mut text.as_bytes()).map_err(|e| {
                    LoadError::new(&mtl_path, None, LoadErrorKind::Syntax(e.to_string()))
                })
            });
        match parsed {
            Ok((materials, map)) => {
                libraries.borrow_mut().push(Library {
                    folder: mtl_path.parent().unwrap_or(Path::new(".")).to_path_buf(),
                    materials: materials.len(),
                });
                Ok((materials, map))
            }
            Err(e) => {
                library_error.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::MaterialParseError)
            }
        }
    });
    if let Some(e) = library_error.into_inner() {
        // Named from the OBJ file, which is what the user gave, and then the library's place.
        return Err(LoadError::new(
            path,
            None,
            LoadErrorKind::Include {
                key: "mtllib".into(),
                source: Box::new(e),
            },
        ));
    }
    let (models, materials) = result.map_err(|e| obj_error(bytes, path, e))?;
    Ok(Parsed {
        models,
        // tobj reports a missing library as an error in place of the materials; the note says so.
        materials: materials.unwrap_or_default(),
        libraries: libraries.into_inner(),
        notes: notes.into_inner(),
    })
}

/// An error on the first line whose numbers tobj read without complaint but quadray cannot use:
/// a coordinate, normal, texture coordinate or colour that is not finite, or a face index 0.
fn check_numbers(bytes: &[u8], path: &Path, models: &[tobj::Model]) -> Result<(), LoadError> {
    let non_finite = models.iter().any(|m| {
        let mesh = &m.mesh;
        [
            &mesh.positions,
            &mesh.normals,
            &mesh.texcoords,
            &mesh.vertex_color,
        ]
        .iter()
        .any(|values| values.iter().any(|x| !x.is_finite()))
    });
    let located = match non_finite {
        true => locate_non_finite(bytes),
        false => None,
    };
    if let Some((key, (line, message))) =
        located.or_else(|| locate_zero_index(bytes).map(|l| ("f", l)))
    {
        return Err(LoadError::new(
            path,
            Some(Location { line, column: 1 }),
            LoadErrorKind::Invalid {
                key: key.into(),
                message,
            },
        ));
    }
    Ok(())
}

/// An error on the first `v` line with a coordinate past [`quadray::MAX_COORDINATE`], if any
/// vertex has one.
fn check_reach(bytes: &[u8], path: &Path, models: &[tobj::Model]) -> Result<(), LoadError> {
    let limit = quadray::MAX_COORDINATE as f32;
    let far = (models.iter()).any(|m| m.mesh.positions.iter().any(|x| x.abs() > limit));
    if !far {
        return Ok(());
    }
    let (line, message) = locate_far_vertex(bytes, limit).unwrap_or((
        0,
        format!("a vertex lies past quadray's coordinate limit of ±{limit:e}"),
    ));
    Err(LoadError::new(
        path,
        (line > 0).then_some(Location { line, column: 1 }),
        LoadErrorKind::Invalid {
            key: "v".into(),
            message,
        },
    ))
}

/// The Whitted materials of the libraries' materials, each with its textures read beside its own
/// library.
fn convert_materials(
    materials: &[tobj::Material],
    libraries: &[Library],
    folder: &Path,
    path: &Path,
    options: &ImportOptions,
    notes: &mut Vec<String>,
) -> Result<Vec<(String, Material)>, LoadError> {
    let mut converted = Vec::with_capacity(materials.len());
    let mut images = ImageCache::new(options.textures.clone());
    let mut library = libraries
        .iter()
        .flat_map(|l| std::iter::repeat_n(l.folder.as_path(), l.materials));
    for m in materials {
        let lib_folder = library.next().unwrap_or(folder);
        let w = whitted_material(m, lib_folder, &mut images, notes).map_err(|message| {
            LoadError::invalid(path, None, format!("material \"{}\"", m.name), message)
        })?;
        converted.push((m.name.clone(), w));
    }
    Ok(converted)
}

/// One object's triangles as a mesh in quadray's world (`options`' up axis and placement), with
/// its normals, texture coordinates and vertex colours where the file gives one per vertex.
fn convert_mesh(
    model: &tobj::Model,
    material: u32,
    path: &Path,
    options: &ImportOptions,
) -> Result<Mesh, LoadError> {
    let mesh = &model.mesh;
    let root = options.root(options.up);
    let normal_matrix = root.matrix3.inverse().transpose();
    let flip = root.matrix3.determinant() < 0.0;
    let positions: Vec<Vec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| {
            root.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
                .as_vec3()
        })
        .collect();
    let vertices = positions.len();
    let normals = (mesh.normals.len() == vertices * 3).then(|| {
        mesh.normals
            .chunks_exact(3)
            .map(|n| {
                (normal_matrix * DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64))
                    .normalize_or_zero()
                    .as_vec3()
            })
            .collect()
    });
    let indices: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| {
            if flip {
                [t[0], t[2], t[1]]
            } else {
                [t[0], t[1], t[2]]
            }
        })
        .collect();
    let invalid = |e: quadray::MeshError| {
        LoadError::invalid(
            path,
            None,
            format!("object \"{}\"", model.name),
            e.to_string(),
        )
    };
    let mut built = Mesh::new(positions, indices, normals, material).map_err(invalid)?;
    if mesh.texcoords.len() == vertices * 2 {
        let uv = mesh
            .texcoords
            .chunks_exact(2)
            .map(|t| Vec2::new(t[0], 1.0 - t[1]))
            .collect();
        built = built.with_texcoords(0, uv).map_err(invalid)?;
    }
    if mesh.vertex_color.len() == vertices * 3 {
        // OBJ vertex colours are display values (sRGB), as Blender writes them.
        let decode = quadray::colour::decode_srgb;
        let colors = mesh
            .vertex_color
            .chunks_exact(3)
            .map(|c| Vec4::new(decode(c[0]), decode(c[1]), decode(c[2]), 1.0))
            .collect();
        built = built.with_colors(colors).map_err(invalid)?;
    }
    Ok(built)
}

/// A tobj error as a [`LoadError`], located on its line when a second look at the text finds it
/// (tobj does not say where its errors are).
fn obj_error(bytes: &[u8], path: &Path, e: tobj::LoadError) -> LoadError {
    if let Some((line, message)) = locate_parse_error(bytes, &e) {
        return LoadError::new(
            path,
            Some(Location { line, column: 1 }),
            LoadErrorKind::Syntax(message),
        );
    }
    let message = match e {
        tobj::LoadError::ReadError => "the file is not text (invalid UTF-8)".to_string(),
        other => other.to_string(),
    };
    LoadError::new(path, None, LoadErrorKind::Syntax(message))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("quadray-obj-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";

    #[test]
    fn quads_are_triangulated_with_uv_flipped_and_axes_converted() {
        let obj = import_obj_bytes(
            QUAD.as_bytes(),
            Path::new("q.obj"),
            &ImportOptions::default(),
        )
        .unwrap();
        assert_eq!(obj.triangle_count(), 2);
        let m = &obj.geometry.meshes[0];
        // y-up file: (1, 1, 0) becomes (1, 0, 1); the +z normal becomes -y.
        assert!(m.positions().contains(&Vec3::new(1.0, 0.0, 1.0)));
        assert!(
            m.normals()
                .unwrap()
                .iter()
                .all(|n| (*n - Vec3::NEG_Y).length() < 1e-6)
        );
        // vt (0, 0) is the bottom-left of the image: v = 1 in the image convention.
        let i = m.positions().iter().position(|p| *p == Vec3::ZERO).unwrap();
        assert_eq!(m.texcoords(0).unwrap()[i], Vec2::new(0.0, 1.0));
        assert_eq!(obj.materials.len(), 1);
        let z_up = ImportOptions {
            up: crate::import::UpAxis::Z,
            ..ImportOptions::default()
        };
        let obj = import_obj_bytes(QUAD.as_bytes(), Path::new("q.obj"), &z_up).unwrap();
        assert!(
            obj.geometry.meshes[0]
                .positions()
                .contains(&Vec3::new(1.0, 1.0, 0.0))
        );
    }

    #[test]
    fn out_of_range_index_is_located() {
        let e = import_obj_bytes(
            b"v 0 0 0\nv 1 0 0\n\nf 1 2 7\n",
            Path::new("bad.obj"),
            &ImportOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("bad.obj:4:1:") && e.contains("face index 7 is out of range"),
            "{e}"
        );
        let e = import_obj_bytes(
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            Path::new("t.obj"),
            &ImportOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains(":5:1:") && e.contains("texture coordinates"),
            "{e}"
        );
    }

    #[test]
    fn materials_textures_and_missing_libraries() {
        let dir = temp_dir("mtl");
        std::fs::create_dir_all(dir.join("tex")).unwrap();
        let mut png = Vec::new();
        image::RgbaImage::from_raw(1, 1, vec![255, 0, 0, 255])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        std::fs::write(dir.join("tex/red.png"), png).unwrap();
        std::fs::write(
            dir.join("m.mtl"),
            "newmtl red\nKd 1 1 1\nmap_Kd tex\\red.png\nnewmtl mirror\nKs 1 1 1\nillum 3\nNs 10\n",
        )
        .unwrap();
        let obj = format!(
            "mtllib m.mtl\nmtllib gone.mtl\n{QUAD}usemtl red\nf 1 2 3\nusemtl mirror\nf 1 3 4\nusemtl nope\nf 2 3 4\n"
        );
        std::fs::write(dir.join("a.obj"), obj).unwrap();
        let got = import_obj(&dir.join("a.obj"), &ImportOptions::default()).unwrap();
        let names: Vec<_> = got.materials.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["red", "mirror", "default"]);
        assert!(matches!(
            got.materials[0].1.texture,
            quadray::Texture::Image(_)
        ));
        assert_eq!(got.materials[1].1.reflectivity, 1.0);
        let notes = got.notes.join("\n");
        assert!(
            notes.contains("gone.mtl") && notes.contains("not found"),
            "{notes}"
        );
        assert!(notes.contains("2 object(s) name no material"), "{notes}");
        // With no library read at all (none named, or only one not found), the names a `usemtl`
        // gives are still warned about, each once; a file that names none gets no warning.
        for libraries in ["", "mtllib gone.mtl\n"] {
            let obj = format!(
                "{libraries}{QUAD}usemtl red\nf 1 2 3\nusemtl nope\nf 1 3 4\nusemtl red\nf 2 3 4\n"
            );
            std::fs::write(dir.join("b.obj"), obj).unwrap();
            let got = import_obj(&dir.join("b.obj"), &ImportOptions::default()).unwrap();
            let notes = got.notes.join("\n");
            let expected = "`usemtl` names red, nope, which no material library read defines";
            assert!(notes.contains(expected), "{notes}");
        }
        std::fs::write(dir.join("c.obj"), format!("{QUAD}f 1 2 3\n")).unwrap();
        let got = import_obj(&dir.join("c.obj"), &ImportOptions::default()).unwrap();
        assert!(!got.notes.join("\n").contains("usemtl"), "{:?}", got.notes);
        // A broken library is an error naming it.
        std::fs::write(dir.join("m.mtl"), "newmtl red\nKd 1 1\n").unwrap();
        let e = import_obj(&dir.join("a.obj"), &ImportOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("m.mtl:2:1:") && e.contains("`Kd` needs one or three numbers"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        for text in [
            &b"v 0 0\n"[..],
            b"f 1 2 3\n",
            b"v 1 2 3\nf 1\n",
            b"\xff\xfe\x00v",
            b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        ] {
            let r = import_obj_bytes(text, Path::new("g.obj"), &ImportOptions::default());
            if let Err(e) = &r {
                assert!(e.to_string().starts_with("g.obj"), "{e}");
            }
        }
        let e = import_obj(Path::new("/nonexistent/x.obj"), &ImportOptions::default()).unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::Io(_)));
    }
}
