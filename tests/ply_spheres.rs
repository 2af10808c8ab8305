//! `[[spheres]] path = "….ply"` end to end: spheres read from a PLY file render exactly as the
//! same spheres written as `[[sphere]]` tables.
//!
//! The independent check: tests/scenes/ply-spheres-inline.toml spells out each vertex of
//! tests/scenes/ply-spheres.ply as a `[[sphere]]` with the same transform, and each of its four
//! 8-bit colours as a `[[material]]` (the "atom" material with `color` = the sRGB code decoded to
//! linear). The scene loader's `[[sphere]]` path and the PLY path must give the same pixels, bit
//! for bit, from the ASCII file and from a binary little-endian copy of it.

use quadray::{Film, NoProgress, Scene};
use quadray_tests::repo_root;
use std::path::Path;

/// The loaded scene's material count and its film at the scene's own settings.
fn render(path: &Path) -> (usize, Film) {
    let loaded = quadray_loader::load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    let materials = loaded.description.materials.len();
    let settings = loaded.settings.render_settings();
    let scene = Scene::new(loaded.description).expect("scene is valid");
    let film = quadray::render(&scene, &settings, &NoProgress)
        .unwrap()
        .film;
    (materials, film)
}

fn bits(film: &Film) -> Vec<[u32; 3]> {
    film.pixels()
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

/// The vertex rows of the ASCII file (x y z radius as doubles, red green blue as bytes) written
/// as binary little-endian PLY.
fn binary_copy(ascii: &str) -> Vec<u8> {
    let (_, body) = ascii.split_once("end_header\n").expect("a PLY header");
    let rows: Vec<Vec<&str>> = body
        .lines()
        .map(|l| l.split_whitespace().collect())
        .collect();
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\n\
         property double y\nproperty double z\nproperty double radius\nproperty uchar red\n\
         property uchar green\nproperty uchar blue\nend_header\n",
        rows.len()
    )
    .into_bytes();
    for row in rows {
        for v in &row[..4] {
            out.extend(v.parse::<f64>().unwrap().to_le_bytes());
        }
        for v in &row[4..] {
            out.push(v.parse::<u8>().unwrap());
        }
    }
    out
}

#[test]
fn ply_spheres_render_like_the_same_inline_spheres() {
    let scenes = repo_root().join("tests/scenes");
    let (materials, from_ply) = render(&scenes.join("ply-spheres.toml"));
    let (inline_materials, inline) = render(&scenes.join("ply-spheres-inline.toml"));
    // floor, atom, and one material a colour (four colours over nine spheres).
    assert_eq!(materials, 6);
    assert_eq!(inline_materials, 6);
    let (ply_bits, inline_bits) = (bits(&from_ply), bits(&inline));
    // Not a blank image: the spheres cover many pixels of many colours.
    let mut distinct = inline_bits.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() > 100, "{} distinct pixels", distinct.len());
    let differing = ply_bits
        .iter()
        .zip(&inline_bits)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "pixels differ between the PLY and inline scenes"
    );

    // The same spheres from a binary little-endian file.
    let dir = tempfile::tempdir().unwrap();
    let ascii = std::fs::read_to_string(scenes.join("ply-spheres.ply")).unwrap();
    std::fs::write(dir.path().join("binary.ply"), binary_copy(&ascii)).unwrap();
    let scene = std::fs::read_to_string(scenes.join("ply-spheres.toml"))
        .unwrap()
        .replace("\"ply-spheres.ply\"", "\"binary.ply\"");
    assert!(scene.contains("binary.ply"));
    std::fs::write(dir.path().join("binary.toml"), scene).unwrap();
    let (_, from_binary) = render(&dir.path().join("binary.toml"));
    assert!(
        bits(&from_binary) == inline_bits,
        "the binary file renders differently"
    );
}
