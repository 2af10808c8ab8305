//! Wavefront MTL materials mapped onto quadray's Whitted material.
//!
//! | MTL | quadray |
//! |---|---|
//! | `Kd` (default 0.8 grey) | base colour: `Texture::Constant(Kd)` |
//! | `map_Kd` | `Texture::Image` (sRGB, bilinear, repeat), multiplied by `Kd` as the MTL spec says |
//! | `Ks`, `Ns` | `specular` = largest channel of `Ks`, `shininess` = `Ns` (Phong); no highlight when `Ns` < 1, an exporter artefact that would otherwise light the whole surface |
//! | `illum` 3, 5 or 7, or a mirror-like `Ks` (every channel ≥ 0.9 with `Ns` ≥ 500) | `reflectivity` = largest channel of `Ks`, capped at 1 |
//! | `Ka` | ignored: exporters write it inconsistently (Blender writes 1, which would flatten every surface); `ambient` keeps quadray's default 0.1 |
//! | `Ke` | `emission`: the surface's own light, seen directly and in mirrors |
//! | `d` < 1, `Tr` > 0, `map_d`, `map_Bump` | ignored, with a note |
//!
//! `diffuse` keeps quadray's default 0.9.

use crate::image_file::{ImageCache, resolve_reference};
use glam::Vec3;
use quadray::{Filter, ImageMap, ImageTexture, Material, SpecularModel, Texture, Wrap};
use std::path::Path;

/// The Whitted material for an MTL material whose library lives in `folder`, or what is wrong
/// with it (a colour or exponent that is not a finite number).
pub fn whitted_material(
    m: &tobj::Material,
    folder: &Path,
    images: &mut ImageCache,
    notes: &mut Vec<String>,
) -> Result<Material, String> {
    for (statement, value) in [("Ka", m.ambient), ("Kd", m.diffuse), ("Ks", m.specular)] {
        if let Some(c) = value.filter(|c| c.iter().any(|x| !x.is_finite())) {
            return Err(format!("{statement} {c:?} is not three finite numbers"));
        }
    }
    if let Some(ns) = m.shininess.filter(|n| !n.is_finite()) {
        return Err(format!("Ns {ns} is not a finite number"));
    }
    let rgb = |c: Option<[f32; 3]>| c.map(|c| Vec3::from_array(c).max(Vec3::ZERO));
    let kd = rgb(m.diffuse);
    let ks = rgb(m.specular).unwrap_or(Vec3::ZERO);
    let ns = m.shininess.unwrap_or(0.0).clamp(0.0, 1e4);
    let mut texture = Texture::Constant(kd.unwrap_or(Vec3::splat(0.8)));
    if let Some(reference) = m.diffuse_texture.as_deref().and_then(texture_file_name) {
        let path = resolve_reference(folder, reference);
        let user = format!("material \"{}\" map_Kd", m.name);
        if let Some(image) = images.get(&path, &user, notes) {
            texture = Texture::Image(ImageTexture {
                map: ImageMap {
                    image,
                    wrap: [Wrap::Repeat; 2],
                    filter: Filter::Bilinear,
                    set: 0,
                },
                factor: kd.unwrap_or(Vec3::ONE),
            });
        }
    }
    let (specular, shininess) = if ns >= 1.0 {
        (ks.max_element(), ns)
    } else {
        (0.0, 1.0)
    };
    let traced = matches!(m.illumination_model, Some(3 | 5 | 7));
    let mirror_like = ks.min_element() >= 0.9 && ns >= 500.0;
    let reflectivity = if traced || mirror_like {
        ks.max_element().min(1.0)
    } else {
        0.0
    };
    let mut ignored = Vec::new();
    if m.dissolve.is_some_and(|d| d < 1.0) {
        ignored.push("transparency (d)");
    }
    if m.unknown_param
        .get("Tr")
        .and_then(|t| t.trim().parse::<f32>().ok())
        .is_some_and(|t| t > 0.0)
    {
        ignored.push("transparency (Tr)");
    }
    if m.dissolve_texture.is_some() {
        ignored.push("map_d");
    }
    if m.normal_texture.is_some() || m.unknown_param.contains_key("map_Bump") {
        ignored.push("bump map");
    }
    // Ke: light the surface gives off (exporters write 0 0 0 for every other material).
    let emission = m
        .emissive
        .map(Vec3::from_array)
        .filter(|e| e.is_finite() && e.min_element() >= 0.0 && e.max_element() > 0.0)
        .map(Texture::Constant);
    if !ignored.is_empty() {
        notes.push(format!(
            "material \"{}\": {} not supported, ignored",
            m.name,
            ignored.join(", ")
        ));
    }
    let defaults = Material::default();
    Ok(Material {
        texture,
        ambient: defaults.ambient,
        diffuse: defaults.diffuse,
        specular,
        shininess,
        specular_model: SpecularModel::Phong,
        reflectivity,
        reflection_tint: 0.0,
        specular_tint: 0.0,
        emission,
        roughness: 0.0,
        transmission: None,
    })
}

