//! Damage in a PDB file that chemfiles passes over or reports without a place: a file that ends
//! inside a `MODEL` (a cut multi-model file; chemfiles dropped the cut model, or read it with
//! fewer atoms, without a word), and a damaged `ATOM`/`HETATM` record, whose error chemfiles
//! gives with the record's text but not its line number.

/// Where a PDB file's last model is cut: the file ends after a `MODEL` record with no `ENDMDL`
/// or `END` record closing it. Returns the number of whole models before it and a message
/// naming the lines; `None` when every model is closed (or the file has no `MODEL` record).
pub(crate) fn cut_model(bytes: &[u8]) -> Option<(usize, String)> {
    let mut whole = 0usize;
    let mut open: Option<usize> = None;
    let mut last = 0usize;
    for (i, line) in super::fast::lines(bytes).enumerate() {
        last = i + 1;
        if line.starts_with(b"MODEL") {
            if open.is_some() {
                // A MODEL inside a model: the previous one was closed by nothing; chemfiles
                // reads on, so this is left to it.
                return None;
            }
            open = Some(i + 1);
        } else if line.starts_with(b"END") && open.is_some() {
            open = None;
            whole += 1;
        }
    }
    let start = open?;
    Some((
        whole,
        format!(
            "the file ends at line {last}, inside the model that starts at line {start} (no ENDMDL: the file is cut?)"
        ),
    ))
}

/// `message` with `line N: ` in front when it quotes a line of `bytes` (chemfiles quotes the
/// record it cannot read: `could not read positions in 'ATOM ...'`), else `None`.
#[cfg(feature = "chemfiles")]
pub(crate) fn name_line(bytes: &[u8], message: &str) -> Option<String> {
    let start = message.find('\'')?;
    let end = message.rfind('\'')?;
    let quoted = message.get(start + 1..end).filter(|q| q.len() >= 6)?;
    let number = super::fast::lines(bytes)
        .position(|line| line == quoted.as_bytes())
        .or_else(|| {
            super::fast::lines(bytes).position(|line| line.starts_with(quoted.as_bytes()))
        })?;
    Some(format!("line {}: {message}", number + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_without_its_end_is_found() {
        let whole = b"MODEL 1\nATOM\nENDMDL\nMODEL 2\nATOM\nENDMDL\nEND\n";
        assert_eq!(cut_model(whole), None);
        assert_eq!(cut_model(b"ATOM\nATOM\n"), None);
        let (models, message) = cut_model(b"MODEL 1\nATOM\nENDMDL\nMODEL 2\nATOM\nATO").unwrap();
        assert_eq!(models, 1);
        assert!(
            message.contains("line 6") && message.contains("line 4"),
            "{message}"
        );
    }

    #[cfg(feature = "chemfiles")]
    #[test]
    fn quoted_records_get_their_line() {
        let text = b"HEADER\nATOM      1  N   ALA A   1      xx\nEND\n";
        let m = name_line(
            text,
            "could not read positions in 'ATOM      1  N   ALA A   1      xx'",
        );
        assert_eq!(m.unwrap().split(':').next(), Some("line 2"));
        assert_eq!(name_line(text, "no quote"), None);
    }
}
