//! The Simulation section of the viewer's controls, shown while the frames come from a running
//! simulation over IMD (`--imd`): pause or resume it, or detach (the simulation goes on, the
//! frames received stay). The buttons send the same [`Command::Live`] as the console's
//! `imd pause`, `imd resume` and `imd detach`.

use super::command::Command;
use super::state::AppCore;
use crate::io::LiveAction;

/// Draws the Simulation section (and a separator after it) when `core`'s source is a running
/// simulation that can still be reached; returns the commands its buttons asked for.
pub fn simulation_ui(ui: &mut egui::Ui, core: &AppCore) -> Vec<Command> {
    let mut cmds = Vec::new();
    let reachable = core.source.as_ref().is_some_and(|s| s.live_controllable());
    if !reachable {
        return cmds;
    }
    egui::CollapsingHeader::new("Simulation")
        .default_open(true)
        .show(ui, |ui| {
            let state = if core.live_paused {
                "paused"
            } else {
                "running"
            };
            ui.label(format!("{} frames received, {state}", core.timeline.len));
            ui.horizontal(|ui| {
                let toggle = if core.live_paused {
                    "Resume simulation"
                } else {
                    "Pause simulation"
                };
                if ui
                    .button(toggle)
                    .on_hover_text("Pauses or resumes the engine (IMD)")
                    .clicked()
                {
                    cmds.push(Command::Live(LiveAction::TogglePause));
                }
                if ui
                    .button("Detach")
                    .on_hover_text(
                        "Stop receiving frames; the simulation goes on and the frames \
                         received stay",
                    )
                    .clicked()
                {
                    cmds.push(Command::Live(LiveAction::Detach));
                }
            });
        });
    ui.separator();
    cmds
}
