//! Atomic output: a write that fails (a writer error, an unknown format, a missing directory, a
//! stats file never finished) leaves the existing file byte for byte as it was and leaves no
//! temporary file behind; a write that succeeds replaces it completely.

use std::fs;
use std::io;
use std::path::Path;

use mdsurf::export::{self, MeshFormat, StatsRow, StatsWriter, write_atomic};
use mdsurf::surface::Mesh;

const OLD: &[u8] = b"precious old content\n";

/// The names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn failed_write_keeps_the_old_file_and_leaves_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.ply");
    fs::write(&target, OLD).unwrap();
    let err = write_atomic(&target, |w| {
        w.write_all(b"half a file")?;
        Err(io::Error::other("disk on fire"))
    })
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("out.ply") && msg.contains("disk on fire"),
        "{msg}"
    );
    assert!(!msg.contains('\n'));
    assert_eq!(fs::read(&target).unwrap(), OLD);
    assert_eq!(listing(dir.path()), ["out.ply"]);
}

#[test]
fn successful_write_replaces_the_whole_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.txt");
    fs::write(
        &target,
        b"a much longer old content that must not survive at the end",
    )
    .unwrap();
    write_atomic(&target, |w| w.write_all(b"new")).unwrap();
    assert_eq!(fs::read(&target).unwrap(), b"new");
    assert_eq!(listing(dir.path()), ["out.txt"]);
}

#[test]
fn unknown_format_and_missing_directory_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("mesh.xyz");
    let err = export::write_mesh(&bad, &Mesh::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("mesh.xyz") && err.contains(".ply"), "{err}");
    assert!(!bad.exists());
    assert!(MeshFormat::from_path(Path::new("noext")).is_err());
    assert_eq!(
        MeshFormat::from_path(Path::new("a.GLB")).unwrap(),
        MeshFormat::Glb
    );

    let missing = dir.path().join("no/such/dir/out.ply");
    let err = export::write_mesh(&missing, &Mesh::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("out.ply") && !err.contains('\n'), "{err}");
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn stats_file_appears_only_when_finished() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("stats.csv");
    fs::write(&target, OLD).unwrap();
    let row = StatsRow {
        frame: 3,
        rep: "protein".into(),
        time_ps: Some(30.0),
        atoms: 10,
        dims: [4, 5, 6],
        vertices: 12,
        triangles: 20,
        area: 50.5,
        volume: 33.25,
        total_ms: 1.5,
        ..Default::default()
    };
    {
        let mut w = StatsWriter::create(&target).unwrap();
        w.write_row(&row).unwrap();
        // Dropped without finish: an interrupted run.
    }
    assert_eq!(fs::read(&target).unwrap(), OLD);
    assert_eq!(listing(dir.path()), ["stats.csv"]);

    let mut w = StatsWriter::create(&target).unwrap();
    w.write_row(&row).unwrap();
    w.write_row(&StatsRow {
        frame: 4,
        time_ps: None,
        ..row.clone()
    })
    .unwrap();
    assert_eq!(w.rows(), 2);
    w.finish().unwrap();
    let text = fs::read_to_string(&target).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with(
        "frame,rep,time_ps,atoms,nx,ny,nz,vertices,triangles,area_A2,volume_A3,ms_total"
    ));
    assert_eq!(lines.len(), 3);
    let cols = lines[0].split(',').count();
    assert!(lines[1..].iter().all(|l| l.split(',').count() == cols));
    assert!(
        lines[1].starts_with("3,protein,30,10,4,5,6,12,20,50.5000,33.2500,1.500"),
        "{}",
        lines[1]
    );
    assert!(lines[2].starts_with("4,protein,,10,"), "{}", lines[2]);
}

#[cfg(unix)]
#[test]
fn replaced_file_keeps_its_permissions_and_new_files_are_readable() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("old.obj");
    fs::write(&old, OLD).unwrap();
    fs::set_permissions(&old, fs::Permissions::from_mode(0o600)).unwrap();
    export::write_mesh(&old, &Mesh::default()).unwrap();
    assert_eq!(
        fs::metadata(&old).unwrap().permissions().mode() & 0o777,
        0o600
    );
    let new = dir.path().join("new.obj");
    export::write_mesh(&new, &Mesh::default()).unwrap();
    assert_eq!(
        fs::metadata(&new).unwrap().permissions().mode() & 0o777,
        0o644
    );
}

/// A symbolic link is written through: the file it points at gets the new content, the link
/// stays a link (also when it dangles).
#[test]
fn symbolic_links_are_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("real.csv");
    fs::write(&real, OLD).unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    write_atomic(&link, |w| w.write_all(b"new\n")).unwrap();
    assert!(
        fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(fs::read(&real).unwrap(), b"new\n");
    let dangling = dir.path().join("dangling.csv");
    std::os::unix::fs::symlink("made_later.csv", &dangling).unwrap();
    write_atomic(&dangling, |w| w.write_all(b"later\n")).unwrap();
    assert!(
        fs::symlink_metadata(&dangling)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(
        fs::read(dir.path().join("made_later.csv")).unwrap(),
        b"later\n"
    );
}

/// A special file (here a named pipe) is written in place, never replaced by a regular file.
#[test]
fn special_files_are_written_in_place() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || fs::read(fifo).unwrap())
    };
    write_atomic(&fifo, |w| w.write_all(b"through the pipe\n")).unwrap();
    assert_eq!(reader.join().unwrap(), b"through the pipe\n");
    use std::os::unix::fs::FileTypeExt;
    assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
}

/// `surface` refuses two outputs on one file, and an output on an input, in one line.
#[test]
fn one_file_for_two_outputs_or_an_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pdb = dir.path().join("in.pdb");
    fs::copy(crate::data_support::data("1hpv.pdb"), &pdb).unwrap();
    let same = dir.path().join("same.ply");
    fs::write(&same, OLD).unwrap();
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_mdsurf"))
            .arg("surface")
            .arg(&pdb)
            .args(["--backend", "cpu", "-q"])
            .args(args)
            .output()
            .unwrap()
    };
    let s = same.to_str().unwrap();
    for (args, what) in [
        (vec!["-o", s, "--stats", s], "same file"),
        (vec!["--stats", pdb.to_str().unwrap()], "input file"),
    ] {
        let out = run(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(what), "{err}");
    }
    assert_eq!(fs::read(&same).unwrap(), OLD);
    assert_eq!(
        fs::read(&pdb).unwrap(),
        fs::read(crate::data_support::data("1hpv.pdb")).unwrap()
    );
}
