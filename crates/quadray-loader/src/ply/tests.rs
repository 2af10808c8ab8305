//! Unit tests of PLY sphere reading: ASCII and binary files written here, every error with the
//! file and vertex it names, and damaged files that must give errors, never panics.

use super::*;

/// A PLY header for `format` with `vertices` vertices of `properties` ("float x", …).
fn header(format: &str, vertices: u64, properties: &[&str]) -> Vec<u8> {
    let mut h =
        format!("ply\nformat {format} 1.0\ncomment made by a test\nelement vertex {vertices}\n");
    for p in properties {
        h.push_str(&format!("property {p}\n"));
    }
    h.push_str("end_header\n");
    h.into_bytes()
}

fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn read_all(path: &Path, default_radius: Option<f64>) -> Result<Vec<SphereVertex>, LoadError> {
    let file = SphereFile::read(path, default_radius)?;
    let mut out = Vec::new();
    file.for_each(|i, v| {
        assert_eq!(i, out.len());
        out.push(v);
        Ok(())
    })?;
    Ok(out)
}

/// The error for `bytes` as `name`, checked to name the file.
fn error(bytes: &[u8], default_radius: Option<f64>) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "bad.ply", bytes);
    let e = read_all(&path, default_radius)
        .expect_err("an error")
        .to_string();
    assert!(e.contains("bad.ply"), "names the file: {e}");
    e
}

fn binary_le(properties: &[&str], rows: &[&[f32]]) -> Vec<u8> {
    let mut bytes = header("binary_little_endian", rows.len() as u64, properties);
    for row in rows {
        for v in *row {
            bytes.extend(v.to_le_bytes());
        }
    }
    bytes
}

#[test]
fn ascii_vertices_with_radii_and_8_bit_colours() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = header(
        "ascii",
        2,
        &[
            "float x",
            "float y",
            "double z",
            "float radius",
            "uchar red",
            "uchar green",
            "uchar blue",
            "float nx",
        ],
    );
    bytes.extend(b"1 2 3 0.5 255 0 188 9\n-1.5 0 1e3 2 0 0 0 9\n");
    let path = write(&dir, "a.ply", &bytes);
    let file = SphereFile::read(&path, Some(7.0)).unwrap();
    assert!(file.has_radius());
    assert_eq!(file.capacity(), 2);
    let v = read_all(&path, Some(7.0)).unwrap();
    assert_eq!(
        v,
        vec![
            SphereVertex {
                center: DVec3::new(1.0, 2.0, 3.0),
                radius: 0.5,
                colour: Some(Vec3::new(1.0, 0.0, quadray::colour::decode_srgb8(188))),
            },
            SphereVertex {
                center: DVec3::new(-1.5, 0.0, 1000.0),
                radius: 2.0,
                colour: Some(Vec3::ZERO),
            },
        ]
    );
}

#[test]
fn binary_vertices_in_both_byte_orders_with_a_default_radius_and_linear_colours() {
    let dir = tempfile::tempdir().unwrap();
    let props = [
        "float x",
        "float y",
        "float z",
        "float red",
        "float green",
        "float blue",
    ];
    let rows: [&[f32]; 2] = [
        &[1.0, 2.0, 3.0, 0.25, 0.5, 2.0],
        &[4.0, 5.0, 6.0, 0.0, -0.0, 1.0],
    ];
    let le = write(&dir, "le.ply", &binary_le(&props, &rows));
    let mut be_bytes = header("binary_big_endian", 2, &props);
    for row in rows {
        for v in row {
            be_bytes.extend(v.to_be_bytes());
        }
    }
    let be = write(&dir, "be.ply", &be_bytes);
    for path in [le, be] {
        let v = read_all(&path, Some(0.1)).unwrap();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].center, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(v[0].radius, 0.1);
        assert_eq!(v[0].colour, Some(Vec3::new(0.25, 0.5, 2.0)));
        assert_eq!(v[1].center, DVec3::new(4.0, 5.0, 6.0));
        // -0 and 0 are one colour.
        assert_eq!(v[1].colour.unwrap().y.to_bits(), 0);
    }
}

