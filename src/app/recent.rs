//! Recently opened files, remembered between runs in `$XDG_CONFIG_HOME/mdsurf/recent.txt`
//! (else `~/.config/mdsurf/recent.txt`), one `TOP<TAB>TRAJ` line per entry, newest first.

use std::path::PathBuf;

/// How many entries are kept.
pub const MAX_RECENT: usize = 10;

/// One opened pair of files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecentEntry {
    /// Topology (or single structure/trajectory) file.
    pub top: PathBuf,
    /// Trajectory file, when separate.
    pub traj: Option<PathBuf>,
}

/// The list and where it is stored (`None`: not stored, as in tests).
#[derive(Debug, Clone, Default)]
pub struct Recent {
    /// Entries, newest first.
    pub entries: Vec<RecentEntry>,
    file: Option<PathBuf>,
}

fn default_file() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("mdsurf").join("recent.txt"))
}

impl Recent {
    /// Loads the stored list (empty when there is none or it cannot be read).
    pub fn load() -> Recent {
        let file = default_file();
        let entries = file
            .as_ref()
            .and_then(|f| std::fs::read_to_string(f).ok())
            .map(|text| parse(&text))
            .unwrap_or_default();
        Recent { entries, file }
    }

    /// Puts `entry` first and saves (saving errors are ignored: the list is a convenience).
    pub fn push(&mut self, entry: RecentEntry) {
        self.entries.retain(|e| *e != entry);
        self.entries.insert(0, entry);
        self.entries.truncate(MAX_RECENT);
        if let Some(f) = &self.file {
            if let Some(dir) = f.parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            let _ = std::fs::write(f, format(&self.entries));
        }
    }
}

fn parse(text: &str) -> Vec<RecentEntry> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut parts = l.splitn(2, '\t');
            let top = PathBuf::from(parts.next().unwrap_or_default());
            let traj = parts.next().filter(|t| !t.is_empty()).map(PathBuf::from);
            RecentEntry { top, traj }
        })
        .take(MAX_RECENT)
        .collect()
}

fn format(entries: &[RecentEntry]) -> String {
    entries
        .iter()
        .map(|e| {
            let traj = e
                .traj
                .as_ref()
                .map(|t| t.display().to_string())
                .unwrap_or_default();
            format!("{}\t{traj}\n", e.top.display())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_newest_first_without_duplicates() {
        let mut r = Recent::default();
        let a = RecentEntry {
            top: "a.gro".into(),
            traj: Some("a.xtc".into()),
        };
        let b = RecentEntry {
            top: "b.pdb".into(),
            traj: None,
        };
        r.push(a.clone());
        r.push(b.clone());
        r.push(a.clone());
        assert_eq!(r.entries, vec![a.clone(), b.clone()]);
        assert_eq!(parse(&format(&r.entries)), vec![a, b]);
    }
}
