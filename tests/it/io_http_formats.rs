//! Reading over HTTP beyond XTC (issue 35 section 3), against the test's server
//! (`http_server`): a DCD and an Amber NetCDF trajectory are read in place (their surfaces
//! equal those of the local files row for row, and the bytes served for a few frames stay
//! under a bound computed from the frame size), a TNG trajectory is downloaded whole with a
//! note saying so, redirects (301, 302, 307, 308) are followed with the range requests intact,
//! and the XTC header walk costs one request per frame at most (frames of 21 kB), a few for
//! the whole walk when frames are small (a 1,000-atom system).

use std::path::Path;

use crate::cli_common::{Run, data, mdsurf};
use crate::http_server::{Mode, Server};
use crate::io_http::surface;

/// Bytes the reader fetches past each read once frames are read (`http::READ_AHEAD_BYTES`).
const READ_AHEAD: u64 = 256 * 1024;
/// The reader's block (`http::BLOCK_BYTES`): a read may fetch up to one more at each end.
const BLOCK: u64 = 4 * 1024;

/// Runs `surface` on the local files and on the URLs; both succeed with the same stats
/// (`rows` frames). Returns the remote run.
fn same_as_local(local: (&str, &str), remote: (&str, &str), frames: &str, rows: usize) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let here = surface(
        dir.path(),
        local.0,
        local.1,
        "local.csv",
        &["--frames", frames],
    );
    assert_eq!(here.code, 0, "{}", here.stderr);
    let there = surface(
        dir.path(),
        remote.0,
        remote.1,
        "remote.csv",
        &["--frames", frames],
    );
    assert_eq!(there.code, 0, "{}", there.stderr);
    let here = std::fs::read_to_string(dir.path().join("local.csv")).unwrap();
    let there_stats = std::fs::read_to_string(dir.path().join("remote.csv")).unwrap();
    assert_eq!(here.lines().count(), rows + 1, "{here}");
    assert_eq!(there_stats, here);
    there
}

/// The most bytes `reads` reads of a frame of `frame_bytes` may fetch after a header read of
/// `header_bytes` (each with the read-ahead and a block at each end).
fn bound(header_bytes: u64, frame_bytes: u64, reads: u64) -> u64 {
    header_bytes + READ_AHEAD + 2 * BLOCK + reads * (frame_bytes + READ_AHEAD + 2 * BLOCK)
}

#[test]
fn a_dcd_over_http_reads_the_header_and_the_frames_played() {
    let names = ["adk_open.pdb", "adk_dims.dcd"];
    let server = Server::start(Mode::Ranges, &names);
    same_as_local(
        (&data(names[0]), &data(names[1])),
        (&server.url(names[0]), &server.url(names[1])),
        "0:30:10",
        3,
    );
    // 98 frames after a header: a frame is at most size / 98 bytes. Frames 0, 10 and 20 are
    // read (frame 0 also when the file opens, from the cache).
    let size = std::fs::metadata(data(names[1])).unwrap().len();
    let frame_bytes = size / 98;
    let served = server.served(names[1]);
    eprintln!("DCD over HTTP, 3 frames: {served} of {size} bytes served");
    assert!(served >= 3 * frame_bytes, "{served}");
    assert!(served <= bound(BLOCK, frame_bytes, 3), "{served} of {size}");
    assert!(served * 3 < size, "{served} of {size}");
}

