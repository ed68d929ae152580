//! Which engine computes a surface, and the per-process state behind that choice: the GPU
//! device (opened on first use, never at import) and the thread pool the CPU engine runs on.
//!
//! Both are keyed by process id. A process forked from one that had opened them (the
//! `multiprocessing` and Dask process schedulers fork or spawn workers) inherits their memory
//! but not their threads: a child that finds its parent's device or pool leaks it without
//! touching it and opens its own. (A fork while another thread of the parent holds the GPU
//! lock, mid-computation, leaves that lock held in the child: fork before computing on threads,
//! or use the `spawn`/`forkserver` start methods.)
//!
//! The backend choice mirrors `mdsurf surface --backend`: `auto` is the GPU when a hardware
//! adapter exists, else the CPU engine (a software adapter such as lavapipe is slower than the
//! CPU engine).

use std::sync::{Arc, Mutex, PoisonError};

use mdsurf::gpu::{Backend, GpuEngine};
use mdsurf::surface::{CpuEngine, SurfaceEngine, VertexMode};
use rayon::ThreadPool;

/// The `backend=` argument: the CLI's [`Backend`] (`cpu`, `gpu` or `auto`, any case).
pub fn parse_backend(s: &str) -> Result<Backend, String> {
    match s.to_ascii_lowercase().as_str() {
        "cpu" => Ok(Backend::Cpu),
        "gpu" => Ok(Backend::Gpu),
        "auto" => Ok(Backend::Auto),
        _ => Err(format!("unknown backend '{s}' (expected cpu, gpu or auto)")),
    }
}

/// What opening the GPU gave in this process.
enum Probe {
    /// A hardware adapter's engine.
    Hardware(Box<GpuEngine>),
    /// A software adapter's engine (used only when asked for by name).
    Software(Box<GpuEngine>),
    /// Why no engine could be started.
    Failed(String),
}

/// Per-process state: the process it belongs to and its value.
struct Owned<T> {
    pid: u32,
    value: T,
}

static GPU: Mutex<Option<Owned<Probe>>> = Mutex::new(None);
static POOL: Mutex<Option<Owned<Arc<ThreadPool>>>> = Mutex::new(None);

/// The value in `slot` for this process, made by `make` when there is none yet or when the one
/// there was inherited from a parent process (which is then leaked, not dropped: its threads
/// and device do not exist in this process).
fn this_process<T>(slot: &mut Option<Owned<T>>, make: impl FnOnce() -> T) -> &mut T {
    let pid = std::process::id();
    if slot.as_ref().is_some_and(|o| o.pid != pid)
        && let Some(inherited) = slot.take()
    {
        std::mem::forget(inherited);
    }
    &mut slot
        .get_or_insert_with(|| Owned { pid, value: make() })
        .value
}

fn open_gpu() -> Probe {
    match GpuEngine::new() {
        Ok(gpu) if gpu.context().software_adapter => Probe::Software(Box::new(gpu)),
        Ok(gpu) => Probe::Hardware(Box::new(gpu)),
        Err(err) => Probe::Failed(err.to_string()),
    }
}

/// This process's thread pool for the CPU engine (and the GPU engine's CPU-side work).
fn pool() -> Result<Arc<ThreadPool>, String> {
    let mut guard = POOL.lock().unwrap_or_else(PoisonError::into_inner);
    let pid = std::process::id();
    if let Some(o) = guard.as_ref().filter(|o| o.pid == pid) {
        return Ok(o.value.clone());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("mdsurf-{i}"))
        .build()
        .map_err(|e| format!("cannot start the CPU engine's threads: {e}"))?;
    Ok(this_process(&mut guard, || Arc::new(pool)).clone())
}

/// Runs `f` on this process's thread pool: every parallel step (transformations, selections,
/// the CPU engine) runs there, never on rayon's global pool, which a forked child inherits
/// without its threads.
pub fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> Result<R, String> {
    Ok(pool()?.install(f))
}

/// The engine `backend` resolves to, in words, and whether it is the GPU. Opens the GPU when
/// the choice needs it.
pub fn describe(backend: Backend) -> Result<(bool, String), String> {
    if backend == Backend::Cpu {
        return Ok((false, "cpu".into()));
    }
    let mut guard = GPU.lock().unwrap_or_else(PoisonError::into_inner);
    Ok(match (this_process(&mut guard, open_gpu), backend) {
        (Probe::Hardware(gpu), _) | (Probe::Software(gpu), Backend::Gpu) => {
            (true, format!("gpu ({})", gpu.context().adapter_name))
        }
        (Probe::Software(gpu), _) => (
            false,
            format!(
                "cpu (the only GPU adapter, {}, is a software rasterizer, slower than the CPU \
                 engine; backend='gpu' uses it anyway)",
                gpu.context().adapter_name
            ),
        ),
        (Probe::Failed(err), Backend::Gpu) => return Err(no_gpu(err)),
        (Probe::Failed(err), _) => (false, format!("cpu (no usable GPU: {err})")),
    })
}

fn no_gpu(err: &str) -> String {
    format!("backend='gpu': cannot start the GPU engine: {err}")
}

/// True when this process has opened (or tried to open) the GPU.
pub fn gpu_opened() -> bool {
    let guard = GPU.lock().unwrap_or_else(PoisonError::into_inner);
    guard.as_ref().is_some_and(|o| o.pid == std::process::id())
}

/// Runs `f` with the engine `backend` picks, set to place vertices by `vertices`, on this
/// process's thread pool. The GPU engine is shared by the threads of a process (one at a time);
/// the CPU engine is made per call. Fails when the GPU was asked for and cannot start.
pub fn with_engine<R: Send>(
    backend: Backend,
    vertices: VertexMode,
    f: impl FnOnce(&mut dyn SurfaceEngine) -> R + Send,
) -> Result<R, String> {
    let pool = pool()?;
    let on_gpu = backend != Backend::Cpu && describe(backend)?.0;
    if !on_gpu {
        let mut cpu = CpuEngine::new();
        cpu.set_vertices(vertices);
        return Ok(pool.install(|| f(&mut cpu)));
    }
    let mut guard = GPU.lock().unwrap_or_else(PoisonError::into_inner);
    match this_process(&mut guard, open_gpu) {
        Probe::Hardware(gpu) | Probe::Software(gpu) => {
            gpu.set_vertices(vertices);
            Ok(pool.install(|| f(gpu.as_mut())))
        }
        Probe::Failed(err) => Err(no_gpu(err)),
    }
}
