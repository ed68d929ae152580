//! Measurement tables of a job array: `--per-residue`, `--per-atom`, `--interface-csv` and
//! `--interface-residues` split by `--chunk I/N` into part files that `mdsurf merge` joins into
//! the tables one run writes, byte for byte (exposures included: a later chunk builds them from
//! the run's first frame); a missing part or a part of another table is refused in one line;
//! cavity tables, tracked from frame to frame, refuse `--chunk`.

use std::fs;

use crate::cli_chunks::run_chunks;
use crate::cli_common::{data, mdsurf};

/// The tables of one run and of its merged chunks.
const TABLES: [&str; 4] = ["res.csv", "atoms.csv", "if.csv", "ir.csv"];

fn table_args<'a>(top: &'a str, traj: &'a str) -> Vec<&'a str> {
    vec![
        "surface",
        top,
        traj,
        "--select",
        "protein",
        "--frames",
        "2:12:3",
        "--backend",
        "cpu",
        "-q",
        "--interface",
        "protein and resid 1:59",
        "protein and resid 60:214",
        "--per-residue",
        "res.csv",
        "--per-atom",
        "atoms.csv",
        "--interface-csv",
        "if.csv",
        "--interface-residues",
        "ir.csv",
    ]
}

#[test]
fn chunked_measurement_tables_merge_into_the_tables_of_one_run() {
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let args = table_args(&top, &traj);
    let one = tempfile::tempdir().unwrap();
    let run = mdsurf(one.path(), &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let parts = tempfile::tempdir().unwrap();
    run_chunks(parts.path(), &args, 3);
    for table in TABLES {
        assert!(
            !parts.path().join(table).exists(),
            "{table} before the merge"
        );
        let run = mdsurf(parts.path(), &["merge", table]);
        assert_eq!(run.code, 0, "{table}: {}", run.stderr);
        assert!(run.stderr.contains("4 frame(s)"), "{table}: {}", run.stderr);
        let (a, b) = (
            fs::read(one.path().join(table)).unwrap(),
            fs::read(parts.path().join(table)).unwrap(),
        );
        assert!(a == b, "{table}: the merged table differs from one run's");
    }
    // Each frame has one interface row; the exposures are numbers.
    let text = fs::read_to_string(parts.path().join("if.csv")).unwrap();
    assert_eq!(text.lines().count(), 5, "{text}");
    let res = fs::read_to_string(parts.path().join("res.csv")).unwrap();
    assert!(
        res.lines().skip(1).all(|l| !l.ends_with(',')),
        "exposure missing"
    );

    // A part gone: one line naming it, the merged table kept as it was.
    let missing = parts.path().join("ir.part-0001-of-0003.csv");
    fs::remove_file(&missing).unwrap();
    let before = fs::read(parts.path().join("ir.csv")).unwrap();
    let run = mdsurf(parts.path(), &["merge", "ir.csv"]);
    assert_eq!(run.code, 2);
    assert!(
        run.last_line().contains("missing part(s)")
            && run.last_line().contains("ir.part-0001-of-0003.csv"),
        "{}",
        run.stderr
    );
    assert_eq!(fs::read(parts.path().join("ir.csv")).unwrap(), before);
    // A part of another table in its place: one line naming it and the columns.
    fs::copy(parts.path().join("res.part-0001-of-0003.csv"), &missing).unwrap();
    let run = mdsurf(parts.path(), &["merge", "ir.csv"]);
    assert_eq!(run.code, 2);
    assert!(
        run.last_line()
            .contains("ir.part-0001-of-0003.csv:2: the columns differ"),
        "{}",
        run.stderr
    );

    // Cavity ids need every frame in one process.
    let run = mdsurf(
        parts.path(),
        &[
            "surface",
            &top,
            &traj,
            "--chunk",
            "0/2",
            "--cavities",
            "c.csv",
        ],
    );
    assert_eq!(run.code, 2);
    assert!(
        run.last_line().contains("--chunk") && run.last_line().contains("--cavities"),
        "{}",
        run.stderr
    );
}
