//! The viewer's automatic runs, advanced one step per UI update so the window stays live: movie
//! export (seek each frame, wait for its surface, render offscreen, write the numbered PNG) and
//! the scripted run (`--play-frames N --screenshot FILE --quit`).

use std::path::PathBuf;

use super::Viewer;
use crate::app::device_loss;
use crate::app::state::Command;
use crate::app::timeline::TimelineCmd;
use crate::render::colour_bar::draw_colour_bar;
use crate::render::write_png;

/// What a scripted run does (all optional).
#[derive(Debug, Clone, Default)]
pub struct Script {
    /// Frames to play (each computed and shown) before the screenshot.
    pub play_frames: Option<usize>,
    /// Screenshot written through the app's screenshot path.
    pub screenshot: Option<PathBuf>,
    /// Close the window when done.
    pub quit: bool,
    /// Write the process's anonymous memory after each frame shown to this CSV (a leak check).
    pub memory_log: Option<PathBuf>,
    /// Console commands run first (`--script FILE`): the file and its (line number, line)s.
    pub commands: Option<(PathBuf, Vec<(usize, String)>)>,
}

/// This process's anonymous resident memory in KiB (`RssAnon` in `/proc/self/status`; Linux).
fn anonymous_memory_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("RssAnon:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

impl Viewer {
    /// Advances a running movie by at most one image per UI update.
    pub(super) fn step_movie(&mut self) {
        let Some(job) = self.movie.as_mut() else {
            return;
        };
        let Some(step) = job.next().cloned() else {
            let done = job.done;
            let video = self.movie.take().and_then(|j| j.video);
            match video.map(|v| (v.path().to_path_buf(), v.finish())) {
                None => self.core.status = format!("movie: wrote {done} images"),
                Some((path, Ok(summary))) => {
                    self.core.status = format!(
                        "movie: wrote {} ({} frames, {:.1} s)",
                        path.display(),
                        summary.frames,
                        summary.seconds
                    );
                }
                Some((_, Err(e))) => self.core.error = Some(format!("movie stopped: {e}")),
            }
            return;
        };
        if self.core.timeline.current != step.frame {
            self.core
                .apply(Command::Timeline(TimelineCmd::Seek(step.frame)));
            return;
        }
        if self.core.computing()
            || self
                .core
                .shown
                .as_ref()
                .is_none_or(|s| s.computed.frame != step.frame)
        {
            return;
        }
        let (Some(gpu), Some(job)) = (self.gpu.as_mut(), self.movie.as_mut()) else {
            return;
        };
        gpu.sync(&mut self.core);
        let mut camera = self.core.camera;
        camera.yaw = job.start_yaw;
        camera.turn(step.degrees);
        let bar = self.core.colour_bar();
        let result = gpu
            .snapshot(&camera, &self.core.render, job.size)
            .map_err(|e| e.to_string())
            .and_then(|mut img| {
                if let Some((map, range)) = bar {
                    draw_colour_bar(&mut img, map, range);
                }
                match job.video.as_mut() {
                    Some(video) => video.push(&img).map_err(|e| e.to_string()),
                    None => write_png(&step.path, &img).map_err(|e| e.to_string()),
                }
            });
        match result {
            Ok(()) => job.done += 1,
            Err(e) => {
                self.core.error = Some(format!("movie stopped: {e}"));
                self.movie = None;
            }
        }
    }

    /// The scripted run: show frames 0..N one by one (from a running simulation: the next N
    /// frames that reach the screen), then screenshot, then quit.
    pub(super) fn step_script(&mut self, ctx: &egui::Context) {
        if self.core.source.is_none() {
            if self.loading.is_none() && (self.core.error.is_some()) && self.script.quit {
                self.finish_script(ctx, self.core.error.clone());
            }
            return;
        }
        if let Some(e) = self.core.error.clone().filter(|_| self.script.quit) {
            return self.finish_script(ctx, Some(e));
        }
        if self.script.commands.is_some() {
            return self.step_commands(ctx);
        }
        let want = self
            .script
            .play_frames
            .unwrap_or(1)
            .min(self.core.timeline.len.max(1));
        let shown = self.core.shown.as_ref().map(|s| s.computed.frame);
        // A running simulation's newest frame moves on while one is computed, and the window
        // follows it: there each new frame on screen counts, as it comes (and, once the
        // simulation has stopped sending, the last one, as for a file).
        let live = self.core.is_live();
        let caught_up = |frame| !self.core.computing() && frame == self.core.timeline.current;
        let ready = match shown {
            Some(frame) if live => self.script_last_shown != Some(frame) || caught_up(frame),
            Some(frame) => caught_up(frame),
            None => false,
        };
        if !ready {
            return;
        }
        self.script_last_shown = shown;
        if self.script.memory_log.is_some()
            && let Some(kib) = anonymous_memory_kib()
        {
            self.memory_samples.push((self.script_played + 1, kib));
        }
        if self.script_played + 1 < want {
            if self.script_played == 1
                && device_loss::inject_loss_now()
                && let Some(gpu) = &self.gpu
            {
                gpu.destroy_device();
            }
            self.script_played += 1;
            if !live {
                self.core.apply(Command::Timeline(TimelineCmd::Step(1)));
            }
            return;
        }
        let result = match self.script.screenshot.clone() {
            Some(path) => self.screenshot(1, None, &path).err().map(|e| e.to_string()),
            None => None,
        };
        self.finish_script(ctx, result);
    }

    fn finish_script(&mut self, ctx: &egui::Context, error: Option<String>) {
        let mut error = error;
        if let Some(path) = &self.script.memory_log {
            let mut csv = String::from("frames_shown,anonymous_kib\n");
            for (shown, kib) in &self.memory_samples {
                csv.push_str(&format!("{shown},{kib}\n"));
            }
            if let Err(e) = std::fs::write(path, csv) {
                error.get_or_insert(format!("cannot write {}: {e}", path.display()));
            }
        }
        if let Some(asked) = self.script.play_frames
            && asked > self.core.timeline.len
            && error.is_none()
        {
            eprintln!(
                "note: --play-frames {asked} but the trajectory has {} frame(s); played them all",
                self.core.timeline.len
            );
        }
        eprintln!(
            "scripted run: showed {} frame(s), last frame {}, engine {}{}",
            self.script_played + 1,
            self.core.timeline.current,
            self.core.engine_name(),
            error
                .as_deref()
                .map_or(String::new(), |e| format!("; error: {e}"))
        );
        if let Ok(mut r) = self.script_result.lock() {
            *r = error;
        }
        if self.script.quit {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        self.script = Script::default();
        self.script.play_frames = Some(0);
    }

    /// Runs the next line of `--script FILE` once the current frame is on screen; the first
    /// error ends the scripted run with one line naming the file and line.
    fn step_commands(&mut self, ctx: &egui::Context) {
        let shown = self.core.shown.as_ref().map(|s| s.computed.frame);
        if self.loading.is_some()
            || self.core.computing()
            || shown != Some(self.core.timeline.current)
        {
            return;
        }
        let Some((path, lines)) = self.script.commands.as_mut() else {
            return;
        };
        if lines.is_empty() {
            self.script.commands = None;
            return;
        }
        let (number, line) = lines.remove(0);
        let at = format!("{}:{number}", path.display());
        let result = crate::app::console::parse(&line)
            .and_then(|c| c.map(|c| c.resolve(&self.core)).transpose());
        match result {
            Ok(outcome) => {
                let outcome = outcome.unwrap_or_default();
                if let Some(text) = outcome.output {
                    eprintln!("{at}: {text}");
                }
                for cmd in outcome.commands {
                    self.apply(ctx, cmd);
                }
                if let Some(e) = self.core.error.clone() {
                    self.finish_script(ctx, Some(format!("{at}: {e}")));
                }
            }
            Err(e) => {
                let e = format!("{at}: {e}");
                self.core.error = Some(e.clone());
                self.finish_script(ctx, Some(e));
            }
        }
    }

    pub(super) fn scripted(&self) -> bool {
        self.script.commands.is_some()
            || self.script.play_frames.is_some_and(|n| n > 0)
            || self.script.screenshot.is_some()
            || self.script.quit
    }
}
