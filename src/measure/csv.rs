//! CSV tables of the measurements, one row per frame, representation and residue (atom,
//! cavity), filled frame by frame and written atomically ([`crate::export::atomic`]) at the end.
//! Areas in Å², volumes in Å³, coordinates in Å; text fields are quoted when they hold a comma,
//! a quote or a line break.

use std::fmt::Write as _;
use std::path::Path;

use super::residues::{ResidueNames, topology_atoms};
use super::{
    CavityEvent, ContactResidue, ExposureTable, InterfaceResult, MeasureError, ResidueArea, Side,
    TrackedCavity,
};
use crate::export::atomic::write_atomic;
use crate::export::{ExportError, Fixed};
// `text` as one CSV field, quoted when it holds a comma, a quote or a line break.
use crate::export::stats::csv_text as field;
use crate::model::Topology;

/// A table being filled: a header and formatted rows.
#[derive(Debug, Clone)]
struct Table {
    header: &'static str,
    rows: String,
}

impl Table {
    fn new(header: &'static str) -> Table {
        Table {
            header,
            rows: String::new(),
        }
    }

    fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        write_atomic(path, |w| {
            if let Some(line) = first_line {
                writeln!(w, "{line}")?;
            }
            writeln!(w, "{}", self.header)?;
            w.write_all(self.rows.as_bytes())
        })
    }
}

/// Per-residue areas: `frame,rep,chain,resid,resname,area_A2,exposure,residue` (exposure empty
/// when no table or the table lacks the residue's name; `residue` the residue's index in the
/// topology from 0, which `residue N` selects and which tells apart residues that share chain,
/// number and name, as a GRO file's monomers do).
#[derive(Debug, Clone)]
pub struct ResidueCsv(Table);

impl Default for ResidueCsv {
    fn default() -> Self {
        ResidueCsv(Table::new(
            "frame,rep,chain,resid,resname,area_A2,exposure,residue",
        ))
    }
}

impl ResidueCsv {
    /// An empty table.
    pub fn new() -> ResidueCsv {
        ResidueCsv::default()
    }

    /// Adds the residues of one frame of representation `rep`, measured on `topology`.
    pub fn push(
        &mut self,
        frame: usize,
        rep: &str,
        topology: &Topology,
        residues: &[ResidueArea],
        exposure: Option<&ExposureTable>,
    ) {
        let rep = field(rep);
        for r in residues {
            let names = r.names(topology);
            let e = exposure
                .and_then(|t| t.exposure(names.resname, r.area))
                .map_or(String::new(), |e| Fixed(e, 4).to_string());
            let _ = writeln!(
                self.0.rows,
                "{frame},{rep},{},{},{},{},{e},{}",
                field(names.chain_or_segment()),
                names.resid,
                field(names.resname.trim()),
                Fixed(r.area, 3),
                r.residue
            );
        }
    }

    /// Writes the table to `path` atomically, after `first_line` when given (the header of a
    /// chunk's part, [`crate::export::stats_merge::PartHeader::line`]).
    pub fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        self.0.write(path, first_line)
    }
}

/// Per-atom areas: `frame,rep,serial,name,chain,resid,resname,area_A2,residue` (`chain` the
/// chain, else the segment, and `residue` the residue's index, as in [`ResidueCsv`]).
#[derive(Debug, Clone)]
pub struct AtomCsv(Table);

impl Default for AtomCsv {
    fn default() -> Self {
        AtomCsv(Table::new(
            "frame,rep,serial,name,chain,resid,resname,area_A2,residue",
        ))
    }
}

impl AtomCsv {
    /// An empty table.
    pub fn new() -> AtomCsv {
        AtomCsv::default()
    }

    /// Adds the atoms of one frame of representation `rep`: `atom_areas` (Å²) of the topology
    /// atoms `atom_indices` (`None`: all). Fails on mismatched lengths or indices past the
    /// topology.
    pub fn push(
        &mut self,
        frame: usize,
        rep: &str,
        topology: &Topology,
        atom_indices: Option<&[u32]>,
        atom_areas: &[f64],
    ) -> Result<(), MeasureError> {
        let indices = topology_atoms(topology, atom_indices, atom_areas.len(), "atom areas")?;
        let rep = field(rep);
        for (&atom, area) in indices.iter().zip(atom_areas) {
            let i = atom as usize;
            let names = ResidueNames::of_atom(topology, i);
            let _ = writeln!(
                self.0.rows,
                "{frame},{rep},{},{},{},{},{},{},{}",
                names.serial,
                field(names.atom_name.trim()),
                field(names.chain_or_segment()),
                names.resid,
                field(names.resname.trim()),
                Fixed(*area, 3),
                topology.residue_index.get(i).copied().unwrap_or(0),
            );
        }
        Ok(())
    }

