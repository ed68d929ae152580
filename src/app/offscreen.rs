//! The viewer's frame loop without a window, for `mdsurf bench --viewer`: the same compute
//! worker ([`super::worker`]), viewer state ([`AppCore`]), timeline and renderer
//! ([`ViewRenderer`]) as the window, on a headless device, drawing into a texture of the
//! asked size. The timeline plays at its frame rate as in the window (frames whose surface is
//! not ready when the next one falls due are dropped, latest wins), and the loop draws each
//! frame the worker delivers, as the window repaints on each reply.

use std::collections::HashMap;

use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::source::{FrameSource, SourceError};
use super::state::AppCore;
use super::timeline::{EndMode, TimelineCmd};
use super::view_renderer::ViewRenderer;
use super::worker::{Engine, Worker};
use crate::gpu::{DensityGather, EngineOptions, GpuContext, GpuEngine};
use crate::model::{Frame, Topology};
use crate::render::RenderSettings;
use crate::scene::representation::Representation;

/// Why the offscreen viewer could not play (one line).
#[derive(Debug, thiserror::Error)]
pub enum PlayError {
    /// The GPU engine or device failed.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// The viewer reported an error (the source, or a frame's computation).
    #[error("{0}")]
    Viewer(String),
    /// The source has one frame and nothing to play.
    #[error("a single frame cannot play: give a trajectory or --jitter-frames")]
    SingleFrame,
}

/// How to play.
#[derive(Debug, Clone)]
pub struct PlayOptions {
    /// Picture size in pixels.
    pub size: [u32; 2],
    /// Timeline frames to play (the trajectory loops when it is shorter).
    pub frames: usize,
    /// Timeline speed in frames per second (the window's range, 0.5 to 240).
    pub play_fps: f32,
    /// What the default representations start from (parameters, colours, radii).
    pub base: Representation,
    /// The look.
    pub render: RenderSettings,
    /// How the GPU engine's sparse density gather reads its atoms.
    pub density_gather: DensityGather,
}

/// What one offscreen playback measured.
#[derive(Debug, Clone, Default)]
pub struct PlayReport {
    /// Names of the representations drawn.
    pub reps: Vec<String>,
    /// Timeline frames played.
    pub frames_played: usize,
    /// Frames whose surfaces reached the screen.
    pub frames_shown: usize,
    /// Wall-clock length of the playback in s.
    pub wall_s: f64,
    /// Worker time per shown frame in ms ([`super::worker::Computed::compute_ms`]).
    pub compute_ms: Vec<f64>,
    /// Of that, reading the frame (the frame source's time), per shown frame, in ms.
    pub read_ms: Vec<f64>,
    /// From the timeline reaching a frame to its surface arriving, per shown frame, in ms.
    pub latency_ms: Vec<f64>,
    /// From the start of a draw until the device finished it, per shown frame, in ms (on a
    /// shared queue this includes compute work submitted before the draw).
    pub draw_ms: Vec<f64>,
    /// Encoding and submitting a draw on the host, per shown frame, in ms.
    pub draw_host_ms: Vec<f64>,
    /// The last frame drawn again with nothing else on the device, each draw waited for, in
    /// ms ([`DRAWS_ALONE`] draws after playback).
    pub draw_alone_ms: Vec<f64>,
    /// When the look has outlines or shadows: the same draws with both off (the default
    /// look's parts), each timed between two of `draw_alone_ms`'s, in ms. Paired in one
    /// process, their ratios show the outlines' and shadows' cost with less of the machine's
    /// noise than two runs compared.
    pub draw_alone_plain_ms: Vec<f64>,
    /// Most GPU memory the surface engines held, in bytes.
    pub engine_bytes: u64,
    /// Triangles of the last shown frame (every surface together).
    pub triangles: usize,
}

impl PlayReport {
    /// Frames shown per second of wall-clock time.
    pub fn shown_fps(&self) -> f64 {
        self.frames_shown as f64 / self.wall_s.max(1e-9)
    }

