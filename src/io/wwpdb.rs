//! wwPDB enrichment: pdbtbx (mmCIF) or a fixed-column reader (PDB) fills in what chemfiles does
//! not read, the B-factors (and elements and chains when chemfiles found none). Atoms are matched
//! by position, so the order and count of atoms stay chemfiles' (the order of the frames).

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
        if topology.chains[i].is_empty() {
            topology.chains[i].clone_from(&atom.chain);
        }
        if topology.elements[i].is_empty()
            && let Some(element) = atom.element
        {
            topology.elements[i] = element.to_string();
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
                chain: chain.id().to_string(),
                element: atom.element().and_then(|e| canonical_symbol(e.symbol())),
            };
            atoms.entry(key(x, y, z)).or_insert(value);
        }
    }
    Some(atoms)
}

/// Runs pdbtbx with its panics caught and not printed: a panic hook (installed once, chaining
/// the previous hook) stays silent on threads that are inside [`quiet_panics::silenced`].
mod quiet_panics {
    use std::cell::Cell;
    use std::panic::{AssertUnwindSafe, catch_unwind};
    use std::sync::Once;

    thread_local! {
        static SILENT: Cell<bool> = const { Cell::new(false) };
    }
    static INSTALL: Once = Once::new();

    pub(super) fn install() {
        INSTALL.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                if !SILENT.with(Cell::get) {
                    previous(info);
                }
            }));
        });
    }

    /// Calls `f`, turning a panic into `Err(())` without printing it.
    pub(super) fn silenced<T>(f: impl FnOnce() -> T) -> Result<T, ()> {
        SILENT.with(|s| s.set(true));
        let result = catch_unwind(AssertUnwindSafe(f));
        SILENT.with(|s| s.set(false));
        result.map_err(|_| ())
    }
}

/// A plain fixed-column reading of the first model's ATOM/HETATM records, for PDB files pdbtbx
/// rejects or panics on.
/// Columns (1-based): chain 22, x/y/z 31-54, B-factor 61-66, element 77-78.
fn read_columns(path: &Path) -> Option<HashMap<(i64, i64, i64), WwAtom>> {
    let text = std::fs::read_to_string(path).ok()?;
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
