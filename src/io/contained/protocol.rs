//! The messages between a reader process and its parent, over the child's stdin and stdout.
//!
//! Every message is a length (u64, little-endian) and that many bytes; the first byte of a
//! message says what it is. The parent sends requests (`op` byte and a frame index); the child
//! answers each with any number of warnings and then exactly one reply. Numbers are
//! little-endian; positions and boxes are `f32` (what [`Frame`] holds), time is `f64`; strings
//! are a u64 length and UTF-8 bytes. Decoding never trusts a length: a reply that does not parse
//! to the end is garbage ([`Garbage`]), and nothing is allocated ahead of the bytes that arrive.

use std::io::{Read, Write};

use glam::Vec3;

use crate::io::IoError;
use crate::model::{Frame, Labels, Topology};

/// The longest message accepted (64 GiB: 5 billion atoms of positions); longer is garbage.
const MAX_MESSAGE: u64 = 1 << 36;

/// Request: the topology of a frame.
pub(super) const OP_TOPOLOGY: u8 = b'T';
/// Request: a frame (positions unchecked, box, time).
pub(super) const OP_FRAME: u8 = b'F';

/// Reply to the start: the file is open; it has this many frames.
pub(super) const TAG_OPEN: u8 = b'O';
/// Reply: a frame.
pub(super) const TAG_FRAME: u8 = b'F';
/// Reply: a topology.
pub(super) const TAG_TOPOLOGY: u8 = b'T';
/// Reply: the request failed (an error of the reader, not a crash).
pub(super) const TAG_ERROR: u8 = b'E';
/// Before a reply: a warning chemfiles gave.
pub(super) const TAG_WARNING: u8 = b'W';

/// A message that does not parse (the child is not what we started, or is broken).
#[derive(Debug)]
pub(super) struct Garbage;

/// Writes one message made of `body`.
pub(super) fn send(out: &mut impl Write, body: &[u8]) -> std::io::Result<()> {
    out.write_all(&(body.len() as u64).to_le_bytes())?;
    out.write_all(body)?;
    out.flush()
}

/// Reads one message; `Ok(None)` at the end of the stream (the other side is gone).
pub(super) fn receive(input: &mut impl Read) -> std::io::Result<Option<Vec<u8>>> {
    let mut length = [0u8; 8];
    match input.read_exact(&mut length) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
        Err(e) => return Err(e),
    }
    let length = u64::from_le_bytes(length);
    if length > MAX_MESSAGE {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "message too long",
        ));
    }
    let mut body = Vec::new();
    input.take(length).read_to_end(&mut body)?;
    if body.len() as u64 != length {
        return Ok(None);
    }
    Ok(Some(body))
}

/// Builds a message body.
#[derive(Default)]
pub(super) struct Writer(pub(super) Vec<u8>);

impl Writer {
    pub(super) fn tag(tag: u8) -> Self {
        Writer(vec![tag])
    }

    pub(super) fn u8(&mut self, v: u8) -> &mut Self {
        self.0.push(v);
        self
    }

    pub(super) fn u64(&mut self, v: u64) -> &mut Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    pub(super) fn f64(&mut self, v: f64) -> &mut Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    pub(super) fn str(&mut self, v: &str) -> &mut Self {
        self.u64(v.len() as u64);
        self.0.extend_from_slice(v.as_bytes());
        self
    }

    fn f32s(&mut self, v: impl ExactSizeIterator<Item = f32>) {
        self.u64(v.len() as u64);
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }

    fn u32s(&mut self, v: impl ExactSizeIterator<Item = u32>) {
        self.u64(v.len() as u64);
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }

    fn i64s(&mut self, v: &[i64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }

    fn labels(&mut self, labels: &Labels) {
        let (values, ids) = labels.distinct();
        self.u64(values.len() as u64);
        for v in values {
            self.str(v);
        }
        self.u32s(ids.iter().copied());
    }
}

/// Reads a message body from the front.
pub(super) struct Reader<'a>(pub(super) &'a [u8]);

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], Garbage> {
        if n > self.0.len() {
            return Err(Garbage);
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Ok(head)
    }

    pub(super) fn u8(&mut self) -> Result<u8, Garbage> {
        Ok(self.take(1)?[0])
    }

    pub(super) fn u64(&mut self) -> Result<u64, Garbage> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().map_err(|_| Garbage)?,
        ))
    }

    pub(super) fn f64(&mut self) -> Result<f64, Garbage> {
        Ok(f64::from_bits(self.u64()?))
    }

    /// A count of items of `size` bytes each that the rest of the message can hold.
    fn count(&mut self, size: usize) -> Result<usize, Garbage> {
        let n = usize::try_from(self.u64()?).map_err(|_| Garbage)?;
        if n.checked_mul(size).is_none_or(|bytes| bytes > self.0.len()) {
            return Err(Garbage);
        }
        Ok(n)
    }

    pub(super) fn str(&mut self) -> Result<String, Garbage> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| Garbage)
    }

    fn words<const N: usize>(&mut self) -> Result<Vec<[u8; N]>, Garbage> {
        let n = self.count(N)?;
        let bytes = self.take(n * N)?;
        Ok(bytes
            .chunks_exact(N)
            .map(|c| c.try_into().unwrap_or([0; N]))
            .collect())
    }

    fn f32s(&mut self) -> Result<Vec<f32>, Garbage> {
        Ok(self
            .words::<4>()?
            .into_iter()
            .map(f32::from_le_bytes)
            .collect())
    }

    fn u32s(&mut self) -> Result<Vec<u32>, Garbage> {
        Ok(self
            .words::<4>()?
            .into_iter()
            .map(u32::from_le_bytes)
            .collect())
    }

    fn i64s(&mut self) -> Result<Vec<i64>, Garbage> {
        Ok(self
            .words::<8>()?
            .into_iter()
            .map(i64::from_le_bytes)
            .collect())
    }

    fn labels(&mut self, atoms: Option<usize>) -> Result<Labels, Garbage> {
        let n = self.count(8)?;
        let mut labels = Labels::default();
        let mut map = Vec::with_capacity(n);
        for _ in 0..n {
            map.push(labels.intern(&self.str()?));
        }
        let ids = self.u32s()?;
        if atoms.is_some_and(|a| a != ids.len()) {
            return Err(Garbage);
        }
        let ids: Option<Vec<u32>> = ids.iter().map(|&i| map.get(i as usize).copied()).collect();
        labels.extend_ids(&ids.ok_or(Garbage)?);
        Ok(labels)
    }

    /// Fails unless the whole message was read.
    pub(super) fn end(&self) -> Result<(), Garbage> {
        if self.0.is_empty() {
            Ok(())
        } else {
            Err(Garbage)
        }
    }
}

/// A frame reply: time, box and positions of `frame`.
pub(super) fn encode_frame(frame: &Frame) -> Vec<u8> {
    let mut w = Writer::tag(TAG_FRAME);
    w.u8(u8::from(frame.time_ps.is_some()))
        .f64(frame.time_ps.unwrap_or(0.0));
    w.u8(u8::from(frame.cell.is_some()));
    let cell = frame.cell.unwrap_or([Vec3::ZERO; 3]);
    w.f32s(
        cell.iter()
            .flat_map(|r| r.to_array())
            .collect::<Vec<_>>()
            .into_iter(),
    );
    w.f32s(
        frame
            .positions
            .iter()
            .flat_map(|p| p.to_array())
            .collect::<Vec<_>>()
            .into_iter(),
    );
    w.0
}

/// The frame of a frame reply (after its tag), numbered `index`.
pub(super) fn decode_frame(r: &mut Reader<'_>, index: usize) -> Result<Frame, Garbage> {
    let has_time = r.u8()? != 0;
    let time = r.f64()?;
    let has_cell = r.u8()? != 0;
    let cell = r.f32s()?;
    let positions = r.f32s()?;
    r.end()?;
    if cell.len() != 9 || positions.len() % 3 != 0 {
        return Err(Garbage);
    }
    let row = |i: usize| Vec3::new(cell[3 * i], cell[3 * i + 1], cell[3 * i + 2]);
    Ok(Frame {
        index,
        time_ps: has_time.then_some(time),
        positions: positions
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect(),
        cell: has_cell.then(|| [row(0), row(1), row(2)]),
    })
}

/// A topology reply.
pub(super) fn encode_topology(t: &Topology) -> Vec<u8> {
    let mut w = Writer::tag(TAG_TOPOLOGY);
    w.u64(t.len() as u64);
    for labels in [
        &t.names,
        &t.elements,
        &t.residue_names,
        &t.chains,
        &t.segments,
        &t.types,
        &t.insertion_codes,
    ] {
        w.labels(labels);
    }
    for floats in [
        &t.radii,
        &t.b_factors,
        &t.occupancies,
        &t.masses,
        &t.charges,
    ] {
        w.f32s(floats.iter().copied());
    }
    w.i64s(&t.residue_ids);
    w.i64s(&t.serials);
    w.u32s(t.residue_index.iter().copied());
    w.u32s(
        t.bonds
            .iter()
            .flatten()
            .copied()
            .collect::<Vec<_>>()
            .into_iter(),
    );
    w.0
}

