//! Where a multi-frame XYZ file stops being whole, found before chemfiles opens it: chemfiles
//! indexes every frame when it opens an XYZ file and refuses the whole file when one frame is
//! cut or damaged ("not enough lines at step 3"), so a file cut inside frame k lost frames
//! 0..k-1 too. [`first_damage`] walks the frames (an atom count line, a comment line, that many
//! atom lines) and says where the first one that is not whole starts; the caller gives chemfiles
//! a copy holding only the frames before it, and that frame becomes the damage (frame 0: an
//! error naming frame 0). Blank lines after
//! the last frame and a missing final newline are no damage.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

/// The first frame that is not whole: its index, the byte where it starts, and why (one line).
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct FirstDamage {
    pub(crate) frame: usize,
    pub(crate) start: u64,
    pub(crate) reason: String,
}

/// Walks the frames of the XYZ file at `path` (`\n` or `\r\n` line ends); `None` when every
/// frame is whole.
pub(crate) fn first_damage(path: &Path) -> std::io::Result<Option<FirstDamage>> {
    let mut input = BufReader::with_capacity(1 << 20, File::open(path)?);
    let mut line = Vec::new();
    let mut read_line = |line: &mut Vec<u8>| {
        line.clear();
        input.read_until(b'\n', line)
    };
    let (mut offset, mut line_number, mut frame) = (0u64, 0u64, 0usize);
    loop {
        let start = offset;
        let n = read_line(&mut line)?;
        if n == 0 {
            return Ok(None);
        }
        offset += n as u64;
        line_number += 1;
        let damage = |reason: String| {
            Ok(Some(FirstDamage {
                frame,
                start,
                reason,
            }))
        };
        let first_token = line
            .split(|b| b.is_ascii_whitespace())
            .find(|t| !t.is_empty());
        let Some(token) = first_token else {
            // A blank line: fine when only blank lines follow.
            loop {
                let n = read_line(&mut line)?;
                if n == 0 {
                    return Ok(None);
                }
                if !line.iter().all(u8::is_ascii_whitespace) {
                    return damage(format!(
                        "line {line_number}: a blank line where an atom count belongs"
                    ));
                }
            }
        };
        let Some(atoms) = std::str::from_utf8(token)
            .ok()
            .and_then(|t| t.parse::<u64>().ok())
        else {
            return damage(format!(
                "line {line_number}: the atom count is not a number"
            ));
        };
        // The comment line, then the atoms.
        for i in 0..=atoms {
            let n = read_line(&mut line)?;
            if n == 0 {
                let missing = if i == 0 {
                    "its comment line is missing".to_string()
                } else {
                    format!("atom {i} of {atoms} is missing")
                };
                return damage(format!("the file ends inside this frame ({missing})"));
            }
            offset += n as u64;
            line_number += 1;
        }
        frame += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(text: &str) -> Option<FirstDamage> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.xyz");
        std::fs::write(&path, text).unwrap();
        first_damage(&path).unwrap()
    }

    #[test]
    fn whole_frames_pass_and_the_first_cut_or_damaged_one_is_found() {
        let frame = "2\nc\nC 0 0 0\nO 1 0 0\n";
        assert_eq!(walk(&frame.repeat(3)), None);
        assert_eq!(walk(&format!("{}\n\n", frame.repeat(2))), None);
        assert_eq!(walk(frame.trim_end()), None);
        assert_eq!(walk(&frame.replace('\n', "\r\n")), None);
        let cut = walk(&format!("{frame}{frame}2\nc\nC 0 0")).unwrap();
        assert_eq!((cut.frame, cut.start), (2, 2 * frame.len() as u64));
        assert!(
            cut.reason.contains("atom 2 of 2 is missing"),
            "{}",
            cut.reason
        );
        let bad = walk(&format!("{frame}x\nc\n")).unwrap();
        assert_eq!((bad.frame, bad.start), (1, frame.len() as u64));
        assert!(bad.reason.contains("line 5"), "{}", bad.reason);
        let blank = walk(&format!("{frame}\n{frame}")).unwrap();
        assert_eq!(blank.frame, 1);
    }
}
