//! The fast path of [`open`](super::open) for large single-frame text files: plain PDB (`.pdb`,
//! `.ent`) and plain XYZ files (also compressed ones in a build without the `chemfiles`
//! feature) are read here in one pass over their bytes, without chemfiles.
//! Through chemfiles a 129k-atom PDB was parsed four times (topology, positions, the frame-0
//! check, the first frame), plus once by the wwPDB column reader and once for CONECT records,
//! each time with per-atom strings and C calls.
//!
//! The readers give what the chemfiles path gives (names, types, elements, masses,
//! charges, residues and their runs, chains, segments, B-factors, occupancies, serials, bonds,
//! positions in Å and the box); `tests/it/io_fast.rs` compares both on every test file. Numbers
//! are parsed with Rust's correctly rounded parser (chemfiles' own is not, so an f64 may differ
//! in its last bit; the f32 positions agree within 1e-5 Å), lines are found with `memchr`. Any file they do not reproduce exactly (several frames, extended XYZ, a line
//! chemfiles would reject, an odd CONECT record) returns `None` and goes the chemfiles way, which
//! also gives the usual one-line errors. Bytes that are not ASCII never panic: in PDB columns
//! each becomes `?` (as [`super::prepare`] does for chemfiles), in XYZ names invalid UTF-8 is read
//! as Latin-1.
//!
//! Large files are cut into pieces of whole lines ([`line_pieces`]) parsed in parallel; what
//! carries state from line to line (residues, TER and CONECT records in PDB files) is then
//! applied piece after piece, in file order, so the result is the same for any number of
//! threads.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::format::FileFormat;
use super::{fast_pdb, fast_xyz};
use crate::model::{Frame, Labels, Topology};

/// What a fast reader read: the topology (as the chemfiles path leaves it before
/// [`Topology::complete_elements_and_radii`]) and the file's only frame (positions in Å, box).
pub(crate) struct FastRead {
    /// Names, residues, bonds, ... (radii still 0).
    pub topology: Topology,
    /// Frame 0.
    pub frame: Frame,
}

/// Reads `path` through a fast reader when its format has one and the file is one it reproduces
/// exactly (see the module notes); `None` sends it to chemfiles.
pub(crate) fn read(path: &Path, format: &FileFormat) -> Option<FastRead> {
    if std::env::var_os("MDSURF_NO_FAST_READ").is_some() {
        return None;
    }
    let compressed = format.chemfiles != format.base;
    if !matches!(format.base, "PDB" | "XYZ") {
        return None;
    }
    let bytes = if compressed {
        // With chemfiles a compressed file goes its way (as it always has); without it, ours
        // reads the whole decompressed stream (a cut stream is left to the error of that path).
        if cfg!(feature = "chemfiles") {
            return None;
        }
        match super::prepare::read_all(path, format).ok()? {
            (bytes, None) => bytes,
            (_, Some(_cut)) => return None,
        }
    } else {
        super::line_ends::lone_cr_to_lf(std::fs::read(path).ok()?)
    };
    match format.base {
        "PDB" => fast_pdb::read(&bytes),
        _ => fast_xyz::read(&bytes),
    }
}

/// The lines of `bytes` as chemfiles' `readline` gives them: split at `\n`, a `\r` before it
/// dropped; a last line without `\n` counts, an empty tail after the last `\n` does not.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = bytes;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let (line, next) = match memchr::memchr(b'\n', rest) {
            Some(i) => (&rest[..i], &rest[i + 1..]),
            None => (rest, &rest[rest.len()..]),
        };
        rest = next;
        Some(line.strip_suffix(b"\r").unwrap_or(line))
    })
}

/// Bytes per piece when a file's lines are split for parsing in parallel ([`line_pieces`]).
pub(crate) const PIECE_BYTES: usize = 1 << 19;

