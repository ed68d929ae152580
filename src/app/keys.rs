//! Keyboard shortcuts, beside the panels in the viewer's data flow: one table ([`SHORTCUTS`]:
//! key, modifiers, description, action), [`keys_ui`] turning this frame's key presses into
//! [`Command`]s for the viewer's one command path, and [`shortcuts_overlay_ui`], the help window
//! that lists the same table (so the list and the handling cannot disagree). While a widget has
//! the keyboard focus (a text field being typed into), no shortcut fires: the keys stay there.

use egui::{Key, Modifiers};

use super::state::{AppCore, Command};
use super::timeline::TimelineCmd;
use crate::render::Projection;

/// Title of the help window (also the Help menu's entry).
pub const OVERLAY_TITLE: &str = "Keyboard shortcuts";

/// What a shortcut does; [`Action::commands`] turns it into commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Play or pause.
    PlayPause,
    /// Move this many steps (of the timeline's stride; negative: back).
    Step(i64),
    /// First frame.
    First,
    /// Last frame.
    Last,
    /// Camera back to the default direction, fitted.
    ResetView,
    /// Fit the scene, keeping the direction.
    FitView,
    /// Perspective ↔ orthographic.
    ToggleOrthographic,
    /// Screenshot of the view at the window's size (the File menu's Screenshot…).
    Screenshot,
    /// The open-files dialog.
    Open,
    /// Save the view as a state file (the File menu's Save view…).
    SaveView,
    /// Show or hide representation `i` (0-based).
    ToggleRep(usize),
    /// Show or hide the shortcut list.
    ToggleHelp,
    /// Close the shortcut list.
    CloseHelp,
    /// Show or hide the console under the viewport.
    ToggleConsole,
}

/// One keyboard shortcut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shortcut {
    /// The logical key.
    pub key: Key,
    /// Modifiers held with it ([`Modifiers::COMMAND`]: Ctrl, or Cmd on a Mac).
    pub modifiers: Modifiers,
    /// What it does, as the help window lists it.
    pub description: &'static str,
    /// What it does, as commands.
    pub action: Action,
}

const fn key(key: Key, description: &'static str, action: Action) -> Shortcut {
    Shortcut {
        key,
        modifiers: Modifiers::NONE,
        description,
        action,
    }
}

const fn with(modifiers: Modifiers, k: Key, description: &'static str, action: Action) -> Shortcut {
    Shortcut {
        modifiers,
        ..key(k, description, action)
    }
}

/// Every shortcut of the viewer, in the order the help window lists them.
pub const SHORTCUTS: &[Shortcut] = &[
    key(Key::Space, "Play or pause", Action::PlayPause),
    key(Key::ArrowLeft, "Step back one frame", Action::Step(-1)),
    key(Key::ArrowRight, "Step forward one frame", Action::Step(1)),
    with(
        Modifiers::SHIFT,
        Key::ArrowLeft,
        "Step back ten frames",
        Action::Step(-10),
    ),
    with(
        Modifiers::SHIFT,
        Key::ArrowRight,
        "Step forward ten frames",
        Action::Step(10),
    ),
    key(Key::Home, "First frame", Action::First),
    key(Key::End, "Last frame", Action::Last),
    key(Key::R, "Reset the view", Action::ResetView),
    key(Key::F, "Fit the view to the scene", Action::FitView),
    key(
        Key::O,
        "Orthographic or perspective projection",
        Action::ToggleOrthographic,
    ),
    key(Key::S, "Save a screenshot", Action::Screenshot),
    with(Modifiers::COMMAND, Key::O, "Open files", Action::Open),
    with(
        Modifiers::COMMAND,
        Key::S,
        "Save the view (state file)",
        Action::SaveView,
    ),
    key(
        Key::Num1,
        "Show or hide representation 1",
        Action::ToggleRep(0),
    ),
    key(
        Key::Num2,
        "Show or hide representation 2",
        Action::ToggleRep(1),
    ),
    key(
        Key::Num3,
        "Show or hide representation 3",
        Action::ToggleRep(2),
    ),
    key(
        Key::Num4,
        "Show or hide representation 4",
        Action::ToggleRep(3),
    ),
    key(
        Key::Num5,
        "Show or hide representation 5",
        Action::ToggleRep(4),
    ),
    key(
        Key::Num6,
        "Show or hide representation 6",
        Action::ToggleRep(5),
    ),
    key(
        Key::Num7,
        "Show or hide representation 7",
        Action::ToggleRep(6),
    ),
    key(
        Key::Num8,
        "Show or hide representation 8",
        Action::ToggleRep(7),
    ),
    key(
        Key::Num9,
        "Show or hide representation 9",
        Action::ToggleRep(8),
    ),
    key(
        Key::Backtick,
        "Show or hide the console",
        Action::ToggleConsole,
    ),
    key(
        Key::Questionmark,
        "Show or hide this list of shortcuts",
        Action::ToggleHelp,
    ),
    key(
        Key::F1,
        "Show or hide this list of shortcuts",
        Action::ToggleHelp,
    ),
    key(Key::Escape, "Close this list", Action::CloseHelp),
];

