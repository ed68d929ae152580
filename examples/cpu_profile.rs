//! Profiles the CPU surface engine on a large synthetic system (issue 2 section 3): the adk
//! protein from `../shared/data/adk_open.pdb` tiled on a near-cubic lattice with 2 Å between
//! copies and a little jitter, up to a million atoms, at H = 1 Å, R = 1, I = 0.5, quality high.
//! Prints per-stage medians in ms.
//!
//! `cargo run --release --example cpu_profile -- [ATOMS] [REPEATS] [--colour] [--pdb FILE]`
//! (measure peak memory with `/usr/bin/time -v`).

use std::time::Instant;

use glam::Vec3;
use mdsurf::surface::bin::bin_atoms;
use mdsurf::surface::{
    AtomSet, CpuEngine, Quality, SurfaceEngine, SurfaceParams, density, marching_cubes,
};

/// Gap between copies' bounding boxes in Å.
const GAP: f32 = 2.0;
/// Jitter amplitude in Å (uniform within ± this per coordinate).
const JITTER: f32 = 0.1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let colour = args.iter().any(|a| a == "--colour");
    let pdb = args
        .iter()
        .position(|a| a == "--pdb")
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/adk_open.pdb").into()
        });
    let numbers: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let count = numbers.first().copied().unwrap_or(1_000_000);
    let repeats = numbers.get(1).copied().unwrap_or(5).max(1);

    let (pos, radii) = read_pdb(&pdb)?;
    let (positions, radii) = tile(&pos, &radii, count);
    let colours: Vec<[f32; 3]> = (0..positions.len())
        .map(|i| [(i % 7) as f32 / 6.0, (i % 5) as f32 / 4.0, 0.5])
        .collect();
    let atoms = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: colour.then_some(&colours[..]),
    };
    let params = SurfaceParams {
        spacing: 1.0,
        radius_scale: 1.0,
        isovalue: 0.5,
        quality: Quality::High,
    };
    let mut engine = CpuEngine::new();
    println!(
        "{} atoms from {pdb}, colour {colour}, {} threads",
        positions.len(),
        rayon::current_num_threads()
    );
    // One engine run (validation, summary), then the stages alone with wall and CPU time: the
    // machine is shared, so CPU seconds / threads estimate the wall time on idle cores.
    let out = engine.compute(&atoms, &params)?;
    println!(
        "engine: grid {:?}, {} vertices, {} triangles, area {:.0} A2, volume {:.0} A3, {:?}",
        out.grid.dims,
        out.mesh.vertex_count(),
        out.mesh.triangle_count(),
        out.area,
        out.volume,
        out.timings
    );
    drop(out);
    let grid = engine.plan(&atoms, &params)?;
    // The engine keeps its buffers; free them so the stage runs below measure their own.
    drop(engine);
    let mut rows = Vec::new();
    let mut vol = mdsurf::surface::DensityVolume::default();
    let mut scratch = marching_cubes::McScratch::default();
    for r in 0..repeats {
        let mut row = [0.0f64; 6];
        let (bins, w, c) = timed(|| bin_atoms(&atoms, &params, &grid, density::slab_planes(&grid)));
        (row[0], row[1]) = (w, c);
        let ((), w, c) =
            timed(|| density::compute_binned_into(&bins, &params, &grid, colour, &mut vol));
        (row[2], row[3]) = (w, c);
        drop(bins);
        let ((mesh, area, volume), w, c) = timed(|| {
            let mesh = marching_cubes::extract_with(&grid, &vol, params.isovalue, &mut scratch);
            let (a, v) = mesh.area_and_volume();
            (mesh, a, v)
        });
        (row[4], row[5]) = (w, c);
        println!(
            "run {r}: {} triangles, area {area:.0}, volume {volume:.0}; wall/cpu ms: bin {:.0}/{:.0}, \
             density {:.0}/{:.0}, mc {:.0}/{:.0}",
            mesh.triangle_count(),
            row[0],
            row[1],
            row[2],
            row[3],
            row[4],
            row[5]
        );
        rows.push(row);
    }
    let median = |k: usize| {
        let mut v: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let threads = rayon::current_num_threads() as f64;
    println!(
        "median of {repeats} (wall ms / cpu ms / cpu ms per thread): bin {:.0}/{:.0}/{:.0}, \
         density {:.0}/{:.0}/{:.0}, mc {:.0}/{:.0}/{:.0}; density+mc wall {:.0}, cpu/thread {:.0}",
        median(0),
        median(1),
        median(1) / threads,
        median(2),
        median(3),
        median(3) / threads,
        median(4),
        median(5),
        median(5) / threads,
        median(2) + median(4),
        (median(3) + median(5)) / threads
    );
    Ok(())
}

