//! Tab completion for the console ([`super::console`]): the last word of a line completed
//! from the command words, the rep settings, styles, colour schemes and qualities, and the
//! representations' names.

use super::console::{COMMAND_WORDS, REP_WORDS};
use crate::scene::representation::RepStyle;

/// Completes the last word of `line` (command words, rep settings, styles, representation
/// names); the completed line, or `None` when nothing (or more than one thing) fits.
pub fn complete(line: &str, rep_names: &[String]) -> Option<String> {
    let start = line.rfind(' ').map_or(0, |i| i + 1);
    let (head, last) = line.split_at(start);
    let words: Vec<&str> = head.split_whitespace().collect();
    let styles: Vec<String> = RepStyle::ALL.iter().map(|s| s.name().to_string()).collect();
    let candidates: Vec<String> = match words.as_slice() {
        [] => COMMAND_WORDS.iter().map(|s| s.to_string()).collect(),
        ["rep"] => std::iter::once("add".to_string())
            .chain(rep_names.iter().filter(|n| !n.contains(' ')).cloned())
            .collect(),
        ["rep", "add", ..] if head.matches('"').count() % 2 == 0 && words.len() >= 3 => styles,
        ["rep", _, "style"] => styles,
        ["rep", _] => REP_WORDS[..13].iter().map(|s| s.to_string()).collect(),
        ["rep", _, "color" | "colour"] => [
            "element",
            "chain",
            "residue-type",
            "residue-index",
            "b-factor",
            "single:",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        ["rep", _, "quality"] => ["low", "medium", "high", "max"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        ["rep", _, "cavities"] => vec!["on".into(), "off".into(), "probe".into()],
        ["rep", _, "cavities", "probe"] => vec!["1.4".into()],
        ["view"] => vec!["save".into(), "open".into()],
        ["imd"] => vec!["pause".into(), "resume".into(), "detach".into()],
        ["help"] => vec!["rep".into()],
        _ => Vec::new(),
    };
    let fits: Vec<&String> = candidates.iter().filter(|c| c.starts_with(last)).collect();
    match fits.as_slice() {
        [one] => {
            let space = if one.ends_with(':') { "" } else { " " };
            Some(format!("{head}{one}{space}"))
        }
        [] => None,
        many => {
            // The longest common prefix, when it adds something.
            let mut prefix = many[0].clone();
            for c in &many[1..] {
                while !c.starts_with(prefix.as_str()) {
                    prefix.pop();
                }
            }
            (prefix.len() > last.len()).then(|| format!("{head}{prefix}"))
        }
    }
}
