//! The viewer's state without any window or GPU: the loaded trajectory, the representations
//! (each a selection with its style, colours, opacity and surface parameters), look settings,
//! timeline, latest surfaces, history for the plot and messages.
//! UI functions (`*_ui`) return [`Command`]s (see [`super::command`]); [`AppCore::apply`] is
//! the one place that changes state. Tests drive this directly (see tests/app_panels.rs).

use std::sync::Arc;
use std::time::Duration;

pub use super::command::Command;
use super::plot::History;
use super::source::FrameSource;
use super::timeline::Timeline;
use super::worker::{Computed, RepRequest, Reply, Request, Worker};
use crate::model::{ColourMap, Frame, RadiusOverrides};
use crate::render::{Camera, RenderSettings};
use crate::scene::defaults::default_representations;
use crate::scene::representation::{RepStyle, Representation};
use crate::surface::{GridSpec, SurfaceParams};

/// The latest surface on screen plus what produced it.
pub struct Shown {
    /// The computed surface and particles.
    pub computed: Computed,
    /// True when the GPU copy is out of date.
    pub dirty: bool,
}

/// Everything the viewer knows, apart from the GPU.
pub struct AppCore {
    /// The trajectory.
    pub source: Option<Arc<dyn FrameSource>>,
    /// The representations, in drawing order.
    pub reps: Vec<Representation>,
    /// Stable id of each representation (parallel to `reps`), for the worker's per-rep slots.
    pub rep_ids: Vec<u64>,
    /// The representation the panel edits.
    pub selected: usize,
    /// Parameters and colours the default representations start from (command line).
    pub base: Representation,
    /// Radius overrides for every representation (command line).
    pub radius_overrides: RadiusOverrides,
    /// True while `reps` came from the user (`--state`, `--select`) and the next loaded file
    /// should keep them instead of getting its default representations.
    pub keep_reps_on_load: bool,
    /// Look of the picture.
    pub render: RenderSettings,
    /// Camera.
    pub camera: Camera,
    /// True when the camera should be fitted to the next surface.
    pub fit_pending: bool,
    /// True when the camera should also turn to the system's own view with the next fit: a
    /// membrane seen from the side ([`super::membrane_view`]). Off when a saved view gives the
    /// direction.
    pub orient_pending: bool,
    /// Turntable speed in degrees per second.
    pub turntable: Option<f32>,
    /// Playback.
    pub timeline: Timeline,
    /// The surface on screen.
    pub shown: Option<Shown>,
    /// Area and volume per frame for the current parameters.
    pub history: History,
    /// Cavities tracked over the shown frames, per representation (their `cavities` switch on).
    pub cavity_tracks: super::cavity_panel::CavityTracks,
    /// Latest error (one line), shown until dismissed.
    pub error: Option<String>,
    /// Latest informational message.
    pub status: String,
    /// True while the running simulation (`--imd`) is paused from here.
    pub live_paused: bool,
    /// Largest grid accepted, in bytes.
    pub grid_limit_bytes: u64,
    /// Commands for the window layer (dialogs, screenshots, movies).
    pub outbox: Vec<Command>,
    worker: Worker,
    next_id: u64,
    generation: u64,
    in_flight: Option<(u64, usize)>,
    requested: Option<(u64, usize)>,
}

impl AppCore {
    /// A core computing with `worker`, showing nothing yet.
    pub fn new(worker: Worker) -> AppCore {
        AppCore {
            source: None,
            reps: Vec::new(),
            rep_ids: Vec::new(),
            selected: 0,
            base: Representation::default(),
            radius_overrides: RadiusOverrides::default(),
            keep_reps_on_load: false,
            next_id: 1,
            render: RenderSettings::default(),
            camera: Camera::default(),
            fit_pending: true,
            orient_pending: true,
            turntable: None,
            timeline: Timeline::new(0),
            shown: None,
            history: History::default(),
            cavity_tracks: Default::default(),
            error: None,
            status: String::new(),
            live_paused: false,
            grid_limit_bytes: default_grid_limit(),
            outbox: Vec::new(),
            worker,
            generation: 0,
            in_flight: None,
            requested: None,
        }
    }

    /// Name of the surface engine.
    pub fn engine_name(&self) -> &str {
        self.worker.engine_name()
    }

