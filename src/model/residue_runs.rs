//! How every reader (and the Python package's topologies) numbers residues: as contiguous
//! runs of atoms, never grouped by residue number alone (see
//! [`Topology::number_residue_runs`]).

use super::Topology;

impl Topology {
    /// Sets [`Topology::residue_index`]: a new residue starts at every atom whose (residue
    /// number, name, chain, segment) or `group` (the reader's own residue of each atom) differs
    /// from the previous atom's; atoms whose `group` is `u32::MAX` (in no residue) are residues
    /// of their own, as are atoms past the end of `group`.
    pub fn number_residue_runs(&mut self, group: &[u32]) {
        let n = self.len();
        let group = |i: usize| group.get(i).copied().unwrap_or(u32::MAX);
        self.residue_index.resize(n, 0);
        let mut next = 0u32;
        for i in 0..n {
            let same = i > 0
                && group(i) != u32::MAX
                && group(i) == group(i - 1)
                && self.residue_ids[i] == self.residue_ids[i - 1]
                && self.residue_names[i] == self.residue_names[i - 1]
                && self.chains[i] == self.chains[i - 1]
                && self.segments[i] == self.segments[i - 1];
            if i > 0 && !same {
                next += 1;
            }
            self.residue_index[i] = next;
        }
    }
}

impl Topology {
    /// A test topology of carbon atoms with these (residue number, residue name) pairs, no
    /// chains or segments, residues not numbered yet.
    #[cfg(test)]
    pub(crate) fn of_residues(residues: &[(i64, &str)]) -> Topology {
        let n = residues.len();
        Topology {
            names: super::Labels::filled("C", n),
            residue_ids: residues.iter().map(|r| r.0).collect(),
            residue_names: residues.iter().map(|r| r.1.to_string()).collect(),
            chains: super::Labels::filled("", n),
            segments: super::Labels::filled("", n),
            ..Default::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_split_where_number_or_group_change() {
        let mut top = Topology::of_residues(&[(5, "SOL"), (5, "SOL"), (6, "SOL"), (5, "SOL")]);
        top.number_residue_runs(&[0, 0, 1, 0]);
        assert_eq!(top.residue_index, vec![0, 0, 1, 2]);
        top.number_residue_runs(&[u32::MAX; 4]);
        assert_eq!(top.residue_index, vec![0, 1, 2, 3]);
    }
}
