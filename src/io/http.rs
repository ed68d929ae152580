//! Reading a trajectory over HTTP(S) without downloading it: [`RangeSource`] is a `Read + Seek`
//! view of a URL that fetches only the byte ranges read (HTTP range requests, status 206),
//! in aligned blocks kept in a bounded least-recently-used cache, so that the XTC/TRR header
//! walk and frame reader ([`super::xdr`], [`super::xdr_reader`]) run over it as over a file.
//! [`download`] fetches a file whole: a topology, or a trajectory that cannot be read in place.
//!
//! The client is `ureq` (blocking, rustls for HTTPS), with connect and read timeouts. A server
//! that answers a ranged GET with anything but 206 does not support ranges and is refused; a
//! 404 or any other status, a refused or dropped connection, or a reply shorter than asked for
//! is a one-line error naming the URL (and the byte range).

use std::collections::{BTreeMap, HashMap};
use std::io::{self, IsTerminal, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use indicatif::{HumanBytes, ProgressBar, ProgressStyle};
use ureq::Agent;

use super::IoError;
use super::http_prefetch::{Prefetcher, prefetch_frames};
use super::xdr_error::RemoteFailure;

/// The cache's unit: bytes fetched and kept together, aligned to multiples of this (4 KiB).
/// Small, so that walking the frame headers fetches little more than the headers.
pub(crate) const BLOCK_BYTES: u64 = 4 * 1024;
/// Most bytes the cache keeps (64 MiB); the least recently read blocks go first.
pub(crate) const CACHE_BYTES: u64 = 64 * 1024 * 1024;
/// Bytes fetched past a read's end in the same request while frames are read (256 KiB), up to
/// the first block already cached (the next frame's header, after the walk).
pub(crate) const READ_AHEAD_BYTES: u64 = 256 * 1024;
/// While the headers are walked (no read-ahead set), a fetch that starts less than this many
/// bytes (12 KiB) after the previous fetch's end also fetches [`READ_AHEAD_BYTES`] past it
/// (frames further apart are prefetched, `super::http_prefetch`):
/// frames that small (a small system's XTC frames are a few kB) are walked in a request per
/// 256 KiB instead of one per frame, for at most 4 times the bytes of fetching each header's
/// block. Frames further apart are fetched header by header: where the next header lies is
/// known only once this one is read.
pub(crate) const WALK_GAP_BYTES: u64 = 3 * BLOCK_BYTES;
/// Longest wait for a connection (10 s).
const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);
/// Longest wait for a reply's head, and for its body (30 s each).
const READ_TIMEOUT: Duration = Duration::from_secs(30);

/// The URL `path` holds, when it is one (`http://` or `https://`).
pub(crate) fn url_of(path: &Path) -> Option<&str> {
    let text = path.to_str()?;
    let scheme = text.get(..8).unwrap_or(text).to_ascii_lowercase();
    (scheme.starts_with("http://") || scheme.starts_with("https://")).then_some(text)
}

/// The last segment of `url`'s path, without a query or fragment (`top.gro`).
pub(crate) fn file_name(url: &str) -> &str {
    let end = url.find(['?', '#']).unwrap_or(url.len());
    let path = &url[..end];
    path.rsplit('/').next().unwrap_or(path)
}

/// The environment variable naming a PEM file of certificates trusted for HTTPS beside the
/// built-in web roots (a self-hosted server's own certificate authority; curl's `--cacert`
/// would trust only the file, we keep the public roots so a public URL still opens in the
/// same run).
pub(crate) const CA_FILE_VAR: &str = "MDSURF_CA_FILE";

/// The HTTP client: timeouts, statuses as replies, and the certificates of [`CA_FILE_VAR`]
/// added to the web roots when set (the reason, one line, when that file gives none).
fn agent() -> Result<Agent, String> {
    let mut config = Agent::config_builder()
        .timeout_connect(Some(CONNECT_TIMEOUT))
        .timeout_recv_response(Some(READ_TIMEOUT))
        .timeout_recv_body(Some(READ_TIMEOUT))
        .http_status_as_error(false);
    if let Some(file) = std::env::var_os(CA_FILE_VAR) {
        let roots = roots_with_ca_file(Path::new(&file))?;
        let tls = ureq::tls::TlsConfig::builder()
            .root_certs(ureq::tls::RootCerts::new_with_certs(&roots))
            .build();
        config = config.tls_config(tls);
    }
    Ok(config.build().into())
}

