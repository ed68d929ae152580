//! The eframe application: lays out the menu, panels, timeline, plot and viewport, collects the
//! commands the `*_ui` functions return and applies them in one place ([`Viewer::apply`]), runs
//! background loads and file dialogs, screenshots and movie exports, and the scripted run
//! (`--play-frames N --screenshot FILE --quit`).

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::device_loss::{DeviceWatch, Reopen, ReopenSlot};
use super::export::{MovieJob, MoviePlan, export_ui};
use super::panels::{SurfaceDraft, look_ui, readouts_ui, surface_ui};
use super::plot::plot_ui;
use super::recent::{Recent, RecentEntry};
use super::source::{FrameSource, SourceError, open_files_with, open_live_with};
use super::state::{AppCore, Command};
use super::timeline::timeline_ui;
use super::viewport::{GpuView, viewport_ui};
use crate::export::movie::Movie;
use crate::render::colour_bar::draw_colour_bar;
use crate::render::{RenderSettings, write_png};
use crate::scene::state_file::StateFile;

mod menu;
mod scripted;
pub use scripted::Script;

/// Where a scripted run reports failure (read after the window closes).
pub type ScriptResult = Arc<Mutex<Option<String>>>;

type Loaded = (Result<Arc<dyn FrameSource>, SourceError>, RecentEntry);

/// The viewer window.
pub struct Viewer {
    core: AppCore,
    gpu: Option<GpuView>,
    draft: SurfaceDraft,
    plan: MoviePlan,
    shot_scale: u32,
    movie: Option<MovieJob>,
    recent: Recent,
    loading: Option<Receiver<Loaded>>,
    picked: Option<Receiver<Command>>,
    script: Script,
    script_played: usize,
    /// The frame the scripted run last counted as shown.
    script_last_shown: Option<usize>,
    script_result: ScriptResult,
    /// (frames shown, anonymous memory in KiB) after each frame of a scripted run with a
    /// memory log.
    memory_samples: Vec<(usize, u64)>,
    last_update: Instant,
    fps: f64,
    /// Files of the trajectory on screen (set when a load succeeds).
    files: Option<(PathBuf, Option<PathBuf>)>,
    /// Watch on eframe's wgpu device, and where to leave the state when it is lost.
    device: Option<(DeviceWatch, ReopenSlot)>,
    /// Per-frame transformations of the frames loaded, and the Trajectory section's draft.
    transforms: super::trajectory_panel::TransformDraft,
    /// The Interface section's selections, switches and measured frames.
    interface: super::interface_panel::InterfaceDraft,
    /// True while the keyboard shortcut list is shown.
    shortcuts_shown: bool,
    /// The console under the viewport.
    console: super::console_ui::ConsoleState,
    /// True when the window keeps its layout and look for the next session.
    keeps_settings: bool,
}

impl Viewer {
    /// A viewer on `core`; `gpu` is `None` when eframe has no wgpu device (then nothing is drawn).
    pub fn new(
        core: AppCore,
        gpu: Option<GpuView>,
        script: Script,
        script_result: ScriptResult,
    ) -> Viewer {
        let draft = SurfaceDraft::new(core.base.params());
        Viewer {
            core,
            gpu,
            draft,
            plan: MoviePlan::default(),
            shot_scale: 1,
            movie: None,
            recent: Recent::load(),
            loading: None,
            picked: None,
            script,
            script_played: 0,
            script_last_shown: None,
            memory_samples: Vec::new(),
            script_result,
            last_update: Instant::now(),
            fps: 0.0,
            files: None,
            device: None,
            transforms: Default::default(),
            interface: Default::default(),
            shortcuts_shown: false,
            console: Default::default(),
            keeps_settings: false,
        }
    }

