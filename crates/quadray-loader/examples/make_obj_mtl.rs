//! Writes the project's own OBJ + MTL example, `scenes/obj-mtl/`: a pedestal whose top is tiled
//! with a texture (named with a Windows-style path, as many exporters write it), stone sides and a
//! mirror slab. Run from the repository root:
//!
//! ```text
//! cargo run -p quadray-loader --example make_obj_mtl
//! ```
//!
//! Everything is computed here, so the files are the project's own work and can be regenerated.

use std::fmt::Write as _;
use std::path::Path;

/// The tile texture: 64×64, two glazes separated by grout lines, sRGB.
fn tiles() -> image::RgbaImage {
    image::RgbaImage::from_fn(64, 64, |x, y| {
        let (cx, cy) = (x / 16, y / 16);
        let grout = x % 16 == 0 || y % 16 == 0;
        if grout {
            image::Rgba([200, 196, 186, 255])
        } else if (cx + cy) % 2 == 0 {
            image::Rgba([32, 92, 150, 255])
        } else {
            image::Rgba([224, 176, 64, 255])
        }
    })
}

/// An axis-aligned box as six quads with per-face normals and 0..1 texture coordinates,
/// appended to `obj`; `first` is the index of the box's first vertex (OBJ counts from 1).
fn box_quads(
    obj: &mut String,
    min: [f32; 3],
    max: [f32; 3],
    material_top: &str,
    material_sides: &str,
) {
    let [x0, y0, z0] = min;
    let [x1, y1, z1] = max;
    // Corners by bit: x = 1, y = 2, z = 4.
    for i in 0..8 {
        let x = if i & 1 == 0 { x0 } else { x1 };
        let y = if i & 2 == 0 { y0 } else { y1 };
        let z = if i & 4 == 0 { z0 } else { z1 };
        writeln!(obj, "v {x} {y} {z}").unwrap();
    }
    for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        writeln!(obj, "vt {u} {v}").unwrap();
    }
    for n in ["1 0 0", "-1 0 0", "0 1 0", "0 -1 0", "0 0 1", "0 0 -1"] {
        writeln!(obj, "vn {n}").unwrap();
    }
    // Faces counter-clockwise seen from outside; negative indices count back from the last
    // element written, so the box can be appended anywhere in the file.
    let v = |c: i32| c - 8;
    let faces: [(&str, [i32; 4], i32); 6] = [
        (material_top, [2, 6, 7, 3], -4),
        (material_sides, [0, 1, 5, 4], -3),
        (material_sides, [1, 3, 7, 5], -6),
        (material_sides, [0, 4, 6, 2], -5),
        (material_sides, [4, 5, 7, 6], -2),
        (material_sides, [0, 2, 3, 1], -1),
    ];
    let mut current = "";
    for (material, corners, normal) in faces {
        if material != current {
            writeln!(obj, "usemtl {material}").unwrap();
            current = material;
        }
        let corner = |k: usize| format!("{}/{}/{normal}", v(corners[k]), k as i32 - 4);
        writeln!(
            obj,
            "f {} {} {} {}",
            corner(0),
            corner(1),
            corner(2),
            corner(3)
        )
        .unwrap();
    }
}

fn main() {
    let dir = Path::new("scenes/obj-mtl");
    std::fs::create_dir_all(dir.join("textures")).expect("create scenes/obj-mtl");
    tiles()
        .save(dir.join("textures/tiles.png"))
        .expect("write the tile texture");
    let mtl = "\
# quadray example materials (written by crates/quadray-loader/examples/make_obj_mtl.rs)
newmtl tiles
Kd 1 1 1
Ks 0.3 0.3 0.3
Ns 60
illum 2
map_Kd textures\\tiles.png

newmtl stone
Kd 0.55 0.52 0.48
Ks 0.05 0.05 0.05
Ns 10
illum 2

newmtl mirror
Kd 0.1 0.1 0.1
Ks 0.85 0.85 0.85
Ns 400
illum 3
";
    std::fs::write(dir.join("pedestal.mtl"), mtl).expect("write the MTL");
    let mut obj = String::from(
        "# quadray example pedestal (written by crates/quadray-loader/examples/make_obj_mtl.rs)\n\
         # y is up, as most OBJ files have it.\nmtllib pedestal.mtl\n",
    );
    obj.push_str("o pedestal\n");
    box_quads(
        &mut obj,
        [-1.5, 0.0, -1.5],
        [1.5, 0.4, 1.5],
        "tiles",
        "stone",
    );
    obj.push_str("o slab\n");
    box_quads(
        &mut obj,
        [-1.2, 0.4, -1.45],
        [1.2, 1.6, -1.35],
        "mirror",
        "mirror",
    );
    std::fs::write(dir.join("pedestal.obj"), obj).expect("write the OBJ");
    println!("wrote {}", dir.display());
}