impl Shortcut {
    /// The keys as the help window shows them: `Shift+Right`, `Ctrl+O` (`Cmd+O` on a Mac).
    pub fn label(&self, is_mac: bool) -> String {
        let mut s = String::new();
        let m = self.modifiers;
        if m.ctrl || (m.command && !is_mac) {
            s.push_str("Ctrl+");
        }
        if m.mac_cmd || (m.command && is_mac) {
            s.push_str("Cmd+");
        }
        if m.alt {
            s.push_str("Alt+");
        }
        if m.shift {
            s.push_str("Shift+");
        }
        s.push_str(match self.key {
            Key::Questionmark => "?",
            k => k.name(),
        });
        s
    }

    /// True when a key press with `pressed` modifiers triggers this shortcut: Ctrl/Cmd and Alt
    /// must match; Shift too, unless `ignore_shift` (for keys like `?` that need Shift on some
    /// keyboards and not on others).
    fn matches(&self, key: Key, pressed: Modifiers, ignore_shift: bool) -> bool {
        self.key == key
            && if ignore_shift {
                Modifiers {
                    shift: self.modifiers.shift,
                    ..pressed
                }
                .matches_exact(self.modifiers)
            } else {
                pressed.matches_exact(self.modifiers)
            }
    }
}

/// The shortcut a key press triggers: the entry with exactly these modifiers, else one that
/// matches ignoring Shift.
pub fn lookup(key: Key, modifiers: Modifiers) -> Option<&'static Shortcut> {
    SHORTCUTS
        .iter()
        .find(|s| s.matches(key, modifiers, false))
        .or_else(|| SHORTCUTS.iter().find(|s| s.matches(key, modifiers, true)))
}

/// The keys of every shortcut doing `action`, as menus show them (`? / F1`).
pub fn keys_for(action: Action, is_mac: bool) -> String {
    let labels: Vec<String> = SHORTCUTS
        .iter()
        .filter(|s| s.action == action)
        .map(|s| s.label(is_mac))
        .collect();
    labels.join(" / ")
}

/// The toggled state the actions read, kept up to date as a frame's presses are turned into
/// commands (so two presses in one frame toggle twice).
struct Toggles {
    playing: bool,
    projection: Projection,
    help: bool,
}

impl Action {
    /// The commands this action gives with the app in `core` and the help window `help_shown`.
    pub fn commands(self, core: &AppCore, help_shown: bool) -> Vec<Command> {
        let mut toggles = Toggles {
            playing: core.timeline.playing,
            projection: core.camera.projection,
            help: help_shown,
        };
        let mut reps = core.reps.clone();
        self.commands_with(&mut toggles, &mut reps)
    }

    fn commands_with(
        self,
        t: &mut Toggles,
        reps: &mut [crate::scene::representation::Representation],
    ) -> Vec<Command> {
        let timeline = |c| vec![Command::Timeline(c)];
        match self {
            Action::PlayPause => {
                t.playing = !t.playing;
                timeline(TimelineCmd::SetPlaying(t.playing))
            }
            Action::Step(n) => timeline(TimelineCmd::Step(n)),
            Action::First => timeline(TimelineCmd::First),
            Action::Last => timeline(TimelineCmd::Last),
            Action::ResetView => vec![Command::ResetCamera],
            Action::FitView => vec![Command::FitCamera],
            Action::ToggleOrthographic => {
                t.projection = match t.projection {
                    Projection::Perspective => Projection::Orthographic,
                    Projection::Orthographic => Projection::Perspective,
                };
                vec![Command::SetProjection(t.projection)]
            }
            Action::Screenshot => vec![Command::Screenshot {
                scale: 1,
                size: None,
                path: None,
            }],
            Action::Open => vec![Command::OpenDialog],
            Action::SaveView => vec![Command::SaveView(None)],
            Action::ToggleRep(i) => match reps.get_mut(i) {
                Some(rep) => {
                    rep.visible = !rep.visible;
                    vec![Command::UpdateRep(i, Box::new(rep.clone()))]
                }
                None => Vec::new(),
            },
            Action::ToggleHelp => {
                t.help = !t.help;
                vec![Command::ShowShortcuts(t.help)]
            }
            Action::CloseHelp if t.help => {
                t.help = false;
                vec![Command::ShowShortcuts(false)]
            }
            Action::CloseHelp => Vec::new(),
            Action::ToggleConsole => vec![Command::ToggleConsole],
        }
    }
}