    /// Keeps the panel layout and the look for the next session (see `settings_store`), and
    /// starts from the look the last one kept when `use_kept_look` (no state file was given).
    pub fn keep_settings(&mut self, storage: Option<&dyn eframe::Storage>, use_kept_look: bool) {
        self.keeps_settings = true;
        if let Some(look) = super::settings_store::kept_look(storage).filter(|_| use_kept_look) {
            let stereo = self.core.render.stereo;
            self.core.render = RenderSettings {
                // A stereo mode asked for on the command line wins.
                stereo: if stereo == RenderSettings::default().stereo {
                    look.stereo
                } else {
                    stereo
                },
                ..look
            };
        }
    }

    /// Reloads the files on screen with the transformations in use (the representations stay).
    fn reload_transformed(&mut self, ctx: &egui::Context) {
        if let Some((top, traj)) = self.files.clone() {
            self.core.keep_reps_on_load = true;
            self.open(ctx, top, traj);
        } else if self.loading.is_some() {
            // A load is under way: reload when it lands.
            self.transforms.request_reload();
        }
    }

    /// Sets the per-frame transformations used by the next load.
    pub fn set_transforms(&mut self, options: crate::transform::TransformOptions) {
        self.transforms = super::trajectory_panel::TransformDraft::new(options);
    }

    /// Applies a command as if the UI had issued it (tests, scripted use).
    pub fn command(&mut self, ctx: &egui::Context, cmd: Command) {
        self.apply(ctx, cmd);
    }

    /// True while a movie export runs.
    pub fn movie_running(&self) -> bool {
        self.movie.is_some()
    }

    /// The state behind the window (for tests).
    pub fn core(&self) -> &AppCore {
        &self.core
    }

    /// The console's state (for tests).
    pub fn console(&self) -> &super::console_ui::ConsoleState {
        &self.console
    }

    /// True while the keyboard shortcut list is shown.
    pub fn shortcuts_shown(&self) -> bool {
        self.shortcuts_shown
    }

    /// Starts loading `top` (+ `traj`) on a background thread; the current data stays until it
    /// succeeds.
    pub fn open(&mut self, ctx: &egui::Context, top: PathBuf, traj: Option<PathBuf>) {
        let (tx, rx) = channel();
        let ctx = ctx.clone();
        self.core.status = format!("loading {}…", top.display());
        let transforms = self.transforms.applied().clone();
        std::thread::spawn(move || {
            let result = open_files_with(&top, traj.as_deref(), &transforms);
            let _ = tx.send((result, RecentEntry { top, traj }));
            ctx.request_repaint();
        });
        self.loading = Some(rx);
    }

    /// Starts following a running simulation or a growing file (atoms from `top`) on a
    /// background thread; the current data stays until the first frame arrives.
    pub fn open_live(&mut self, ctx: &egui::Context, top: PathBuf, live: crate::io::LiveSource) {
        let (tx, rx) = channel();
        let ctx = ctx.clone();
        self.core.status = format!("following {}…", live.describe());
        let transforms = self.transforms.applied().clone();
        std::thread::spawn(move || {
            let result = open_live_with(&top, &live, &transforms);
            let _ = tx.send((result, RecentEntry { top, traj: None }));
            ctx.request_repaint();
        });
        self.loading = Some(rx);
    }

