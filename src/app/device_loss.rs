//! Recovery from a lost GPU device (driver reset, GPU removed, `Device::destroy`). eframe keeps
//! one wgpu device for the life of its window and cannot replace it, and a window whose device
//! was lost cannot be reopened in the same process (winit's event loop does not survive the
//! egui-wgpu panic that a lost device causes). So the viewer watches the device, keeps its
//! session (files, surface parameters, particle options) up to date, and when the device is
//! lost [`super::run`] starts mdsurf again, on a new device, with that session as arguments.

use std::ffi::OsString;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::model::ParticleOptions;
use crate::surface::SurfaceParams;

/// Reopens allowed in one run before the viewer gives up (a device that keeps getting lost).
pub const MAX_REOPENS: usize = 3;

/// Uncaptured GPU errors reported on stderr per device; later ones are not printed.
const MAX_REPORTED_ERRORS: usize = 1;

/// Fault injection for tests: with this variable set, a scripted run destroys its window's
/// device after the first frame (in the first process only), as a driver reset would.
pub const LOSE_DEVICE_ENV: &str = "MDSURF_TEST_LOSE_DEVICE";

/// True once per process, in a scripted run of the first process, when [`LOSE_DEVICE_ENV`] is
/// set.
pub fn inject_loss_now() -> bool {
    static INJECTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    std::env::var_os(LOSE_DEVICE_ENV).is_some()
        && std::env::var_os(REOPENS_ENV).is_none()
        && !INJECTED.swap(true, Ordering::SeqCst)
}

/// Watches one wgpu device; [`DeviceWatch::lost`] says whether (and why) it was lost. Clones
/// share one state, so [`super::run`] keeps one while the window holds another.
#[derive(Debug, Clone, Default)]
pub struct DeviceWatch {
    reason: Arc<Mutex<Option<String>>>,
    device: Arc<Mutex<Option<wgpu::Device>>>,
}

impl DeviceWatch {
    /// Registers the device-lost callback of `device`; `wake` is called when it fires (the
    /// window asks for a repaint so it notices at once). Also replaces wgpu's default handler
    /// of uncaptured errors, which panics: until the window notices the loss, every call on the
    /// lost device fails, and any other GPU error should not take the window down either; the
    /// first few are reported on stderr, one line each.
    pub fn attach(&self, device: &wgpu::Device, wake: impl Fn() + Send + 'static) {
        let seen = self.reason.clone();
        let reported = AtomicUsize::new(0);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            let lost = seen.lock().map(|r| r.is_some()).unwrap_or(false);
            if !lost && reported.fetch_add(1, Ordering::Relaxed) < MAX_REPORTED_ERRORS {
                let text = error.to_string();
                let lines: Vec<&str> = text
                    .lines()
                    .map(str::trim)
                    .filter(|l| !l.is_empty())
                    .collect();
                eprintln!("GPU error (the window carries on): {}", lines.join(" "));
            }
        }));
        let reason = self.reason.clone();
        device.set_device_lost_callback(move |why, message| {
            if let Ok(mut slot) = reason.lock() {
                *slot = Some(format!("{why:?}: {message}"));
            }
            wake();
        });
        if let Ok(mut slot) = self.device.lock() {
            *slot = Some(device.clone());
        }
    }

    /// The reason, one line, once the device has been lost (as wgpu has reported it so far;
    /// the window's own per-frame polling delivers the report).
    pub fn lost(&self) -> Option<String> {
        self.reason.lock().ok().and_then(|r| r.clone())
    }

    /// [`DeviceWatch::lost`] after polling the device once, so that a loss the driver has
    /// signalled but no one has polled for yet is seen too (after the window has stopped).
    pub fn lost_after_poll(&self) -> Option<String> {
        if let Some(device) = self.device.lock().ok().and_then(|d| d.clone()) {
            let _ = device.poll(wgpu::PollType::Poll);
        }
        self.lost()
    }

    /// [`DeviceWatch::lost_after_poll`], first waiting up to `timeout` for the work submitted
    /// to the device: a device destroyed while work is in flight reports its loss only once
    /// that work has ended, which on a busy machine can come after the panic the loss caused.
    pub fn lost_after_wait(&self, timeout: std::time::Duration) -> Option<String> {
        if let Some(reason) = self.lost() {
            return Some(reason);
        }
        if let Some(device) = self.device.lock().ok().and_then(|d| d.clone()) {
            let _ = device.poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(timeout),
            });
        }
        self.lost_after_poll()
    }
}

/// How long a panicking window waits for its device to report a loss.
const LOSS_REPORT_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// What a reopened window restores.
#[derive(Debug, Clone)]
pub struct Reopen {
    /// Topology and trajectory that were open (`None`: the bundled demo).
    pub files: Option<(PathBuf, Option<PathBuf>)>,
    /// Applied surface parameters.
    pub params: SurfaceParams,
    /// Beads, colours and radius overrides.
    pub particles: ParticleOptions,
    /// The representations on screen.
    pub reps: Vec<crate::scene::representation::Representation>,
}

/// Environment variable counting the reopens of one viewer session (see [`MAX_REOPENS`]).
pub const REOPENS_ENV: &str = "MDSURF_REOPENS";

