//! The window's menu bar (File, View, Help): entries that show their keyboard shortcut, the
//! recent files, and the status line at its right. Returns the [`Command`]s picked.

use super::Viewer;
use crate::app::state::Command;

impl Viewer {
    /// Draws the menu bar; the commands of the entries clicked this frame.
    pub(super) fn menu_ui(&mut self, ui: &mut egui::Ui) -> Vec<Command> {
        let mut out = Vec::new();
        let is_mac = ui.ctx().os() == egui::os::OperatingSystem::Mac;
        // A menu entry showing the keys of `action` from the shortcut table.
        let entry = |text: &str, action| {
            egui::Button::new(text).shortcut_text(crate::app::keys::keys_for(action, is_mac))
        };
        use crate::app::keys::Action;
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.add(entry("Open…", Action::Open)).clicked() {
                    out.push(Command::OpenDialog);
                }
                ui.menu_button("Recent", |ui| {
                    for e in &self.recent.entries {
                        let label = match &e.traj {
                            Some(t) => format!("{} + {}", e.top.display(), t.display()),
                            None => e.top.display().to_string(),
                        };
                        if ui.button(label).clicked() {
                            out.push(Command::Open(e.top.clone(), e.traj.clone()));
                        }
                    }
                });
                ui.separator();
                if ui.button("Open view…").clicked() {
                    out.push(Command::OpenView(None));
                }
                if ui.add(entry("Save view…", Action::SaveView)).clicked() {
                    out.push(Command::SaveView(None));
                }
                ui.separator();
                if ui.add(entry("Screenshot…", Action::Screenshot)).clicked() {
                    out.push(Command::Screenshot {
                        scale: 1,
                        size: None,
                        path: None,
                    });
                }
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("View", |ui| {
                if ui.add(entry("Console", Action::ToggleConsole)).clicked() {
                    out.push(Command::ToggleConsole);
                }
                if ui.button("Reset layout").clicked() {
                    out.push(Command::ResetLayout);
                }
            });
            ui.menu_button("Help", |ui| {
                if ui
                    .add(entry(crate::app::keys::OVERLAY_TITLE, Action::ToggleHelp))
                    .clicked()
                {
                    out.push(Command::ShowShortcuts(true));
                }
            });
            ui.label(&self.core.status);
        });
        out
    }
}