    /// Applies one command: window-level ones here, the rest in [`AppCore::apply`].
    fn apply(&mut self, ctx: &egui::Context, cmd: Command) {
        self.core.apply(cmd);
        for cmd in std::mem::take(&mut self.core.outbox) {
            match cmd {
                Command::Open(top, traj) => self.open(ctx, top, traj),
                Command::OpenDialog => self.dialog(
                    ctx,
                    |paths| {
                        let mut it = paths.into_iter();
                        it.next().map(|top| Command::Open(top, it.next()))
                    },
                    true,
                ),
                Command::Screenshot {
                    scale,
                    size,
                    path: Some(path),
                } => {
                    if let Err(e) = self.screenshot(scale, size, &path) {
                        self.core.error = Some(e.to_string());
                    }
                }
                Command::Screenshot {
                    scale,
                    size,
                    path: None,
                } => self.dialog(
                    ctx,
                    move |p| {
                        p.into_iter().next().map(|path| Command::Screenshot {
                            scale,
                            size,
                            path: Some(path),
                        })
                    },
                    false,
                ),
                Command::ExportCsv(Some(path)) => match self.core.history.write_csv(&path) {
                    Ok(()) => self.core.status = format!("wrote {}", path.display()),
                    Err(e) => self.core.error = Some(e.to_string()),
                },
                Command::SaveView(Some(path)) => match self.state_file().save(&path) {
                    Ok(()) => self.core.status = format!("saved view {}", path.display()),
                    Err(e) => self.core.error = Some(e.to_string()),
                },
                Command::SaveView(None) => self.dialog(
                    ctx,
                    |p| p.into_iter().next().map(|p| Command::SaveView(Some(p))),
                    false,
                ),
                Command::OpenView(Some(path)) => match StateFile::load(&path) {
                    Ok(state) => {
                        self.apply_state(state);
                        self.core.status = format!("opened view {}", path.display());
                    }
                    // The view on screen stays as it was.
                    Err(e) => self.core.error = Some(e.to_string()),
                },
                Command::OpenView(None) => self.dialog(
                    ctx,
                    |p| p.into_iter().next().map(|p| Command::OpenView(Some(p))),
                    true,
                ),
                Command::ExportCsv(None) => self.dialog(
                    ctx,
                    |p| p.into_iter().next().map(|p| Command::ExportCsv(Some(p))),
                    false,
                ),
                Command::StartMovie(plan) => {
                    let video = match &plan.video {
                        // The movie goes to a temporary file beside the target, renamed when
                        // the last image is in.
                        Some(v) => match Movie::create(&v.path, plan.size, v.fps, v.quality, 0) {
                            Ok(m) => Some(m),
                            Err(e) => {
                                self.core.error = Some(e.to_string());
                                continue;
                            }
                        },
                        None => {
                            // The folder typed in the movie panel is made here (image writes
                            // never create folders, as for every other output).
                            if let Err(e) = std::fs::create_dir_all(&plan.dir) {
                                self.core.error =
                                    Some(format!("cannot create {}: {e}", plan.dir.display()));
                                continue;
                            }
                            None
                        }
                    };
                    let steps = plan.steps(self.core.timeline.current);
                    self.core.timeline.playing = false;
                    self.movie = Some(MovieJob {
                        steps,
                        done: 0,
                        start_yaw: self.core.camera.yaw,
                        size: plan.size,
                        video,
                    });
                }
                Command::CancelMovie => {
                    if let Some(job) = self.movie.take() {
                        self.core.status = format!("movie cancelled after {} images", job.done);
                    }
                }
                Command::ShowShortcuts(shown) => self.shortcuts_shown = shown,
                Command::ToggleConsole => self.console.toggle(),
                Command::ResetLayout => {
                    ctx.memory_mut(|m| *m = egui::Memory::default());
                    self.core.render = RenderSettings::default();
                    let [w, h] = super::settings_store::DEFAULT_SIZE;
                    ctx.send_viewport_cmd(egui::ViewportCommand::InnerSize(egui::vec2(w, h)));
                    self.core.status = "layout and look reset".into();
                }
                _ => {}
            }
        }
    }

    /// The view as a state file: representations, camera, look, timeline and the frame
    /// transformations.
    pub fn state_file(&self) -> StateFile {
        let mut state = self.core.view_state();
        state.trajectory.set_transforms(self.transforms.applied());
        state
    }

    /// Applies a state file (already checked): representations, camera, look, timeline and
    /// the frame transformations.
    pub fn apply_state(&mut self, state: StateFile) {
        let transforms = state.trajectory.transforms();
        if let Err(e) = self.core.apply_view_state(state) {
            self.core.error = Some(e.to_string());
            return;
        }
        if &transforms != self.transforms.applied() {
            self.set_transforms(transforms);
            self.transforms.request_reload();
        }
    }