/// Mozilla's web roots followed by the certificates of the PEM file `file` (the reason, one
/// line naming [`CA_FILE_VAR`] and the file, when it cannot be read or holds none).
fn roots_with_ca_file(file: &Path) -> Result<Vec<ureq::tls::Certificate<'static>>, String> {
    let shown = file.display();
    let pem = std::fs::read(file).map_err(|e| format!("{CA_FILE_VAR}={shown}: {e}"))?;
    let mut added = Vec::new();
    for item in ureq::tls::parse_pem(&pem) {
        match item {
            Ok(ureq::tls::PemItem::Certificate(cert)) => added.push(cert),
            Ok(_) => {}
            Err(e) => return Err(format!("{CA_FILE_VAR}={shown}: {}", one_line(e))),
        }
    }
    if added.is_empty() {
        return Err(format!(
            "{CA_FILE_VAR}={shown}: no PEM certificate in the file"
        ));
    }
    let web = webpki_root_certs::TLS_SERVER_ROOT_CERTS
        .iter()
        .map(|cert| ureq::tls::Certificate::from_der(cert.as_ref()));
    Ok(web.chain(added).collect())
}

/// One line from a client error (ureq's messages may wrap).
fn one_line(error: impl std::fmt::Display) -> String {
    error.to_string().replace(['\n', '\r'], " ")
}

/// Why a reply with `status` cannot be used: the status and its reason.
fn status_line(status: ureq::http::StatusCode) -> String {
    format!(
        "HTTP {} {}",
        status.as_u16(),
        status.canonical_reason().unwrap_or("")
    )
    .trim_end()
    .to_string()
}

/// A network failure on bytes `start..end` as an I/O error the readers pass on.
fn failure(start: u64, end: u64, reason: impl std::fmt::Display) -> io::Error {
    io::Error::other(RemoteFailure(format!(
        "bytes {start}-{}: {reason}",
        end.saturating_sub(1)
    )))
}

/// Downloads `url` (the user's `path`) whole into `dir`, under the URL's file name (so that
/// its extension says its format). Returns the file written. With `why` (a trajectory that
/// cannot be read in place), a note on stderr says the file is downloaded whole, its size and
/// why, and a bar shows the download when stderr is a terminal.
pub(crate) fn download(
    path: &Path,
    url: &str,
    dir: &Path,
    why: Option<&str>,
) -> Result<PathBuf, IoError> {
    let fail = |message: String| IoError::unreadable(path, message);
    let mut reply = match agent().map_err(&fail)?.get(url).call() {
        Ok(reply) => reply,
        Err(e) => return Err(fail(one_line(e))),
    };
    let status = reply.status();
    if !status.is_success() {
        return Err(IoError::NotFound {
            path: path.to_path_buf(),
            reason: status_line(status),
        });
    }
    let announced = reply
        .headers()
        .get("content-length")
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    let bar = match why {
        Some(why) => download_note(url, announced, why),
        None => ProgressBar::hidden(),
    };
    let name = file_name(url);
    let name = if name.is_empty() { "download" } else { name };
    let target = dir.join(name);
    let mut file = std::fs::File::create(&target).map_err(|e| fail(e.to_string()))?;
    let mut body = bar.wrap_read(reply.body_mut().as_reader());
    let copied = io::copy(&mut body, &mut file)
        .map_err(|e| fail(format!("the download broke off ({})", one_line(e))))?;
    bar.finish_and_clear();
    if let Some(announced) = announced
        && copied != announced
    {
        return Err(fail(format!(
            "the download broke off after {copied} of {announced} bytes"
        )));
    }
    file.flush().map_err(|e| fail(e.to_string()))?;
    Ok(target)
}

/// Prints the note that `url` (of `size` bytes, when announced) is downloaded whole and `why`;
/// returns a bar of the download, on stderr when it is a terminal (hidden otherwise).
fn download_note(url: &str, size: Option<u64>, why: &str) -> ProgressBar {
    let shown = size.map_or("size not announced".to_string(), |n| {
        HumanBytes(n).to_string()
    });
    eprintln!("note: downloading {url} whole ({shown}): {why}");
    if !io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = size.map_or_else(ProgressBar::no_length, ProgressBar::new);
    if let Ok(style) =
        ProgressStyle::with_template("downloading {msg} {bar:30} {bytes}/{total_bytes} {eta}")
    {
        bar.set_style(style);
    }
    bar.set_message(file_name(url).to_string());
    bar
}