    /// Replaces the data; the old data stays until this is called (so failed loads keep it).
    pub fn set_source(&mut self, source: Arc<dyn FrameSource>) {
        self.status = format!(
            "{}: {} atoms, {} frames",
            source.name(),
            source.topology().len(),
            source.len()
        );
        self.timeline = Timeline::new(source.len());
        if source.is_live() {
            // A running simulation opens on its newest frame, and follows it.
            self.timeline.current = source.len().saturating_sub(1);
        }
        if !self.keep_reps_on_load || self.reps.is_empty() {
            // Static selections only: the class counts need no coordinates.
            let topology = source.topology();
            let placeholder = Frame {
                positions: vec![glam::Vec3::ZERO; topology.len()],
                ..Frame::default()
            };
            let reps = default_representations(topology, &placeholder, &self.base);
            self.set_reps(reps);
        }
        self.keep_reps_on_load = false;
        self.source = Some(source);
        self.fit_pending = true;
        self.invalidate();
    }

    /// Replaces every representation (new ids, the first selected).
    pub fn set_reps(&mut self, reps: Vec<Representation>) {
        self.rep_ids = reps.iter().map(|_| self.fresh_id()).collect();
        self.reps = reps;
        self.selected = 0;
        self.invalidate();
    }

    fn fresh_id(&mut self) -> u64 {
        self.next_id += 1;
        self.next_id
    }

    /// The colour map and value range of the colour bar screenshots and movie frames carry:
    /// that of the first visible representation coloured by data (`--color data:FILE.csv`) or
    /// exposure, as `mdsurf render` draws it; `None` without one.
    pub fn colour_bar(&self) -> Option<(ColourMap, [f32; 2])> {
        self.reps
            .iter()
            .filter(|r| r.visible)
            .find_map(|r| r.colour.colour_bar())
    }

    /// The representation the panel edits, if any.
    pub fn selected_rep(&self) -> Option<&Representation> {
        self.reps.get(self.selected)
    }

    /// Replaces representation `i`: recomputes when what it computes changed, else only
    /// redraws (name, opacity).
    fn update_rep(&mut self, i: usize, rep: Representation) {
        let Some(old) = self.reps.get_mut(i) else {
            return;
        };
        if *old == rep {
            return;
        }
        let recompute = old.selection != rep.selection
            || old.style != rep.style
            || old.colour != rep.colour
            || old.params() != rep.params()
            || old.vertices != rep.vertices
            || old.radii != rep.radii
            || old.cavities != rep.cavities
            || old.cavity_probe != rep.cavity_probe
            || old.visible != rep.visible;
        *old = rep;
        if recompute {
            self.invalidate();
        } else if let Some(s) = &mut self.shown {
            s.dirty = true;
        }
    }

    /// Applies `edit` to a copy of the selected representation and updates it.
    fn edit_selected(&mut self, edit: impl FnOnce(&mut Representation)) {
        if let Some(mut rep) = self.selected_rep().cloned() {
            edit(&mut rep);
            self.update_rep(self.selected, rep);
        }
    }

    /// Applies one command. Window-level commands go to [`AppCore::outbox`].
    pub fn apply(&mut self, cmd: Command) {
        match cmd {
            Command::SetParams(p) => self.edit_selected(|r| r.set_params(&p)),
            Command::ApplyPreset(preset) => self.edit_selected(|r| {
                if r.style.is_surface() {
                    r.vertices = preset.vertices();
                    r.radii = preset.radius_set();
                }
            }),
            Command::SetBeads(b) => self.edit_selected(|r| {
                if r.style.is_surface() {
                    r.style = if b {
                        RepStyle::Beads
                    } else {
                        RepStyle::Surface
                    };
                }
            }),
            Command::SetColours(c) => self.edit_selected(|r| r.colour = c),
            Command::SelectRep(i) => {
                if i < self.reps.len() {
                    self.selected = i;
                }
            }
            Command::AddRep => {
                let n = self.reps.len() + 1;
                let rep = Representation {
                    name: format!("rep {n}"),
                    ..self.base.clone()
                };
                self.reps.push(rep);
                let id = self.fresh_id();
                self.rep_ids.push(id);
                self.selected = self.reps.len() - 1;
                self.invalidate();
            }
            Command::DuplicateRep(i) => {
                if let Some(rep) = self.reps.get(i).cloned() {
                    let copy = Representation {
                        name: format!("{} copy", rep.name),
                        ..rep
                    };
                    self.reps.insert(i + 1, copy);
                    let id = self.fresh_id();
                    self.rep_ids.insert(i + 1, id);
                    self.selected = i + 1;
                    self.invalidate();
                }
            }
            Command::DeleteRep(i) => {
                if i < self.reps.len() {
                    self.reps.remove(i);
                    self.rep_ids.remove(i);
                    self.selected = self.selected.min(self.reps.len().saturating_sub(1));
                    self.invalidate();
                }
            }
            Command::UpdateRep(i, rep) => self.update_rep(i, *rep),
            Command::SetReps(reps) => self.set_reps(reps),
            Command::SetRender(r) => {
                self.render = r;
                if let Some(s) = &mut self.shown {
                    s.dirty = true;
                }
            }
            Command::Timeline(t) => {
                self.timeline.apply(t);
                self.request_current();
            }
            Command::ResetCamera => {
                let projection = self.camera.projection;
                self.camera = Camera {
                    projection,
                    ..Camera::default()
                };
                if let Some(shown) = &self.shown {
                    super::membrane_view::orient_to_membrane(&mut self.camera, &shown.computed);
                } else {
                    self.orient_pending = true;
                }
                self.fit_camera();
            }
            Command::FitCamera => self.fit_camera(),
            Command::Live(action) => self.control_live(action),
            Command::FitSphere(centre, radius) => {
                self.camera.fit_sphere(centre, radius);
                self.fit_pending = false;
            }
            Command::SetProjection(p) => self.camera.projection = p,
            Command::Orbit(dx, dy) => self.camera.orbit(dx, dy),
            Command::Pan(dx, dy) => self.camera.pan(dx, dy),
            Command::Zoom(f) => self.camera.zoom(f),
            Command::SetTurntable(t) => self.turntable = t,
            Command::DismissError => self.error = None,
            other => self.outbox.push(other),
        }
    }

