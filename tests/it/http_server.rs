//! The HTTP/1.1 server the HTTP tests read from: std's `TcpListener` on 127.0.0.1, a thread per
//! connection, one request per connection (`Connection: close`), files served from memory.
//! It honours `Range: bytes=a-b` (206 and `Content-Range`) and counts, per file, the requests
//! and the body bytes it sends; other modes ignore ranges (200 and the whole file) or drop the
//! connection part way. `/redirect/CODE/NAME` answers status CODE (301, 302, 307, 308) with
//! `Location: /NAME`. [`Server::serve_tls`] serves HTTPS (rustls) with a self-signed
//! certificate for 127.0.0.1 made by rcgen, whose PEM it gives for `MDSURF_CA_FILE`.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::{Arc, Mutex};

use rustls::pki_types::{CertificateDer, PrivateKeyDer, PrivatePkcs8KeyDer};

use crate::cli_common::data;

/// How the test server answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Ranges honoured (206 with `Content-Range`).
    Ranges,
    /// Ranges ignored: 200 and the whole file, as a server without range support.
    NoRanges,
    /// Ranges honoured, but the connection drops once this many XTC bytes have been sent.
    DropAfter(u64),
    /// Ranges honoured, each reply held back this many milliseconds (a distant server), so
    /// that requests sent together are in flight together.
    Slow(u64),
}

/// What the server saw of one file.
#[derive(Debug, Clone, Copy, Default)]
struct FileCounts {
    /// Requests answered.
    requests: u64,
    /// Body bytes sent.
    served: u64,
    /// Requests being answered now (arrived, reply not yet started).
    in_flight: u64,
    /// Requests that arrived while none other of the file was in flight: the rounds a
    /// client took (a client that sends one request after the other has one per request).
    rounds: u64,
}

/// Per file (its path, `/name`).
type Counts = Arc<Mutex<HashMap<String, FileCounts>>>;

/// A running test server.
pub struct Server {
    /// `http://127.0.0.1:PORT`.
    base: String,
    counts: Counts,
}

impl Server {
    /// Serves the files of `tests/data` named in `names` under `/NAME` (any other path is a
    /// 404).
    pub fn start(mode: Mode, names: &[&str]) -> Server {
        let files = names
            .iter()
            .map(|name| (name.to_string(), std::fs::read(data(name)).unwrap()))
            .collect();
        Server::serve(mode, files)
    }

    /// Serves `files` (name, bytes) under `/NAME`.
    pub fn serve(mode: Mode, files: Vec<(String, Vec<u8>)>) -> Server {
        Server::listen(mode, files, None)
    }

    /// Serves `files` over HTTPS with a new self-signed certificate for 127.0.0.1; returns the
    /// server and the certificate's PEM.
    pub fn serve_tls(files: Vec<(String, Vec<u8>)>) -> (Server, String) {
        let made = rcgen::generate_simple_self_signed(vec!["127.0.0.1".to_string()]).unwrap();
        let key = PrivatePkcs8KeyDer::from(made.signing_key.serialize_der());
        let chain = vec![CertificateDer::from(made.cert.der().to_vec())];
        let provider = Arc::new(rustls::crypto::ring::default_provider());
        let config = rustls::ServerConfig::builder_with_provider(provider)
            .with_safe_default_protocol_versions()
            .unwrap()
            .with_no_client_auth()
            .with_single_cert(chain, PrivateKeyDer::Pkcs8(key))
            .unwrap();
        let server = Server::listen(Mode::Ranges, files, Some(Arc::new(config)));
        (server, made.cert.pem())
    }