    /// Timeline frames that never reached the screen.
    pub fn frames_dropped(&self) -> usize {
        self.frames_played.saturating_sub(self.frames_shown)
    }
}

/// Plays `source` through the viewer's worker, state and renderer on `ctx`'s device, with the
/// GPU surface engine, and measures it. The first frame is computed and drawn before the
/// clock starts (pipelines, buffers). Errors are one line.
pub fn play(
    ctx: &GpuContext,
    source: Arc<dyn FrameSource>,
    opts: &PlayOptions,
) -> Result<PlayReport, PlayError> {
    let mut engine = GpuEngine::with_context(ctx.clone())?;
    engine.set_options(EngineOptions {
        density_gather: opts.density_gather,
        ..engine.options()
    });
    let worker = Worker::spawn_engine(Engine::Gpu(Box::new(engine)), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    core.base = opts.base.clone();
    core.render = opts.render;
    core.set_source(source);
    let mut view = ViewRenderer::new(ctx.device.clone(), ctx.queue.clone());
    core.wait_idle(Duration::from_secs(3600));
    if let Some(e) = core.error.take() {
        return Err(PlayError::Viewer(e));
    }
    let mut report = PlayReport {
        reps: core
            .reps
            .iter()
            .filter(|r| r.visible)
            .map(|r| r.name.clone())
            .collect(),
        ..PlayReport::default()
    };
    view.sync(&mut core);
    view.draw(&core.camera, &core.render, opts.size);
    ctx.wait()?;

    core.timeline.apply(TimelineCmd::SetFps(opts.play_fps));
    core.timeline.apply(TimelineCmd::SetEndMode(EndMode::Loop));
    core.timeline.apply(TimelineCmd::SetPlaying(true));
    if !core.timeline.playing {
        return Err(PlayError::SingleFrame);
    }
    let fps = core.timeline.fps as f64;
    let length = Duration::from_secs_f64(opts.frames as f64 / fps);
    let start = Instant::now();
    let mut last = start;
    let mut reached: HashMap<usize, Instant> = HashMap::new();
    loop {
        let now = Instant::now();
        if now.duration_since(start) >= length {
            break;
        }
        if core
            .timeline
            .advance(now.duration_since(last).as_secs_f64())
        {
            reached.insert(core.timeline.current, now);
            core.request_current();
        }
        last = now;
        let wait = core.timeline.until_next_s().min(0.05);
        if !core.poll_wait(Duration::from_secs_f64(wait)) {
            if let Some(e) = core.error.take() {
                return Err(PlayError::Viewer(e));
            }
            continue;
        }
        let arrived = Instant::now();
        if let Some(shown) = &core.shown {
            let c = &shown.computed;
            report.frames_shown += 1;
            report.compute_ms.push(c.compute_ms);
            report.read_ms.push(c.read_ms);
            report.engine_bytes = report.engine_bytes.max(c.gpu_bytes);
            report.triangles = c.triangle_count();
            if let Some(t) = reached.remove(&c.frame) {
                report.latency_ms.push(ms(arrived.duration_since(t)));
            }
        }
        view.sync(&mut core);
        let t = Instant::now();
        view.draw(&core.camera, &core.render, opts.size);
        report.draw_host_ms.push(ms(t.elapsed()));
        ctx.wait()?;
        report.draw_ms.push(ms(t.elapsed()));
    }
    report.wall_s = start.elapsed().as_secs_f64();
    report.frames_played = opts.frames;
    core.timeline.apply(TimelineCmd::SetPlaying(false));
    core.wait_idle(Duration::from_secs(600));
    view.sync(&mut core);
    let plain = RenderSettings {
        outline_width: 0.0,
        shadows: 0.0,
        ..core.render
    };
    let paired = core.render.has_look_pass();
    let mut timed_draw = |settings: &RenderSettings| -> Result<f64, PlayError> {
        view.redraw();
        let t = Instant::now();
        view.draw(&core.camera, settings, opts.size);
        ctx.wait()?;
        Ok(ms(t.elapsed()))
    };
    if paired {
        // The plain look's pipelines are made on first use: not timed.
        timed_draw(&plain)?;
    }
    for _ in 0..DRAWS_ALONE {
        report.draw_alone_ms.push(timed_draw(&core.render)?);
        if paired {
            report.draw_alone_plain_ms.push(timed_draw(&plain)?);
        }
    }
    Ok(report)
}

/// Draws of the last frame timed alone after playback.
pub const DRAWS_ALONE: usize = 20;

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A single frame played as a trajectory of `frames` frames: frame k moves every atom by a
/// small pseudo-random offset (at most `jitter` Å per axis, fixed per atom and frame), so each
/// frame is new work for the engine, as a trajectory is. For single-structure files (a PDB,
/// the 1M-atom box) in the viewer benchmark.
pub struct JitteredSource {
    inner: Arc<dyn FrameSource>,
    first: Arc<Frame>,
    frames: usize,
    jitter: f32,
}

impl JitteredSource {
    /// Plays frame 0 of `inner` as `frames` frames jittered by up to `jitter` Å.
    pub fn new(
        inner: Arc<dyn FrameSource>,
        frames: usize,
        jitter: f32,
    ) -> Result<JitteredSource, SourceError> {
        let first = inner.read_frame(0)?;
        Ok(JitteredSource {
            inner,
            first,
            frames,
            jitter,
        })
    }
}

/// A number in [-1, 1) from `(frame, atom)` (SplitMix64's finaliser).
fn unit_noise(frame: u64, atom: u64, axis: u64) -> f32 {
    let mut z = frame
        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
        .wrapping_add(atom.wrapping_mul(0xbf58_476d_1ce4_e5b9))
        .wrapping_add(axis.wrapping_mul(0x94d0_49bb_1331_11eb));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

impl FrameSource for JitteredSource {
    fn topology(&self) -> &Topology {
        self.inner.topology()
    }
    fn len(&self) -> usize {
        self.frames
    }
    fn read_frame(&self, index: usize) -> Result<Arc<Frame>, SourceError> {
        if index >= self.frames {
            return Err(SourceError::NoFrame {
                name: self.name(),
                index,
                len: self.frames,
            });
        }
        let mut frame = Frame::clone(&self.first);
        frame.index = index;
        if index > 0 {
            let k = index as u64;
            frame
                .positions
                .par_iter_mut()
                .enumerate()
                .for_each(|(i, p)| {
                    let i = i as u64;
                    *p += glam::Vec3::new(
                        unit_noise(k, i, 0),
                        unit_noise(k, i, 1),
                        unit_noise(k, i, 2),
                    ) * self.jitter;
                });
        }
        Ok(Arc::new(frame))
    }
    fn name(&self) -> String {
        format!("{} (jittered)", self.inner.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::source::helix_source;

    #[test]
    fn jittered_frames_are_new_but_close() {
        let inner: Arc<dyn FrameSource> = Arc::new(helix_source(20, 1));
        let first = inner.read_frame(0).unwrap();
        let s = JitteredSource::new(inner, 5, 0.3).unwrap();
        assert_eq!(s.len(), 5);
        assert_eq!(s.read_frame(0).unwrap().positions, first.positions);
        let f3 = s.read_frame(3).unwrap();
        assert_eq!(f3.index, 3);
        assert_ne!(f3.positions, first.positions);
        assert_eq!(
            f3.positions,
            s.read_frame(3).unwrap().positions,
            "not repeatable"
        );
        for (a, b) in f3.positions.iter().zip(&first.positions) {
            let d = (*a - *b).abs().max_element();
            assert!(d <= 0.3 + 1e-6, "moved {d} Å");
        }
        assert!(s.read_frame(5).is_err());
    }
}