    /// Writes the table to `path` atomically, after `first_line` when given (the header of a
    /// chunk's part, [`crate::export::stats_merge::PartHeader::line`]).
    pub fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        self.0.write(path, first_line)
    }
}

/// Cavities: `frame,rep,cavity_id,volume_A3,area_A2,cx,cy,cz,lining` with the lining residues
/// as `A:LEU12 A:GLY13` (topology order).
#[derive(Debug, Clone)]
pub struct CavityCsv(Table);

impl Default for CavityCsv {
    fn default() -> Self {
        CavityCsv(Table::new(
            "frame,rep,cavity_id,volume_A3,area_A2,cx,cy,cz,lining",
        ))
    }
}

impl CavityCsv {
    /// An empty table.
    pub fn new() -> CavityCsv {
        CavityCsv::default()
    }

    /// Adds the tracked cavities of one frame of representation `rep`, whose atom set holds
    /// the topology atoms `atom_indices` (`None`: all). Fails on a lining atom past the set or
    /// an index past the topology.
    pub fn push(
        &mut self,
        frame: usize,
        rep: &str,
        topology: &Topology,
        atom_indices: Option<&[u32]>,
        cavities: &[TrackedCavity],
    ) -> Result<(), MeasureError> {
        let rep = field(rep);
        for t in cavities {
            let c = &t.cavity;
            let lining = lining_residues(topology, atom_indices, &c.lining_atoms)?;
            let _ = writeln!(
                self.0.rows,
                "{frame},{rep},{},{},{},{},{},{},{}",
                t.id,
                Fixed(c.volume, 3),
                Fixed(c.area, 3),
                Fixed(c.centroid.x, 3),
                Fixed(c.centroid.y, 3),
                Fixed(c.centroid.z, 3),
                field(&lining.join(" "))
            );
        }
        Ok(())
    }

    /// Writes the table to `path` atomically, after `first_line` when given (the header of a
    /// chunk's part, [`crate::export::stats_merge::PartHeader::line`]).
    pub fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        self.0.write(path, first_line)
    }
}

/// Cavity tracking events: `frame,rep,event,cavity_id,ids` with `event` one of `birth`,
/// `death`, `merge`, `split`; `cavity_id` the cavity born or dead, the one a merge continues
/// in, or the one parts split off from; `ids` the others (a merge's ended ids, a split's new
/// ids), space-separated. The first frame's cavities are births.
#[derive(Debug, Clone)]
pub struct CavityEventCsv(Table);

impl Default for CavityEventCsv {
    fn default() -> Self {
        CavityEventCsv(Table::new("frame,rep,event,cavity_id,ids"))
    }
}

impl CavityEventCsv {
    /// An empty table.
    pub fn new() -> CavityEventCsv {
        CavityEventCsv::default()
    }

    /// Adds the events of one frame of representation `rep`.
    pub fn push(&mut self, frame: usize, rep: &str, events: &[CavityEvent]) {
        let rep = field(rep);
        let list = |ids: &[u64]| ids.iter().map(u64::to_string).collect::<Vec<_>>().join(" ");
        for e in events {
            let (kind, id, others) = match e {
                CavityEvent::Birth { id } => ("birth", id, String::new()),
                CavityEvent::Death { id } => ("death", id, String::new()),
                CavityEvent::Merge { from, into } => ("merge", into, list(from)),
                CavityEvent::Split { from, into } => ("split", from, list(into)),
            };
            let _ = writeln!(self.0.rows, "{frame},{rep},{kind},{id},{others}");
        }
    }

    /// Writes the table to `path` atomically, after `first_line` when given (the header of a
    /// chunk's part, [`crate::export::stats_merge::PartHeader::line`]).
    pub fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        self.0.write(path, first_line)
    }
}

