//! Table 1's GPU memory without a device (`mdsurf bench --table1 --plan-only`): the same
//! synthetic systems, grids and frame plans as the measured table, under given device limits,
//! with the mesh buffers sized from the CPU engine's surface or at their largest.

use super::*;

/// GPU memory of an 80 GB card in bytes (decimal, as sold; 80 GiB would be 7 % more).
pub const GPU_80GB: u64 = 80_000_000_000;

/// How [`plan_rows`] sizes the mesh buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshSizing {
    /// From the vertex and triangle counts of the CPU engine's surface of the row's first
    /// frame (the GPU engine's mesh has the same counts), under the GPU engine's growth rule
    /// ([`MeshCapacity::settled`]). Costs a CPU surface per row (about 15 s for the
    /// 22.8M-atom row on two cores).
    CpuSurface,
    /// Every mesh buffer at the largest binding ([`MeshCapacity::largest`]): an upper bound
    /// for any surface, and no surface computed.
    Largest,
}

/// One row of Table 1 sized without a GPU (bytes as in [`GpuEngine::gpu_bytes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedRow {
    /// The paper's row.
    pub paper: PaperRow,
    /// Atoms in the synthetic system.
    pub atoms: usize,
    /// Grid samples along x, y, z (of the first frame).
    pub grid: [u32; 3],
    /// Z-slabs per frame.
    pub slabs: usize,
    /// Vertices and triangles of the CPU surface ([`MeshSizing::CpuSurface`] only).
    pub counts: Option<(u64, u64)>,
    /// Mesh capacity of each output set.
    pub mesh: MeshCapacity,
    /// GPU memory of the engine after the row's frames, with `mesh`.
    pub memory: GpuMemory,
    /// GPU memory with the mesh buffers at their largest: the most the row can take.
    pub bound: GpuMemory,
}

/// Sizes the GPU memory of `paper_rows` (up to `opts.max_atoms`) without a device: for each
/// row the synthetic system and first frame [`run_rows`] would compute, its grid and frame
/// plan under `limits` and the engine's default volume budget, and the engine's buffers for
/// it ([`BufferPlan::fresh_memory`]), with the mesh sized as `sizing` says. `progress` hears
/// a line per row.
pub fn plan_rows(
    structure: &Structure,
    paper_rows: &[PaperRow],
    opts: &Table1Options,
    limits: &DeviceLimits,
    sizing: MeshSizing,
    mut progress: impl FnMut(&str),
) -> Result<Vec<PlannedRow>, Table1Error> {
    let colours = if opts.colours {
        structure.colours.as_deref()
    } else {
        None
    };
    let max_binding = limits.max_binding();
    let mut rows = Vec::new();
    for (index, paper) in paper_rows.iter().enumerate() {
        if opts.max_atoms.is_some_and(|m| paper.atoms > m) {
            continue;
        }
        progress(&format!(
            "table 1 plan: {} atoms at H = {} ...",
            paper.atoms, paper.spacing
        ));
        let fail = |source| Table1Error::Surface {
            atoms: paper.atoms,
            spacing: paper.spacing,
            source,
        };
        let system = row_system(structure, colours, index, paper)?;
        let params = row_params(paper);
        let positions = system.frame(0);
        let atoms = AtomSet {
            positions: &positions,
            radii: system.radii(),
            colours: system.colours(),
        };
        // What the engine's first frame does: bounds, grid, plan, the per-atom size check.
        let (lo, hi, max_r) = crate::gpu::inputs::bounds(&atoms, true, None).map_err(fail)?;
        let grid = GridSpec::for_atoms(&[lo, hi], &[max_r], &params).map_err(fail)?;
        let plan = plan_frame(
            grid,
            &params,
            max_r,
            max_binding,
            limits.volume_budget(),
            None,
        )
        .map_err(|e| fail(e.into()))?;
        let n = system.len() as u64;
        if n * 16 > max_binding {
            return Err(fail(
                GpuError::TooLarge {
                    what: "the sorted atom array",
                    needed: n * 16,
                    limit: max_binding,
                }
                .into(),
            ));
        }
        let (counts, bricks) = match sizing {
            MeshSizing::CpuSurface => {
                let mut cpu = CpuEngine::new();
                cpu.set_keep_mesh(false);
                let out = cpu.compute(&atoms, &params).map_err(fail)?;
                let bricks = count_reached_bricks(
                    &plan,
                    atoms.positions,
                    atoms.radii,
                    params.radius_scale,
                    params.cutoff(),
                );
                let counts = (out.vertex_count() as u64, out.triangle_count() as u64);
                (Some(counts), Some(bricks.slab_need(&plan)))
            }
            MeshSizing::Largest => (None, None),
        };
        let largest = MeshCapacity::largest(max_binding);
        let mesh = counts.map_or(largest, |c| {
            MeshCapacity::settled(first_mesh_want(&plan), c, DEFAULT_HEADROOM, max_binding)
        });
        let with_colour = atoms.colours.is_some();
        // The engine runs on sparse bricks: its brick slots settle at the reached count (the
        // bricks its mark pass reaches, counted on the host), or hold every brick a slab can
        // use for the bound.
        let largest_slots = largest_brick_slots(&plan, max_binding);
        let slots = bricks.map_or(largest_slots, |reached| {
            settled_brick_slots(&plan, reached, max_binding)
        });
        let memory =
            BufferPlan::new(&plan, n, with_colour, mesh, Some(slots), limits).fresh_memory();
        let bound = BufferPlan::new(&plan, n, with_colour, largest, Some(largest_slots), limits)
            .fresh_memory();
        rows.push(PlannedRow {
            paper: *paper,
            atoms: system.len(),
            grid: grid.dims,
            slabs: plan.slabs.len(),
            counts,
            mesh,
            memory,
            bound,
        });
    }
    Ok(rows)
}