    /// Pauses, resumes or detaches from the running simulation; says so on the status line.
    fn control_live(&mut self, action: crate::io::LiveAction) {
        use crate::io::LiveAction;
        let Some(source) = self.source.clone() else {
            self.error = Some("no trajectory loaded".into());
            return;
        };
        match source.live_control(action) {
            Ok(()) => {
                self.status = match action {
                    LiveAction::TogglePause if self.live_paused => "simulation resumed",
                    LiveAction::TogglePause => "simulation paused",
                    LiveAction::Detach => "detached: the simulation goes on without us",
                }
                .into();
                if action == LiveAction::TogglePause {
                    self.live_paused = !self.live_paused;
                }
            }
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    fn fit_camera(&mut self) {
        if let Some((centre, radius)) = self.shown.as_ref().and_then(|s| scene_bounds(&s.computed))
        {
            self.camera.fit_sphere(centre, radius);
        } else {
            self.fit_pending = true;
        }
    }

    /// Parameters or particles changed: new generation, new history, recompute the current frame.
    fn invalidate(&mut self) {
        self.generation += 1;
        self.history.clear();
        self.cavity_tracks.clear();
        self.request_current();
    }

    /// For a running simulation: takes in the frames that arrived since the last call, and
    /// moves to the newest when the newest was shown. Returns true when frames arrived.
    pub fn follow_live(&mut self) -> bool {
        let Some(source) = self.source.clone().filter(|s| s.is_live()) else {
            return false;
        };
        let len = source.len();
        if len == self.timeline.len {
            if let Some(end) = source.live_ended()
                && self.status != end
            {
                self.status = end;
            }
            return false;
        }
        self.status = format!(
            "{}: {} atoms, live: {len} frames received",
            source.name(),
            source.topology().len()
        );
        let at_newest = self.timeline.current + 1 >= self.timeline.len;
        self.timeline.len = len;
        if at_newest && len > 0 {
            self.timeline.current = len - 1;
            self.request_current();
        }
        true
    }

    /// True when the data comes from a running simulation.
    pub fn is_live(&self) -> bool {
        self.source.as_ref().is_some_and(|s| s.is_live())
    }

    /// Asks the worker for the current frame unless it is already on screen or on its way.
    pub fn request_current(&mut self) {
        let Some(source) = self.source.clone() else {
            return;
        };
        if source.is_empty() {
            return;
        }
        let want = (self.generation, self.timeline.current);
        let on_screen = self
            .shown
            .as_ref()
            .map(|s| (s.computed.generation, s.computed.frame));
        if on_screen == Some(want) || self.requested == Some(want) {
            return;
        }
        self.requested = Some(want);
        self.in_flight = Some(want);
        let reps = self
            .rep_ids
            .iter()
            .zip(&self.reps)
            .map(|(&id, rep)| RepRequest {
                id,
                rep: rep.clone(),
            })
            .collect();
        self.worker.submit(Request {
            generation: want.0,
            frame: want.1,
            source,
            reps,
            radius_overrides: self.radius_overrides.clone(),
        });
    }

    /// Takes finished work from the worker; returns true when the picture changed.
    pub fn poll(&mut self) -> bool {
        let mut changed = false;
        while let Some(reply) = self.worker.try_recv() {
            changed |= self.accept(reply);
        }
        changed
    }

    /// Waits up to `timeout` for the worker's next reply and takes it with any after it;
    /// returns true when the picture changed.
    pub fn poll_wait(&mut self, timeout: Duration) -> bool {
        let mut changed = false;
        if let Some(reply) = self.worker.recv_timeout(timeout) {
            changed |= self.accept(reply);
        }
        changed | self.poll()
    }

    /// Waits (up to `timeout`) until the worker has nothing queued and its replies are taken.
    pub fn wait_idle(&mut self, timeout: Duration) -> bool {
        let end = std::time::Instant::now() + timeout;
        while self.worker.is_busy() || self.requested != self.shown_key() && self.error.is_none() {
            let left = end.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return false;
            }
            if let Some(r) = self
                .worker
                .recv_timeout(left.min(Duration::from_millis(50)))
            {
                self.accept(r);
            }
        }
        self.poll();
        true
    }

    fn shown_key(&self) -> Option<(u64, usize)> {
        self.shown
            .as_ref()
            .map(|s| (s.computed.generation, s.computed.frame))
    }

    fn accept(&mut self, reply: Reply) -> bool {
        match reply {
            Reply::Done(mut c) => {
                if c.generation == self.generation {
                    for l in c.surfaces() {
                        self.history
                            .record(c.frame, &l.rep.name, l.output.area, l.output.volume);
                    }
                    self.cavity_tracks.record(&mut c.scene);
                }
                if self.in_flight == Some((c.generation, c.frame)) {
                    self.in_flight = None;
                }
                if self.fit_pending
                    && let Some((centre, radius)) = scene_bounds(&c)
                {
                    if std::mem::take(&mut self.orient_pending) {
                        super::membrane_view::orient_to_membrane(&mut self.camera, &c);
                    }
                    self.camera.fit_sphere(centre, radius);
                    self.fit_pending = false;
                }
                self.shown = Some(Shown {
                    computed: *c,
                    dirty: true,
                });
                true
            }
            Reply::Failed {
                frame,
                message,
                generation,
            } => {
                if self.in_flight == Some((generation, frame)) {
                    self.in_flight = None;
                }
                self.requested = None;
                self.error = Some(message);
                false
            }
        }
    }

    /// True while a surface is being computed.
    pub fn computing(&self) -> bool {
        self.worker.is_busy()
    }

    /// The grid the parameters `p` would need for representation `i`'s particles on screen
    /// (a periodic surface's: its cell's), and its size in bytes (density and colour volumes),
    /// or `None` before its first surface (or when it is hidden or not a surface).
    pub fn grid_estimate(&self, i: usize, p: &SurfaceParams) -> Option<(GridSpec, u64)> {
        let c = &self.shown.as_ref()?.computed;
        let id = *self.rep_ids.get(i)?;
        let l = c.layer(id).filter(|l| l.is_surface())?;
        if l.particles.positions.is_empty() {
            return None;
        }
        // A periodic surface samples its cell, whatever the atoms' box.
        let grid = match l.output.periodic.as_deref() {
            Some(seams) => GridSpec {
                origin: seams.cell.origin,
                spacing: p.spacing,
                dims: seams.cell.samples(p.spacing),
            },
            None => GridSpec::for_atoms(&l.particles.positions, &l.particles.radii, p).ok()?,
        };
        let bytes = crate::surface::estimate_grid_bytes(grid.dims.map(u64::from), true);
        Some((grid, bytes))
    }

    /// Grid memory in bytes of every visible surface representation with its current
    /// parameters, except representation `except`, which is counted with `p` instead.
    pub fn total_grid_bytes(&self, except: usize, p: &SurfaceParams) -> u64 {
        (0..self.reps.len())
            .filter(|&i| self.reps[i].visible && self.reps[i].style.is_surface())
            .filter_map(|i| {
                let params = if i == except {
                    *p
                } else {
                    self.reps[i].params()
                };
                self.grid_estimate(i, &params).map(|(_, b)| b)
            })
            .sum()
    }
}

/// Bounding sphere (centre, radius in Å) of the surfaces, or of the particles when there is
/// no surface.
fn scene_bounds(c: &Computed) -> Option<(glam::Vec3, f32)> {
    let mesh_points = c.layers.iter().flat_map(|l| l.output.mesh.positions.iter());
    crate::render::bounding_sphere(mesh_points).or_else(|| {
        crate::render::bounding_sphere(c.layers.iter().flat_map(|l| l.particles.positions.iter()))
    })
}

/// Half of the memory available now (or 8 GB when unknown), at most 16 GB.
fn default_grid_limit() -> u64 {
    let avail = crate::surface::available_memory_bytes();
    (avail / 2).min(16 << 30)
}