/// A frame's time in ps as a CSV field: empty when the frame has none.
fn time_field(time_ps: Option<f64>) -> String {
    time_ps.map(|t| t.to_string()).unwrap_or_default()
}

/// The buried area between two selections, one row per frame:
/// `frame,time_ps,area_a_A2,area_b_A2,area_ab_A2,buried_A2,contacts_a,contacts_b`, the contact
/// residues of each side as labels (`A:LEU23`) separated by spaces.
#[derive(Debug, Clone)]
pub struct InterfaceCsv(Table);

impl Default for InterfaceCsv {
    fn default() -> Self {
        InterfaceCsv(Table::new(
            "frame,time_ps,area_a_A2,area_b_A2,area_ab_A2,buried_A2,contacts_a,contacts_b",
        ))
    }
}

impl InterfaceCsv {
    /// An empty table.
    pub fn new() -> InterfaceCsv {
        InterfaceCsv::default()
    }

    /// Adds one frame (time in ps): its areas and contact residues, measured on `topology`.
    pub fn push(
        &mut self,
        frame: usize,
        time_ps: Option<f64>,
        topology: &Topology,
        result: &InterfaceResult,
        contacts: &[ContactResidue],
    ) {
        let labels = |side: Side| -> String {
            let labels: Vec<String> = contacts
                .iter()
                .filter(|c| c.side == side)
                .map(|c| c.residue.names(topology).label())
                .collect();
            field(&labels.join(" "))
        };
        let _ = writeln!(
            self.0.rows,
            "{frame},{},{},{},{},{},{},{}",
            time_field(time_ps),
            Fixed(result.area_a, 4),
            Fixed(result.area_b, 4),
            Fixed(result.area_complex, 4),
            Fixed(result.buried, 4),
            labels(Side::A),
            labels(Side::B),
        );
    }

    /// Writes the table to `path` atomically, after `first_line` when given (the header of a
    /// chunk's part, [`crate::export::stats_merge::PartHeader::line`]).
    pub fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        self.0.write(path, first_line)
    }

    /// The column line.
    pub fn header(&self) -> &'static str {
        self.0.header
    }

    /// The rows so far, each ending in a newline.
    pub fn rows(&self) -> &str {
        &self.0.rows
    }
}

/// The residues an interface buries, one row per contact residue and frame:
/// `frame,time_ps,side,chain,resid,resname,area_alone_A2,area_complex_A2,buried_A2,residue`,
/// side `A` or `B` (the two selections in the order given), `buried_A2` = alone minus in the
/// complex (the residue's own loss, not halved), `time_ps` empty when the frame has no time,
/// `residue` as in [`ResidueCsv`].
#[derive(Debug, Clone)]
pub struct ContactCsv(Table);

impl Default for ContactCsv {
    fn default() -> Self {
        ContactCsv(Table::new(
            "frame,time_ps,side,chain,resid,resname,area_alone_A2,area_complex_A2,buried_A2,residue",
        ))
    }
}

impl ContactCsv {
    /// An empty table.
    pub fn new() -> ContactCsv {
        ContactCsv::default()
    }

    /// Adds the contact residues of one frame (time in ps), measured on `topology`.
    pub fn push(
        &mut self,
        frame: usize,
        time_ps: Option<f64>,
        topology: &Topology,
        contacts: &[ContactResidue],
    ) {
        let time = time_field(time_ps);
        for c in contacts {
            let names = c.residue.names(topology);
            let side = match c.side {
                Side::A => "A",
                Side::B => "B",
            };
            let _ = writeln!(
                self.0.rows,
                "{frame},{time},{side},{},{},{},{},{},{},{}",
                field(names.chain_or_segment()),
                names.resid,
                field(names.resname.trim()),
                Fixed(c.residue.area, 3),
                Fixed(c.area_complex, 3),
                Fixed(c.buried, 3),
                c.residue.residue
            );
        }
    }

    /// Writes the table to `path` atomically, after `first_line` when given (the header of a
    /// chunk's part, [`crate::export::stats_merge::PartHeader::line`]).
    pub fn write(&self, path: &Path, first_line: Option<&str>) -> Result<(), ExportError> {
        self.0.write(path, first_line)
    }
}