#[test]
fn a_cut_dcd_over_http_keeps_its_whole_frames_like_the_local_file() {
    // 1,000 bytes short: frame 97 is cut, found from the size alone (no frame is read).
    let dcd = std::fs::read(data("adk_dims.dcd")).unwrap();
    let cut = dcd[..dcd.len() - 1000].to_vec();
    let dir = tempfile::tempdir().unwrap();
    let local = dir.path().join("cut.dcd");
    std::fs::write(&local, &cut).unwrap();
    let pdb = std::fs::read(data("adk_open.pdb")).unwrap();
    let files = vec![
        ("adk_open.pdb".to_string(), pdb),
        ("cut.dcd".to_string(), cut.clone()),
    ];
    let server = Server::serve(Mode::Ranges, files);
    // Frames 90 to the end: the 7 whole ones are written, then the cut frame 97 is the error,
    // for the URL as for the file.
    let pdb = data("adk_open.pdb");
    let here = surface(
        dir.path(),
        &pdb,
        local.to_str().unwrap(),
        "l.csv",
        &["--frames", "90:"],
    );
    let url = server.url("cut.dcd");
    let there = surface(
        dir.path(),
        &server.url("adk_open.pdb"),
        &url,
        "r.csv",
        &["--frames", "90:"],
    );
    assert_ne!(here.code, 0, "{}", here.stderr);
    assert_eq!(there.code, here.code, "{}", there.stderr);
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap();
    assert_eq!(read("l.csv").lines().count(), 8, "{}", read("l.csv"));
    assert_eq!(read("r.csv"), read("l.csv"));
    let line = there.stderr.lines().find(|l| l.starts_with("error: "));
    let line = line.unwrap_or_else(|| panic!("no error line: {}", there.stderr));
    assert!(line.contains(&url) && line.contains("frame 97"), "{line}");
    let (served, size) = (server.served("cut.dcd"), cut.len() as u64);
    assert!(served * 2 < size, "{served} of {size}");
}

/// An Amber NetCDF copy of the first `frames` frames of `adk_dims.dcd` (3,341 atoms), written
/// by chemfiles.
fn adk_netcdf(frames: usize) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("adk.nc");
    let mut input = chemfiles::Trajectory::open(data("adk_dims.dcd"), 'r').unwrap();
    let mut output = chemfiles::Trajectory::open_with_format(&path, 'w', "Amber NetCDF").unwrap();
    let mut frame = chemfiles::Frame::new();
    for _ in 0..frames {
        input.read(&mut frame).unwrap();
        output.write(&frame).unwrap();
    }
    drop(output);
    std::fs::read(&path).unwrap()
}

#[test]
fn an_amber_netcdf_over_http_reads_the_header_and_the_frames_played() {
    let frames = 60;
    let nc = adk_netcdf(frames);
    let dir = tempfile::tempdir().unwrap();
    let local = dir.path().join("adk.nc");
    std::fs::write(&local, &nc).unwrap();
    let pdb = std::fs::read(data("adk_open.pdb")).unwrap();
    let files = vec![
        ("adk_open.pdb".to_string(), pdb),
        ("adk.nc".to_string(), nc.clone()),
    ];
    let server = Server::serve(Mode::Ranges, files);
    same_as_local(
        (&data("adk_open.pdb"), local.to_str().unwrap()),
        (&server.url("adk_open.pdb"), &server.url("adk.nc")),
        "0:60:30",
        2,
    );
    // The header is read in 64 KiB (with the read-ahead); a frame is at most size / frames.
    let size = nc.len() as u64;
    let served = server.served("adk.nc");
    eprintln!("NetCDF over HTTP, 2 frames: {served} of {size} bytes served");
    assert!(
        served <= bound(64 * 1024, size / frames as u64, 2),
        "{served}"
    );
    assert!(served * 2 < size, "{served} of {size}");
}

#[test]
fn a_tng_over_http_is_downloaded_whole_with_a_note() {
    let name = "argon_npt_compressed.tng";
    let server = Server::start(Mode::Ranges, &[name]);
    let url = server.url(name);
    let remote = same_as_local((&data(name), &data(name)), (&data(name), &url), "0:3", 3);
    let size = std::fs::metadata(data(name)).unwrap().len();
    let note = format!("note: downloading {url} whole (");
    let line = remote.stderr.lines().find(|l| l.starts_with(&note));
    let line = line.unwrap_or_else(|| panic!("no download note in: {}", remote.stderr));
    assert!(line.contains("KiB") && line.contains("TNG"), "{line}");
    assert_eq!(server.served(name), size);
    assert_eq!(server.requests(name), 1);
}

