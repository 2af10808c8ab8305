//! A scene as the user named it: the file, the command line's `--set` overrides (native scenes),
//! import options and a camera choice (OBJ and glTF), and `--res`; and where its render goes when
//! the user names no output.

use std::path::{Path, PathBuf};

/// A request that cannot run as given (a usage error: the command line's status 2), such as
/// `--set` on a file that has no keys to set.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// Loads the scene at `path` with the command line's `--set` overrides (native scenes only),
/// import options, camera choice and `--res`. The resolution is known while loading, so that a
/// camera made to frame a scene that has none fits the image being rendered.
pub fn load(
    path: &Path,
    set: &[quadray_loader::Override],
    options: &quadray_loader::ImportOptions,
    camera: Option<&quadray_loader::Selector>,
    res: Option<(u32, u32)>,
) -> anyhow::Result<quadray_loader::LoadedScene> {
    use quadray_loader::FileFormat;
    let format = FileFormat::of(path);
    let native = format == Some(FileFormat::Native);
    let gltf = format == Some(FileFormat::Gltf);
    // Choices that only a glTF file offers would be dropped without a word elsewhere.
    for (given, flag, what) in [
        (options.scene.is_some(), "--gltf-scene", "scene"),
        (camera.is_some(), "--camera", "camera"),
    ] {
        if given && !gltf {
            return Err(UsageError(format!(
                "{flag} chooses a glTF file's {what}; {} is not a .gltf or .glb file",
                path.display()
            ))
            .into());
        }
    }
    if !native {
        if !set.is_empty() {
            return Err(UsageError(
                "--set overrides values of .toml scenes; OBJ and glTF files have no such keys"
                    .into(),
            )
            .into());
        }
        let options = quadray_loader::ImportOptions {
            resolution: res.map(|(w, h)| [w, h]),
            ..options.clone()
        };
        return Ok(quadray_loader::load_any_with(path, &options, camera)?);
    }
    // In a native scene `--res` is the [render] resolution, as `--set` would write it.
    let mut overrides = set.to_vec();
    if let Some((w, h)) = res {
        overrides.push(quadray_loader::Override {
            key: "render.resolution".into(),
            value: format!("[{w}, {h}]"),
        });
    }
    Ok(quadray_loader::load_scene_with(path, &overrides)?)
}

/// The default output of `render SCENE`: the scene's file name with `.png`, beside the scene.
pub fn default_output(scene: &Path) -> PathBuf {
    scene.with_extension("png")
}