/// Labels (`A:LEU12`) of the residues of `atoms` (indices into an atom set holding the
/// topology atoms `atom_indices`, `None`: all), once each, in topology order.
pub fn lining_residues(
    topology: &Topology,
    atom_indices: Option<&[u32]>,
    atoms: &[u32],
) -> Result<Vec<String>, MeasureError> {
    let n = atom_indices.map_or(topology.len(), <[u32]>::len);
    let top = topology.len().min(topology.residue_index.len());
    let mut residues: Vec<(u32, usize)> = Vec::with_capacity(atoms.len());
    for &a in atoms {
        let atom = match atom_indices {
            Some(ix) => ix.get(a as usize).copied(),
            None => Some(a),
        }
        .filter(|&t| (t as usize) < top)
        .ok_or(MeasureError::IndexOutOfRange {
            what: "lining atom",
            index: a as usize,
            len: n,
        })?;
        residues.push((topology.residue_index[atom as usize], atom as usize));
    }
    residues.sort_unstable();
    residues.dedup_by_key(|r| r.0);
    Ok(residues
        .into_iter()
        .map(|(_, i)| ResidueNames::of_atom(topology, i).label())
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measure_fields_are_quoted_only_when_needed() {
        assert_eq!(field("protein"), "protein");
        assert_eq!(field("a,b"), "\"a,b\"");
        assert_eq!(field("say \"hi\""), "\"say \"\"hi\"\"\"");
    }

    #[test]
    fn measure_cavity_events_are_one_row_each() {
        let mut csv = CavityEventCsv::new();
        csv.push(
            4,
            "a,b",
            &[
                CavityEvent::Birth { id: 7 },
                CavityEvent::Merge {
                    from: vec![3, 5],
                    into: 2,
                },
                CavityEvent::Split {
                    from: 1,
                    into: vec![8],
                },
                CavityEvent::Death { id: 6 },
            ],
        );
        assert_eq!(
            csv.0.rows,
            "4,\"a,b\",birth,7,\n4,\"a,b\",merge,2,3 5\n4,\"a,b\",split,1,8\n4,\"a,b\",death,6,\n"
        );
    }

    #[test]
    fn measure_contact_rows_name_side_chain_and_areas() {
        let mut top = Topology::default();
        for (name, chain, resid, index) in [("LEU", "A", 12, 0), ("ASP", "B", 25, 1)] {
            top.names.push("CA");
            top.residue_names.push(name);
            top.chains.push(chain);
            top.residue_ids.push(resid);
            top.residue_index.push(index);
        }
        let contact = |side, atom: u32, alone: f64, with: f64| ContactResidue {
            side,
            residue: ResidueArea {
                residue: atom,
                atom,
                atoms: 1,
                area: alone,
            },
            area_complex: with,
            buried: alone - with,
        };
        let mut csv = ContactCsv::new();
        csv.push(
            3,
            Some(40.5),
            &top,
            &[
                contact(Side::A, 0, 80.0, 12.5),
                contact(Side::B, 1, 60.25, 59.0),
            ],
        );
        csv.push(4, None, &top, &[]);
        assert_eq!(
            csv.0.rows,
            "3,40.5,A,A,12,LEU,80.000,12.500,67.500,0\n3,40.5,B,B,25,ASP,60.250,59.000,1.250,1\n"
        );
    }

    #[test]
    fn measure_lining_residues_are_labelled_once_in_order() {
        let mut top = Topology::default();
        for (name, chain, resid, index) in [
            ("GLY", "A", 13, 1),
            ("LEU", "A", 12, 0),
            ("GLY", "A", 13, 1),
            ("SOL", "", 7, 2),
        ] {
            top.names.push("X");
            top.residue_names.push(name);
            top.chains.push(chain);
            top.residue_ids.push(resid);
            top.residue_index.push(index);
        }
        let labels = lining_residues(&top, None, &[3, 2, 0, 1]).expect("labels");
        assert_eq!(labels, ["A:LEU12", "A:GLY13", "SOL7"]);
        let labels = lining_residues(&top, Some(&[3, 1]), &[1, 0]).expect("subset");
        assert_eq!(labels, ["A:LEU12", "SOL7"]);
        assert!(lining_residues(&top, Some(&[3, 1]), &[2]).is_err());
        assert!(lining_residues(&top, None, &[9]).is_err());
    }
}