#[test]
fn redirects_are_followed_with_their_ranges() {
    let names = ["md_1u19.gro", "md_1u19.xtc"];
    let server = Server::start(Mode::Ranges, &names);
    let local = (data(names[0]), data(names[1]));
    for code in [301, 302, 307, 308] {
        let top = server.url(&format!("redirect/{code}/{}", names[0]));
        let traj = server.url(&format!("redirect/{code}/{}", names[1]));
        same_as_local((&local.0, &local.1), (&top, &traj), "50", 1);
    }
    // A server that ignored the ranges after a redirect would have been refused; each run
    // read a fraction of the file.
    let size = std::fs::metadata(&local.1).unwrap().len();
    let served = server.served(names[1]);
    assert!(
        served > 0 && served < 4 * size * 4 / 10,
        "{served} of {size}"
    );
}

/// A server of `md_1u19.gro` and `twice.xtc` (md_1u19.xtc twice: 102 frames of about 21 kB),
/// and the bytes of `twice.xtc`.
fn serve_md_twice(mode: Mode) -> (Server, Vec<u8>) {
    let xtc = std::fs::read(data("md_1u19.xtc")).unwrap();
    let twice = [xtc.clone(), xtc].concat();
    let gro = std::fs::read(data("md_1u19.gro")).unwrap();
    let files = vec![
        ("md_1u19.gro".to_string(), gro),
        ("twice.xtc".to_string(), twice.clone()),
    ];
    (Server::serve(mode, files), twice)
}