/// A file behind a URL, read through range requests: `Read + Seek` over its bytes.
pub(crate) struct RangeSource {
    url: String,
    agent: Agent,
    /// The file's size in bytes.
    size: u64,
    /// Where the next read starts (bytes).
    position: u64,
    /// Cached blocks by index (offset / [`BLOCK_BYTES`]): last use and bytes.
    blocks: HashMap<u64, (u64, Vec<u8>)>,
    /// Block indices by last use, oldest first.
    by_use: BTreeMap<u64, u64>,
    /// Counts reads, to order the blocks by use.
    clock: u64,
    /// Bytes fetched past a read's end (0 while the headers are walked).
    read_ahead: u64,
    /// The block after the last one fetched (where a forward walk's next fetch would start).
    fetched_to: u64,
    /// The frame headers fetched ahead while the headers are walked.
    prefetch: Prefetcher,
}

impl RangeSource {
    /// Opens `url` (the user's `path`, for messages): the first ranged GET learns the file's size
    /// from `Content-Range` and refuses a server that does not reply 206. Reads fetch nothing
    /// ahead until [`RangeSource::set_read_ahead`].
    pub(crate) fn open(path: &Path, url: &str) -> Result<RangeSource, IoError> {
        let fail = |message: String| IoError::unreadable(path, message);
        let agent = agent().map_err(&fail)?;
        let reply = agent
            .get(url)
            .header("Range", format!("bytes=0-{}", BLOCK_BYTES - 1))
            .call()
            .map_err(|e| fail(one_line(e)))?;
        let status = reply.status().as_u16();
        match status {
            206 => {}
            200 => {
                return Err(fail(
                    "the server does not support range requests (HTTP 206)".to_string(),
                ));
            }
            416 => return Err(fail("the file is empty (HTTP 416)".to_string())),
            _ => {
                return Err(IoError::NotFound {
                    path: path.to_path_buf(),
                    reason: status_line(reply.status()),
                });
            }
        }
        let size = reply
            .headers()
            .get("content-range")
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.rsplit('/').next())
            .and_then(|total| total.trim().parse::<u64>().ok())
            .ok_or_else(|| {
                fail("the server gave no file size (Content-Range: bytes a-b/SIZE)".to_string())
            })?;
        let mut source = RangeSource {
            url: url.to_string(),
            agent,
            size,
            position: 0,
            blocks: HashMap::new(),
            by_use: BTreeMap::new(),
            clock: 0,
            read_ahead: 0,
            fetched_to: 1,
            prefetch: Prefetcher::new(prefetch_frames()),
        };
        let first = BLOCK_BYTES.min(size);
        let bytes = body(reply, 0, first).map_err(|e| fail(e.to_string()))?;
        source.store(0, bytes);
        Ok(source)
    }

    /// The file's size in bytes.
    pub(crate) fn size(&self) -> u64 {
        self.size
    }

    /// Sets how many bytes past a read's end each request also fetches (see
    /// [`READ_AHEAD_BYTES`]).
    pub(crate) fn set_read_ahead(&mut self, bytes: u64) {
        self.read_ahead = bytes;
    }

    /// Fetches bytes `start..end` (block aligned, or ending at the file's end) in one request.
    fn fetch(&self, start: u64, end: u64) -> io::Result<Vec<u8>> {
        fetch_range(&self.agent, &self.url, start, end)
    }

    /// Keeps `bytes` (starting at block `first`) as cached blocks, dropping the least recently
    /// used ones beyond [`CACHE_BYTES`].
    fn store(&mut self, first: u64, bytes: Vec<u8>) {
        for (k, chunk) in bytes.chunks(BLOCK_BYTES as usize).enumerate() {
            let index = first + k as u64;
            self.clock += 1;
            if let Some((used, _)) = self.blocks.remove(&index) {
                self.by_use.remove(&used);
            }
            self.blocks.insert(index, (self.clock, chunk.to_vec()));
            self.by_use.insert(self.clock, index);
        }
        while self.blocks.len() as u64 * BLOCK_BYTES > CACHE_BYTES {
            let Some((_, oldest)) = self.by_use.pop_first() else {
                break;
            };
            self.blocks.remove(&oldest);
        }
    }

    /// Makes blocks `first..=last` cached, fetching the missing ones (and the read-ahead) in
    /// one request.
    fn ensure(&mut self, first: u64, last: u64) -> io::Result<()> {
        let missing = |s: &Self, b: u64| !s.blocks.contains_key(&b);
        let Some(start) = (first..=last).find(|&b| missing(self, b)) else {
            return Ok(());
        };
        let blocks_in_file = self.size.div_ceil(BLOCK_BYTES);
        let walking_small_frames = self.read_ahead == 0
            && start >= self.fetched_to
            && (start - self.fetched_to) * BLOCK_BYTES < WALK_GAP_BYTES;
        let ahead = match walking_small_frames {
            true => READ_AHEAD_BYTES / BLOCK_BYTES,
            false => self.read_ahead / BLOCK_BYTES,
        };
        let mut end = (start..=last)
            .rev()
            .find(|&b| missing(self, b))
            .unwrap_or(start);
        while end + 1 < blocks_in_file && end < last + ahead && missing(self, end + 1) {
            end += 1;
        }
        let end_byte = ((end + 1) * BLOCK_BYTES).min(self.size);
        let bytes = self.fetch(start * BLOCK_BYTES, end_byte)?;
        self.store(start, bytes);
        self.fetched_to = end + 1;
        if self.read_ahead == 0 && !walking_small_frames {
            self.prefetch_headers(self.position);
        }
        Ok(())
    }

    /// After a walk's fetch for a read at byte `start` (a frame header): fetches, in
    /// parallel, the windows where the next headers should lie when the walk's stride is
    /// steady ([`Prefetcher::plan`]), and keeps them. Failed prefetches are ignored (the
    /// walk's own fetch reports the error).
    fn prefetch_headers(&mut self, start: u64) {
        let windows = self.prefetch.plan(start, self.size);
        if windows.is_empty() {
            return;
        }
        let fetched: Vec<(u64, io::Result<Vec<u8>>)> = std::thread::scope(|scope| {
            let jobs: Vec<_> = windows
                .iter()
                .map(|&(first, end)| {
                    let (agent, url) = (self.agent.clone(), self.url.as_str());
                    (
                        first,
                        scope.spawn(move || fetch_range(&agent, url, first, end)),
                    )
                })
                .collect();
            jobs.into_iter()
                .map(|(first, job)| {
                    let bytes = job
                        .join()
                        .unwrap_or_else(|_| Err(io::Error::other("a prefetch thread panicked")));
                    (first, bytes)
                })
                .collect()
        });
        for (first, bytes) in fetched {
            if let Ok(bytes) = bytes {
                self.prefetch.keep(first, bytes);
            }
        }
    }

    /// Marks block `index` as just used and returns its bytes.
    fn touch(&mut self, index: u64) -> Option<&[u8]> {
        self.clock += 1;
        let clock = self.clock;
        let (used, bytes) = self.blocks.get_mut(&index)?;
        self.by_use.remove(used);
        *used = clock;
        self.by_use.insert(clock, index);
        Some(bytes)
    }
}