#[test]
fn other_elements_before_and_after_the_vertices_are_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let mut ascii = b"ply\nformat ascii 1.0\nelement face 2\nproperty list uchar int vertex_indices\nelement vertex 1\nproperty int x\nproperty short y\nproperty uint z\nproperty list uchar float extra\nelement edge 1\nproperty int a\nend_header\n".to_vec();
    ascii.extend(b"3 0 1 2\n3 2 1 0\n-4 5 6 2 0.5 0.5\n0\n");
    let v = read_all(&write(&dir, "a.ply", &ascii), Some(1.0)).unwrap();
    assert_eq!(v.len(), 1);
    assert_eq!(v[0].center, DVec3::new(-4.0, 5.0, 6.0));

    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement marker 1000000000000\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\nproperty double radius\nend_header\n".to_vec();
    binary.push(2);
    binary.extend(7i32.to_le_bytes());
    binary.extend(8i32.to_le_bytes());
    for x in [1.0f64, 2.0, 3.0, 4.0] {
        binary.extend(x.to_le_bytes());
    }
    // A property-less element declared 10^12 times takes no time to skip.
    let v = read_all(&write(&dir, "b.ply", &binary), None).unwrap();
    assert_eq!(
        v,
        vec![SphereVertex {
            center: DVec3::new(1.0, 2.0, 3.0),
            radius: 4.0,
            colour: None,
        }]
    );
}

#[test]
fn header_problems_are_errors_naming_the_file_and_property() {
    let e = error(
        b"ply\nformat ascii 1.0\nelement face 0\nend_header\n",
        Some(1.0),
    );
    assert!(e.contains("no `vertex` element"), "{e}");
    let e = error(&header("ascii", 0, &["float x", "float y"]), Some(1.0));
    assert!(
        e.contains("`vertex.z`") && e.contains("no `z` property"),
        "{e}"
    );
    let e = error(
        &header("ascii", 0, &["float x", "float y", "float z"]),
        None,
    );
    assert!(
        e.contains("no `radius` property") && e.contains("`radius`"),
        "{e}"
    );
    let e = error(
        &header("ascii", 0, &["float x", "float y", "list uchar float z"]),
        Some(1.0),
    );
    assert!(
        e.contains("`vertex.z`: must be a number, not a list"),
        "{e}"
    );
    let e = error(
        &header(
            "ascii",
            0,
            &["float x", "float y", "float z", "uchar red", "uchar blue"],
        ),
        Some(1.0),
    );
    assert!(
        e.contains("`vertex.green`") && e.contains("red, blue"),
        "{e}"
    );
    let e = error(
        &header(
            "ascii",
            0,
            &[
                "float x",
                "float y",
                "float z",
                "short red",
                "short green",
                "short blue",
            ],
        ),
        Some(1.0),
    );
    assert!(e.contains("`vertex.red`") && e.contains("not Short"), "{e}");
    // Malformed headers, with the line where known.
    let e = error(b"not a ply file\n", Some(1.0));
    assert!(e.contains("bad.ply:1:1: not a PLY header"), "{e}");
    let e = error(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x y\n",
        Some(1.0),
    );
    assert!(e.contains("bad.ply:4:1: not a PLY header"), "{e}");
    let e = error(b"ply\nformat ascii 1.0\nelement vertex 1\n", Some(1.0));
    assert!(
        e.contains("not a PLY header") && e.contains("end_header"),
        "{e}"
    );
    let e = error(
        b"ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n",
        Some(1.0),
    );
    assert!(e.contains("not a PLY header"), "{e}");
    let e = error(b"", Some(1.0));
    assert!(e.contains("not a PLY header"), "{e}");
    let e = error(b"ply\n\xff\xfe\n", Some(1.0));
    assert!(e.contains("not a PLY header"), "{e}");
}