/// This frame's shortcuts as commands, in the order pressed. Reads nothing while a widget
/// has the keyboard focus (typing into a text field); key presses that give commands are
/// taken out of the input, the others stay for egui. Held keys repeat only the steps.
pub fn keys_ui(ctx: &egui::Context, core: &AppCore, help_shown: bool) -> Vec<Command> {
    if ctx.egui_wants_keyboard_input() {
        return Vec::new();
    }
    let mut toggles = Toggles {
        playing: core.timeline.playing,
        projection: core.camera.projection,
        help: help_shown,
    };
    let mut reps = core.reps.clone();
    let mut out = Vec::new();
    ctx.input_mut(|input| {
        input.events.retain(|event| {
            let egui::Event::Key {
                key,
                pressed: true,
                modifiers,
                repeat,
                ..
            } = event
            else {
                return true;
            };
            let Some(shortcut) = lookup(*key, *modifiers) else {
                return true;
            };
            if *repeat && !matches!(shortcut.action, Action::Step(_)) {
                return true;
            }
            let cmds = shortcut.action.commands_with(&mut toggles, &mut reps);
            let used = !cmds.is_empty();
            out.extend(cmds);
            !used
        });
    });
    out
}

/// The help window listing every shortcut of [`SHORTCUTS`] (when `shown`); closing it gives
/// [`Command::ShowShortcuts`]`(false)`.
pub fn shortcuts_overlay_ui(ctx: &egui::Context, shown: bool) -> Vec<Command> {
    if !shown {
        return Vec::new();
    }
    let is_mac = ctx.os() == egui::os::OperatingSystem::Mac;
    let mut open = true;
    egui::Window::new(OVERLAY_TITLE)
        .open(&mut open)
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
        .show(ctx, |ui| {
            egui::Grid::new("shortcuts")
                .num_columns(2)
                .striped(true)
                .show(ui, |ui| {
                    for s in SHORTCUTS {
                        ui.monospace(s.label(is_mac));
                        ui.label(s.description);
                        ui.end_row();
                    }
                });
            ui.separator();
            ui.label(
                "Shortcuts are off while a text field is being typed into (Escape leaves it).",
            );
        });
    if open {
        Vec::new()
    } else {
        vec![Command::ShowShortcuts(false)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shortcut_has_a_description_and_its_own_keys() {
        for (i, a) in SHORTCUTS.iter().enumerate() {
            assert!(!a.description.trim().is_empty(), "{a:?}");
            for b in &SHORTCUTS[i + 1..] {
                assert!(
                    !(a.key == b.key && a.modifiers == b.modifiers),
                    "{} and {} share {}",
                    a.description,
                    b.description,
                    a.label(false)
                );
            }
        }
        // Labels are distinct too (the help window shows them).
        let mut labels: Vec<String> = SHORTCUTS.iter().map(|s| s.label(false)).collect();
        labels.sort();
        labels.dedup();
        assert_eq!(labels.len(), SHORTCUTS.len());
    }

    #[test]
    fn lookup_tells_shift_and_ctrl_apart() {
        let find = |m, k| lookup(k, m).map(|s| s.action);
        assert_eq!(
            find(Modifiers::NONE, Key::ArrowRight),
            Some(Action::Step(1))
        );
        assert_eq!(
            find(Modifiers::SHIFT, Key::ArrowRight),
            Some(Action::Step(10))
        );
        assert_eq!(
            find(Modifiers::NONE, Key::O),
            Some(Action::ToggleOrthographic)
        );
        assert_eq!(find(Modifiers::COMMAND, Key::O), Some(Action::Open));
        // Ctrl on Linux and Windows comes as both `ctrl` and `command`.
        let ctrl = Modifiers::CTRL | Modifiers::COMMAND;
        assert_eq!(find(ctrl, Key::S), Some(Action::SaveView));
        assert_eq!(find(Modifiers::NONE, Key::S), Some(Action::Screenshot));
        // `?` is Shift+/ on many keyboards: Shift does not matter for it.
        assert_eq!(
            find(Modifiers::SHIFT, Key::Questionmark),
            Some(Action::ToggleHelp)
        );
        assert_eq!(find(Modifiers::ALT, Key::O), None);
        assert_eq!(find(Modifiers::COMMAND, Key::ArrowRight), None);
    }
}