/// `bytes` cut into runs of whole lines of about `size` bytes each (every piece but the last
/// ends just after a `\n`), so that [`lines`] of the pieces, one after the other, are the
/// lines of `bytes`. Pieces are parsed in parallel and their results joined in order; where
/// the cuts fall depends on the bytes only, never on the number of threads.
pub(crate) fn line_pieces(bytes: &[u8], size: usize) -> Vec<&[u8]> {
    let mut pieces = Vec::with_capacity(bytes.len() / size.max(1) + 1);
    let mut rest = bytes;
    while !rest.is_empty() {
        let cut = if rest.len() <= size {
            rest.len()
        } else {
            memchr::memchr(b'\n', &rest[size..]).map_or(rest.len(), |k| size + k + 1)
        };
        let (piece, tail) = rest.split_at(cut);
        pieces.push(piece);
        rest = tail;
    }
    pieces
}

/// The number of lines [`lines`] finds in `bytes`.
pub(crate) fn line_count(bytes: &[u8]) -> usize {
    let breaks = memchr::memchr_iter(b'\n', bytes).count();
    breaks + usize::from(bytes.last().is_some_and(|&b| b != b'\n'))
}

/// The bytes of `bytes` after its first `count` lines (as [`lines`] counts them); empty when
/// it has fewer.
pub(crate) fn skip_lines(bytes: &[u8], count: usize) -> &[u8] {
    let mut rest = bytes;
    for _ in 0..count {
        rest = match memchr::memchr(b'\n', rest) {
            Some(i) => &rest[i + 1..],
            None => &rest[rest.len()..],
        };
    }
    rest
}

/// A hasher for short byte strings and small integers (the multiply-rotate hash of rustc's
/// `FxHasher`): much faster than the default SipHash, and these tables hold file contents
/// whose order never depends on hashing, so its lack of DoS resistance does not matter.
#[derive(Default, Clone, Copy)]
pub(crate) struct QuickHasher(u64);

impl std::hash::Hasher for QuickHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn write_u8(&mut self, b: u8) {
        self.write_u64(u64::from(b));
    }

    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }

    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }

    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// A `HashMap` hashed with [`QuickHasher`].
pub(crate) type QuickMap<K, V> = HashMap<K, V, std::hash::BuildHasherDefault<QuickHasher>>;

/// Distinct values in the order they were first seen, and each item's index among them: one
/// piece's names, interned while it is parsed (see [`line_pieces`]).
pub(crate) struct LocalValues<K> {
    /// Index into `values` of each item.
    pub ids: Vec<u32>,
    /// The distinct values, first seen first.
    pub values: Vec<K>,
    lookup: QuickMap<K, u32>,
}

impl<K: std::hash::Hash + Eq + Copy> LocalValues<K> {
    /// An empty list with room for `n` items.
    pub(crate) fn with_capacity(n: usize) -> Self {
        LocalValues {
            ids: Vec::with_capacity(n),
            values: Vec::new(),
            lookup: QuickMap::default(),
        }
    }

    /// Appends an item with value `value`.
    pub(crate) fn push(&mut self, value: K) {
        // Neighbours often share a value: no lookup then.
        if let Some(&last) = self.ids.last()
            && self.values[last as usize] == value
        {
            self.ids.push(last);
            return;
        }
        let next = self.values.len() as u32;
        let id = *self.lookup.entry(value).or_insert(next);
        if id == next {
            self.values.push(value);
        }
        self.ids.push(id);
    }
}

/// chemfiles' whitespace (`is_ascii_whitespace`: space, tab, CR, LF, form feed).
pub(crate) fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | b'\x0C')
}

/// `s` without chemfiles' whitespace at either end.
pub(crate) fn trim(s: &[u8]) -> &[u8] {
    let start = s.iter().position(|&b| !is_space(b)).unwrap_or(s.len());
    let end = s
        .iter()
        .rposition(|&b| !is_space(b))
        .map_or(start, |e| e + 1);
    &s[start..end]
}

/// `line[a..b]`, clipped to the line (empty past its end), like C++ `substr(a, b - a)`.
pub(crate) fn cols(line: &[u8], a: usize, b: usize) -> &[u8] {
    line.get(a.min(line.len())..b.min(line.len()))
        .unwrap_or_default()
}

