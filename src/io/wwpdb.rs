//! wwPDB enrichment: pdbtbx (mmCIF) or a fixed-column reader (PDB) fills in what chemfiles does
//! not read, the B-factors, occupancies and serial numbers (and elements and chains when
//! chemfiles found none). Atoms are matched by position, so the order and count of atoms stay
//! chemfiles' (the order of the frames). mmCIF files reach chemfiles, and so this, only on the
//! reference path ([`super::open_via_chemfiles`]); our mmCIF reader ([`super::mmcif`]) reads
//! these columns itself.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::format::WwFormat;
use crate::model::Topology;
use crate::model::elements::canonical_symbol;

/// Positions are matched after rounding to this many steps per Å (files print 3 decimals).
const STEPS_PER_ANGSTROM: f64 = 1000.0;

/// What pdbtbx knows about one atom.
struct WwAtom {
    b_factor: f32,
    occupancy: f32,
    serial: Option<i64>,
    chain: String,
    element: Option<&'static str>,
}

/// Copies B-factors (and chains where empty) from pdbtbx's reading of `path` into `topology`,
/// whose frame-0 positions are `positions`. Returns false and changes nothing when pdbtbx
/// cannot read the file or some atom has no match.
pub(crate) fn enrich(
    path: &Path,
    format: WwFormat,
    topology: &mut Topology,
    positions: &[Vec3],
) -> bool {
    // PDB: our column reader. pdbtbx rejects old files with an ID code and line number in
    // columns 73-80 (as in 1hpv.pdb) and panics on some MD-written files.
    let atoms = match format {
        WwFormat::Pdb => read_columns(path),
        WwFormat::Mmcif => read_atoms(path, format),
    };
    let Some(atoms) = atoms else {
        return false;
    };
    let mut matched = Vec::with_capacity(positions.len());
    for p in positions {
        match atoms.get(&key(p.x as f64, p.y as f64, p.z as f64)) {
            Some(atom) => matched.push(atom),
            None => return false,
        }
    }
    for (i, atom) in matched.into_iter().enumerate() {
        topology.b_factors[i] = atom.b_factor;
        if let Some(o) = topology.occupancies.get_mut(i) {
            *o = atom.occupancy;
        }
        if let (Some(s), Some(serial)) = (topology.serials.get_mut(i), atom.serial) {
            *s = serial;
        }
        if topology.chains[i].is_empty() {
            topology.chains.set(i, &atom.chain);
        }
        if topology.elements[i].is_empty()
            && let Some(element) = atom.element
        {
            topology.elements.set(i, element);
        }
    }
    true
}

/// The first model's atoms keyed by rounded position, or `None` when pdbtbx fails (or panics).
fn read_atoms(path: &Path, format: WwFormat) -> Option<HashMap<(i64, i64, i64), WwAtom>> {
    let path = path.to_str()?;
    quiet_panics::install();
    let read = quiet_panics::silenced(|| {
        pdbtbx::ReadOptions::new()
            .set_format(format.pdbtbx())
            .set_level(pdbtbx::StrictnessLevel::Loose)
            .read(path)
    });
    let (pdb, _warnings) = read.ok()?.ok()?;
    let model = pdb.models().next()?;
    let mut atoms = HashMap::new();
    for chain in model.chains() {
        for atom in chain.atoms() {
            let (x, y, z) = atom.pos();
            let value = WwAtom {
                b_factor: atom.b_factor() as f32,
                occupancy: atom.occupancy() as f32,
                serial: i64::try_from(atom.serial_number()).ok(),
                chain: chain.id().to_string(),
                element: atom.element().and_then(|e| canonical_symbol(e.symbol())),
            };
            atoms.entry(key(x, y, z)).or_insert(value);
        }
    }
    Some(atoms)
}

use super::quiet as quiet_panics;

/// A plain fixed-column reading of the first model's ATOM/HETATM records, for PDB files pdbtbx
/// rejects or panics on.
/// Columns (1-based): serial 7-11, chain 22, x/y/z 31-54, occupancy 55-60, B-factor 61-66,
/// element 77-78.
fn read_columns(path: &Path) -> Option<HashMap<(i64, i64, i64), WwAtom>> {
    let bytes = std::fs::read(path).ok()?;
    let text = String::from_utf8_lossy(&bytes);
    let mut atoms = HashMap::new();
    for line in text.lines() {
        if line.starts_with("ENDMDL") {
            break;
        }
        if !(line.starts_with("ATOM") || line.starts_with("HETATM")) {
            continue;
        }
        let field =
            |a: usize, b: usize| line.get(a..b.min(line.len())).map(str::trim).unwrap_or("");
        let number = |a: usize, b: usize| field(a, b).parse::<f64>().ok();
        let (Some(x), Some(y), Some(z)) = (number(30, 38), number(38, 46), number(46, 54)) else {
            continue;
        };
        let value = WwAtom {
            b_factor: number(60, 66).unwrap_or(0.0) as f32,
            occupancy: number(54, 60).unwrap_or(1.0) as f32,
            serial: field(6, 11).parse().ok(),
            chain: field(21, 22).to_string(),
            element: canonical_symbol(field(76, 78)),
        };
        atoms.entry(key(x, y, z)).or_insert(value);
    }
    (!atoms.is_empty()).then_some(atoms)
}

fn key(x: f64, y: f64, z: f64) -> (i64, i64, i64) {
    let q = |v: f64| (v * STEPS_PER_ANGSTROM).round() as i64;
    (q(x), q(y), q(z))
}