    /// Runs a file dialog on a background thread (open: several files; else save) and turns the
    /// chosen paths into a command.
    fn dialog(
        &mut self,
        ctx: &egui::Context,
        then: impl FnOnce(Vec<PathBuf>) -> Option<Command> + Send + 'static,
        open: bool,
    ) {
        let (tx, rx) = channel();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            let d = rfd::FileDialog::new();
            let paths = if open {
                d.pick_files().unwrap_or_default()
            } else {
                d.save_file().into_iter().collect()
            };
            if let Some(cmd) = then(paths) {
                let _ = tx.send(cmd);
            }
            ctx.request_repaint();
        });
        self.picked = Some(rx);
    }

    /// Renders the current view at `scale` × the viewport (or `size`) and writes a PNG.
    fn screenshot(
        &mut self,
        scale: u32,
        size: Option<[u32; 2]>,
        path: &std::path::Path,
    ) -> Result<(), crate::render::RenderError> {
        let gpu = self
            .gpu
            .as_mut()
            .ok_or(crate::render::RenderError::NoDevice)?;
        let base = gpu.size().unwrap_or([1280, 720]);
        let size = size.unwrap_or([base[0] * scale.clamp(1, 4), base[1] * scale.clamp(1, 4)]);
        gpu.sync(&mut self.core);
        let mut image = gpu.snapshot(&self.core.camera, &self.core.render, size)?;
        if let Some((map, range)) = self.core.colour_bar() {
            draw_colour_bar(&mut image, map, range);
        }
        write_png(path, &image)?;
        self.core.status = format!("wrote {} ({}×{})", path.display(), size[0], size[1]);
        Ok(())
    }

    fn poll_background(&mut self, ctx: &egui::Context) {
        if let Some((result, entry)) = self.loading.as_ref().and_then(|rx| rx.try_recv().ok()) {
            self.loading = None;
            match result {
                Ok(source) => {
                    self.core.set_source(source);
                    self.files = Some((entry.top.clone(), entry.traj.clone()));
                    self.recent.push(entry);
                }
                Err(e) => {
                    self.core.error = Some(format!("could not open {}: {e}", entry.top.display()))
                }
            }
        }
        if let Some(cmd) = self.picked.as_ref().and_then(|rx| rx.try_recv().ok()) {
            self.picked = None;
            self.apply(ctx, cmd);
        }
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(top) = dropped.first().cloned() {
            self.apply(ctx, Command::Open(top, dropped.get(1).cloned()));
        }
    }
}

