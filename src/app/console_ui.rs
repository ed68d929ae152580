//! The console under the viewport: a one-line text field and a few lines of output, shown and
//! hidden with the backtick key or View → Console. Enter runs the line ([`super::console`]),
//! Up/Down walk the history, Tab completes command words and representation names. Like every
//! `*_ui` function it returns [`Command`]s; its own state (text, history, output) lives in
//! [`ConsoleState`].

use std::collections::VecDeque;

use super::console::{complete, parse};
use super::state::{AppCore, Command};

/// Lines of output kept.
const OUTPUT_LINES: usize = 200;

/// Id of the console's text field (tests give it the focus by this id).
pub const INPUT_ID: &str = "console-input";

/// The console's own state.
#[derive(Debug, Default)]
pub struct ConsoleState {
    /// True while the console is shown.
    pub open: bool,
    /// The line being typed.
    pub input: String,
    /// Lines run, oldest first.
    pub history: Vec<String>,
    /// Position in `history` while walking it with Up/Down.
    history_pos: Option<usize>,
    /// Output lines, oldest first.
    pub output: VecDeque<String>,
    /// True when the text field should take the focus at the next frame.
    focus: bool,
}

impl ConsoleState {
    /// Shows or hides the console (the text field takes the focus when shown).
    pub fn toggle(&mut self) {
        self.open = !self.open;
        self.focus = self.open;
    }

    /// Adds a line to the output.
    pub fn print(&mut self, line: impl Into<String>) {
        self.output.push_back(line.into());
        while self.output.len() > OUTPUT_LINES {
            self.output.pop_front();
        }
    }

    /// Runs one line against `core`: the commands it gives; errors and results go to the
    /// output.
    pub fn submit(&mut self, line: &str, core: &AppCore) -> Vec<Command> {
        let line = line.trim();
        if line.is_empty() {
            return Vec::new();
        }
        if self.history.last().map(String::as_str) != Some(line) {
            self.history.push(line.to_string());
        }
        self.history_pos = None;
        self.print(format!("> {line}"));
        if line == "clear" {
            self.output.clear();
            return Vec::new();
        }
        match parse(line).and_then(|c| c.map(|c| c.resolve(core)).transpose()) {
            Ok(Some(outcome)) => {
                if let Some(text) = outcome.output {
                    self.print(text);
                }
                outcome.commands
            }
            Ok(None) => Vec::new(),
            Err(e) => {
                self.print(format!("error: {e}"));
                Vec::new()
            }
        }
    }

    fn walk_history(&mut self, back: bool) {
        if self.history.is_empty() {
            return;
        }
        let last = self.history.len() - 1;
        self.history_pos = match (self.history_pos, back) {
            (None, true) => Some(last),
            (None, false) => None,
            (Some(p), true) => Some(p.saturating_sub(1)),
            (Some(p), false) if p < last => Some(p + 1),
            (Some(_), false) => None,
        };
        self.input = self
            .history_pos
            .map_or_else(String::new, |p| self.history[p].clone());
    }
}

/// The console as a panel under the viewport, when open.
pub fn console_panel(ui: &mut egui::Ui, state: &mut ConsoleState, core: &AppCore) -> Vec<Command> {
    if !state.open {
        return Vec::new();
    }
    let mut out = Vec::new();
    egui::Panel::bottom("console").show(ui, |ui| out = console_ui(ui, state, core));
    out
}

/// The console panel's contents (output above, the text field below).
pub fn console_ui(ui: &mut egui::Ui, state: &mut ConsoleState, core: &AppCore) -> Vec<Command> {
    let id = egui::Id::NULL.with(INPUT_ID);
    let focused = ui.memory(|m| m.has_focus(id));
    let (mut up, mut down, mut tab) = (false, false, false);
    if focused {
        ui.input_mut(|i| {
            up = i.consume_key(egui::Modifiers::NONE, egui::Key::ArrowUp);
            down = i.consume_key(egui::Modifiers::NONE, egui::Key::ArrowDown);
            tab = i.consume_key(egui::Modifiers::NONE, egui::Key::Tab);
        });
    }
    if up || down {
        state.walk_history(up);
    }
    if tab {
        let names: Vec<String> = core.reps.iter().map(|r| r.name.clone()).collect();
        if let Some(done) = complete(&state.input, &names) {
            state.input = done;
        }
    }
    egui::ScrollArea::vertical()
        .max_height(ui.text_style_height(&egui::TextStyle::Monospace) * 5.0)
        .stick_to_bottom(true)
        .auto_shrink([false, true])
        .show(ui, |ui| {
            for line in &state.output {
                let text = egui::RichText::new(line).monospace();
                if line.starts_with("error:") {
                    ui.colored_label(ui.visuals().error_fg_color, text);
                } else {
                    ui.label(text);
                }
            }
        });
    let mut out = Vec::new();
    let edit = egui::TextEdit::singleline(&mut state.input)
        .id(id)
        .font(egui::TextStyle::Monospace)
        .hint_text("command (help, Tab completes, Up/Down history)")
        .desired_width(f32::INFINITY);
    let response = ui.add(edit);
    if tab || up || down {
        // Keep the cursor at the end of the completed or recalled line.
        if let Some(mut s) = egui::TextEdit::load_state(ui.ctx(), id) {
            let end = egui::text::CCursor::new(state.input.chars().count());
            s.cursor
                .set_char_range(Some(egui::text::CCursorRange::one(end)));
            s.store(ui.ctx(), id);
        }
        response.request_focus();
    }
    if response.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
        let line = std::mem::take(&mut state.input);
        out = state.submit(&line, core);
        response.request_focus();
    }
    if state.focus {
        state.focus = false;
        response.request_focus();
    }
    out
}