/// The file name in a `map_Kd` statement, past any options (`-s 1 1 1`, `-clamp on`, `-bm 0.5`).
fn texture_file_name(statement: &str) -> Option<&str> {
    let mut rest = statement.trim();
    while rest.starts_with('-') {
        let (option, after) = rest.split_once(char::is_whitespace)?;
        rest = after.trim_start();
        let arguments = match option {
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-bm" | "-boost" | "-texres"
            | "-imfchan" => 1,
            "-mm" => 2,
            // -o, -s, -t take one to three numbers.
            "-o" | "-s" | "-t" => 3,
            _ => 0,
        };
        for _ in 0..arguments {
            let Some((word, after)) = rest.split_once(char::is_whitespace) else {
                break;
            };
            let numeric = word.parse::<f32>().is_ok();
            let flag = matches!(word, "on" | "off" | "r" | "g" | "b" | "m" | "l" | "z");
            if !(numeric || flag) {
                break;
            }
            rest = after.trim_start();
        }
    }
    (!rest.is_empty()).then_some(rest)
}

/// Checks MTL text line by line and prepares it for tobj, so every problem is named with its line
/// (tobj's own errors have none):
/// - a colour statement (`Ka`, `Kd`, `Ks`, `Ke`, `Tf`) takes one or three finite numbers of at
///   least 0; a single number means grey (the MTL spec: "g and b default to r") and is expanded
///   to three, because tobj 4 panics on fewer;
/// - a scalar statement (`Ns`, `Ni`, `d`, `Tr`, `illum`) takes one finite number.
pub fn prepare_mtl_text(text: &str) -> Result<String, (usize, String)> {
    let mut out = String::with_capacity(text.len() + 64);
    for (n, line) in text.lines().enumerate() {
        // A `#` starts a comment, on a line of its own or after a statement's numbers.
        let statement = line.split('#').next().unwrap_or_default();
        let mut words = statement.split_whitespace();
        let keyword = words.next();
        let values: Vec<&str> = words.collect();
        let fail = |message: String| -> Result<String, (usize, String)> { Err((n + 1, message)) };
        let one_finite = |key: &str, v: &[&str]| {
            if v.len() == 1 && v[0].parse::<f32>().is_ok_and(f32::is_finite) {
                Ok(())
            } else {
                Err((n + 1, format!("`{key}` needs one finite number, got {v:?}")))
            }
        };
        match keyword {
            Some("illum") if values.len() != 1 || values[0].parse::<u8>().is_err() => {
                return fail(format!(
                    "`illum` needs one whole number from 0 to 255, got {values:?}"
                ));
            }
            Some("d") if values.first() == Some(&"-halo") => {
                return fail("`d -halo` (halo dissolve) is not supported".into());
            }
            Some(key @ ("Ns" | "Ni" | "d" | "Tr")) => one_finite(key, &values)?,
            // The CIE XYZ and spectral forms of a transmission filter: quadray does not read `Tf`.
            Some("Tf") if matches!(values.first(), Some(&("xyz" | "spectral"))) => {}
            Some(key @ ("Ka" | "Kd" | "Ks" | "Ke" | "Tf")) => {
                if let Some(bad) = values.iter().find(|v| v.parse::<f32>().is_err()) {
                    return fail(format!("`{key}`: `{bad}` is not a number"));
                }
                // `Ka` is not read (see the table above), so only its form is checked.
                let colour_read = key != "Ka";
                if let Some(bad) = values.iter().find(|v| {
                    v.parse::<f32>()
                        .is_ok_and(|x| !x.is_finite() || (colour_read && x < 0.0))
                }) {
                    return fail(format!(
                        "`{key}` {bad}: a colour takes finite numbers of 0 or more"
                    ));
                }
                match values.len() {
                    1 => {
                        let v = values[0];
                        out.push_str(&format!("{key} {v} {v} {v}\n"));
                        continue;
                    }
                    3 => {
                        out.push_str(statement);
                        out.push('\n');
                        continue;
                    }
                    count => {
                        return fail(format!("`{key}` needs one or three numbers, got {count}"));
                    }
                }
            }
            _ => {}
        }
        out.push_str(line);
        out.push('\n');
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(text: &str) -> (tobj::Material, Vec<String>, Material) {
        let text = prepare_mtl_text(text).unwrap();
        let (mats, _) = tobj::load_mtl_buf(&mut text.as_bytes()).unwrap();
        let mut notes = Vec::new();
        let m = whitted_material(
            &mats[0],
            Path::new("/nonexistent"),
            &mut ImageCache::default(),
            &mut notes,
        )
        .unwrap();
        (mats[0].clone(), notes, m)
    }

    /// Every number a statement needs is checked with its line: tobj's own errors have none.
    #[test]
    fn bad_numbers_are_refused_with_their_line() {
        for (text, line, says) in [
            (
                "newmtl a\nKd nan 0.5 0.5\n",
                2,
                "finite numbers of 0 or more",
            ),
            ("newmtl a\n\nKd -1 -1 -1\n", 3, "`Kd` -1"),
            ("newmtl a\nKs 0.1 x 0.2\n", 2, "`x` is not a number"),
            ("newmtl a\nNs inf\n", 2, "`Ns` needs one finite number"),
            ("newmtl a\nillum\n", 2, "`illum` needs one whole number"),
            ("newmtl a\nillum 2.5\n", 2, "`illum` needs one whole number"),
            ("newmtl a\nd -halo 0.5\n", 2, "`d -halo`"),
            ("newmtl a\nKd 1 1 1 1\n", 2, "one or three numbers"),
            ("newmtl a\nTf 0.5 0.5\n", 2, "one or three numbers"),
        ] {
            let (at, message) = prepare_mtl_text(text).unwrap_err();
            assert_eq!(at, line, "{text:?}");
            assert!(message.contains(says), "{text:?}: {message}");
        }
        // Legal forms still pass: comments after numbers, Tf's xyz and spectral forms, and a
        // negative Ka (which quadray does not read).
        for text in [
            "newmtl a\nKd 1 0.5 0.25 # orange\nNs 10 # sharp\nillum 2\n",
            "newmtl a\nTf xyz 0.5 0.5 0.5\nTf spectral glass.rfl 1.0\n",
            "newmtl a\nKa -0.1 0 0\n",
        ] {
            let prepared = prepare_mtl_text(text).unwrap_or_else(|e| panic!("{text:?}: {e:?}"));
            tobj::load_mtl_buf(&mut prepared.as_bytes()).unwrap();
        }
    }

    /// A material made in code, past the text checks, is still refused by the conversion.
    #[test]
    fn non_finite_colours_are_refused() {
        let text = "newmtl a\nKd 0.5 0.5 0.5\n";
        let (mut mats, _) = tobj::load_mtl_buf(&mut text.as_bytes()).unwrap();
        mats[0].diffuse = Some([f32::NAN, 0.5, 0.5]);
        let e = whitted_material(
            &mats[0],
            Path::new("."),
            &mut ImageCache::default(),
            &mut vec![],
        )
        .unwrap_err();
        assert!(e.contains("Kd"), "{e}");
    }

    #[test]
    fn maps_kd_ks_ns_and_illum() {
        let (_, notes, m) =
            material("newmtl a\nKd 0.5 0.25 1\nKs 0.2 0.4 0.3\nNs 64\nillum 3\nKa 1 1 1\n");
        assert_eq!(m.texture, Texture::Constant(Vec3::new(0.5, 0.25, 1.0)));
        assert_eq!((m.specular, m.shininess), (0.4, 64.0));
        assert_eq!(m.reflectivity, 0.4);
        assert_eq!(m.ambient, Material::default().ambient);
        assert!(notes.is_empty());
        let (_, _, plain) = material("newmtl b\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nNs 250\nillum 2\n");
        assert_eq!(plain.reflectivity, 0.0);
        let (_, _, mirror) = material("newmtl c\nKs 0.95 0.95 1\nNs 900\n");
        assert_eq!(mirror.reflectivity, 1.0);
        let (_, _, flat) = material("newmtl d\nKs 0.9 0.9 0.9\nNs 0\n");
        assert_eq!(flat.specular, 0.0);
    }

    #[test]
    fn single_number_colours_are_grey_and_bad_counts_are_errors() {
        let (raw, _, m) = material("newmtl a\nKd 0.3\n");
        assert_eq!(raw.diffuse, Some([0.3; 3]));
        assert_eq!(m.texture, Texture::Constant(Vec3::splat(0.3)));
        assert_eq!(prepare_mtl_text("newmtl a\n\nKs 1 2\n").unwrap_err().0, 3);
        assert!(prepare_mtl_text("Kd\n").is_err());
    }

    #[test]
    fn missing_texture_falls_back_with_a_note_and_unsupported_features_are_named() {
        let (_, notes, m) = material("newmtl a\nKd 0.2 0.3 0.4\nmap_Kd tex\\wood.png\nd 0.5\n");
        assert_eq!(m.texture, Texture::Constant(Vec3::new(0.2, 0.3, 0.4)));
        assert!(
            notes
                .iter()
                .any(|n| n.contains("wood.png") && n.contains("base colour")),
            "{notes:?}"
        );
        assert!(
            notes.iter().any(|n| n.contains("transparency (d)")),
            "{notes:?}"
        );
    }

    #[test]
    fn texture_options_are_skipped() {
        assert_eq!(texture_file_name("wood.png"), Some("wood.png"));
        assert_eq!(
            texture_file_name("-s 1 2 1 -clamp on my wood.png"),
            Some("my wood.png")
        );
        assert_eq!(texture_file_name("-bm 0.5 bump.png"), Some("bump.png"));
        assert_eq!(texture_file_name("-o 0.5 wood.png"), Some("wood.png"));
        assert_eq!(texture_file_name("-s"), None);
    }
}
