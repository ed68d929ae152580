//! How every reader (and the Python package's topologies) numbers residues: as contiguous
//! runs of atoms, never grouped by residue number alone (see
//! [`Topology::number_residue_runs`]).

use std::collections::HashMap;

use super::Topology;

/// The name a residue's place goes by: its chain, else its segment, trimmed (empty with
/// neither). Labels, tables and the copies of [`Topology::residue_copies`] all use it.
pub fn chain_or_segment<'a>(chain: &'a str, segment: &'a str) -> &'a str {
    match chain.trim() {
        "" => segment.trim(),
        chain => chain,
    }
}

impl Topology {
    /// Sets [`Topology::residue_index`]: a new residue starts at every atom whose (residue
    /// number, insertion code, name, chain, segment) or `group` (the reader's own residue of each atom) differs
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
                && self.insertion_codes.get(i) == self.insertion_codes.get(i - 1)
                && self.chains[i] == self.chains[i - 1]
                && self.segments[i] == self.segments[i - 1];
            if i > 0 && !same {
                next += 1;
            }
            self.residue_index[i] = next;
        }
        self.number_residue_copies();
    }

    /// Sets [`Topology::residue_copies`] from [`Topology::residue_index`]: residues sharing
    /// chain (else segment), number, insertion code and name are numbered 1, 2, … in file
    /// order, the rest 0.
    /// Residues that name nothing (no chain, segment or name and number 0: the particles of a
    /// LAMMPS dump or an XYZ file) are left at 0.
    pub fn number_residue_copies(&mut self) {
        let mut firsts: Vec<usize> = Vec::new();
        for (i, &r) in self.residue_index.iter().enumerate() {
            if r as usize == firsts.len() {
                firsts.push(i);
            } else if r as usize > firsts.len() {
                // Not numbered in runs from 0: no copies are told apart.
                self.residue_copies.clear();
                return;
            }
        }
        fn text(labels: &crate::model::Labels, atom: usize) -> &str {
            labels.get(atom).unwrap_or("").trim()
        }
        // Per (chain or segment, number, insertion code, name): how many so far, and the first
        // one's index.
        let mut seen: HashMap<(&str, i64, &str, &str), (u32, usize)> = HashMap::new();
        let mut copies = vec![0u32; firsts.len()];
        for (residue, &atom) in firsts.iter().enumerate() {
            let place = chain_or_segment(text(&self.chains, atom), text(&self.segments, atom));
            let number = self.residue_ids.get(atom).copied().unwrap_or(0);
            let name = text(&self.residue_names, atom);
            if place.is_empty() && name.is_empty() && number == 0 {
                continue;
            }
            let code = text(&self.insertion_codes, atom);
            let entry = (seen.entry((place, number, code, name))).or_insert((0, residue));
            entry.0 += 1;
            if entry.0 == 2 {
                copies[entry.1] = 1;
            }
            if entry.0 >= 2 {
                copies[residue] = entry.0;
            }
        }
        self.residue_copies = copies;
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

    #[test]
    fn residues_that_share_chain_number_and_name_are_numbered_as_copies() {
        // Two monomers of a chainless file (GRO), a lipid of their own, and a particle that
        // names nothing twice.
        let mut top = Topology::of_residues(&[
            (7, "TYR"),
            (7, "TYR"),
            (8, "ASP"),
            (297, "POPE"),
            (7, "TYR"),
            (8, "ASP"),
            (0, ""),
            (0, ""),
        ]);
        top.number_residue_runs(&[0, 0, 1, 2, 3, 4, u32::MAX, u32::MAX]);
        assert_eq!(top.residue_index, vec![0, 0, 1, 2, 3, 4, 5, 6]);
        assert_eq!(top.residue_copies, vec![1, 1, 0, 2, 2, 0, 0]);
        // A chain tells the monomers apart.
        top.chains = crate::model::Labels::filled("A", 8);
        top.chains.set(4, "B");
        top.chains.set(5, "B");
        top.chains.set(6, "");
        top.chains.set(7, "");
        top.number_residue_copies();
        assert_eq!(top.residue_copies, vec![0, 0, 0, 0, 0, 0, 0]);
    }
}
