//! The viewer's state without any window or GPU: the loaded trajectory, surface parameters,
//! particle options, look settings, timeline, latest surface, history for the plot and messages.
//! UI functions (`*_ui`) return [`Command`]s; [`AppCore::apply`] is the one place that changes
//! state. Tests drive this directly (see tests/app_panels.rs).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use super::plot::History;
use super::source::FrameSource;
use super::timeline::{Timeline, TimelineCmd};
use super::worker::{Computed, Reply, Request, Worker};
use crate::model::{ColorScheme, ParticleOptions};
use crate::render::{Camera, Projection, RenderSettings};
use crate::surface::{GridSpec, SurfaceParams};

/// Something the user asked for.
#[derive(Debug, Clone)]
pub enum Command {
    /// Open files (topology, optional trajectory) in the background.
    Open(PathBuf, Option<PathBuf>),
    /// Show the file dialog (in the background).
    OpenDialog,
    /// New surface parameters (already checked against the grid limit).
    SetParams(SurfaceParams),
    /// One bead per residue on or off.
    SetBeads(bool),
    /// Colour scheme of the surface and atoms.
    SetColours(ColorScheme),
    /// Look of the picture.
    SetRender(RenderSettings),
    /// Playback.
    Timeline(TimelineCmd),
    /// Camera back to the default direction, fitted to the scene.
    ResetCamera,
    /// Fit the scene, keeping the direction.
    FitCamera,
    /// Perspective or orthographic.
    SetProjection(Projection),
    /// Rotate the camera about its target (radians right, up).
    Orbit(f32, f32),
    /// Move the camera in the view plane (fractions of the view height, right, up).
    Pan(f32, f32),
    /// Multiply the camera distance.
    Zoom(f32),
    /// Turntable speed in degrees per second (`None`: off).
    SetTurntable(Option<f32>),
    /// Save a screenshot: scale of the window size, or an explicit size, to a path (dialog when
    /// `None`).
    Screenshot {
        /// Multiple of the viewport size (1 to 4) when `size` is `None`.
        scale: u32,
        /// Explicit width and height in pixels.
        size: Option<[u32; 2]>,
        /// Output file; `None` asks with a dialog.
        path: Option<PathBuf>,
    },
    /// Start a movie export.
    StartMovie(super::export::MoviePlan),
    /// Stop the movie export.
    CancelMovie,
    /// Write the area/volume history as CSV (dialog when `None`).
    ExportCsv(Option<PathBuf>),
    /// Close the error message.
    DismissError,
}

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
    /// Applied surface parameters.
    pub params: SurfaceParams,
    /// Particle options (beads, colours).
    pub options: ParticleOptions,
    /// Look of the picture.
    pub render: RenderSettings,
    /// Camera.
    pub camera: Camera,
    /// True when the camera should be fitted to the next surface.
    pub fit_pending: bool,
    /// Turntable speed in degrees per second.
    pub turntable: Option<f32>,
    /// Playback.
    pub timeline: Timeline,
    /// The surface on screen.
    pub shown: Option<Shown>,
    /// Area and volume per frame for the current parameters.
    pub history: History,
    /// Latest error (one line), shown until dismissed.
    pub error: Option<String>,
    /// Latest informational message.
    pub status: String,
    /// Largest grid accepted, in bytes.
    pub grid_limit_bytes: u64,
    /// Commands for the window layer (dialogs, screenshots, movies).
    pub outbox: Vec<Command>,
    worker: Worker,
    generation: u64,
    in_flight: Option<(u64, usize)>,
    requested: Option<(u64, usize)>,
}

impl AppCore {
    /// A core computing with `worker`, showing nothing yet.
    pub fn new(worker: Worker) -> AppCore {
        AppCore {
            source: None,
            params: SurfaceParams::default(),
            options: ParticleOptions::default(),
            render: RenderSettings::default(),
            camera: Camera::default(),
            fit_pending: true,
            turntable: None,
            timeline: Timeline::new(0),
            shown: None,
            history: History::default(),
            error: None,
            status: String::new(),
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
        self.source = Some(source);
        self.fit_pending = true;
        self.invalidate();
    }

    /// Applies one command. Window-level commands go to [`AppCore::outbox`].
    pub fn apply(&mut self, cmd: Command) {
        match cmd {
            Command::SetParams(p) => {
                if p != self.params {
                    self.params = p;
                    self.invalidate();
                }
            }
            Command::SetBeads(b) => {
                if b != self.options.beads {
                    self.options.beads = b;
                    self.invalidate();
                }
            }
            Command::SetColours(c) => {
                if c != self.options.colours {
                    self.options.colours = c;
                    self.invalidate();
                }
            }
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
                self.fit_camera();
            }
            Command::FitCamera => self.fit_camera(),
            Command::SetProjection(p) => self.camera.projection = p,
            Command::Orbit(dx, dy) => self.camera.orbit(dx, dy),
            Command::Pan(dx, dy) => self.camera.pan(dx, dy),
            Command::Zoom(f) => self.camera.zoom(f),
            Command::SetTurntable(t) => self.turntable = t,
            Command::DismissError => self.error = None,
            other => self.outbox.push(other),
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
        self.request_current();
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
        self.worker.submit(Request {
            generation: want.0,
            frame: want.1,
            source,
            params: self.params,
            options: self.options.clone(),
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
            Reply::Done(c) => {
                if c.generation == self.generation {
                    self.history.record(c.frame, c.output.area, c.output.volume);
                }
                if self.in_flight == Some((c.generation, c.frame)) {
                    self.in_flight = None;
                }
                if self.fit_pending
                    && let Some((centre, radius)) = scene_bounds(&c)
                {
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

    /// The grid the edited parameters `p` would need for the surface on screen, and its size in
    /// bytes (density and colour volumes), or `None` before the first surface.
    pub fn grid_estimate(&self, p: &SurfaceParams) -> Option<(GridSpec, u64)> {
        let c = &self.shown.as_ref()?.computed;
        let grid = GridSpec::for_atoms(&c.particles.positions, &c.particles.radii, p).ok()?;
        let bytes = crate::surface::estimate_grid_bytes(grid.dims.map(u64::from), true);
        Some((grid, bytes))
    }
}

/// Bounding sphere (centre, radius in Å) of the surface, or of the particles when there is no
/// surface.
fn scene_bounds(c: &Computed) -> Option<(glam::Vec3, f32)> {
    crate::render::bounding_sphere(&c.output.mesh.positions)
        .or_else(|| crate::render::bounding_sphere(&c.particles.positions))
}

/// Half of the memory available now (or 8 GB when unknown), at most 16 GB.
fn default_grid_limit() -> u64 {
    let avail = crate::surface::available_memory_bytes();
    (avail / 2).min(16 << 30)
}