#[test]
fn the_header_walk_of_102_xtc_frames_takes_few_requests() {
    let (server, twice) = serve_md_twice(Mode::Ranges);
    let dir = tempfile::tempdir().unwrap();
    let run = surface(
        dir.path(),
        &server.url("md_1u19.gro"),
        &server.url("twice.xtc"),
        "s.csv",
        &["--frames", "101"],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let requests = server.requests("twice.xtc");
    let served = server.served("twice.xtc");
    let size = twice.len() as u64;
    eprintln!("102-frame XTC walk + frame 101: {requests} requests, {served} of {size} bytes");
    // One request per header (frame 0's came with the open), frame 0 (checked at open) and
    // frame 101, and at most one more per round of 16 headers fetched ahead (a window that
    // missed its header).
    assert!(
        requests <= 1 + 101 + 2 + 102 / 16 + 1,
        "{requests} requests"
    );
    // Each header costs a window of a few kB, not its frame of 21 kB.
    assert!(served * 2 < size, "{served} of {size}");
}

/// The 102-frame XTC of 21 kB frames from a distant server (each reply held back 20 ms): with
/// the headers prefetched in parallel once the walk's stride is steady, the walk takes a round
/// of requests per 16 frames instead of one per frame (at least 4x fewer rounds), for at most
/// twice the requests; with
/// `MDSURF_HTTP_PREFETCH=0` it takes one round per request, as before. Both read the same
/// frame. (Elapsed times are printed, not checked.)
#[test]
fn the_header_walk_of_large_xtc_frames_prefetches_headers_in_parallel() {
    let mut rows = Vec::new();
    for prefetch in ["16", "0"] {
        let (server, _) = serve_md_twice(Mode::Slow(20));
        let dir = tempfile::tempdir().unwrap();
        let (top, traj) = (server.url("md_1u19.gro"), server.url("twice.xtc"));
        let started = std::time::Instant::now();
        let run = crate::cli_common::mdsurf_env(
            dir.path(),
            &[
                "surface",
                &top,
                &traj,
                "--backend",
                "cpu",
                "--no-timings",
                "--stats",
                "s.csv",
                "--frames",
                "101",
            ],
            &[("MDSURF_HTTP_PREFETCH", prefetch)],
        );
        let seconds = started.elapsed().as_secs_f64();
        assert_eq!(run.code, 0, "{}", run.stderr);
        let (requests, rounds) = (server.requests("twice.xtc"), server.rounds("twice.xtc"));
        eprintln!("prefetch {prefetch}: {requests} requests in {rounds} rounds, {seconds:.2} s");
        let area = std::fs::read_to_string(dir.path().join("s.csv")).unwrap();
        rows.push((requests, rounds, area));
    }
    let (with, without) = (&rows[0], &rows[1]);
    assert_eq!(with.2, without.2, "the same frame read");
    assert!(
        without.1 + 3 >= without.0,
        "one round per request without prefetch: {without:?}"
    );
    assert!(
        with.1 * 4 <= without.1,
        "{} rounds with prefetch, {} without",
        with.1,
        without.1
    );
    assert!(
        with.0 <= 2 * (1 + 101 + 2),
        "{} requests with prefetch",
        with.0
    );
}

/// The argon fluid of `argon_npt_compressed.tng` (1,000 atoms, 101 frames) as an XTC file
/// and a PDB of its first frame, written by chemfiles.
fn argon_xtc(dir: &Path) -> (Vec<u8>, Vec<u8>) {
    let mut input = chemfiles::Trajectory::open(data("argon_npt_compressed.tng"), 'r').unwrap();
    let (xtc, pdb) = (dir.join("argon.xtc"), dir.join("argon.pdb"));
    let mut output = chemfiles::Trajectory::open(&xtc, 'w').unwrap();
    let mut frame = chemfiles::Frame::new();
    for k in 0..input.nsteps() {
        input.read(&mut frame).unwrap();
        output.write(&frame).unwrap();
        if k == 0 {
            let mut top = chemfiles::Trajectory::open(&pdb, 'w').unwrap();
            top.write(&frame).unwrap();
        }
    }
    drop(output);
    (std::fs::read(&xtc).unwrap(), std::fs::read(&pdb).unwrap())
}

#[test]
fn the_header_walk_of_small_xtc_frames_takes_a_few_requests() {
    let dir = tempfile::tempdir().unwrap();
    let (xtc, pdb) = argon_xtc(dir.path());
    let size = xtc.len() as u64;
    let files = vec![
        ("argon.pdb".to_string(), pdb),
        ("argon.xtc".to_string(), xtc),
    ];
    let server = Server::serve(Mode::Ranges, files);
    let local = (dir.path().join("argon.pdb"), dir.path().join("argon.xtc"));
    same_as_local(
        (local.0.to_str().unwrap(), local.1.to_str().unwrap()),
        (&server.url("argon.pdb"), &server.url("argon.xtc")),
        "100",
        1,
    );
    let requests = server.requests("argon.xtc");
    let served = server.served("argon.xtc");
    eprintln!(
        "101-frame argon XTC walk + frame 100: {requests} requests, {served} of {size} bytes"
    );
    // A request per 256 KiB walked, and the open's and the frame's.
    let walk_requests = size.div_ceil(READ_AHEAD) + 3;
    assert!(
        requests <= walk_requests,
        "{requests} requests for {size} bytes"
    );
}

#[test]
fn a_damaged_downloaded_trajectory_names_its_url_not_the_copy() {
    // The argon TNG cut inside its second frame set (which starts at byte 398576): locally
    // frames 0-99 are read, then frame 100 is the damage.
    let mut tng = std::fs::read(data("argon_npt_compressed.tng")).unwrap();
    tng.truncate(398_576 + 103);
    let server = Server::serve(Mode::Ranges, vec![("cut.tng".to_string(), tng)]);
    let url = server.url("cut.tng");
    let dir = tempfile::tempdir().unwrap();
    let run = mdsurf(
        dir.path(),
        &["surface", &url, "--backend", "cpu", "--spacing", "2", "-q"],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    let error = run.stderr.lines().find(|l| l.starts_with("error:"));
    let error = error.unwrap_or_else(|| panic!("no error line in: {}", run.stderr));
    assert!(
        error.starts_with(&format!("error: {url}: frame 100: cannot read:")),
        "{error}"
    );
    assert!(
        !error.contains("mdsurf-http"),
        "names the temporary copy: {error}"
    );
}
