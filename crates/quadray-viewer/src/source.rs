//! Where the viewer's scene comes from: a scene file (TOML, OBJ, glTF, GLB) loaded off the UI
//! thread exactly as `quadray render` loads it, and watched so an edit on disk reloads it.

use anyhow::{Context, Result};
use quadray::{RenderSettings, Scene};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::{Duration, SystemTime};

/// How often the watcher looks at the file's modification time.
const WATCH_INTERVAL: Duration = Duration::from_millis(300);

/// A loaded, built scene and what its file says about rendering it.
pub struct LoadedFile {
    /// The scene, built.
    pub scene: Arc<Scene>,
    /// The file's render settings (resolution, samples, depth, adaptive sampling).
    pub settings: RenderSettings,
    /// The image `quadray render` would write for this scene.
    pub output: PathBuf,
    /// Material names by index, for the object under the cursor.
    pub material_names: Vec<String>,
    /// What the loader assumed or skipped.
    pub notes: Vec<String>,
}

/// Loads and builds the scene at `path` as `quadray render` does; the error reads like the CLI's.
pub fn load(path: &Path) -> Result<LoadedFile> {
    let loaded = quadray_app::scene_file::load(
        path,
        &[],
        &quadray_loader::ImportOptions::default(),
        None,
        None,
    )?;
    let output = loaded
        .output
        .clone()
        .unwrap_or_else(|| quadray_app::scene_file::default_output(path));
    let settings = loaded.settings.render_settings();
    let scene = Scene::build(loaded.description, loaded.settings.build_options())
        .with_context(|| format!("invalid scene {}", path.display()))?;
    Ok(LoadedFile {
        scene: Arc::new(scene),
        settings,
        output,
        material_names: loaded.material_names,
        notes: loaded.notes,
    })
}

/// A scene file being shown: loads in the background and reports edits on disk.
pub struct FileSource {
    path: PathBuf,
    loading: Option<Receiver<Result<LoadedFile>>>,
    changes: Receiver<()>,
}

impl FileSource {
    /// Starts loading `path` and watching it; `notify` wakes the UI when a load finishes or the
    /// file changes.
    pub fn open(path: PathBuf, notify: impl Fn() + Clone + Send + 'static) -> FileSource {
        let (changed, changes) = channel();
        {
            let (path, notify) = (path.clone(), notify.clone());
            std::thread::spawn(move || {
                let mut seen = modified(&path);
                loop {
                    std::thread::sleep(WATCH_INTERVAL);
                    let now = modified(&path);
                    if now != seen {
                        seen = now;
                        // The source is gone when nobody listens: stop watching.
                        if changed.send(()).is_err() {
                            return;
                        }
                        notify();
                    }
                }
            });
        }
        let mut source = FileSource {
            path,
            loading: None,
            changes,
        };
        source.reload(notify);
        source
    }

    /// The file shown.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Starts loading the file again (a load in progress is abandoned).
    pub fn reload(&mut self, notify: impl Fn() + Send + 'static) {
        let (send, receive) = channel();
        let path = self.path.clone();
        let failed = send.clone();
        let spawned = std::thread::Builder::new()
            .name("scene loader".into())
            .spawn(move || {
                let _ = send.send(load(&path));
                notify();
            });
        if let Err(e) = spawned {
            let _ = failed.send(Err(e).context("could not start a thread to load the scene"));
        }
        self.loading = Some(receive);
    }

    /// Whether the file changed on disk since the last call.
    pub fn changed(&mut self) -> bool {
        self.changes.try_iter().count() > 0
    }

    /// Whether a load is under way.
    pub fn loading(&self) -> bool {
        self.loading.is_some()
    }

    /// The finished load, once (`None` while loading or when nothing was started).
    pub fn finished(&mut self) -> Option<Result<LoadedFile>> {
        let result = match self.loading.as_ref()?.try_recv() {
            Ok(result) => result,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => Err(anyhow::anyhow!(
                "loading {} stopped without a result",
                self.path.display()
            )),
        };
        self.loading = None;
        Some(result)
    }
}

/// The file's modification time and length (`None` when it cannot be read), which change on
/// every save.
fn modified(path: &Path) -> Option<(SystemTime, u64)> {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.modified().ok()?, meta.len()))
}