/// Fixed-column text: every byte that is not ASCII becomes `?` (one byte for one byte, as
/// [`super::prepare`] cleans PDB files for chemfiles).
pub(crate) fn columns_text(s: &[u8]) -> String {
    s.iter()
        .map(|&b| if b.is_ascii() { b as char } else { '?' })
        .collect()
}

/// Whitespace-separated text: valid UTF-8 stays, every other byte is read as Latin-1 (as
/// [`super::prepare`] cleans free-format files for chemfiles).
pub(crate) fn free_text(s: &[u8]) -> String {
    match std::str::from_utf8(s) {
        Ok(text) => text.to_string(),
        Err(_) => {
            let mut out = String::with_capacity(s.len() + 4);
            for chunk in s.utf8_chunks() {
                out.push_str(chunk.valid());
                out.extend(chunk.invalid().iter().map(|&b| char::from(b)));
            }
            out
        }
    }
}

/// A decimal number as the text formats write one: optional whitespace and sign, digits, an
/// optional fraction and exponent, optional whitespace; `None` for anything else (no `inf` or
/// `nan` words). Correctly rounded (Rust's own parser), so a position can differ from
/// chemfiles' reading in its last bit of f64, never after conversion to our f32 except in rare
/// ties (see the `io_fast` tests).
pub(crate) fn parse_f64(input: &[u8]) -> Option<f64> {
    let text = trim(input);
    // Plain decimals (nearly every number in a file) are parsed in one pass.
    if let Some(value) = parse_plain_decimal(text) {
        return Some(value);
    }
    let (mut digits, mut exponent_at) = (0usize, None);
    for (k, &b) in text.iter().enumerate() {
        match b {
            b'0'..=b'9' => digits += 1,
            b'+' | b'-' | b'.' => {}
            b'e' | b'E' if exponent_at.is_none() => exponent_at = Some(k),
            _ => return None,
        }
    }
    if digits == 0 || exponent_at.is_some_and(|k| k + 1 >= text.len()) {
        return None;
    }
    std::str::from_utf8(text).ok()?.parse().ok()
}

/// `s.parse::<f64>()` (Rust's own rules: `inf`, `nan` and exponents allowed), with the common
/// plain decimals taken by [`parse_plain_decimal`]'s fast path.
pub(crate) fn parse_f64_std(s: &str) -> Option<f64> {
    parse_plain_decimal(s.as_bytes()).or_else(|| s.parse().ok())
}

