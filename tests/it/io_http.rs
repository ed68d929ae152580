//! Reading over HTTP (issue 35 section 3): `mdsurf surface URL_GRO URL_XTC` against a local
//! HTTP/1.1 server started by the test (std's `TcpListener` on 127.0.0.1, a thread per
//! connection) that serves `tests/data/md_1u19.gro` and `.xtc` from memory. It honours
//! `Range: bytes=a-b` (206 and `Content-Range`) and counts the XTC bytes it sends; other modes
//! ignore ranges (200 and the whole file) or drop the connection part way. The surface of the
//! URLs equals that of the local files row for row, one frame costs a fraction of the file,
//! and each server failure is exit status 2 with one line naming the URL.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::cli_common::{Run, data, mdsurf};

/// How the test server answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Ranges honoured (206 with `Content-Range`).
    Ranges,
    /// Ranges ignored: 200 and the whole file, as a server without range support.
    NoRanges,
    /// Ranges honoured, but the connection drops once this many XTC bytes have been sent.
    DropAfter(u64),
}

/// A running test server.
struct Server {
    /// `http://127.0.0.1:PORT`.
    base: String,
    /// Bytes of XTC data sent so far (response bodies).
    xtc_served: Arc<AtomicU64>,
}

impl Server {
    /// Serves the test system's GRO and XTC under `/md_1u19.gro` and `/md_1u19.xtc` (any other
    /// path is a 404).
    fn start(mode: Mode) -> Server {
        let files: Arc<Vec<(String, Vec<u8>)>> = Arc::new(
            ["md_1u19.gro", "md_1u19.xtc"]
                .iter()
                .map(|name| (format!("/{name}"), std::fs::read(data(name)).unwrap()))
                .collect(),
        );
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let base = format!("http://{}", listener.local_addr().unwrap());
        let xtc_served = Arc::new(AtomicU64::new(0));
        let served = Arc::clone(&xtc_served);
        std::thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let (files, served) = (Arc::clone(&files), Arc::clone(&served));
                std::thread::spawn(move || {
                    let _ = answer(stream, &files, mode, &served);
                });
            }
        });
        Server { base, xtc_served }
    }

    fn url(&self, name: &str) -> String {
        format!("{}/{name}", self.base)
    }

    fn xtc_served(&self) -> u64 {
        self.xtc_served.load(Ordering::SeqCst)
    }
}

/// Answers one request on `stream` and closes it (`Connection: close`).
fn answer(
    mut stream: TcpStream,
    files: &[(String, Vec<u8>)],
    mode: Mode,
    served: &AtomicU64,
) -> std::io::Result<()> {
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut request = String::new();
    reader.read_line(&mut request)?;
    // The path without its query string, as static file servers (and signed URLs) serve it.
    let target = request.split_whitespace().nth(1).unwrap_or("");
    let target = target.split('?').next().unwrap_or("").to_string();
    let mut range = None;
    loop {
        let mut line = String::new();
        if reader.read_line(&mut line)? == 0 || line.trim().is_empty() {
            break;
        }
        let lower = line.to_ascii_lowercase();
        if let Some(spec) = lower.strip_prefix("range:") {
            let spec = spec.trim().trim_start_matches("bytes=");
            if let Some((a, b)) = spec.split_once('-') {
                range = Some((a.parse::<u64>().unwrap(), b.parse::<u64>().unwrap()));
            }
        }
    }
    let Some((_, bytes)) = files.iter().find(|(path, _)| *path == target) else {
        let head = "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";
        return stream.write_all(head.as_bytes());
    };
    let total = bytes.len() as u64;
    let (status, body, extra) = match range {
        Some((a, b)) if mode != Mode::NoRanges && a < total => {
            let end = b.min(total - 1);
            let extra = format!("Content-Range: bytes {a}-{end}/{total}\r\n");
            (
                "206 Partial Content",
                &bytes[a as usize..=end as usize],
                extra,
            )
        }
        _ => ("200 OK", &bytes[..], String::new()),
    };
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Length: {}\r\nAccept-Ranges: {}\r\n{extra}Connection: close\r\n\r\n",
        body.len(),
        if mode == Mode::NoRanges {
            "none"
        } else {
            "bytes"
        },
    );
    stream.write_all(head.as_bytes())?;
    let is_xtc = target.ends_with(".xtc");
    let mut body = body;
    if let (true, Mode::DropAfter(limit)) = (is_xtc, mode) {
        let already = served.load(Ordering::SeqCst);
        let allowed = limit.saturating_sub(already).min(body.len() as u64) as usize;
        body = &body[..allowed];
    }
    if is_xtc {
        served.fetch_add(body.len() as u64, Ordering::SeqCst);
    }
    stream.write_all(body)?;
    stream.flush()?;
    stream.shutdown(std::net::Shutdown::Both)
}

/// `mdsurf surface TOP TRAJ --backend cpu --no-timings --stats STATS [EXTRA]` in `dir`.
fn surface(dir: &Path, top: &str, traj: &str, stats: &str, extra: &[&str]) -> Run {
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
    let server = Server::start(Mode::Ranges);
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
    assert!(server.xtc_served() > 0);
}

#[test]
fn one_frame_over_http_transfers_a_fraction_of_the_file() {
    let server = Server::start(Mode::Ranges);
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
    let served = server.xtc_served();
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
    let server = Server::start(Mode::NoRanges);
    fails_naming_the_url(&server, "md_1u19.xtc", &["does not support range requests"]);
}

#[test]
fn a_missing_url_is_one_line() {
    let server = Server::start(Mode::Ranges);
    fails_naming_the_url(&server, "missing.xtc", &["404"]);
}

#[test]
fn a_dropped_connection_is_one_line() {
    let server = Server::start(Mode::DropAfter(30_000));
    fails_naming_the_url(&server, "md_1u19.xtc", &["bytes ", "connection dropped"]);
}

#[test]
fn other_formats_over_http_are_one_line() {
    let server = Server::start(Mode::Ranges);
    fails_naming_the_url(&server, "md_1u19.dcd", &["only XTC and TRR"]);
}

#[test]
fn urls_with_a_query_string_read_as_their_file() {
    // Signed URLs (object stores) carry a token after the name.
    let server = Server::start(Mode::Ranges);
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
