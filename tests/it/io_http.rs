//! Reading over HTTP (issue 35 section 3): `mdsurf surface URL_GRO URL_XTC` against a local
//! HTTP/1.1 server started by the test (`http_server`) that serves `tests/data/md_1u19.gro`
//! and `.xtc` from memory. It honours `Range: bytes=a-b` (206 and `Content-Range`) and counts
//! the bytes it sends; other modes ignore ranges (200 and the whole file) or drop the
//! connection part way. The surface of the
//! URLs equals that of the local files row for row, one frame costs a fraction of the file,
//! and each server failure is exit status 2 with one line naming the URL.

use std::path::Path;

use crate::cli_common::{Run, data, mdsurf, mdsurf_env};
use crate::http_server::{Mode, Server};

/// The test system's files.
const MD: [&str; 2] = ["md_1u19.gro", "md_1u19.xtc"];

/// `mdsurf surface TOP TRAJ --backend cpu --no-timings --stats STATS [EXTRA]` in `dir`.
pub(crate) fn surface(dir: &Path, top: &str, traj: &str, stats: &str, extra: &[&str]) -> Run {
    let mut args = vec![
        "surface",
        top,
        traj,
        "--backend",
        "cpu",
        "--no-timings",
        "--stats",
        stats,
    ];
    args.extend_from_slice(extra);
    mdsurf(dir, &args)
}

#[test]
fn surface_of_urls_equals_the_local_files() {
    let server = Server::start(Mode::Ranges, &MD);
    let dir = tempfile::tempdir().unwrap();
    let frames = ["--frames", "0:51:10"];
    let local = surface(
        dir.path(),
        &data("md_1u19.gro"),
        &data("md_1u19.xtc"),
        "local.csv",
        &frames,
    );
    assert_eq!(local.code, 0, "{}", local.stderr);
    let remote = surface(
        dir.path(),
        &server.url("md_1u19.gro"),
        &server.url("md_1u19.xtc"),
        "remote.csv",
        &frames,
    );
    assert_eq!(remote.code, 0, "{}", remote.stderr);
    let local = std::fs::read_to_string(dir.path().join("local.csv")).unwrap();
    let remote = std::fs::read_to_string(dir.path().join("remote.csv")).unwrap();
    assert_eq!(local.lines().count(), 7, "{local}");
    assert_eq!(remote, local);
    assert!(server.served("md_1u19.xtc") > 0);
}