/// Powers of ten that are exact in f64 (10^0 to 10^22).
const EXACT_POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The fast path of decimal parsing: an optional sign, digits, and an optional `.` with more
/// digits (at least one digit in all, no exponent, no whitespace), whose digits as an integer
/// `m` are below 2^53 and that has at most 22 decimals: then `m` and `10^decimals` are exact
/// f64 and one IEEE division gives the correctly rounded value, the very number Rust's parser
/// returns (this is its own fast path). `None` for every other text, which the caller parses
/// the slow way.
pub(crate) fn parse_plain_decimal(s: &[u8]) -> Option<f64> {
    let (negative, body) = match s.first()? {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    let mut mantissa: u64 = 0;
    let (mut digits, mut decimals) = (0usize, 0usize);
    let mut seen_point = false;
    for &b in body {
        match b {
            b'0'..=b'9' => {
                if digits == 19 {
                    return None; // could overflow u64
                }
                mantissa = mantissa * 10 + u64::from(b - b'0');
                digits += 1;
                decimals += usize::from(seen_point);
            }
            b'.' if !seen_point => seen_point = true,
            _ => return None,
        }
    }
    if digits == 0 || mantissa >= 1 << 53 || decimals >= EXACT_POWERS_OF_TEN.len() {
        return None;
    }
    let value = mantissa as f64 / EXACT_POWERS_OF_TEN[decimals];
    Some(if negative { -value } else { value })
}

/// chemfiles' `parse<int64_t>`: whitespace, sign, digits, whitespace (an empty run of digits
/// is 0); `None` where chemfiles throws.
pub(crate) fn parse_i64(input: &[u8]) -> Option<i64> {
    if input.is_empty() {
        return None;
    }
    let t = trim(input);
    let (negative, digits) = match t.first() {
        Some(b'-') => (true, &t[1..]),
        Some(b'+') => (false, &t[1..]),
        _ => (false, t),
    };
    let mut value: i64 = 0;
    for &b in digits {
        if !b.is_ascii_digit() {
            return None;
        }
        let d = i64::from(b - b'0');
        value = value.checked_mul(10)?;
        value = if negative {
            value.checked_sub(d)?
        } else {
            value.checked_add(d)?
        };
    }
    Some(value)
}

/// chemfiles' `parse<uint64_t>` (whitespace, `+`, digits, whitespace).
pub(crate) fn parse_u64(input: &[u8]) -> Option<u64> {
    if input.is_empty() {
        return None;
    }
    let t = trim(input);
    let digits = t.strip_prefix(b"+").unwrap_or(t);
    let mut value: u64 = 0;
    for &b in digits {
        if !b.is_ascii_digit() {
            return None;
        }
        value = value.checked_mul(10)?.checked_add(u64::from(b - b'0'))?;
    }
    Some(value)
}

/// chemfiles' `decode_hybrid36(width, s)`: decimal (or blank, 0) below 10^width, then
/// upper-case and lower-case base-36 ranges (PDB serials past 99,999, residue numbers past
/// 9,999); `None` where chemfiles throws.
pub(crate) fn decode_hybrid36(width: u32, s: &[u8]) -> Option<i64> {
    let first = *s.first()?;
    if s.len() > width as usize {
        return None;
    }
    if first == b'-' || first == b' ' || first.is_ascii_digit() {
        return parse_i64(s);
    }
    if trim(s).is_empty() {
        return Some(0);
    }
    let pure = |digits_ok: fn(&u8) -> bool| -> Option<i64> {
        if !s.iter().all(digits_ok) {
            return None;
        }
        let mut v: i64 = 0;
        for &c in s {
            let d = match c {
                b'0'..=b'9' => c - b'0',
                b'A'..=b'Z' => c - b'A' + 10,
                _ => c - b'a' + 10,
            };
            v = v * 36 + i64::from(d);
        }
        Some(v)
    };
    let p36 = 36i64.pow(width - 1);
    let p10 = 10i64.pow(width);
    if first.is_ascii_uppercase() {
        let v = pure(|c| c.is_ascii_digit() || c.is_ascii_uppercase())?;
        Some(v - 10 * p36 + p10)
    } else if first.is_ascii_lowercase() {
        let v = pure(|c| c.is_ascii_digit() || c.is_ascii_lowercase())?;
        Some(v + 16 * p36 + p10)
    } else {
        None
    }
}

/// Masses (amu) and charges (e) chemfiles gives an atom of a type, looked up once per type.
#[derive(Default)]
pub(crate) struct TypeTable {
    known: HashMap<String, (f32, f32)>,
}

impl TypeTable {
    /// The mass and charge chemfiles gives an atom whose type is `kind` (see
    /// [`super::type_masses`]; 0 for unknown types).
    pub(crate) fn get(&mut self, kind: &str) -> (f32, f32) {
        if let Some(&v) = self.known.get(kind) {
            return v;
        }
        let v = (super::type_masses::type_mass(kind) as f32, 0.0);
        self.known.insert(kind.to_string(), v);
        v
    }
}

/// A topology of `n` atoms with every per-atom vector at the default the chemfiles conversion
/// starts from (serials 1..=n, occupancy 1, each atom outside any residue).
pub(crate) fn empty_topology(n: usize) -> Topology {
    Topology {
        names: Labels::with_capacity(n),
        elements: Labels::with_capacity(n),
        radii: vec![0.0; n],
        residue_names: Labels::filled("", n),
        residue_ids: vec![0; n],
        insertion_codes: Labels::filled("", n),
        residue_index: vec![u32::MAX; n],
        residue_copies: Vec::new(),
        chains: Labels::filled("", n),
        segments: Labels::filled("", n),
        b_factors: vec![0.0; n],
        occupancies: vec![1.0; n],
        types: Labels::with_capacity(n),
        masses: Vec::with_capacity(n),
        charges: Vec::with_capacity(n),
        serials: (1..=n as i64).collect(),
        bonds: Vec::new(),
    }
}

/// f64 positions (Å) to ours (f32, Å), as the chemfiles path converts them.
pub(crate) fn to_vec3(p: [f64; 3]) -> Vec3 {
    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_parse_as_chemfiles_parses_them() {
        assert_eq!(parse_f64(b"  -12.345"), Some(-12.345f64.mul_add(1.0, 0.0)));
        assert_eq!(parse_f64(b"1e3"), Some(1000.0));
        assert_eq!(parse_f64(b"nan"), None);
        assert_eq!(parse_f64(b"1.5x"), None);
        assert_eq!(parse_f64(b"   "), None);
        assert_eq!(parse_f64(b"."), None);
        assert_eq!(parse_i64(b"    "), Some(0));
        assert_eq!(parse_i64(b"  -7 "), Some(-7));
        assert_eq!(parse_i64(b"1 2"), None);
        assert_eq!(parse_u64(b" 12\r"), Some(12));
        assert_eq!(parse_u64(b"-1"), None);
    }

    #[test]
    fn the_decimal_fast_path_gives_what_rusts_parser_gives() {
        let texts = [
            "0",
            "-0",
            "-0.000",
            "+1.5",
            "1.",
            ".5",
            "12.345",
            "-999.999",
            "0.1",
            "0.3",
            "123456789.123456",
            "9007199254740991",
            "9007199254740993",
            "1.0000000000000000000001",
            "0.0000000000000000000001",
            "17.000",
            "-3.396",
            "18.732",
            "4.160000",
            "99999.99999",
        ];
        for text in texts {
            let want: f64 = text.parse().expect(text);
            match parse_plain_decimal(text.as_bytes()) {
                Some(got) => assert_eq!(got.to_bits(), want.to_bits(), "{text}"),
                None => assert!(
                    text.bytes().filter(u8::is_ascii_digit).count() > 15,
                    "{text} should take the fast path"
                ),
            }
            assert_eq!(parse_f64_std(text).map(f64::to_bits), Some(want.to_bits()));
        }
        // A deterministic sweep of three-decimal coordinates, as PDB and XYZ files write them.
        let mut x: u64 = 12345;
        for _ in 0..100_000 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let text = format!("{}.{:03}", (x >> 40) as i64 % 2000 - 1000, (x >> 20) % 1000);
            let want: f64 = text.parse().expect("number");
            assert_eq!(
                parse_plain_decimal(text.as_bytes()).map(f64::to_bits),
                Some(want.to_bits()),
                "{text}"
            );
        }
        for other in [
            "1e3", "inf", "nan", "1.2.3", "--1", "", "-", ".", " 1", "1 ",
        ] {
            assert_eq!(parse_plain_decimal(other.as_bytes()), None, "{other}");
        }
    }

    #[test]
    fn hybrid36_matches_the_pdb_convention() {
        assert_eq!(decode_hybrid36(5, b"99999"), Some(99_999));
        assert_eq!(decode_hybrid36(5, b"A0000"), Some(100_000));
        assert_eq!(decode_hybrid36(5, b"A0001"), Some(100_001));
        assert_eq!(decode_hybrid36(4, b"A000"), Some(10_000));
        assert_eq!(
            decode_hybrid36(5, b"a0000"),
            Some(100_000 + 26 * 36i64.pow(4))
        );
        assert_eq!(decode_hybrid36(5, b"    "), Some(0));
        assert_eq!(decode_hybrid36(5, b"A00a0"), None);
        assert_eq!(decode_hybrid36(5, b"?1234"), None);
        assert_eq!(decode_hybrid36(5, b""), None);
    }

    #[test]
    fn text_is_decoded_lossily() {
        assert_eq!(columns_text(b"C\xe9A"), "C?A");
        assert_eq!(free_text(b"caf\xe9"), "café");
        assert_eq!(free_text("café".as_bytes()), "café");
        let got: Vec<&[u8]> = lines(b"a\r\nb\n\nc").collect();
        assert_eq!(got, vec![&b"a"[..], b"b", b"", b"c"]);
    }
}