/// Fetches bytes `start..end` of `url` in one ranged GET.
fn fetch_range(agent: &Agent, url: &str, start: u64, end: u64) -> io::Result<Vec<u8>> {
    let reply = agent
        .get(url)
        .header("Range", format!("bytes={start}-{}", end - 1))
        .call()
        .map_err(|e| failure(start, end, one_line(e)))?;
    if reply.status().as_u16() != 206 {
        return Err(failure(start, end, status_line(reply.status())));
    }
    body(reply, start, end)
}

/// The body of `reply`, which must hold bytes `start..end`.
fn body(mut reply: ureq::http::Response<ureq::Body>, start: u64, end: u64) -> io::Result<Vec<u8>> {
    let want = end - start;
    let mut bytes = Vec::with_capacity(want as usize);
    let read = reply
        .body_mut()
        .as_reader()
        .take(want)
        .read_to_end(&mut bytes);
    if let Err(e) = read {
        return Err(failure(
            start,
            end,
            format!("the connection dropped ({})", one_line(e)),
        ));
    }
    if (bytes.len() as u64) < want {
        return Err(failure(
            start,
            end,
            format!("the connection dropped after {} bytes", bytes.len()),
        ));
    }
    Ok(bytes)
}

impl Read for RangeSource {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.position >= self.size || buf.is_empty() {
            return Ok(0);
        }
        // At most half the cache per call, so that one read never evicts its own blocks.
        let want = (buf.len() as u64)
            .min(self.size - self.position)
            .min(CACHE_BYTES / 2);
        if self.read_ahead == 0 && self.prefetch.read(self.position, &mut buf[..want as usize]) {
            self.position += want;
            return Ok(want as usize);
        }
        let first = self.position / BLOCK_BYTES;
        let last = (self.position + want - 1) / BLOCK_BYTES;
        self.ensure(first, last)?;
        let mut done = 0u64;
        while done < want {
            let at = self.position + done;
            let within = (at % BLOCK_BYTES) as usize;
            let (start, end) = (self.position, self.position + want);
            let block = self
                .touch(at / BLOCK_BYTES)
                .ok_or_else(|| failure(start, end, "a fetched block is missing"))?;
            let n = (block.len().saturating_sub(within) as u64).min(want - done) as usize;
            if n == 0 {
                break;
            }
            buf[done as usize..done as usize + n].copy_from_slice(&block[within..within + n]);
            done += n as u64;
        }
        self.position += done;
        Ok(done as usize)
    }
}

