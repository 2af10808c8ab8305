//! Changing what the viewer shows: a scene file opened (the Open window, a dropped file) or
//! the explorer again, and the default output that goes with it.

use super::{OUTPUT_FOLDER, Source, Viewer};
use crate::explorer::Explorer;
use crate::open_dialog::{Choice, OpenDialog};
use crate::source::FileSource;
use eframe::egui;
use std::path::PathBuf;

/// Where the Render button writes a scene file's view unless told otherwise: the file's name
/// with .png in the viewer's outputs folder (beside the scene, the image would land among the
/// scene files, in a repository untracked).
pub(super) fn file_output(scene: &std::path::Path) -> PathBuf {
    let name = scene.file_stem().unwrap_or(scene.as_os_str());
    // Appended, not set: `a.v1.toml` and `a.v2.toml` keep apart as `a.v1.png` and `a.v2.png`.
    PathBuf::from(OUTPUT_FOLDER).join(format!("{}.png", name.to_string_lossy()))
}

impl Viewer {
    /// Shows the scene file at `path` instead of what is shown (the Open window and a dropped
    /// file call this). Until it loads the window says so; an error shows in the panel.
    pub fn open(&mut self, path: PathBuf) {
        let waker = self.waker.clone();
        if !self.output_edited {
            self.output = file_output(&path).display().to_string();
        }
        self.source = Source::File(FileSource::open(path, move || waker.wake()));
        self.forget_scene();
    }

    /// Back to the quadric explorer, at its first kind's textbook view.
    pub fn show_explorer(&mut self) {
        let explorer = Explorer::default();
        self.orbit = explorer.textbook_view();
        if !self.output_edited {
            self.output = explorer.output_name();
        }
        self.source = Source::Explorer(explorer);
        self.forget_scene();
        self.rebuild_explorer();
    }

    /// Drops what belongs to the scene shown before (its frame, its picked object, its error),
    /// and the work still under way on it, whose frames would otherwise land under the new one.
    fn forget_scene(&mut self) {
        self.generation = self.worker.cancel();
        self.shown = None;
        self.frame = None;
        self.texture = None;
        self.requested = None;
        self.picked = None;
        self.error = None;
        self.message = None;
    }

    /// The Open window, while open: opens what the user picks.
    pub(super) fn open_window(&mut self, ctx: &egui::Context) {
        let Some(dialog) = &mut self.open_dialog else {
            return;
        };
        match dialog.show(ctx) {
            Choice::Pending => {}
            Choice::Cancel => self.open_dialog = None,
            Choice::Open(path) => {
                self.open_dialog = None;
                self.open(path);
            }
        }
    }

    /// Opens the first scene file dropped on the window; other files get a message.
    pub(super) fn take_dropped_file(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        let Some(path) = dropped
            .iter()
            .map(|f| f.path().to_path_buf())
            .find(|p| !p.as_os_str().is_empty())
        else {
            return;
        };
        if crate::open_dialog::is_scene_file(&path) {
            self.open(path);
        } else {
            self.message = Some(format!(
                "error: {} is not a scene file (.toml, .obj, .gltf, .glb)",
                path.display()
            ));
        }
    }

    /// Opens the Open window at the shown file's folder (or the current one).
    pub fn show_open_dialog(&mut self) {
        let folder = self
            .file()
            .and_then(|p| p.parent())
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), std::path::Path::to_path_buf);
        self.open_dialog = Some(OpenDialog::new(folder));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_files_default_output_keeps_its_whole_name() {
        assert_eq!(
            file_output(std::path::Path::new("scenes/a.v1.toml")),
            PathBuf::from("renders/a.v1.png")
        );
        assert_eq!(
            file_output(std::path::Path::new("duck.glb")),
            PathBuf::from("renders/duck.png")
        );
    }
}
