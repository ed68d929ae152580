//! `mdsurf bench --viewer`: plays a trajectory through the viewer's own frame loop offscreen
//! ([`mdsurf::app::offscreen`]: the window's worker, state, timeline and renderer on a
//! headless device, no window or X server) and prints frames shown per second, frames dropped,
//! per-frame compute, latency and draw times (medians and 95th percentiles) and peak host and
//! GPU memory.

use std::sync::Arc;

use anyhow::{Result, anyhow};
use mdsurf::app::offscreen::{JitteredSource, PlayOptions, PlayReport, play};
use mdsurf::app::source::open_files;
use mdsurf::gpu::GpuContext;
use mdsurf::render::RenderSettings;
use mdsurf::scene::representation::Representation;

use super::bench::BenchArgs;
use super::bench_table::peak_rss_bytes;
use super::common::demo_files;

/// Runs the viewer benchmark the arguments ask for and prints its report.
pub fn run(args: &BenchArgs) -> Result<()> {
    let (top, traj) = match &args.top {
        Some(top) => (top.clone(), args.traj.clone()),
        None => {
            let (gro, xtc) = demo_files()?;
            (gro, Some(xtc))
        }
    };
    let mut source = open_files(&top, traj.as_deref()).map_err(|e| anyhow!("{e}"))?;
    if source.len() < 2 || args.jitter_frames.is_some() {
        let frames = args.jitter_frames.unwrap_or(args.frames) as usize;
        let jittered = JitteredSource::new(source, frames, 0.3).map_err(|e| anyhow!("{e}"))?;
        source = Arc::new(jittered);
    }
    let ctx = GpuContext::new_headless().map_err(|e| anyhow!("--viewer needs a GPU: {e}"))?;
    let mut base = Representation::default();
    base.set_params(&args.params.params()?);
    base.vertices = args.params.vertex_mode();
    base.radii = args.params.radius_set();
    base.colour = args.particles.options()?.colours;
    let opts = PlayOptions {
        size: args.size,
        frames: args.frames as usize,
        play_fps: args.play_fps,
        base,
        render: {
            let mut render = RenderSettings::default();
            args.look.apply(&mut render);
            render
        },
        density_gather: args.density_gather.into(),
    };
    let atoms = source.topology().len();
    let name = source.name();
    let frames_in_source = source.len();
    eprintln!(
        "viewer benchmark: {name}, {atoms} atoms, {frames_in_source} frames, {} x {} pixels, \
         timeline at {} fps, on {} ...",
        opts.size[0], opts.size[1], opts.play_fps, ctx.adapter_name
    );
    let report = play(&ctx, source, &opts).map_err(|e| anyhow!("--viewer: {e}"))?;
    println!(
        "{}",
        format_report(&report, &name, atoms, &opts, &ctx.adapter_name)
    );
    Ok(())
}

/// Median and 95th percentile of `v` in ms ("-" when empty).
fn spread(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |q: f64| s[((s.len() - 1) as f64 * q).round() as usize];
    format!("{:.2} ms (p95 {:.2})", at(0.5), at(0.95))
}

/// The outlines' and shadows' share of the draw: the draws alone with the look against the same
/// draws with both off, interleaved (median of the pairs' ratios); a dash without them.
fn look_cost(r: &PlayReport) -> String {
    if r.draw_alone_plain_ms.is_empty() {
        return "  look's extra cost  - (no outlines or shadows)".into();
    }
    let mut ratios: Vec<f64> = r
        .draw_alone_ms
        .iter()
        .zip(&r.draw_alone_plain_ms)
        .map(|(with, without)| with / without.max(1e-9) - 1.0)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    format!(
        "  look's extra cost  {:+.1} % over the same draw without outlines and shadows ({}; median of {} interleaved pairs)",
        median * 100.0,
        spread(&r.draw_alone_plain_ms),
        ratios.len()
    )
}

/// The report as aligned lines.
fn format_report(
    r: &PlayReport,
    name: &str,
    atoms: usize,
    opts: &PlayOptions,
    adapter: &str,
) -> String {
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    let rss = peak_rss_bytes().map_or("-".into(), |b| format!("{:.0} MiB", mib(b)));
    [
        format!("viewer benchmark on {adapter}"),
        format!("  input              {name} ({atoms} atoms)"),
        format!(
            "  look               outlines {} px, shadows {}",
            opts.render.outline_width, opts.render.shadows
        ),
        format!("  representations    {}", r.reps.join(", ")),
        format!(
            "  picture            {} x {} pixels, timeline at {} fps for {} frames",
            opts.size[0], opts.size[1], opts.play_fps, r.frames_played
        ),
        format!(
            "  shown              {} frames in {:.2} s: {:.1} fps",
            r.frames_shown,
            r.wall_s,
            r.shown_fps()
        ),
        format!("  dropped            {} frames", r.frames_dropped()),
        format!("  compute per frame  {}", spread(&r.compute_ms)),
        format!("    of which reading {}", spread(&r.read_ms)),
        format!("  latency            {}", spread(&r.latency_ms)),
        format!("  draw, to GPU done  {}", spread(&r.draw_ms)),
        format!("  draw, host side    {}", spread(&r.draw_host_ms)),
        format!("  draw alone         {}", spread(&r.draw_alone_ms)),
        look_cost(r),
        format!("  triangles          {}", r.triangles),
        format!("  peak host memory   {rss}"),
        format!(
            "  GPU memory         {:.0} MiB in the surface engines",
            mib(r.engine_bytes)
        ),
    ]
    .join("\n")
}
