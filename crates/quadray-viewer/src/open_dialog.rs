//! The Open window: a folder's scene files and subfolders to click through, or a path to type.
//!
//! Drawn with egui itself: a native dialog (rfd) needs GTK or a desktop portal at run time, which
//! a bare X server (the CI's Xvfb, a remote session) does not have. Files can also be dropped on
//! the window (the viewer handles that).

use eframe::egui;
use std::path::{Path, PathBuf};

/// The extensions the viewer opens, as `quadray render` reads them.
pub const SCENE_EXTENSIONS: [&str; 4] = ["toml", "obj", "gltf", "glb"];

/// Most entries listed from one folder (a huge folder stays quick to draw).
const MAX_ENTRIES: usize = 2000;

/// Whether `path` names a file the viewer opens, by its extension.
pub fn is_scene_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| SCENE_EXTENSIONS.iter().any(|s| e.eq_ignore_ascii_case(s)))
}

/// One entry of the listed folder.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Entry {
    /// Folders first, then files, each by name.
    is_file: bool,
    name: String,
}

/// The Open window's state.
#[derive(Clone, Debug)]
pub struct OpenDialog {
    /// The folder listed.
    folder: PathBuf,
    /// Its subfolders and scene files, or why it cannot be listed.
    entries: Result<Vec<Entry>, String>,
    /// The path typed or picked.
    path: String,
}

/// What the user did with the window this frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Choice {
    /// Nothing yet.
    Pending,
    /// Open this file.
    Open(PathBuf),
    /// Close the window without opening anything.
    Cancel,
}

impl OpenDialog {
    /// The window listing `folder`.
    pub fn new(folder: PathBuf) -> OpenDialog {
        let mut dialog = OpenDialog {
            folder: PathBuf::new(),
            entries: Ok(Vec::new()),
            path: String::new(),
        };
        dialog.list(folder);
        dialog
    }

    /// Lists `folder` (made absolute, so that `..` always leads somewhere): its subfolders and
    /// the scene files in it.
    fn list(&mut self, folder: PathBuf) {
        let folder = std::path::absolute(&folder).unwrap_or(folder);
        self.entries = std::fs::read_dir(&folder)
            .map_err(|e| format!("cannot list {}: {e}", folder.display()))
            .map(|dir| {
                let mut entries: Vec<Entry> = dir
                    .filter_map(Result::ok)
                    .filter_map(|e| {
                        let path = e.path();
                        let name = e.file_name().to_string_lossy().into_owned();
                        let hidden = name.starts_with('.');
                        match (path.is_dir(), is_scene_file(&path)) {
                            _ if hidden => None,
                            (true, _) => Some(Entry {
                                is_file: false,
                                name,
                            }),
                            (false, true) => Some(Entry {
                                is_file: true,
                                name,
                            }),
                            (false, false) => None,
                        }
                    })
                    .collect();
                entries.sort();
                entries.truncate(MAX_ENTRIES);
                entries
            });
        self.folder = folder;
    }

    /// Draws the window; returns what the user chose.
    pub fn show(&mut self, ctx: &egui::Context) -> Choice {
        let mut choice = Choice::Pending;
        let mut open = true;
        egui::Window::new("Open")
            .open(&mut open)
            .default_width(420.0)
            .show(ctx, |ui| {
                ui.label(format!(
                    "{} ({})",
                    self.folder.display(),
                    SCENE_EXTENSIONS.map(|e| format!(".{e}")).join(" ")
                ));
                let mut go_to = None;
                egui::ScrollArea::vertical()
                    .max_height(300.0)
                    .show(ui, |ui| {
                        if self.folder.parent().is_some() && ui.button("..").clicked() {
                            go_to = self.folder.parent().map(Path::to_path_buf);
                        }
                        match &self.entries {
                            Err(e) => {
                                ui.colored_label(ui.visuals().error_fg_color, e);
                            }
                            Ok(entries) => {
                                for entry in entries {
                                    let path = self.folder.join(&entry.name);
                                    if !entry.is_file {
                                        if ui.button(format!("{}/", entry.name)).clicked() {
                                            go_to = Some(path);
                                        }
                                    } else {
                                        let picked = self.path == path.display().to_string();
                                        let response = ui.selectable_label(picked, &entry.name);
                                        if response.clicked() {
                                            self.path = path.display().to_string();
                                        }
                                        if response.double_clicked() {
                                            choice = Choice::Open(path);
                                        }
                                    }
                                }
                            }
                        }
                    });
                if let Some(folder) = go_to {
                    self.list(folder);
                }
                ui.horizontal(|ui| {
                    let label = ui.label("file");
                    let field = ui
                        .text_edit_singleline(&mut self.path)
                        .labelled_by(label.id);
                    let entered =
                        field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                    if (ui.button("Open file").clicked() || entered) && !self.path.is_empty() {
                        // A bare name is in the folder listed.
                        choice = Choice::Open(self.folder.join(&self.path));
                    }
                });
            });
        if !open {
            choice = Choice::Cancel;
        }
        choice
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_lists_subfolders_then_scene_files() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["b.toml", "a.GLB", "notes.txt", ".hidden.toml"] {
            std::fs::write(dir.path().join(name), "").unwrap();
        }
        std::fs::create_dir(dir.path().join("scenes")).unwrap();
        let dialog = OpenDialog::new(dir.path().to_path_buf());
        let names: Vec<_> = dialog
            .entries
            .unwrap()
            .into_iter()
            .map(|e| e.name)
            .collect();
        assert_eq!(names, ["scenes", "a.GLB", "b.toml"]);
        let missing = OpenDialog::new(dir.path().join("nothing"));
        assert!(missing.entries.unwrap_err().contains("cannot list"));
    }
}
