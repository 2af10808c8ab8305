//! The examples of docs/gltf-quadrics.md read with quadray's own reader, and the JSON schemas in
//! docs/schema/ are well-formed: the specification cannot drift from the implementation.

use glam::DAffine3;
use quadray::Texture;
use quadray_loader::gltf::quadrics_ext::{
    MaterialExtension, NodeExtension, RootExtension, place, whitted_material,
};
use serde_json::Value;
use std::path::Path;

fn docs() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs")
}

/// The ```json blocks of the spec, each wrapped in braces (they are fragments of a glTF object).
fn json_blocks() -> Vec<Value> {
    let text = std::fs::read_to_string(docs().join("gltf-quadrics.md")).unwrap();
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match (&mut current, line.trim_start()) {
            (None, "```json") => current = Some(String::new()),
            (Some(_), "```") => {
                let body = current.take().unwrap();
                blocks.push(
                    serde_json::from_str(&format!("{{{body}}}"))
                        .unwrap_or_else(|e| panic!("{e}\n{body}")),
                );
            }
            (Some(b), _) => {
                b.push_str(line);
                b.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

#[test]
fn every_spec_example_reads_back() {
    let blocks = json_blocks();
    assert_eq!(blocks.len(), 3);
    let root: RootExtension =
        serde_json::from_value(blocks[0]["extensions"]["QUADRAY_quadrics"].clone()).unwrap();
    assert_eq!(blocks[0]["extensionsUsed"][0], "QUADRAY_quadrics");
    assert_eq!(root.shapes.len(), 4);
    for (i, shape) in root.shapes.iter().enumerate() {
        place(shape, DAffine3::IDENTITY, 0).unwrap_or_else(|e| panic!("shape {i}: {e}"));
    }
    let node: NodeExtension =
        serde_json::from_value(blocks[1]["nodes"][0]["extensions"]["QUADRAY_quadrics"].clone())
            .unwrap();
    assert!(node.shape < root.shapes.len());
    let material: MaterialExtension =
        serde_json::from_value(blocks[2]["materials"][0]["extensions"]["QUADRAY_quadrics"].clone())
            .unwrap();
    let m = whitted_material(&material.whitted, Texture::Constant(glam::Vec3::ONE)).unwrap();
    assert_eq!(m.texture, Texture::HeightRamp);
}

#[test]
fn schemas_are_json_with_the_ids_the_spec_links() {
    let text = std::fs::read_to_string(docs().join("gltf-quadrics.md")).unwrap();
    for name in [
        "glTF.QUADRAY_quadrics.schema.json",
        "shape.schema.json",
        "node.QUADRAY_quadrics.schema.json",
        "material.QUADRAY_quadrics.schema.json",
    ] {
        let schema: Value = serde_json::from_str(
            &std::fs::read_to_string(docs().join("schema").join(name)).unwrap(),
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(schema["$id"], name);
        assert!(
            text.contains(&format!("(schema/{name})")),
            "the spec does not link {name}"
        );
    }
}