/// Command-line arguments that reopen the viewer on `session`, with the same engine choice
/// (`backend`: `cpu`, `gpu` or `auto`) and scripted-run flags (`script`); `state` is a state
/// file holding the session's representations.
pub fn reopen_args(
    session: &Reopen,
    backend: &str,
    script: &super::Script,
    state: Option<&std::path::Path>,
) -> Vec<OsString> {
    let mut args: Vec<OsString> = Vec::new();
    if let Some((top, traj)) = &session.files {
        args.push(top.into());
        args.extend(traj.iter().map(OsString::from));
    }
    let p = &session.params;
    for (flag, value) in [
        ("--spacing", p.spacing.to_string()),
        ("--radius-scale", p.radius_scale.to_string()),
        ("--isovalue", p.isovalue.to_string()),
        ("--quality", p.quality.to_string()),
        ("--color", session.particles.colours.to_string()),
        ("--backend", backend.to_string()),
    ] {
        args.push(flag.into());
        args.push(value.into());
    }
    for o in &session.particles.radius_overrides.0 {
        args.push("--radius".into());
        args.push(format!("{}={}", o.key, o.radius).into());
    }
    if session.particles.beads {
        args.push("--beads".into());
    }
    if let Some(state) = state {
        args.push("--state".into());
        args.push(state.into());
    }
    if let Some(n) = script.play_frames {
        args.push("--play-frames".into());
        args.push(n.to_string().into());
    }
    if let Some(shot) = &script.screenshot {
        args.push("--screenshot".into());
        args.push(shot.into());
    }
    if script.quit {
        args.push("--quit".into());
    }
    if let Some(log) = &script.memory_log {
        args.push("--memory-log".into());
        args.push(log.into());
    }
    args
}

/// The window's latest files and settings, kept up to date every frame so that
/// [`super::run`] can reopen on them whichever way the window ended.
pub type ReopenSlot = Arc<Mutex<Option<Reopen>>>;

/// The process's panic hook, as `std::panic::take_hook` returns it.
type PanicHook = dyn Fn(&std::panic::PanicHookInfo<'_>) + Send + Sync + 'static;

/// Runs one window: `Some(its result)`, or `None` when it panicked because its device was lost.
/// egui-wgpu panics when it cannot create a buffer, which is what every call on a lost device
/// does, and the loss may be signalled only after that frame began; such a panic is caught here
/// without its message. Any other panic goes on unwinding as before.
pub fn run_guarded<T>(watch: &DeviceWatch, window: impl FnOnce() -> T) -> Option<T> {
    let previous: Arc<PanicHook> = Arc::from(std::panic::take_hook());
    let (hook, quiet) = (previous.clone(), watch.clone());
    std::panic::set_hook(Box::new(move |info| {
        // Polling here (waiting briefly for the work in flight) is what delivers the loss
        // report in time. wgpu itself no longer panics (its error handler is replaced in
        // `attach`), so the panics that reach this hook come from egui-wgpu's own checks,
        // outside wgpu's locks.
        if quiet.lost_after_wait(LOSS_REPORT_WAIT).is_none() {
            hook(info);
        }
    }));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(window));
    drop(std::panic::take_hook());
    std::panic::set_hook(Box::new(move |info| previous(info)));
    match outcome {
        Ok(value) => Some(value),
        Err(_) if watch.lost_after_wait(LOSS_REPORT_WAIT).is_some() => None,
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicBool;

    #[test]
    fn reopen_arguments_carry_the_session() {
        let session = Reopen {
            files: Some(("a.gro".into(), Some("b.xtc".into()))),
            params: SurfaceParams {
                spacing: 1.5,
                radius_scale: 1.2,
                isovalue: 0.3,
                quality: crate::surface::Quality::High,
            },
            particles: ParticleOptions {
                beads: true,
                radius_overrides: crate::model::RadiusOverrides::parse_all(&["C=1.7"])
                    .expect("valid override"),
                colours: "chain".parse().expect("scheme"),
                exposure: None,
            },
            reps: Vec::new(),
        };
        let script = crate::app::Script {
            play_frames: Some(3),
            screenshot: Some("s.png".into()),
            quit: true,
            memory_log: None,
            ..Default::default()
        };
        let args: Vec<String> = reopen_args(
            &session,
            "gpu",
            &script,
            Some(std::path::Path::new("s.toml")),
        )
        .into_iter()
        .map(|a| a.into_string().expect("utf-8"))
        .collect();
        let line = args.join(" ");
        assert!(line.starts_with("a.gro b.xtc "), "{line}");
        for part in [
            "--spacing 1.5",
            "--radius-scale 1.2",
            "--isovalue 0.3",
            "--quality high",
            "--color chain",
            "--backend gpu",
            "--radius C=1.7",
            "--beads",
            "--play-frames 3",
            "--screenshot s.png",
            "--quit",
            "--state s.toml",
        ] {
            assert!(line.contains(part), "{part} missing from {line}");
        }
    }

    #[test]
    fn a_destroyed_device_is_reported_lost() {
        let gpu = match crate::render::HeadlessGpu::new() {
            Ok(gpu) => gpu,
            Err(err) if !crate::gpu::gpu_required() => {
                eprintln!("note: no GPU adapter ({err}); skipping");
                return;
            }
            Err(err) => panic!("REQUIRE_GPU=1 but no adapter: {err}"),
        };
        let woken = Arc::new(AtomicBool::new(false));
        let flag = woken.clone();
        let watch = DeviceWatch::default();
        watch.attach(&gpu.device, move || flag.store(true, Ordering::SeqCst));
        assert_eq!(watch.lost(), None, "a fresh device is not lost");
        gpu.device.destroy();
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
        let reason = watch.lost().expect("the destroyed device is reported lost");
        assert!(reason.contains("Destroyed"), "{reason}");
        assert!(woken.load(Ordering::SeqCst), "the window is woken");
    }
}
