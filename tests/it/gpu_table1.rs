//! The Table 1 runner end to end on a scaled-down row (lavapipe is slow): tiles the bundled demo
//! structure, times a few jittered frames and formats the table. Speed itself is measured by
//! `mdsurf bench --table1 --backend gpu` on real hardware, never asserted here.

use std::path::Path;

use mdsurf::gpu::table1::{PaperRow, Structure, Table1Options, format, run_rows};

#[test]
fn small_row_runs_and_formats() {
    let Some(ctx) = crate::gpu_support::context() else {
        return;
    };
    let top = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/md_1u19.gro");
    let structure = Structure::from_file(&top, None).expect("demo structure");
    let row = PaperRow {
        atoms: 12_000,
        spacing: 2.0,
        t_sort: 0.001,
        t_d: 0.001,
        t_mc: 0.001,
    };
    let opts = Table1Options {
        repeats: 2,
        ..Default::default()
    };
    let mut lines = 0;
    let rows = run_rows(&ctx, &structure, &[row], &opts, |_| lines += 1).expect("table row");
    assert_eq!(lines, 1);
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    assert_eq!(r.atoms, 12_000);
    assert!(r.triangles > 1000, "{} triangles", r.triangles);
    assert!(
        r.density_ms > 0.0 && r.mc_ms > 0.0 && r.bin_ms > 0.0,
        "{r:?}"
    );
    assert!(r.frame_ms >= r.upload_ms);
    let voxels: u64 = r.grid.iter().map(|&d| d as u64).product();
    // Memory target: 48 bytes per voxel + 48 per atom, plus the mesh (36 B per vertex, 12 per
    // triangle; vertices are fewer than triangles).
    let budget = 48 * voxels + 48 * r.atoms as u64 + 48 * r.triangles as u64 * 2 + (1 << 20);
    assert!(
        r.gpu_bytes <= budget,
        "{} GPU bytes > budget {budget}",
        r.gpu_bytes
    );
    let text = format(&rows, &ctx.adapter_name, ctx.timestamps);
    assert!(text.contains("12000"), "{text}");
    eprintln!("{text}");
}
