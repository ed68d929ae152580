//! The viewer's command language, independent of egui: one line of text becomes a
//! [`ConsoleCommand`] ([`parse`]), which [`ConsoleCommand::resolve`] turns into the app's
//! [`Command`]s against the current [`AppCore`] (plus an optional line to print). The console
//! under the viewport (`console_ui`) and `mdsurf --script FILE` both use it.
//!
//! Words are separated by spaces; a selection (or any word with spaces) is written in double
//! quotes; a word without spaces may be bare. Representations are named by their 1-based number
//! in the panel's list or by their name. Errors are one line; parse errors give the 1-based
//! column, selection errors the column in the whole line.

use std::path::PathBuf;

use super::command::OnOff;
pub use super::console_command::{ConsoleCommand, ImdVerb, RepEdit, RepRef};
use super::state::{AppCore, Command};
use super::timeline::TimelineCmd;
use crate::scene::representation::Representation;
use crate::selection::Selection;

/// A one-line console error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConsoleError {
    /// The line does not parse (1-based column).
    #[error("column {column}: {message}")]
    Parse {
        /// 1-based column of the bad word.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// The line parses but cannot be applied now.
    #[error("{0}")]
    Apply(String),
    /// The frame the line needs cannot be read.
    #[error(transparent)]
    Frame(#[from] super::source::SourceError),
    /// The representation the line makes cannot be shown.
    #[error(transparent)]
    Representation(#[from] crate::scene::state_file::RepresentationError),
}

fn perr<T>(column: usize, message: impl Into<String>) -> Result<T, ConsoleError> {
    Err(ConsoleError::Parse {
        column,
        message: message.into(),
    })
}

/// The first words of commands (Tab completion, `help`).
pub const COMMAND_WORDS: [&str; 11] = [
    "rep",
    "frame",
    "play",
    "pause",
    "fit",
    "view",
    "screenshot",
    "select",
    "imd",
    "help",
    "clear",
];

/// The words after `rep N`.
pub const REP_WORDS: [&str; 14] = [
    "color",
    "spacing",
    "radius-scale",
    "isovalue",
    "quality",
    "opacity",
    "vertices",
    "cavities",
    "style",
    "select",
    "hide",
    "show",
    "delete",
    "add",
];

const HELP: &str = "commands: rep add \"SEL\" STYLE [as NAME] | rep N|NAME color|spacing|radius-scale|isovalue|quality|opacity|vertices|cavities|style|select VALUE | rep N hide|show|delete | frame N | play | pause | fit [\"SEL\"] | view save|open FILE | screenshot FILE [WxH] | select \"SEL\" | imd pause|resume|detach | clear | help [rep]";
const HELP_REP: &str = "rep add \"SEL\" surface|beads|spheres|sticks|ball-and-stick [as NAME]; rep N (1-based) or rep NAME, then: color SCHEME (element, chain, residue-type, residue-index, b-factor, exposure, single:#rrggbb), spacing Å, radius-scale R, isovalue I, quality low|medium|high|max, opacity 0..1, vertices interpolated|refined, cavities on|off|probe Å (the voids a probe of that radius fits in, 1.4 for water), style STYLE, select \"SEL\", hide, show, delete";

/// A word of the line and its 1-based column.
#[derive(Debug, Clone, PartialEq)]
struct Word {
    text: String,
    column: usize,
    quoted: bool,
}

/// Splits a line into words: bare words end at spaces, quoted ones at the closing quote.
fn split(line: &str) -> Result<Vec<Word>, ConsoleError> {
    let mut words = Vec::new();
    let chars: Vec<char> = line.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if chars[i].is_whitespace() {
            i += 1;
            continue;
        }
        let column = i + 1;
        if chars[i] == '"' {
            let start = i + 1;
            let Some(end) = chars[start..].iter().position(|&c| c == '"') else {
                return perr(column, "unclosed quote");
            };
            words.push(Word {
                text: chars[start..start + end].iter().collect(),
                column,
                quoted: true,
            });
            i = start + end + 1;
            if i < chars.len() && !chars[i].is_whitespace() {
                return perr(i + 1, "expected a space after the closing quote");
            }
        } else {
            let start = i;
            while i < chars.len() && !chars[i].is_whitespace() {
                if chars[i] == '"' {
                    return perr(i + 1, "quote inside a word");
                }
                i += 1;
            }
            words.push(Word {
                text: chars[start..i].iter().collect(),
                column,
                quoted: false,
            });
        }
    }
    Ok(words)
}

/// Checks a selection word, placing a selection error's column in the whole line.
fn selection(w: &Word) -> Result<String, ConsoleError> {
    match Selection::parse(&w.text) {
        Ok(_) => Ok(w.text.clone()),
        Err(e) => perr(
            w.column + e.column.saturating_sub(1) + usize::from(w.quoted),
            format!("selection: {}", e.message),
        ),
    }
}

fn number<T: std::str::FromStr>(w: &Word, what: &str) -> Result<T, ConsoleError> {
    w.text.parse().or_else(|_| {
        perr(
            w.column,
            format!("{what}: expected a number, got '{}'", w.text),
        )
    })
}

fn value<T: std::str::FromStr<Err = E>, E: std::fmt::Display>(w: &Word) -> Result<T, ConsoleError> {
    w.text.parse().or_else(|e: E| perr(w.column, e.to_string()))
}

fn size(w: &Word) -> Result<[u32; 2], ConsoleError> {
    let bad = || {
        perr(
            w.column,
            format!("size: expected WIDTHxHEIGHT, got '{}'", w.text),
        )
    };
    let Some((a, b)) = w.text.split_once(['x', 'X']) else {
        return bad();
    };
    match (a.parse::<u32>(), b.parse::<u32>()) {
        (Ok(a), Ok(b)) if a > 0 && b > 0 && a <= 16384 && b <= 16384 => Ok([a, b]),
        _ => bad(),
    }
}

/// Parses one line; `Ok(None)` for an empty line or a `#` comment.
pub fn parse(line: &str) -> Result<Option<ConsoleCommand>, ConsoleError> {
    let words = split(line)?;
    let Some(first) = words.first() else {
        return Ok(None);
    };
    if !first.quoted && first.text.starts_with('#') {
        return Ok(None);
    }
    let end = line.chars().count() + 1;
    let need = |i: usize, what: &str| -> Result<&Word, ConsoleError> {
        words
            .get(i)
            .map_or_else(|| perr(end, format!("expected {what}")), Ok)
    };
    let max = |n: usize| -> Result<(), ConsoleError> {
        match words.get(n) {
            Some(w) => perr(w.column, format!("unexpected '{}'", w.text)),
            None => Ok(()),
        }
    };
    let cmd = match first.text.as_str() {
        "rep" => {
            let what = need(1, "'add' or a representation number or name")?;
            if what.text == "add" && !what.quoted {
                let sel = selection(need(2, "a selection")?)?;
                let style = value(need(3, "a style")?)?;
                let name = match words.get(4) {
                    None => None,
                    Some(w) if w.text == "as" => {
                        max(6)?;
                        Some(need(5, "a name")?.text.clone())
                    }
                    Some(w) => return perr(w.column, format!("expected 'as', got '{}'", w.text)),
                };
                ConsoleCommand::RepAdd {
                    selection: sel,
                    style,
                    name,
                }
            } else {
                let rep = match what.text.parse::<usize>() {
                    Ok(0) => return perr(what.column, "representations are numbered from 1"),
                    Ok(n) => RepRef::Number(n),
                    Err(_) => RepRef::Name(what.text.clone()),
                };
                let verb = need(2, "what to change (see 'help rep')")?;
                let arg = || need(3, "a value");
                let edit = match verb.text.as_str() {
                    "hide" => RepEdit::Hide,
                    "show" => RepEdit::Show,
                    "delete" => RepEdit::Delete,
                    "color" | "colour" => RepEdit::Color(value(arg()?)?),
                    "spacing" => RepEdit::Spacing(number(arg()?, "spacing")?),
                    "radius-scale" => RepEdit::RadiusScale(number(arg()?, "radius-scale")?),
                    "isovalue" => RepEdit::Isovalue(number(arg()?, "isovalue")?),
                    "opacity" => RepEdit::Opacity(number(arg()?, "opacity")?),
                    "quality" => RepEdit::Quality(value(arg()?)?),
                    "vertices" => RepEdit::Vertices(value(arg()?)?),
                    "cavities" => match arg()?.text.as_str() {
                        "probe" => {
                            let radius = need(4, "a probe radius in Å (1.4 for water)")?;
                            RepEdit::Cavities(true, Some(number(radius, "probe radius")?))
                        }
                        _ => RepEdit::Cavities(value::<OnOff, _>(arg()?)?.0, None),
                    },
                    "style" => RepEdit::Style(value(arg()?)?),
                    "select" => RepEdit::Select(selection(arg()?)?),
                    other => {
                        return perr(verb.column, format!("unknown rep setting '{other}'"));
                    }
                };
                let n = match edit {
                    RepEdit::Hide | RepEdit::Show | RepEdit::Delete => 3,
                    RepEdit::Cavities(_, Some(_)) => 5,
                    _ => 4,
                };
                max(n)?;
                ConsoleCommand::Rep(rep, edit)
            }
        }
        "frame" => {
            max(2)?;
            ConsoleCommand::Frame(number(need(1, "a frame number")?, "frame")?)
        }
        "play" => {
            max(1)?;
            ConsoleCommand::Play
        }
        "pause" => {
            max(1)?;
            ConsoleCommand::Pause
        }
        "fit" => {
            max(2)?;
            ConsoleCommand::Fit(words.get(1).map(selection).transpose()?)
        }
        "view" => {
            max(3)?;
            let verb = need(1, "'save' or 'open'")?;
            let path = PathBuf::from(&need(2, "a file")?.text);
            match verb.text.as_str() {
                "save" => ConsoleCommand::ViewSave(path),
                "open" => ConsoleCommand::ViewOpen(path),
                other => {
                    return perr(
                        verb.column,
                        format!("expected 'save' or 'open', got '{other}'"),
                    );
                }
            }
        }
        "screenshot" => {
            max(3)?;
            let path = PathBuf::from(&need(1, "a file")?.text);
            ConsoleCommand::Screenshot(path, words.get(2).map(size).transpose()?)
        }
        "select" => {
            max(2)?;
            ConsoleCommand::Select(selection(need(1, "a selection")?)?)
        }
        "imd" => {
            max(2)?;
            let verb = need(1, "'pause', 'resume' or 'detach'")?;
            ConsoleCommand::Imd(match verb.text.as_str() {
                "pause" => ImdVerb::Pause,
                "resume" => ImdVerb::Resume,
                "detach" => ImdVerb::Detach,
                other => {
                    return perr(
                        verb.column,
                        format!("expected 'pause', 'resume' or 'detach', got '{other}'"),
                    );
                }
            })
        }
        "help" => {
            max(2)?;
            ConsoleCommand::Help(words.get(1).map(|w| w.text.clone()))
        }
        other => {
            return perr(
                first.column,
                format!("unknown command '{other}' (try 'help')"),
            );
        }
    };
    Ok(Some(cmd))
}

/// What a resolved command does: app commands, and a line for the console.
#[derive(Debug, Default)]
pub struct Outcome {
    /// Commands for [`AppCore::apply`] / the window.
    pub commands: Vec<Command>,
    /// A line to print (counts, help, confirmations).
    pub output: Option<String>,
}

fn find_rep(core: &AppCore, rep: &RepRef) -> Result<usize, ConsoleError> {
    let found = match rep {
        RepRef::Number(n) => (*n >= 1 && *n <= core.reps.len()).then(|| n - 1),
        RepRef::Name(name) => core.reps.iter().position(|r| r.name == *name),
    };
    found.ok_or_else(|| {
        ConsoleError::Apply(match rep {
            RepRef::Number(n) => format!("no representation {n} (there are {})", core.reps.len()),
            RepRef::Name(name) => format!("no representation named '{name}'"),
        })
    })
}

/// Indices of the atoms `expr` selects in the current frame.
fn select_now(core: &AppCore, expr: &str) -> Result<(Vec<u32>, Vec<glam::Vec3>), ConsoleError> {
    let apply = |e: String| ConsoleError::Apply(e);
    let source = core
        .source
        .as_ref()
        .ok_or_else(|| apply("no trajectory loaded".into()))?;
    let sel = Selection::parse(expr).map_err(|e| apply(e.to_string()))?;
    let frame = source.read_frame(core.timeline.current)?;
    let indices = sel.bind(source.topology()).indices(&frame);
    let points = indices
        .iter()
        .filter_map(|&i| frame.positions.get(i as usize).copied())
        .collect();
    Ok((indices, points))
}

impl ConsoleCommand {
    /// The app commands this command gives now (representation numbers and names are looked
    /// up in `core`).
    pub fn resolve(&self, core: &AppCore) -> Result<Outcome, ConsoleError> {
        let mut out = Outcome::default();
        let one = |c: Command| Outcome {
            commands: vec![c],
            output: None,
        };
        match self {
            ConsoleCommand::RepAdd {
                selection,
                style,
                name,
            } => {
                let n = core.reps.len() + 1;
                let mut rep = core.base.clone();
                rep.name = name.clone().unwrap_or_else(|| format!("rep {n}"));
                rep.selection = selection.clone();
                rep.style = *style;
                rep.validate()?;
                out.output = Some(format!("added representation {n} '{}'", rep.name));
                out.commands = vec![Command::AddRep, Command::UpdateRep(n - 1, Box::new(rep))];
            }
            ConsoleCommand::Rep(r, edit) => {
                let i = find_rep(core, r)?;
                let mut rep: Representation = core.reps[i].clone();
                match edit {
                    RepEdit::Delete => return Ok(one(Command::DeleteRep(i))),
                    RepEdit::Hide => rep.visible = false,
                    RepEdit::Show => rep.visible = true,
                    RepEdit::Color(c) => rep.colour = *c,
                    RepEdit::Spacing(v) => rep.spacing = *v,
                    RepEdit::RadiusScale(v) => rep.radius_scale = *v,
                    RepEdit::Isovalue(v) => rep.isovalue = *v,
                    RepEdit::Quality(q) => rep.quality = *q,
                    RepEdit::Opacity(v) => rep.opacity = *v,
                    RepEdit::Vertices(v) => rep.vertices = *v,
                    RepEdit::Cavities(on, probe) => {
                        (rep.cavities, rep.cavity_probe) = (*on, *probe)
                    }
                    RepEdit::Style(s) => rep.style = *s,
                    RepEdit::Select(s) => rep.selection = s.clone(),
                }
                rep.validate()?;
                if rep.style.is_surface() {
                    let params = rep.params();
                    let total = core.total_grid_bytes(i, &params);
                    if total > core.grid_limit_bytes {
                        return Err(ConsoleError::Apply(format!(
                            "the grids would need {} MB, over the limit of {} MB",
                            total >> 20,
                            core.grid_limit_bytes >> 20
                        )));
                    }
                }
                out.commands = vec![Command::UpdateRep(i, Box::new(rep))];
            }
            ConsoleCommand::Frame(f) => {
                let len = core.timeline.len;
                if *f >= len {
                    return Err(ConsoleError::Apply(format!(
                        "frame {f}: the trajectory has {len} frame(s) (from 0)"
                    )));
                }
                return Ok(one(Command::Timeline(TimelineCmd::Seek(*f))));
            }
            ConsoleCommand::Play => {
                return Ok(one(Command::Timeline(TimelineCmd::SetPlaying(true))));
            }
            ConsoleCommand::Pause => {
                return Ok(one(Command::Timeline(TimelineCmd::SetPlaying(false))));
            }
            ConsoleCommand::Fit(None) => return Ok(one(Command::FitCamera)),
            ConsoleCommand::Fit(Some(expr)) => {
                let (indices, points) = select_now(core, expr)?;
                let (centre, radius) = crate::render::bounding_sphere(points.iter())
                    .ok_or_else(|| ConsoleError::Apply(format!("'{expr}' selects no atoms")))?;
                out.output = Some(format!("fitted {} atoms", indices.len()));
                out.commands = vec![Command::FitSphere(centre, radius.max(1.0))];
            }
            ConsoleCommand::ViewSave(p) => return Ok(one(Command::SaveView(Some(p.clone())))),
            ConsoleCommand::ViewOpen(p) => return Ok(one(Command::OpenView(Some(p.clone())))),
            ConsoleCommand::Screenshot(path, size) => {
                return Ok(one(Command::Screenshot {
                    scale: 1,
                    size: *size,
                    path: Some(path.clone()),
                }));
            }
            ConsoleCommand::Select(expr) => {
                let (indices, _) = select_now(core, expr)?;
                out.output = Some(format!(
                    "{} atoms (frame {})",
                    indices.len(),
                    core.timeline.current
                ));
            }
            ConsoleCommand::Imd(verb) => {
                use crate::io::LiveAction::{Detach, TogglePause};
                let action = match (verb, core.live_paused) {
                    (ImdVerb::Pause, true) | (ImdVerb::Resume, false) => {
                        let state = if core.live_paused {
                            "paused"
                        } else {
                            "running"
                        };
                        return Err(ConsoleError::Apply(format!("the simulation is {state}")));
                    }
                    (ImdVerb::Detach, _) => Detach,
                    _ => TogglePause,
                };
                return Ok(one(Command::Live(action)));
            }
            ConsoleCommand::Help(topic) => {
                out.output = Some(match topic.as_deref() {
                    Some("rep") => HELP_REP.to_string(),
                    _ => HELP.to_string(),
                });
            }
        }
        Ok(out)
    }
}

pub use super::console_complete::complete;
pub use super::script_error::ScriptError;

/// Reads a script: one command per line, `#` comments; parse errors name the file and line.
pub fn read_script(path: &std::path::Path) -> Result<Vec<(usize, String)>, ScriptError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScriptError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut lines = Vec::new();
    for (i, line) in text.lines().enumerate() {
        match parse(line) {
            Ok(None) => {}
            Ok(Some(_)) => lines.push((i + 1, line.to_string())),
            Err(source) => {
                return Err(ScriptError::Line {
                    path: path.to_path_buf(),
                    line: i + 1,
                    source,
                });
            }
        }
    }
    Ok(lines)
}