    /// Listens on 127.0.0.1 (HTTPS with `tls`) and answers each connection in a thread.
    fn listen(
        mode: Mode,
        files: Vec<(String, Vec<u8>)>,
        tls: Option<Arc<rustls::ServerConfig>>,
    ) -> Server {
        let files: Arc<Vec<(String, Vec<u8>)>> = Arc::new(
            files
                .into_iter()
                .map(|(name, bytes)| (format!("/{name}"), bytes))
                .collect(),
        );
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let scheme = if tls.is_some() { "https" } else { "http" };
        let base = format!("{scheme}://{}", listener.local_addr().unwrap());
        let counts = Counts::default();
        let shared = Arc::clone(&counts);
        std::thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let (files, counts, tls) = (Arc::clone(&files), Arc::clone(&shared), tls.clone());
                std::thread::spawn(move || {
                    let _ = match tls {
                        Some(config) => answer_tls(stream, config, &files, &counts),
                        None => answer_plain(stream, &files, mode, &counts),
                    };
                });
            }
        });
        Server { base, counts }
    }

    /// The URL of `name` on this server.
    pub fn url(&self, name: &str) -> String {
        format!("{}/{name}", self.base)
    }

    /// Body bytes sent of the file `name` so far.
    pub fn served(&self, name: &str) -> u64 {
        self.counts(name).served
    }

    /// Requests answered for the file `name` so far (redirects not counted).
    pub fn requests(&self, name: &str) -> u64 {
        self.counts(name).requests
    }

    /// Rounds of requests for the file `name` so far: requests that found none other of it in
    /// flight (meaningful with [`Mode::Slow`], where replies overlap when sent together).
    pub fn rounds(&self, name: &str) -> u64 {
        self.counts(name).rounds
    }

    fn counts(&self, name: &str) -> FileCounts {
        let counts = self.counts.lock().unwrap();
        counts.get(&format!("/{name}")).copied().unwrap_or_default()
    }
}

/// Answers one request on the TCP `stream` and closes it.
fn answer_plain(
    mut stream: TcpStream,
    files: &[(String, Vec<u8>)],
    mode: Mode,
    counts: &Mutex<HashMap<String, FileCounts>>,
) -> std::io::Result<()> {
    answer(&mut stream, files, mode, counts)?;
    stream.shutdown(std::net::Shutdown::Both)
}

/// Answers one request over TLS on `stream` and closes it (`close_notify`).
fn answer_tls(
    stream: TcpStream,
    config: Arc<rustls::ServerConfig>,
    files: &[(String, Vec<u8>)],
    counts: &Mutex<HashMap<String, FileCounts>>,
) -> std::io::Result<()> {
    let connection = rustls::ServerConnection::new(config).map_err(std::io::Error::other)?;
    let mut tls = rustls::StreamOwned::new(connection, stream);
    answer(&mut tls, files, Mode::Ranges, counts)?;
    tls.conn.send_close_notify();
    tls.flush()
}

/// Answers one request on `stream` (`Connection: close`).
fn answer<S: Read + Write>(
    stream: &mut S,
    files: &[(String, Vec<u8>)],
    mode: Mode,
    counts: &Mutex<HashMap<String, FileCounts>>,
) -> std::io::Result<()> {
    // A request has no body: nothing is buffered past its blank line.
    let mut reader = BufReader::new(&mut *stream);
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
    drop(reader);
    if let Some(rest) = target.strip_prefix("/redirect/")
        && let Some((code, name)) = rest.split_once('/')
    {
        let head = format!(
            "HTTP/1.1 {code} Moved\r\nLocation: /{name}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"
        );
        return stream.write_all(head.as_bytes());
    }
    let Some((_, bytes)) = files.iter().find(|(path, _)| *path == target) else {
        let head = "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";
        return stream.write_all(head.as_bytes());
    };
    {
        let mut counts = counts.lock().unwrap();
        let file = counts.entry(target.clone()).or_default();
        if file.in_flight == 0 {
            file.rounds += 1;
        }
        file.in_flight += 1;
    }
    reply(stream, bytes, &target, range, mode, counts)
}

/// Sends `bytes` (the file at `target`), or the asked-for `range` of it, as `mode` says.
fn reply<S: Write>(
    stream: &mut S,
    bytes: &[u8],
    target: &str,
    range: Option<(u64, u64)>,
    mode: Mode,
    counts: &Mutex<HashMap<String, FileCounts>>,
) -> std::io::Result<()> {
    if let Mode::Slow(ms) = mode {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
    // The request stops being in flight before its first byte leaves: a client that waits for
    // each reply cannot send its next request while this one still counts.
    counts
        .lock()
        .unwrap()
        .entry(target.to_string())
        .or_default()
        .in_flight -= 1;
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
        _ => ("200 OK", bytes, String::new()),
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
    let mut body = body;
    {
        let mut counts = counts.lock().unwrap();
        let file = counts.entry(target.to_string()).or_default();
        if let (true, Mode::DropAfter(limit)) = (target.ends_with(".xtc"), mode) {
            let allowed = limit.saturating_sub(file.served).min(body.len() as u64) as usize;
            body = &body[..allowed];
        }
        file.requests += 1;
        file.served += body.len() as u64;
    }
    stream.write_all(body)?;
    stream.flush()
}