#[test]
fn bad_vertices_are_errors_naming_the_vertex() {
    let xyz = ["float x", "float y", "float z"];
    let e = error(
        &binary_le(&xyz, &[&[0.0, 0.0, 0.0], &[1.0, f32::NAN, 0.0]]),
        Some(1.0),
    );
    assert!(
        e.contains("`vertex[1].y`: must be a finite number, got NaN"),
        "{e}"
    );
    let e = error(&binary_le(&xyz, &[&[f32::INFINITY, 0.0, 0.0]]), Some(1.0));
    assert!(
        e.contains("`vertex[0].x`: must be a finite number, got inf"),
        "{e}"
    );
    let e = error(&binary_le(&xyz, &[&[0.0, 0.0, -2e30]]), Some(1.0));
    assert!(
        e.contains("`vertex[0].z`: -2.0000000300949324e30 is beyond the limit of ±1e30"),
        "{e}"
    );
    let with_radius = ["float x", "float y", "float z", "float radius"];
    for (r, says) in [
        (0.0, "must be positive, got 0"),
        (-1.0, "must be positive, got -1"),
        (f32::NAN, "must be a finite number, got NaN"),
        (3e30, "2.999999894026671e30 is beyond the limit"),
    ] {
        let e = error(
            &binary_le(
                &with_radius,
                &[
                    &[0.0, 0.0, 0.0, 1.0],
                    &[0.0, 0.0, 0.0, 1.0],
                    &[0.0, 0.0, 0.0, r],
                ],
            ),
            None,
        );
        assert!(e.contains(&format!("`vertex[2].radius`: {says}")), "{e}");
    }
    let colours = [
        "float x",
        "float y",
        "float z",
        "float red",
        "float green",
        "float blue",
    ];
    let e = error(
        &binary_le(&colours, &[&[0.0, 0.0, 0.0, 0.5, -0.5, 0.0]]),
        Some(1.0),
    );
    assert!(
        e.contains("`vertex[0].green`: colour components must be non-negative"),
        "{e}"
    );
    // ASCII errors give the line too: the header is 8 lines, vertex 1 on line 10.
    let mut ascii = header("ascii", 2, &xyz);
    ascii.extend(b"0 0 0\n0 0 1e40\n");
    let e = error(&ascii, Some(1.0));
    assert!(
        e.contains("bad.ply:10:1: `vertex[1].z`: must be a finite number, got inf"),
        "{e}"
    );
    let mut ascii = header("ascii", 2, &xyz);
    ascii.extend(b"0 0 0\n0 nan 1\n");
    let e = error(&ascii, Some(1.0));
    assert!(
        e.contains("bad.ply:10:1: `vertex[1]`: the line does not hold the numbers"),
        "{e}"
    );
    let mut ascii = header("ascii", 2, &xyz);
    ascii.extend(b"0 0 0\n0 1\n");
    let e = error(&ascii, Some(1.0));
    assert!(
        e.contains("`vertex[1]`: the line does not hold the numbers"),
        "{e}"
    );
}

