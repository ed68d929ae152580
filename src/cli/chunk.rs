//! `--chunk I/N` and `--chunk slurm` for `mdsurf surface` and `mdsurf render`: the selected
//! frames are split into N contiguous blocks and this process does block I (0-based), so a job
//! array (Slurm, or N local processes) shares one trajectory. Outputs keep the global frame index
//! in their names; the stats of chunk I go to `STATS.part-IIII-of-NNNN.csv`, which
//! `mdsurf merge STATS.csv` joins (see [`mdsurf::export::stats_merge`]).

use std::fmt;
use std::ops::Range;
use std::str::FromStr;

use anyhow::{Result, bail};
use mdsurf::export::stats_merge::chunk_block;

use super::arg_error::ArgError;

/// The `--chunk` value as given: explicit `I/N`, or `slurm` (read from the environment).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkSpec {
    /// Block `index` of `count` (0-based).
    Explicit(Chunk),
    /// I = `SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN`, N = `SLURM_ARRAY_TASK_COUNT`.
    Slurm,
}

/// One block of a split selection: block `index` of `count`, 0-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Chunk {
    /// This block, `0..count`.
    pub index: usize,
    /// Number of blocks, at least 1.
    pub count: usize,
}

impl FromStr for ChunkSpec {
    type Err = ArgError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("slurm") {
            return Ok(ChunkSpec::Slurm);
        }
        let bad = || ArgError::Chunk(s.to_string());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        Chunk::new(index, count).map(ChunkSpec::Explicit)
    }
}

impl Chunk {
    /// Block `index` of `count`; fails unless `index < count`.
    pub fn new(index: usize, count: usize) -> Result<Chunk, ArgError> {
        if count == 0 || index >= count {
            return Err(ArgError::ChunkRange { index, count });
        }
        Ok(Chunk { index, count })
    }

    /// The positions in a selection of `len` frames that this block covers: contiguous blocks
    /// whose sizes differ by at most one, the larger ones first (empty when `len < count` and
    /// this is one of the last blocks).
    pub fn block(&self, len: usize) -> Range<usize> {
        chunk_block(self.index, self.count, len)
    }
}

impl fmt::Display for Chunk {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl ChunkSpec {
    /// The block to do: the explicit one, or the one the Slurm array variables name.
    pub fn resolve(self) -> Result<Chunk> {
        self.resolve_with(|name| std::env::var(name).ok())
    }

    /// As [`ChunkSpec::resolve`], reading variables through `var` (for tests).
    pub fn resolve_with(self, var: impl Fn(&str) -> Option<String>) -> Result<Chunk> {
        if let ChunkSpec::Explicit(chunk) = self {
            return Ok(chunk);
        }
        let get = |name: &str| -> Result<usize> {
            let Some(text) = var(name) else {
                bail!(
                    "--chunk slurm: {name} is not set (run inside an sbatch --array job, or give --chunk I/N)"
                );
            };
            match text.trim().parse() {
                Ok(v) => Ok(v),
                Err(_) => bail!("--chunk slurm: {name}='{text}' is not a whole number"),
            }
        };
        let id = get("SLURM_ARRAY_TASK_ID")?;
        let min = get("SLURM_ARRAY_TASK_MIN")?;
        let count = get("SLURM_ARRAY_TASK_COUNT")?;
        let Some(index) = id.checked_sub(min) else {
            bail!("--chunk slurm: SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}");
        };
        match Chunk::new(index, count) {
            Ok(chunk) => Ok(chunk),
            Err(_) => bail!(
                "--chunk slurm: task {id} - min {min} = {index} is not below SLURM_ARRAY_TASK_COUNT={count} (use a contiguous --array, e.g. 0-7, or a step of 1)"
            ),
        }
    }
}

/// Fails with one line when `chunk` splits `items` frames or images into more chunks than
/// there are of them (every chunk must have work; a count such as 4294967296 is a typo).
pub fn check_chunk_count(chunk: Chunk, items: usize) -> Result<()> {
    if chunk.count > items {
        bail!(
            "--chunk {chunk}: {} chunks for {items} frame(s) or image(s); use at most {items}",
            chunk.count
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_cover_the_selection_once_in_order() {
        for len in 0..30 {
            for count in 1..9 {
                let mut next = 0;
                for index in 0..count {
                    let b = Chunk { index, count }.block(len);
                    assert_eq!(b.start, next, "len {len} count {count} index {index}");
                    assert!(b.len() == len / count || b.len() == len / count + 1);
                    next = b.end;
                }
                assert_eq!(next, len);
            }
        }
    }

    #[test]
    fn specs_parse_and_slurm_reads_its_variables() {
        assert_eq!(
            "1/4".parse::<ChunkSpec>(),
            Ok(ChunkSpec::Explicit(Chunk { index: 1, count: 4 }))
        );
        assert_eq!("SLURM".parse::<ChunkSpec>(), Ok(ChunkSpec::Slurm));
        for bad in ["4/4", "1/0", "x/2", "3", "-1/2"] {
            let e = bad.parse::<ChunkSpec>().expect_err(bad).to_string();
            assert!(e.contains(bad) || e.contains("bad chunk"), "{e}");
        }
        let env = |vars: &'static [(&'static str, &'static str)]| {
            move |name: &str| {
                vars.iter()
                    .find(|(k, _)| *k == name)
                    .map(|(_, v)| v.to_string())
            }
        };
        let ok = ChunkSpec::Slurm
            .resolve_with(env(&[
                ("SLURM_ARRAY_TASK_ID", "12"),
                ("SLURM_ARRAY_TASK_MIN", "10"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ]))
            .unwrap();
        assert_eq!(ok, Chunk { index: 2, count: 4 });
        let e = ChunkSpec::Slurm
            .resolve_with(env(&[("SLURM_ARRAY_TASK_ID", "1")]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("SLURM_ARRAY_TASK_MIN") && !e.contains('\n'),
            "{e}"
        );
        let e = ChunkSpec::Slurm
            .resolve_with(env(&[
                ("SLURM_ARRAY_TASK_ID", "9"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("SLURM_ARRAY_TASK_COUNT=4"), "{e}");
    }
}
