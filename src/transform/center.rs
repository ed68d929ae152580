//! Centring: a selection's centre (mass-weighted when the topology knows the masses) is moved
//! to the centre of the box, then every molecule whose centre left the box is put back by
//! whole lattice vectors (`gmx trjconv -pbc mol -center`).

use glam::{DVec3, Vec3};

use super::whole::Molecules;
use crate::model::pbc::PbcCell;

/// The weighted centre (Å) of `positions` at `indices`; `masses` (amu, one per atom) weigh it
/// when every selected atom has a positive mass, otherwise all atoms count the same. `None`
/// for no atoms.
pub fn centre_of(positions: &[Vec3], indices: &[u32], masses: &[f32]) -> Option<Vec3> {
    if indices.is_empty() {
        return None;
    }
    let weighted =
        masses.len() == positions.len() && indices.iter().all(|&i| masses[i as usize] > 0.0);
    let (mut sum, mut total) = (DVec3::ZERO, 0.0f64);
    for &i in indices {
        let w = if weighted {
            masses[i as usize] as f64
        } else {
            1.0
        };
        sum += positions[i as usize].as_dvec3() * w;
        total += w;
    }
    Some((sum / total).as_vec3())
}

/// Moves every atom by `box centre - centre` and wraps each molecule (by its centre, mass
/// weighted as in [`centre_of`]) into the box.
pub fn centre_in_box(
    positions: &mut [Vec3],
    centre: Vec3,
    cell: &PbcCell,
    molecules: &Molecules,
    masses: &[f32],
) {
    let shift = cell.centre() - centre;
    for p in positions.iter_mut() {
        *p += shift;
    }
    wrap_molecules(positions, cell, molecules, masses);
}

/// Puts each molecule whose centre lies outside the box (fractional coordinates outside
/// [0, 1)) back in by whole lattice vectors; its atoms move together.
pub fn wrap_molecules(
    positions: &mut [Vec3],
    cell: &PbcCell,
    molecules: &Molecules,
    masses: &[f32],
) {
    for atoms in molecules.iter() {
        let centre = if atoms.len() == 1 {
            positions[atoms[0] as usize]
        } else {
            match centre_of(positions, atoms, masses) {
                Some(c) => c,
                None => continue,
            }
        };
        let n = cell.fractional(centre).floor();
        if n != Vec3::ZERO && n.is_finite() {
            let shift = cell.cartesian(n);
            for &a in atoms {
                positions[a as usize] -= shift;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mass_weighted_only_when_all_masses_are_known() {
        let p = [Vec3::ZERO, Vec3::X * 4.0];
        let c = centre_of(&p, &[0, 1], &[3.0, 1.0]).expect("centre");
        assert!((c - Vec3::X).length() < 1e-6);
        let c = centre_of(&p, &[0, 1], &[3.0, 0.0]).expect("centre");
        assert!((c - Vec3::X * 2.0).length() < 1e-6);
        assert!(centre_of(&p, &[], &[]).is_none());
    }

    #[test]
    fn centred_selection_lands_in_the_middle_and_molecules_in_the_box() {
        let cell = PbcCell::new(&[Vec3::X * 10.0, Vec3::Y * 10.0, Vec3::Z * 10.0]).expect("cell");
        let mut p = vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(2.0, 1.0, 1.0),
            Vec3::new(9.0, 9.0, 9.0),
        ];
        let mols = Molecules::from_bonds(3, &[[0, 1]], &[]);
        let c = centre_of(&p, &[0, 1], &[]).expect("centre");
        centre_in_box(&mut p, c, &cell, &mols, &[]);
        assert!((p[0] - Vec3::new(4.5, 5.0, 5.0)).length() < 1e-5);
        // Atom 2 moved to (12.5, 13, 13), wrapped to (2.5, 3, 3).
        assert!(
            (p[2] - Vec3::new(2.5, 3.0, 3.0)).length() < 1e-5,
            "{}",
            p[2]
        );
    }
}
