//! pdbtbx on wwPDB files (PDB, mmCIF): fills in what chemfiles does not read, the B-factors
//! (and chains when chemfiles found none). Atoms are matched by position, so the order and
//! count of atoms stay chemfiles' (the order of the trajectory frames).

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use glam::Vec3;

use crate::model::Topology;

/// Positions are matched after rounding to this many steps per Å (files print 3 decimals).
const STEPS_PER_ANGSTROM: f64 = 1000.0;

/// What pdbtbx knows about one atom.
struct WwAtom {
    b_factor: f32,
    chain: String,
}

/// Copies B-factors (and chains where empty) from pdbtbx's reading of `path` into `topology`,
/// whose frame-0 positions are `positions`. Returns false and changes nothing when pdbtbx
/// cannot read the file or some atom has no match.
pub(crate) fn enrich(path: &Path, format: pdbtbx::Format, topology: &mut Topology, positions: &[Vec3]) -> bool {
    let Some(atoms) = read_atoms(path, format) else {
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
        if topology.chains[i].is_empty() {
            topology.chains[i].clone_from(&atom.chain);
        }
    }
    true
}

/// The first model's atoms keyed by rounded position, or `None` when pdbtbx fails (or panics).
fn read_atoms(path: &Path, format: pdbtbx::Format) -> Option<HashMap<(i64, i64, i64), WwAtom>> {
    let path = path.to_str()?;
    let read = catch_unwind(AssertUnwindSafe(|| {
        pdbtbx::ReadOptions::new()
            .set_format(format)
            .set_level(pdbtbx::StrictnessLevel::Loose)
            .read(path)
    }));
    let (pdb, _warnings) = read.ok()?.ok()?;
    let model = pdb.models().next()?;
    let mut atoms = HashMap::new();
    for chain in model.chains() {
        for atom in chain.atoms() {
            let (x, y, z) = atom.pos();
            let value = WwAtom { b_factor: atom.b_factor() as f32, chain: chain.id().to_string() };
            atoms.entry(key(x, y, z)).or_insert(value);
        }
    }
    Some(atoms)
}

fn key(x: f64, y: f64, z: f64) -> (i64, i64, i64) {
    let q = |v: f64| (v * STEPS_PER_ANGSTROM).round() as i64;
    (q(x), q(y), q(z))
}
