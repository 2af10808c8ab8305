//! Every TOML example in docs/scene-format.md loads: the documentation cannot drift from the loader.

use std::path::Path;

fn toml_blocks(markdown: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in markdown.lines() {
        match (&mut current, line.trim_start()) {
            (None, "```toml") => current = Some(String::new()),
            (Some(_), "```") => blocks.push(current.take().unwrap()),
            (Some(block), _) => {
                block.push_str(line);
                block.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

#[test]
fn every_documented_example_loads() {
    let doc_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap();
    let blocks = toml_blocks(&doc);
    assert!(blocks.len() >= 10, "found {} examples", blocks.len());
    let materials: String = blocks
        .iter()
        .filter(|b| b.starts_with("[[material]]"))
        .cloned()
        .collect();
    let default_camera = "[camera]\nfrom = [0, -5, 2]\nto = [0, 0, 0]\n";
    // Examples that read files (`[[mesh]] path`, `[[include]]`) name files in scenes/.
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/doc.toml");
    let mut checked = 0;
    for block in &blocks {
        if block.starts_with("transform") {
            // A fragment: try it on a quadric.
            let scene = format!(
                "version = 1\n{default_camera}{materials}[[quadric]]\nkind = \"cone\"\nclip = 1\nmaterial = \"ramp\"\n{block}"
            );
            quadray_loader::parse_scene(&scene, &scene_path)
                .unwrap_or_else(|e| panic!("{e}\n{block}"));
        } else {
            let body = block.replace("version = 1\n", "");
            let mut scene = String::from("version = 1\n");
            if !body.contains("[camera]") {
                scene.push_str(default_camera);
            }
            if !body.contains("[[material]]") {
                scene.push_str(&materials);
            }
            scene.push_str(&body);
            let loaded = quadray_loader::parse_scene(&scene, &scene_path)
                .unwrap_or_else(|e| panic!("{e}\n{scene}"));
            quadray::Scene::new(loaded.description).unwrap_or_else(|e| panic!("{e}\n{scene}"));
        }
        checked += 1;
    }
    assert_eq!(checked, blocks.len());
}
