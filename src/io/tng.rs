//! A structural check of TNG files, done before the TNG library opens one: the library crashes
//! (SIGSEGV) on some damaged files and prints its own complaints to stderr. A TNG file is a chain
//! of blocks, each with a header (its own size, the contents' size, an id, the MD5 of the
//! contents, a name, ...) followed by its contents. This walks the chain and checks each block's
//! MD5 where the writer recorded one, so a flipped byte, a cut or a duplicated or deleted chunk
//! is found here and reported as one line.

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// Header sizes outside this range (bytes) are damage.
const HEADER_SIZES: std::ops::RangeInclusive<i64> = 40..=4096;

/// Checks the block chain of the TNG file at `path`; `Err` gives the first damaged block.
pub(crate) fn check(path: &Path) -> Result<(), String> {
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| e.to_string())?;
    if bytes.len() < 8 {
        return Err("the file ends inside its first block (truncated)".into());
    }
    // The first block's header size says the byte order (a small number: high bytes zero).
    let little = bytes[0] != 0 && bytes[7] == 0;
    let int = |at: usize| -> i64 {
        let b: [u8; 8] = bytes[at..at + 8].try_into().unwrap_or([0; 8]);
        if little {
            i64::from_le_bytes(b)
        } else {
            i64::from_be_bytes(b)
        }
    };
    let size = bytes.len();
    let mut offset = 0usize;
    let mut block = 0usize;
    while offset < size {
        let damaged = |what: &str| format!("block {block} at byte {offset} {what} (damaged file)");
        if size - offset < 40 {
            return Err(damaged("is cut by the end of the file"));
        }
        let header = int(offset);
        let contents = int(offset + 8);
        if !HEADER_SIZES.contains(&header) || contents < 0 {
            return Err(damaged("has an invalid header"));
        }
        let end = (offset as u64)
            .checked_add(header as u64)
            .and_then(|e| e.checked_add(contents as u64));
        let Some(end) = end.filter(|&e| e <= size as u64) else {
            return Err(damaged("runs past the end of the file"));
        };
        let hash: [u8; 16] = bytes[offset + 24..offset + 40]
            .try_into()
            .unwrap_or([0; 16]);
        if hash != [0; 16] && md5(&bytes[offset + header as usize..end as usize]) != hash {
            return Err(damaged("fails its checksum"));
        }
        offset = end as usize;
        block += 1;
    }
    Ok(())
}

/// The MD5 digest of `data` (RFC 1321).
fn md5(data: &[u8]) -> [u8; 16] {
    const S: [u32; 64] = [
        7, 12, 17, 22, 7, 12, 17, 22, 7, 12, 17, 22, 7, 12, 17, 22, 5, 9, 14, 20, 5, 9, 14, 20, 5,
        9, 14, 20, 5, 9, 14, 20, 4, 11, 16, 23, 4, 11, 16, 23, 4, 11, 16, 23, 4, 11, 16, 23, 6, 10,
        15, 21, 6, 10, 15, 21, 6, 10, 15, 21, 6, 10, 15, 21,
    ];
    let k: Vec<u32> = (0..64)
        .map(|i| ((i as f64 + 1.0).sin().abs() * 4_294_967_296.0) as u32)
        .collect();
    let mut state: [u32; 4] = [0x6745_2301, 0xefcd_ab89, 0x98ba_dcfe, 0x1032_5476];
    let mut message = data.to_vec();
    message.push(0x80);
    while message.len() % 64 != 56 {
        message.push(0);
    }
    message.extend_from_slice(&((data.len() as u64).wrapping_mul(8)).to_le_bytes());
    for chunk in message.chunks_exact(64) {
        let m: Vec<u32> = chunk
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .collect();
        let [mut a, mut b, mut c, mut d] = state;
        for i in 0..64 {
            let (f, g) = match i / 16 {
                0 => ((b & c) | (!b & d), i),
                1 => ((d & b) | (!d & c), (5 * i + 1) % 16),
                2 => (b ^ c ^ d, (3 * i + 5) % 16),
                _ => (c ^ (b | !d), (7 * i) % 16),
            };
            let rotated = a
                .wrapping_add(f)
                .wrapping_add(k[i])
                .wrapping_add(m[g])
                .rotate_left(S[i]);
            a = d;
            d = c;
            c = b;
            b = b.wrapping_add(rotated);
        }
        state = [
            state[0].wrapping_add(a),
            state[1].wrapping_add(b),
            state[2].wrapping_add(c),
            state[3].wrapping_add(d),
        ];
    }
    let mut out = [0u8; 16];
    for (i, word) in state.iter().enumerate() {
        out[4 * i..4 * i + 4].copy_from_slice(&word.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::md5;

    fn hex(d: [u8; 16]) -> String {
        d.iter().map(|b| format!("{b:02x}")).collect()
    }

    #[test]
    fn md5_known_answers() {
        assert_eq!(hex(md5(b"")), "d41d8cd98f00b204e9800998ecf8427e");
        assert_eq!(
            hex(md5(b"The quick brown fox jumps over the lazy dog")),
            "9e107d9d372bb6826bd81d3542a419d6"
        );
    }
}
