//! The result table of `mdsurf bench`: one row per case and engine with per-stage medians (ms),
//! frames per second and peak memory, as aligned text for the terminal and as CSV.
//! `exposure_ms` is the GPU's pass of the SES preset's exposure radii (`--preset ses`,
//! [`mdsurf::gpu::exposure`]); the CPU engine's counts are host work before it, in no column.
//! `per_residue_ms` (`--per-residue`) is the median time of the area per atom and per residue
//! on the frame's mesh, after `compute_ms` and not in it.
//! `bricks_active_%` is "-" on the GPU engine: it marches every brick some atom reaches
//! (`bricks_occupied_%`) and does not count the bricks the surface crosses.

use super::bench::BenchResult;

/// Column headers, in order (text and CSV share them).
pub const COLUMNS: [&str; 20] = [
    "case",
    "backend",
    "atoms",
    "H_A",
    "grid",
    "triangles",
    "read_ms",
    "upload_ms",
    "exposure_ms",
    "bin_ms",
    "density_ms",
    "mc_ms",
    "compute_ms",
    "per_residue_ms",
    "frames_per_s",
    "peak_rss_MB",
    "gpu_MB",
    "gpu_objects_per_frame",
    "bricks_occupied_%",
    "bricks_active_%",
];

/// A formatted benchmark table.
#[derive(Debug, Clone, Default)]
pub struct Table {
    rows: Vec<[String; COLUMNS.len()]>,
}

impl Table {
    /// One row per result.
    pub fn from_results(results: &[BenchResult]) -> Table {
        let rows = results
            .iter()
            .map(|r| {
                let s = &r.stages;
                [
                    r.case.clone(),
                    r.backend.clone(),
                    r.atoms.to_string(),
                    format!("{}", r.spacing),
                    format!("{}x{}x{}", r.dims[0], r.dims[1], r.dims[2]),
                    r.triangles.to_string(),
                    format!("{:.2}", r.read_ms),
                    format!("{:.2}", s.upload_ms),
                    format!("{:.2}", s.exposure_ms),
                    format!("{:.2}", s.bin_ms),
                    format!("{:.2}", s.density_ms),
                    format!("{:.2}", s.mc_ms),
                    format!("{:.2}", r.compute_wall_ms),
                    r.per_residue_ms
                        .map(|ms| format!("{ms:.2}"))
                        .unwrap_or_else(|| "-".into()),
                    format!("{:.2}", r.fps),
                    r.peak_rss
                        .map(|b| format!("{:.0}", b as f64 / 1e6))
                        .unwrap_or_else(|| "-".into()),
                    r.gpu_bytes
                        .map(|b| format!("{:.0}", b as f64 / 1e6))
                        .unwrap_or_else(|| "-".into()),
                    r.gpu_objects_per_frame
                        .map(|n| format!("{n:.1}"))
                        .unwrap_or_else(|| "-".into()),
                    r.bricks
                        .map(|b| format!("{:.1}", 100.0 * b.occupied_fraction()))
                        .unwrap_or_else(|| "-".into()),
                    r.bricks
                        .filter(|_| r.bricks_active_counted)
                        .map(|b| format!("{:.1}", 100.0 * b.active_fraction()))
                        .unwrap_or_else(|| "-".into()),
                ]
            })
            .collect();
        Table { rows }
    }

    /// Aligned text: the first two columns left-aligned, numbers right-aligned.
    pub fn to_text(&self) -> String {
        let mut widths = COLUMNS.map(str::len);
        for row in &self.rows {
            for (w, cell) in widths.iter_mut().zip(row) {
                *w = (*w).max(cell.chars().count());
            }
        }
        let line = |cells: &[String]| -> String {
            let parts: Vec<String> = cells
                .iter()
                .zip(widths)
                .enumerate()
                .map(|(i, (c, w))| {
                    if i < 2 {
                        format!("{c:<w$}")
                    } else {
                        format!("{c:>w$}")
                    }
                })
                .collect();
            parts.join("  ").trim_end().to_string()
        };
        let header: Vec<String> = COLUMNS.iter().map(|s| s.to_string()).collect();
        let mut out = vec![line(&header)];
        out.extend(self.rows.iter().map(|r| line(r)));
        out.join("\n")
    }

    /// CSV with a header line; fields containing commas or quotes are quoted.
    pub fn to_csv(&self) -> String {
        let mut out = COLUMNS.join(",");
        out.push('\n');
        for row in &self.rows {
            let fields: Vec<String> = row.iter().map(|f| csv_field(f)).collect();
            out.push_str(&fields.join(","));
            out.push('\n');
        }
        out
    }
}

fn csv_field(f: &str) -> String {
    if f.contains([',', '"', '\n']) {
        format!("\"{}\"", f.replace('"', "\"\""))
    } else {
        f.to_string()
    }
}

/// Peak resident set size of this process in bytes (Linux `VmHWM`), `None` elsewhere.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(case: &str) -> BenchResult {
        BenchResult {
            case: case.into(),
            backend: "cpu".into(),
            atoms: 5547,
            spacing: 1.0,
            dims: [60, 70, 80],
            triangles: 12345,
            read_ms: 0.5,
            compute_wall_ms: 12.0,
            fps: 80.0,
            ..Default::default()
        }
    }

    #[test]
    fn text_is_aligned_and_csv_is_quoted() {
        let t = Table::from_results(&[result("demo"), result("synthetic 10, tiled")]);
        let text = t.to_text();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        // Right-aligned numbers end in the same column on every line.
        let end = |l: &str| l.find("80.00").map(|i| i + 5);
        assert_eq!(end(lines[1]), end(lines[2]));
        assert!(lines[0].starts_with("case"));
        let csv = t.to_csv();
        assert!(csv.contains("\"synthetic 10, tiled\",cpu,5547,1,60x70x80,12345"));
        assert_eq!(csv.lines().count(), 3);
    }

    #[test]
    fn uncounted_active_bricks_print_a_dash() {
        let bricks = mdsurf::surface::BrickStats {
            brick_size: 8,
            bricks: 200,
            occupied: 50,
            active: 50,
        };
        let gpu = BenchResult {
            backend: "gpu".into(),
            bricks: Some(bricks),
            bricks_active_counted: false,
            ..result("demo")
        };
        let cpu = BenchResult {
            backend: "cpu".into(),
            bricks: Some(mdsurf::surface::BrickStats {
                active: 20,
                ..bricks
            }),
            bricks_active_counted: true,
            ..result("demo")
        };
        let csv = Table::from_results(&[gpu, cpu]).to_csv();
        let last_two = |l: &str| {
            let f: Vec<&str> = l.split(',').collect();
            f[f.len() - 2..].join(" ")
        };
        let tails: Vec<String> = csv.lines().map(last_two).collect();
        // bricks_occupied_% then bricks_active_%: the GPU's active share is not a count.
        assert_eq!(
            tails,
            ["bricks_occupied_% bricks_active_%", "25.0 -", "25.0 10.0"],
            "{csv}"
        );
    }

    #[test]
    fn peak_rss_is_known_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(peak_rss_bytes().is_some_and(|b| b > 0));
        }
    }
}