impl eframe::App for Viewer {
    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.keeps_settings {
            super::settings_store::keep_look(storage, &self.core.render);
        }
    }

    fn persist_egui_memory(&self) -> bool {
        self.keeps_settings
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        if self.leave_if_device_lost(&ctx) {
            return;
        }
        let now = Instant::now();
        let dt = now.duration_since(self.last_update).as_secs_f64();
        self.last_update = now;
        self.poll_background(&ctx);
        if self.core.poll() {
            self.fps = if dt > 0.0 {
                0.8 * self.fps + 0.2 / dt
            } else {
                self.fps
            };
        }
        self.core.follow_live();
        if self.movie.is_none() && !self.scripted() && self.core.timeline.advance(dt) {
            self.core.request_current();
        }
        if let Some(speed) = self.core.turntable.filter(|_| self.movie.is_none()) {
            self.core.camera.turn(speed * dt as f32);
        }
        if self.scripted() {
            self.step_script(&ctx);
        }
        self.step_movie();

        // Shortcuts first, from this frame's keys (none while a text field has the focus).
        let mut cmds = super::keys::keys_ui(&ctx, &self.core, self.shortcuts_shown);
        egui::Panel::top("menu").show(ui, |ui| cmds.extend(self.menu_ui(ui)));
        if let Some(err) = self.core.error.clone() {
            egui::Panel::top("error").show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.colored_label(ui.visuals().error_fg_color, err);
                    if ui.button("Dismiss").clicked() {
                        cmds.push(Command::DismissError);
                    }
                });
            });
        }
        egui::Panel::left("controls")
            .resizable(true)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    cmds.extend(surface_ui(ui, &self.core, &mut self.draft));
                    ui.separator();
                    cmds.extend(look_ui(ui, &self.core));
                    ui.separator();
                    cmds.extend(super::cavity_panel::cavity_ui(ui, &self.core));
                    ui.separator();
                    super::interface_panel::interface_ui(ui, &self.core, &mut self.interface);
                    ui.separator();
                    if super::trajectory_panel::trajectory_ui(ui, &mut self.transforms) {
                        self.reload_transformed(ui.ctx());
                    }
                    ui.separator();
                    cmds.extend(super::simulation_panel::simulation_ui(ui, &self.core));
                    let frames = self.core.timeline.len;
                    cmds.extend(export_ui(
                        ui,
                        &mut self.plan,
                        &mut self.shot_scale,
                        frames,
                        self.movie.as_ref(),
                    ));
                });
            });
        let render_ms = self.gpu.as_ref().map_or(0.0, |g| g.render_ms);
        egui::Panel::right("readouts")
            .show(ui, |ui| readouts_ui(ui, &self.core, render_ms, self.fps));
        egui::Panel::bottom("timeline").show(ui, |ui| {
            let on_screen = self
                .core
                .shown
                .as_ref()
                .map(|s| (s.computed.frame, s.computed.time_ps));
            cmds.extend(timeline_ui(ui, &self.core.timeline, on_screen));
            let (h, cur, len) = (
                &self.core.history,
                self.core.timeline.current,
                self.core.timeline.len,
            );
            cmds.extend(plot_ui(ui, h, cur, len));
        });
        let console = super::console_ui::console_panel(ui, &mut self.console, &self.core);
        cmds.extend(console);
        egui::CentralPanel::default().show(ui, |ui| {
            let (view_cmds, size) = viewport_ui(ui, self.gpu_texture());
            cmds.extend(view_cmds);
            if let Some(gpu) = self.gpu.as_mut() {
                gpu.sync(&mut self.core);
                // Progressive samples only while still: one sample per frame while playing.
                let look = match self.core.timeline.playing || self.core.turntable.is_some() {
                    true => RenderSettings {
                        samples: 1,
                        ..self.core.render
                    },
                    false => self.core.render,
                };
                gpu.render(&self.core.camera, &look, size);
            }
        });
        cmds.extend(super::keys::shortcuts_overlay_ui(
            &ctx,
            self.shortcuts_shown,
        ));
        for cmd in cmds {
            self.apply(&ctx, cmd);
        }
        if self.core.timeline.playing
            || self.core.computing()
            || self.core.turntable.is_some()
            || self.movie.is_some()
            || self.scripted()
            || self.loading.is_some()
            || self.gpu.as_ref().is_some_and(|g| g.sampling)
        {
            ctx.request_repaint();
        } else if self.core.is_live() {
            // New frames of a running simulation are looked for ten times a second.
            ctx.request_repaint_after(std::time::Duration::from_millis(100));
        }
    }
}

impl Viewer {
    /// Watches eframe's device: the window keeps its files and settings in `session` every
    /// frame, and once the device is lost it closes; [`crate::app::run`] then opens a new
    /// window on a new device.
    pub fn watch_device(&mut self, watch: DeviceWatch, session: ReopenSlot) {
        self.device = Some((watch, session));
    }

    /// Records the session and, when the device was lost, asks the window to close (and
    /// returns true: nothing may be drawn on a lost device).
    fn leave_if_device_lost(&mut self, ctx: &egui::Context) -> bool {
        let Some((watch, session)) = &self.device else {
            return false;
        };
        if let Ok(mut slot) = session.lock() {
            *slot = Some(Reopen {
                files: self.files.clone(),
                params: self.core.base.params(),
                particles: crate::model::ParticleOptions {
                    beads: self.core.base.style == crate::scene::representation::RepStyle::Beads,
                    radius_overrides: self.core.radius_overrides.clone(),
                    colours: self.core.base.colour,
                    exposure: None,
                },
                reps: self.core.reps.clone(),
            });
        }
        if watch.lost().is_none() {
            return false;
        }
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        true
    }

    fn gpu_texture(&self) -> Option<egui::TextureId> {
        self.gpu.as_ref().and_then(|g| g.texture_id())
    }
}
