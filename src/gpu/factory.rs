//! The one place that decides which surface engine runs: the GPU engine on a given device (the
//! viewer's eframe device, `render`'s headless device) or on a headless device opened here
//! ([`GpuContext::new_headless`], the one device-opening function), or the CPU reference
//! engine. `--backend auto` passes over a software adapter (Mesa lavapipe, WARP: correct but
//! slower than the CPU engine). Used by the viewer, `render`, `surface` and `bench`.

use super::GpuError;
use super::context::GpuContext;
use super::engine::GpuEngine;

/// Which surface engine to use.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Backend {
    /// The CPU reference engine.
    Cpu,
    /// The GPU engine, even on a software adapter; an error when it cannot start.
    Gpu,
    /// The GPU engine on a hardware adapter, else the CPU engine.
    #[default]
    Auto,
}

/// What [`pick_engine`] chose.
#[derive(Debug)]
pub enum Picked {
    /// The GPU engine (on the device it was given, or a headless one).
    Gpu(Box<GpuEngine>),
    /// The CPU engine; `why` says why the GPU was passed over (none for `Backend::Cpu`).
    Cpu {
        /// One line for stderr.
        why: Option<String>,
    },
}

/// The engine for `backend`: on `device` when given, else on a newly opened headless device.
/// `Backend::Gpu` fails when no GPU engine starts; `Backend::Auto` falls back to the CPU
/// engine and says why.
pub fn pick_engine(backend: Backend, device: Option<GpuContext>) -> Result<Picked, GpuError> {
    if backend == Backend::Cpu {
        return Ok(Picked::Cpu { why: None });
    }
    let ctx = match device.map_or_else(GpuContext::new_headless, Ok) {
        Ok(ctx) => ctx,
        Err(e) if backend == Backend::Auto => {
            return Ok(Picked::Cpu {
                why: Some(format!("no usable GPU: {e}")),
            });
        }
        Err(e) => return Err(e),
    };
    if backend == Backend::Auto && ctx.software_adapter {
        return Ok(Picked::Cpu {
            why: Some(format!(
                "the only GPU adapter, {}, is a software rasterizer, slower than the CPU \
                 engine; --backend gpu uses it anyway",
                ctx.adapter_name
            )),
        });
    }
    match GpuEngine::with_context(ctx) {
        Ok(engine) => Ok(Picked::Gpu(Box::new(engine))),
        Err(e) if backend == Backend::Auto => Ok(Picked::Cpu {
            why: Some(format!("the GPU engine cannot start: {e}")),
        }),
        Err(e) => Err(e),
    }
}