#[test]
fn truncated_bodies_and_absurd_counts_are_errors_before_any_allocation() {
    let xyz = ["float x", "float y", "float z"];
    let mut bytes = binary_le(&xyz, &[&[0.0; 3], &[1.0; 3]]);
    bytes.truncate(bytes.len() - 1);
    let e = error(&bytes, Some(1.0));
    assert!(e.contains("`vertex`: the file is truncated: the header declares 2 vertices, which need 24 bytes after the header, and the file has 23"), "{e}");
    // A trillion vertices: refused from the header, nothing reserved.
    let mut bytes = header("binary_big_endian", 1_000_000_000_000, &xyz);
    bytes.extend([0u8; 12]);
    let e = error(&bytes, Some(1.0));
    assert!(e.contains("declares 1000000000000 vertices"), "{e}");
    let mut bytes = header("ascii", 1_000_000_000_000, &xyz);
    bytes.extend(b"1 2 3\n");
    let dir = tempfile::tempdir().unwrap();
    let file = SphereFile::read(&write(&dir, "many.ply", &bytes), Some(1.0)).unwrap();
    assert_eq!(file.capacity(), MAX_GUESS);
    let e = error(&bytes, Some(1.0));
    assert!(
        e.contains(
            "`vertex[1]`: the file ends before this element (the header declares 1000000000000"
        ),
        "{e}"
    );
    // A list before the vertices: the length is found only by reading.
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int i\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    bytes.extend([3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    bytes.extend([0u8; 11]);
    let e = error(&bytes, Some(1.0));
    assert!(
        e.contains("`vertex[0]`: the file ends inside this element"),
        "{e}"
    );
}

#[test]
fn every_truncation_of_valid_files_is_an_error_or_a_prefix_never_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let props = [
        "double x",
        "float y",
        "int z",
        "uchar red",
        "uchar green",
        "uchar blue",
        "list uchar int extra",
    ];
    let mut binary = header("binary_little_endian", 3, &props);
    for i in 0..3 {
        binary.extend((i as f64).to_le_bytes());
        binary.extend(1.5f32.to_le_bytes());
        binary.extend((-7i32).to_le_bytes());
        binary.extend([10, 20, 30, 2]);
        binary.extend([1u8, 0, 0, 0, 2, 0, 0, 0]);
    }
    let mut ascii = header("ascii", 3, &props);
    ascii.extend(b"0 1.5 -7 10 20 30 2 1 2\n1 1.5 -7 10 20 30 0\n2 1.5 -7 10 20 30 1 5\n");
    for full in [binary, ascii] {
        assert_eq!(
            read_all(&write(&dir, "full.ply", &full), Some(1.0))
                .unwrap()
                .len(),
            3
        );
        for len in 0..full.len() {
            let path = write(&dir, "cut.ply", &full[..len]);
            if let Err(e) = read_all(&path, Some(1.0)) {
                assert!(e.to_string().contains("cut.ply"), "{e}");
            }
        }
        // Every byte flipped in turn: errors or spheres, never a panic.
        for at in 0..full.len() {
            let mut damaged = full.clone();
            damaged[at] ^= 0xa5;
            let _ = read_all(&write(&dir, "flip.ply", &damaged), Some(1.0));
        }
    }
}

#[test]
fn missing_files_and_folders_are_io_errors() {
    let dir = tempfile::tempdir().unwrap();
    let e = read_all(&dir.path().join("none.ply"), Some(1.0)).unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Io(_)), "{e}");
    let e = read_all(dir.path(), Some(1.0)).unwrap_err();
    assert!(e.to_string().contains("not a regular file"), "{e}");
}

/// What the PLY parser lets pass is refused with its line: a version other than 1.0, and an
/// element or property declared twice (the parser keeps one, the rows hold both, so the values
/// after it would be read from the wrong place).
#[test]
fn other_versions_and_twice_declared_names_are_errors_with_their_line() {
    let e = error(
        b"ply\nformat ascii 2.0\nelement vertex 0\nproperty float x\nend_header\n",
        Some(1.0),
    );
    assert!(
        e.contains("bad.ply:2:1") && e.contains("PLY version 2.0: only 1.0 exists"),
        "{e}"
    );
    let props = ["float x", "float y", "float x", "float z"];
    let e = error(&header("binary_little_endian", 1, &props), Some(1.0));
    assert!(
        e.contains("bad.ply:7:1") && e.contains("property `vertex.x` is declared twice"),
        "{e}"
    );
    let e = error(
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
          property float z\nelement vertex 0\nend_header\n",
        Some(1.0),
    );
    assert!(
        e.contains("bad.ply:7:1") && e.contains("element `vertex` is declared twice"),
        "{e}"
    );
}