impl Seek for RangeSource {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        let target = match to {
            SeekFrom::Start(at) => Some(at),
            SeekFrom::End(delta) => self.size.checked_add_signed(delta),
            SeekFrom::Current(delta) => self.position.checked_add_signed(delta),
        };
        let target = target
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "seek before the start"))?;
        self.position = target;
        Ok(target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ca_file_adds_its_certificates_to_the_web_roots() {
        let made = rcgen::generate_simple_self_signed(vec!["127.0.0.1".to_string()]).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("ca.pem");
        std::fs::write(&file, made.cert.pem()).unwrap();
        let roots = roots_with_ca_file(&file).unwrap();
        let web = webpki_root_certs::TLS_SERVER_ROOT_CERTS;
        assert!(web.len() > 100, "{} web roots", web.len());
        assert_eq!(roots.len(), web.len() + 1);
        assert_eq!(roots[0].der(), web[0].as_ref());
        assert_eq!(roots.last().unwrap().der(), made.cert.der().as_ref());

        std::fs::write(&file, "not a certificate\n").unwrap();
        let error = roots_with_ca_file(&file).unwrap_err();
        assert!(error.starts_with("MDSURF_CA_FILE="), "{error}");
        assert!(error.ends_with("no PEM certificate in the file"), "{error}");
    }

    #[test]
    fn urls_are_recognised_and_named() {
        assert!(url_of(Path::new("https://h/p/top.gro")).is_some());
        assert!(url_of(Path::new("HTTP://h/t.xtc")).is_some());
        assert!(url_of(Path::new("/tmp/http://x")).is_none());
        assert!(url_of(Path::new("top.gro")).is_none());
        assert_eq!(file_name("https://h/a/b/traj.xtc?sig=1#x"), "traj.xtc");
    }

    #[test]
    fn the_cache_keeps_at_most_its_size_and_drops_the_least_recently_used() {
        let blocks_cached = CACHE_BYTES / BLOCK_BYTES;
        let mut source = RangeSource {
            url: "http://127.0.0.1:1/t.xtc".to_string(),
            agent: agent().unwrap(),
            size: 4 * CACHE_BYTES,
            position: 0,
            blocks: HashMap::new(),
            by_use: BTreeMap::new(),
            clock: 0,
            read_ahead: 0,
            fetched_to: 0,
            prefetch: Prefetcher::new(0),
        };
        let block = |k: u64| vec![k as u8; BLOCK_BYTES as usize];
        for k in 0..blocks_cached {
            source.store(k, block(k));
        }
        assert_eq!(source.blocks.len() as u64, blocks_cached);
        // Block 0 is read again: block 1 is now the least recently used.
        assert_eq!(source.touch(0).map(|b| b[0]), Some(0));
        source.store(blocks_cached, block(7));
        assert_eq!(source.blocks.len() as u64 * BLOCK_BYTES, CACHE_BYTES);
        assert!(source.blocks.contains_key(&0));
        assert!(!source.blocks.contains_key(&1));
        // Cached bytes are read without the network (the URL has no server).
        source.seek(SeekFrom::Start(BLOCK_BYTES * 2 + 5)).unwrap();
        let mut read = [0u8; 3];
        source.read_exact(&mut read).unwrap();
        assert_eq!(read, [2, 2, 2]);
        // A missing block needs the network: a one-line error naming the byte range.
        source.seek(SeekFrom::Start(BLOCK_BYTES)).unwrap();
        let error = source.read_exact(&mut read).unwrap_err();
        let reason = super::super::xdr_error::remote_failure(&error).unwrap();
        assert!(reason.starts_with("bytes 4096-"), "{reason}");
        assert!(!reason.contains('\n'), "{reason}");
    }
}
