//! Line ends as old Mac tools write them: a carriage return alone (`\r`, "CR-only"). The readers
//! split lines at `\n` (and drop a `\r` before it), so such a file read as one long line: "no
//! atoms". Here every `\r` that is not followed by `\n` becomes `\n`, in a whole buffer or in a
//! stream cut into pieces; CRLF and LF files are left as they are.

/// `bytes` with every lone `\r` made `\n` (returned as it is when it has none).
pub(crate) fn lone_cr_to_lf(mut bytes: Vec<u8>) -> Vec<u8> {
    if !has_lone_cr(&bytes) {
        return bytes;
    }
    let next: Vec<bool> = bytes
        .windows(2)
        .map(|w| w[1] == b'\n')
        .chain([false])
        .collect();
    for (b, followed) in bytes.iter_mut().zip(next) {
        if *b == b'\r' && !followed {
            *b = b'\n';
        }
    }
    bytes
}

/// True when `bytes` holds a `\r` not followed by `\n` (a `\r` ending `bytes` counts).
pub(crate) fn has_lone_cr(bytes: &[u8]) -> bool {
    memchr::memchr_iter(b'\r', bytes).any(|i| bytes.get(i + 1) != Some(&b'\n'))
}

/// [`lone_cr_to_lf`] on a stream given piece by piece: a `\r` ending one piece waits for the
/// next piece's first byte.
#[derive(Debug, Default)]
pub(crate) struct CrToLf {
    /// A `\r` ended the previous piece.
    pending_cr: bool,
}

impl CrToLf {
    /// Appends `piece`, its lone `\r`s made `\n`, to `out`; `last` ends the stream.
    pub(crate) fn push(&mut self, piece: &[u8], last: bool, out: &mut Vec<u8>) {
        if self.pending_cr {
            out.push(if piece.first() == Some(&b'\n') {
                b'\r'
            } else {
                b'\n'
            });
            self.pending_cr = false;
        }
        let (body, ends_cr) = match piece.split_last() {
            Some((b'\r', body)) if !last => (body, true),
            _ => (piece, false),
        };
        let start = out.len();
        out.extend_from_slice(body);
        let fixed = lone_cr_to_lf(out.split_off(start));
        out.extend_from_slice(&fixed);
        self.pending_cr = ends_cr;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lone_cr_becomes_lf_and_crlf_stays() {
        assert_eq!(lone_cr_to_lf(b"a\rb\r\nc\r".to_vec()), b"a\nb\r\nc\n");
        assert_eq!(lone_cr_to_lf(b"a\nb\r\n".to_vec()), b"a\nb\r\n");
    }

    #[test]
    fn a_stream_cut_anywhere_gives_the_same_bytes() {
        let text = b"ATOM 1\rATOM 2\r\nATOM 3\r\rEND\r";
        let whole = lone_cr_to_lf(text.to_vec());
        for cut in 0..=text.len() {
            let mut fix = CrToLf::default();
            let mut out = Vec::new();
            fix.push(&text[..cut], false, &mut out);
            fix.push(&text[cut..], false, &mut out);
            fix.push(&[], true, &mut out);
            assert_eq!(out, whole, "cut at {cut}");
        }
    }
}