/// The planned rows as text: memory by group in MiB, the total, the bound with the mesh
/// buffers at their largest, and whether that bound fits [`GPU_80GB`].
pub fn format_plan(rows: &[PlannedRow], limits: &DeviceLimits, device: &str) -> String {
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    let mesh = if rows.iter().any(|r| r.counts.is_some()) {
        format!(
            "mesh buffers from the CPU surface's counts under the engine's growth rule \
             (headroom {DEFAULT_HEADROOM})"
        )
    } else {
        "mesh buffers at the largest binding (no surface computed)".to_string()
    };
    let mut s = format!(
        "Table 1 GPU memory without a device, for {device}: largest storage binding {} bytes, \
         largest buffer {} bytes, volume budget {} bytes; {mesh}, two output sets; \
         MiB = 2^20 bytes; bound = mesh buffers at the largest binding\n",
        limits.max_binding(),
        limits.max_buffer_size,
        limits.volume_budget(),
    );
    s += &format!(
        "{:>10} {:>4} {:>15} {:>5} {:>10} {:>10} | {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} | {:>9} {:>9} {:>7}\n",
        "atoms",
        "H",
        "grid",
        "slabs",
        "vertices",
        "triangles",
        "atoms",
        "cells",
        "volumes",
        "bricks",
        "mesh",
        "fixed",
        "total MiB",
        "bound MiB",
        "fits 80GB"
    );
    for r in rows {
        let (v, t) = r
            .counts
            .map_or(("-".to_string(), "-".to_string()), |(v, t)| {
                (v.to_string(), t.to_string())
            });
        let m = &r.memory;
        s += &format!(
            "{:>10} {:>4.1} {:>15} {:>5} {:>10} {:>10} | {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} | {:>9.0} {:>9.0} {:>7}\n",
            r.atoms,
            r.paper.spacing,
            format!("{}x{}x{}", r.grid[0], r.grid[1], r.grid[2]),
            r.slabs,
            v,
            t,
            mib(m.atoms),
            mib(m.cells),
            mib(m.volumes),
            mib(m.bricks),
            mib(m.mesh),
            mib(m.fixed),
            mib(m.total()),
            mib(r.bound.total()),
            if r.bound.total() <= GPU_80GB {
                "yes"
            } else {
                "no"
            },
        );
    }
    s
}

/// Tiles the first frame of `top` (+ `traj`) and sizes each row's GPU memory for an 80 GB
/// NVIDIA GPU ([`DeviceLimits::NVIDIA_80GB`]) without a device; the mesh as `sizing` says.
#[cfg(feature = "app")]
pub fn table1_plan(
    top: &Path,
    traj: Option<&Path>,
    opts: &Table1Options,
    sizing: MeshSizing,
) -> Result<String, Table1Error> {
    let structure = Structure::from_file(top, traj)?;
    let limits = DeviceLimits::NVIDIA_80GB;
    let rows = plan_rows(&structure, &PAPER_ROWS, opts, &limits, sizing, |line| {
        eprintln!("{line}")
    })?;
    Ok(format_plan(
        &rows,
        &limits,
        "an 80 GB NVIDIA H100 under Vulkan (its limits as wgpu reported them on one)",
    ))
}