/// Runs `f`, returning its result, wall time and process CPU time (user + system) in ms.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (c0, t0) = (cpu_ms(), Instant::now());
    let out = f();
    (out, t0.elapsed().as_secs_f64() * 1e3, cpu_ms() - c0)
}

/// CPU time of this process in ms from `/proc/self/stat` (10 ms ticks; 0 where unavailable).
fn cpu_ms() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = after.split_whitespace().collect();
    let tick = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // Fields 14 and 15 of the line (utime, stime) are 12 and 13 after the command name.
    (tick(11) + tick(12)) * 10.0
}

/// Positions (Å) and radii (Å, DESIGN section 2 by element) of the ATOM/HETATM records.
fn read_pdb(path: &str) -> Result<(Vec<Vec3>, Vec<f32>), Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut pos = Vec::new();
    let mut radii = Vec::new();
    for line in text.lines() {
        if !(line.starts_with("ATOM") || line.starts_with("HETATM")) || line.len() < 54 {
            continue;
        }
        let f = |a: usize, b: usize| line[a..b].trim().parse::<f32>();
        pos.push(Vec3::new(f(30, 38)?, f(38, 46)?, f(46, 54)?));
        let element = line
            .get(76..78)
            .map(str::trim)
            .filter(|e| !e.is_empty())
            .unwrap_or_else(|| {
                line[12..16]
                    .trim()
                    .trim_start_matches(|c: char| c.is_ascii_digit())
            });
        radii.push(match element.chars().next() {
            Some('H') => 1.0,
            Some('C') => 1.5,
            Some('N') => 1.4,
            Some('O') => 1.3,
            Some('S') => 1.9,
            Some('P') => 1.8,
            _ => 1.5,
        });
    }
    if pos.is_empty() {
        return Err(format!("{path}: no atoms").into());
    }
    Ok((pos, radii))
}

/// Tiles the structure on a near-cubic lattice (x fastest) with [`GAP`] between bounding boxes
/// and jitter of ± [`JITTER`] per coordinate, until `count` atoms exist.
fn tile(pos: &[Vec3], radii: &[f32], count: usize) -> (Vec<Vec3>, Vec<f32>) {
    let (lo, hi) = pos.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(l, h), p| (l.min(*p), h.max(*p)),
    );
    let stride = hi - lo + Vec3::splat(GAP);
    let copies = count.div_ceil(pos.len());
    let side = (copies as f64).cbrt().ceil() as usize;
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rand = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let mut out_p = Vec::with_capacity(count);
    let mut out_r = Vec::with_capacity(count);
    'outer: for c in 0..copies {
        let cell = Vec3::new(
            (c % side) as f32,
            (c / side % side) as f32,
            (c / (side * side)) as f32,
        );
        for (p, r) in pos.iter().zip(radii) {
            if out_p.len() == count {
                break 'outer;
            }
            let jitter = Vec3::new(rand(), rand(), rand()) * JITTER;
            out_p.push(*p + cell * stride + jitter);
            out_r.push(*r);
        }
    }
    (out_p, out_r)
}