#[test]
fn one_frame_over_http_transfers_a_fraction_of_the_file() {
    let server = Server::start(Mode::Ranges, &MD);
    let dir = tempfile::tempdir().unwrap();
    let run = surface(
        dir.path(),
        &server.url("md_1u19.gro"),
        &server.url("md_1u19.xtc"),
        "s.csv",
        &["--frames", "50"],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let stats = std::fs::read_to_string(dir.path().join("s.csv")).unwrap();
    assert_eq!(stats.lines().count(), 2, "{stats}");
    let size = std::fs::metadata(data("md_1u19.xtc")).unwrap().len();
    let served = server.served("md_1u19.xtc");
    eprintln!("one frame over HTTP: {served} of {size} XTC bytes served");
    assert!(served > 0 && served * 10 < size * 4, "{served} of {size}");
}

/// Runs `mdsurf surface` on the server's URLs (the XTC as `xtc`), expects status 2 and one
/// error line naming the XTC's URL and containing `words`.
fn fails_naming_the_url(server: &Server, xtc: &str, words: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let url = server.url(xtc);
    let run = surface(dir.path(), &server.url("md_1u19.gro"), &url, "s.csv", &[]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    // Progress lines and the list of default representations are information.
    let lines: Vec<&str> = run
        .stderr
        .lines()
        .filter(|l| !l.starts_with("frame") && !l.starts_with("rep "))
        .collect();
    assert_eq!(lines.len(), 1, "{}", run.stderr);
    assert!(lines[0].starts_with("error: "), "{}", lines[0]);
    assert!(lines[0].contains(&url), "{}", lines[0]);
    for word in words {
        assert!(lines[0].contains(word), "'{word}' not in: {}", lines[0]);
    }
    assert!(!dir.path().join("s.csv").exists());
}

#[test]
fn a_server_without_ranges_is_one_line() {
    let server = Server::start(Mode::NoRanges, &MD);
    fails_naming_the_url(&server, "md_1u19.xtc", &["does not support range requests"]);
}

#[test]
fn a_missing_url_is_one_line() {
    let server = Server::start(Mode::Ranges, &MD);
    fails_naming_the_url(&server, "missing.xtc", &["404"]);
}

#[test]
fn a_dropped_connection_is_one_line() {
    let server = Server::start(Mode::DropAfter(30_000), &MD);
    fails_naming_the_url(&server, "md_1u19.xtc", &["bytes ", "connection dropped"]);
}

#[test]
fn an_unknown_extension_over_http_is_one_line() {
    let server = Server::start(Mode::Ranges, &MD);
    fails_naming_the_url(&server, "md_1u19.abc", &["abc"]);
}

#[test]
fn urls_with_a_query_string_read_as_their_file() {
    // Signed URLs (object stores) carry a token after the name.
    let server = Server::start(Mode::Ranges, &MD);
    let dir = tempfile::tempdir().unwrap();
    let token = "?token=a1b2&expires=99";
    let run = surface(
        dir.path(),
        &format!("{}{token}", server.url("md_1u19.gro")),
        &format!("{}{token}", server.url("md_1u19.xtc")),
        "s.csv",
        &["--frames", "3"],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let stats = std::fs::read_to_string(dir.path().join("s.csv")).unwrap();
    assert_eq!(stats.lines().count(), 2, "{stats}");
}

/// The window on URLs (`mdsurf URL_GRO URL_XTC --script FILE --quit` under Xvfb): the script
/// goes to frame 2 and takes a screenshot; the PNG is not uniform and the XTC was read in
/// place (a fraction of it served). Skipped without Xvfb or a wgpu adapter unless
/// `REQUIRE_GPU=1`.
#[test]
fn the_window_reads_urls() {
    let skip = |reason: &str| {
        if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") {
            panic!("REQUIRE_GPU=1 but {reason}");
        }
        eprintln!("note: skipping the window-over-HTTP test: {reason}");
    };
    let xvfb = std::process::Command::new("xvfb-run")
        .arg("--help")
        .output();
    if xvfb.is_err() {
        return skip("xvfb-run is not installed");
    }
    if let Err(e) = mdsurf::render::HeadlessGpu::new() {
        return skip(&format!("no wgpu adapter: {e}"));
    }
    let server = Server::start(Mode::Ranges, &MD);
    let dir = tempfile::tempdir().unwrap();
    let (shot, script) = (dir.path().join("shot.png"), dir.path().join("s.mdsurf"));
    let text = format!("frame 2\nscreenshot \"{}\" 400x300\n", shot.display());
    std::fs::write(&script, text).unwrap();
    let (_one_server_at_a_time, mut xvfb) = crate::xvfb_support::xvfb_run();
    let out = xvfb
        .arg(env!("CARGO_BIN_EXE_mdsurf"))
        .arg(server.url(MD[0]))
        .arg(server.url(MD[1]))
        .arg("--script")
        .arg(&script)
        .args(["--quit", "--cpu"])
        .env("XDG_RUNTIME_DIR", dir.path())
        .output()
        .expect("run xvfb-run");
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "exit {}: {log}", out.status);
    assert!(log.contains("last frame 2"), "{log}");
    let image = mdsurf::render::RgbaImage::read_png(&shot).unwrap_or_else(|e| panic!("{e}: {log}"));
    assert_eq!((image.width, image.height), (400, 300));
    assert!(image.distinct_colours() > 10, "uniform screenshot: {log}");
    let size = std::fs::metadata(data(MD[1])).unwrap().len();
    let served = server.served(MD[1]);
    assert!(served > 0 && served < size, "{served} of {size}");
}

/// The one error line of a failed `run` (progress and representation lines aside).
fn error_line(run: &Run) -> String {
    assert_eq!(run.code, 2, "{}", run.stderr);
    let lines: Vec<&str> = run
        .stderr
        .lines()
        .filter(|l| !l.starts_with("frame") && !l.starts_with("rep "))
        .collect();
    assert_eq!(lines.len(), 1, "{}", run.stderr);
    lines[0].to_string()
}

#[test]
fn https_trusts_the_certificates_of_mdsurf_ca_file() {
    let files = MD
        .iter()
        .map(|name| (name.to_string(), std::fs::read(data(name)).unwrap()))
        .collect();
    let (server, pem) = Server::serve_tls(files);
    let dir = tempfile::tempdir().unwrap();
    let ca = dir.path().join("ca.pem");
    std::fs::write(&ca, pem).unwrap();
    let (gro, xtc) = (server.url(MD[0]), server.url(MD[1]));
    assert!(gro.starts_with("https://127.0.0.1:"), "{gro}");
    let local = surface(
        dir.path(),
        &data(MD[0]),
        &data(MD[1]),
        "l.csv",
        &["--frames", "3"],
    );
    assert_eq!(local.code, 0, "{}", local.stderr);
    let args = |stats: &'static str| {
        let common = [
            "surface",
            "--backend",
            "cpu",
            "--no-timings",
            "--frames",
            "3",
        ];
        let mut args: Vec<String> = common.iter().map(|a| a.to_string()).collect();
        args.extend([
            gro.clone(),
            xtc.clone(),
            "--stats".to_string(),
            stats.to_string(),
        ]);
        args
    };
    let run = |stats: &'static str, env: &[(&str, &str)]| {
        let args = args(stats);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        mdsurf_env(dir.path(), &args, env)
    };
    let trusted = run("r.csv", &[("MDSURF_CA_FILE", ca.to_str().unwrap())]);
    assert_eq!(trusted.code, 0, "{}", trusted.stderr);
    let read = |name: &str| std::fs::read_to_string(dir.path().join(name)).unwrap();
    assert_eq!(read("r.csv"), read("l.csv"));
    assert!(server.served(MD[1]) > 0);
    // Not trusted (the built-in roots): one line naming the URL and the certificate.
    let line = error_line(&run("u.csv", &[]));
    assert!(
        line.contains(&gro) && line.to_lowercase().contains("certificate"),
        "{line}"
    );
    // A CA file without a certificate: one line naming the variable and the file.
    std::fs::write(&ca, "not a certificate\n").unwrap();
    let line = error_line(&run("b.csv", &[("MDSURF_CA_FILE", ca.to_str().unwrap())]));
    assert!(
        line.contains("MDSURF_CA_FILE=") && line.contains("ca.pem"),
        "{line}"
    );
}
