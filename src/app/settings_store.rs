//! What the window keeps between runs, through eframe's persistence: its size and place
//! (eframe), the panel layout (egui's memory: panel widths, open sections) and the look (a
//! [`LookState`], as in state files). The settings live in the platform's data folder
//! (`~/.local/share/mdsurf` on Linux) or in `$MDSURF_SETTINGS_DIR`. A scripted run (`--quit`)
//! is a batch job whose pictures must not depend on the last session: it neither reads nor
//! writes them unless `MDSURF_SETTINGS_DIR` names a folder. View → Reset layout forgets them.

use std::path::PathBuf;

use crate::render::RenderSettings;
use crate::scene::state_file::LookState;

/// The environment variable naming the folder the settings are kept in.
pub const SETTINGS_DIR_ENV: &str = "MDSURF_SETTINGS_DIR";

/// The window's size when nothing is kept, or after Reset layout (logical pixels).
pub const DEFAULT_SIZE: [f32; 2] = [1400.0, 900.0];

/// The key of the look in eframe's storage.
const LOOK_KEY: &str = "mdsurf.look";

/// Where this run keeps its settings.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Keep {
    /// eframe's folder for the app (the platform's data folder).
    Default,
    /// This file (in `$MDSURF_SETTINGS_DIR`).
    At(PathBuf),
    /// Nowhere: a throwaway file, neither read from before nor kept after.
    Not(PathBuf),
}

impl Keep {
    /// Where a run keeps its settings: `$MDSURF_SETTINGS_DIR` when set, else nowhere for a
    /// scripted run (`scripted`), else eframe's folder.
    pub fn for_run(scripted: bool) -> Keep {
        match std::env::var_os(SETTINGS_DIR_ENV) {
            Some(dir) => Keep::At(PathBuf::from(dir).join("window.ron")),
            None if scripted => Keep::Not(
                std::env::temp_dir().join(format!("mdsurf-batch-{}.ron", std::process::id())),
            ),
            None => Keep::Default,
        }
    }

    /// True when the settings are read at start and written at exit.
    pub fn keeps(&self) -> bool {
        !matches!(self, Keep::Not(_))
    }

    /// Sets eframe's options to keep (or not) the window's size and place and the storage file.
    pub fn configure(&self, native: &mut eframe::NativeOptions) {
        native.persist_window = self.keeps();
        native.persistence_path = match self {
            Keep::Default => None,
            Keep::At(file) | Keep::Not(file) => Some(file.clone()),
        };
    }

    /// Removes the throwaway file of a run that keeps nothing.
    pub fn clean_up(&self) {
        if let Keep::Not(file) = self {
            let _ = std::fs::remove_file(file);
        }
    }
}

/// The look kept from the last session, when there is one and it is valid.
pub fn kept_look(storage: Option<&dyn eframe::Storage>) -> Option<RenderSettings> {
    let look: LookState = eframe::get_value(storage?, LOOK_KEY)?;
    let mut settings = RenderSettings::default();
    look.apply(&mut settings).ok()?;
    Some(settings)
}

/// Keeps `render`'s look for the next session.
pub fn keep_look(storage: &mut dyn eframe::Storage, render: &RenderSettings) {
    eframe::set_value(storage, LOOK_KEY, &LookState::from_settings(render));
}
