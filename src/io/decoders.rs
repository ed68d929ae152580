//! The Rust decoders of compressed inputs (`.gz`, `.bz2`, `.xz`), reading what the command-line
//! tools accept:
//!
//! - gzip: concatenated members, and zero bytes after the last member (tape and block-device
//!   copies pad files so; `gzip -d` ignores them with a warning). Anything else after a member
//!   that is not another member is an error, as before.
//! - xz: decoded in reads of at most [`XZ_READ`] bytes, so that a cut file gives everything
//!   before the cut: the decoder fails a whole read when its input ends inside it, and with one
//!   large read a cut file gave nothing at all.
//! - bzip2: concatenated streams.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};

/// The most an `.xz` read asks for at once (bytes).
const XZ_READ: usize = 16 * 1024;

/// The decoder of `compression` (`GZ`, `XZ`, else bzip2) reading `file`.
pub(crate) fn decoder(file: File, compression: Option<&str>) -> Box<dyn Read> {
    let file = BufReader::new(file);
    match compression {
        Some("GZ") => Box::new(GzMembers::Between(file)),
        Some("XZ") => Box::new(SmallReads(lzma_rust2::XzReader::new(file, true))),
        _ => Box::new(bzip2::read::MultiBzDecoder::new(file)),
    }
}

/// Reads through `0` at most [`XZ_READ`] bytes at a time.
struct SmallReads<R>(R);

impl<R: Read> Read for SmallReads<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(XZ_READ);
        self.0.read(&mut buf[..n])
    }
}

/// The members of a gzip file, one after the other, then optional zero padding.
enum GzMembers<R: BufRead> {
    /// Inside a member.
    Member(flate2::bufread::GzDecoder<R>),
    /// Before the first member or after one: another member, padding or the end follows.
    Between(R),
    /// The end of the file (after padding, or an error).
    Done,
}

impl<R: BufRead> Read for GzMembers<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        loop {
            match std::mem::replace(self, GzMembers::Done) {
                GzMembers::Member(mut member) => {
                    let n = member.read(buf)?;
                    if n > 0 || buf.is_empty() {
                        *self = GzMembers::Member(member);
                        return Ok(n);
                    }
                    *self = GzMembers::Between(member.into_inner());
                }
                GzMembers::Between(mut rest) => {
                    let next = rest.fill_buf()?;
                    match next.first() {
                        None => return Ok(0),
                        Some(0) => {
                            check_zeros(&mut rest)?;
                            return Ok(0);
                        }
                        Some(_) => *self = GzMembers::Member(flate2::bufread::GzDecoder::new(rest)),
                    }
                }
                GzMembers::Done => return Ok(0),
            }
        }
    }
}

/// Reads `rest` to its end; fails unless every byte is zero.
fn check_zeros(rest: &mut impl BufRead) -> std::io::Result<()> {
    let mut padding = 0u64;
    loop {
        let bytes = rest.fill_buf()?;
        if bytes.is_empty() {
            return Ok(());
        }
        if let Some(at) = bytes.iter().position(|&b| b != 0) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "data after {} bytes of zero padding that ends the gzip stream",
                    padding + at as u64
                ),
            ));
        }
        let n = bytes.len();
        padding += n as u64;
        rest.consume(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn gzip(text: &[u8]) -> Vec<u8> {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(text).unwrap();
        e.finish().unwrap()
    }

    fn decode(bytes: Vec<u8>) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::new();
        GzMembers::Between(std::io::Cursor::new(bytes)).read_to_end(&mut out)?;
        Ok(out)
    }

    #[test]
    fn gzip_members_and_zero_padding() {
        let mut bytes = gzip(b"first\n");
        bytes.extend(gzip(b"second\n"));
        assert_eq!(decode(bytes.clone()).unwrap(), b"first\nsecond\n");
        bytes.extend([0u8; 4096]);
        assert_eq!(decode(bytes.clone()).unwrap(), b"first\nsecond\n");
        bytes.push(7);
        let error = decode(bytes).unwrap_err().to_string();
        assert!(
            error.contains("after 4096 bytes of zero padding"),
            "{error}"
        );
        assert_eq!(decode(Vec::new()).unwrap(), b"");
        let mut garbage = gzip(b"x");
        garbage.extend(b"not gzip");
        assert!(decode(garbage).is_err());
    }
}