/// The topology of a topology reply (after its tag).
pub(super) fn decode_topology(r: &mut Reader<'_>) -> Result<Topology, Garbage> {
    let n = usize::try_from(r.u64()?).map_err(|_| Garbage)?;
    let mut t = Topology {
        names: r.labels(Some(n))?,
        elements: r.labels(None)?,
        residue_names: r.labels(None)?,
        chains: r.labels(None)?,
        segments: r.labels(None)?,
        types: r.labels(None)?,
        insertion_codes: r.labels(None)?,
        radii: r.f32s()?,
        b_factors: r.f32s()?,
        occupancies: r.f32s()?,
        masses: r.f32s()?,
        charges: r.f32s()?,
        residue_ids: r.i64s()?,
        serials: r.i64s()?,
        residue_index: r.u32s()?,
        residue_copies: Vec::new(),
        bonds: Vec::new(),
    };
    // Derived from the fields above, so not sent.
    t.number_residue_copies();
    let bonds = r.u32s()?;
    r.end()?;
    if bonds.len() % 2 != 0 || bonds.iter().any(|&a| a as usize >= n) {
        return Err(Garbage);
    }
    t.bonds = bonds.chunks_exact(2).map(|b| [b[0], b[1]]).collect();
    Ok(t)
}

/// An error reply: what kind of [`IoError`] the reader gave, its frame and numbers, its
/// message (the file is named by the parent, which knows it).
pub(super) fn encode_error(error: &IoError) -> Vec<u8> {
    let mut w = Writer::tag(TAG_ERROR);
    match error {
        IoError::Unreadable { message, .. } => w.u8(0).u64(0).u64(0).str(message),
        IoError::BadFrame { frame, message, .. } => w.u8(1).u64(*frame as u64).u64(0).str(message),
        IoError::FrameOutOfRange { frame, len, .. } => {
            w.u8(2).u64(*frame as u64).u64(*len as u64).str("")
        }
        IoError::Empty { what, .. } => w.u8(3).u64(0).u64(0).str(what),
        other => w.u8(0).u64(0).u64(0).str(&other.to_string()),
    };
    w.0
}

/// The error of an error reply (after its tag), naming `path`.
pub(super) fn decode_error(r: &mut Reader<'_>, path: &std::path::Path) -> Result<IoError, Garbage> {
    let kind = r.u8()?;
    let frame = usize::try_from(r.u64()?).map_err(|_| Garbage)?;
    let len = usize::try_from(r.u64()?).map_err(|_| Garbage)?;
    let message = r.str()?;
    r.end()?;
    let path = path.to_path_buf();
    Ok(match kind {
        0 => IoError::unreadable(&path, message),
        1 => IoError::bad_frame(&path, frame, message),
        2 => IoError::FrameOutOfRange { path, frame, len },
        3 => IoError::Empty {
            path,
            what: match message.as_str() {
                "no atoms" => "no atoms",
                "the file is empty" => "the file is empty",
                _ => "no frames",
            },
        },
        _ => return Err(Garbage),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_and_topologies_survive_the_trip() {
        let frame = Frame {
            index: 3,
            time_ps: Some(1.5),
            positions: vec![Vec3::new(1.0, -2.0, 3.5), Vec3::new(f32::NAN, 0.0, 1e30)],
            cell: Some([Vec3::X, Vec3::Y * 2.0, Vec3::Z * 3.0]),
        };
        let body = encode_frame(&frame);
        assert_eq!(body[0], TAG_FRAME);
        let back = decode_frame(&mut Reader(&body[1..]), 3).unwrap();
        assert_eq!(back.cell, frame.cell);
        assert_eq!(back.time_ps, frame.time_ps);
        assert_eq!(back.positions[0], frame.positions[0]);
        assert!(back.positions[1].x.is_nan());
        let mut t = Topology {
            names: ["CA", "CB", "CA"].into_iter().collect(),
            residue_ids: vec![1, 1, 2],
            bonds: vec![[0, 1], [1, 2]],
            ..Default::default()
        };
        t.complete_defaults();
        let body = encode_topology(&t);
        let back = decode_topology(&mut Reader(&body[1..])).unwrap();
        assert_eq!(back.names.to_strings(), t.names.to_strings());
        assert_eq!(back.bonds, t.bonds);
        assert_eq!(back.residue_ids, t.residue_ids);
        // Cut anywhere, a reply is garbage, never a panic.
        for cut in 1..body.len() {
            assert!(decode_topology(&mut Reader(&body[1..cut])).is_err());
        }
    }
}
