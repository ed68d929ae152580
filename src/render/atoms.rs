//! Atoms and bonds as drawable instances: spheres per atom and two half-cylinders per bond (each
//! half in its atom's colour), with bonds from the file or guessed from distances.

use glam::Vec3;

use super::scene::{CylinderInstance, SphereInstance};
use super::settings::{AtomStyle, RenderSettings};

/// Builds the sphere and cylinder instances for `settings.atom_style`.
///
/// `positions` and `radii` in Å, `colours` linear RGB (white when `None`), `bonds` pairs of atom
/// indices (pairs naming missing atoms are ignored). Returns nothing for [`AtomStyle::Hidden`].
pub fn atom_instances(
    positions: &[Vec3],
    radii: &[f32],
    colours: Option<&[[f32; 3]]>,
    bonds: &[[u32; 2]],
    settings: &RenderSettings,
) -> (Vec<SphereInstance>, Vec<CylinderInstance>) {
    let style = settings.atom_style;
    if style == AtomStyle::Hidden {
        return (Vec::new(), Vec::new());
    }
    let colour = |i: usize| {
        let c = colours.and_then(|c| c.get(i)).copied().unwrap_or([1.0; 3]);
        [c[0], c[1], c[2], 1.0]
    };
    let stick = settings.stick_radius.max(0.01);
    let spheres = positions
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_finite())
        .map(|(i, p)| {
            let r = radii.get(i).copied().unwrap_or(1.5);
            let radius = match style {
                AtomStyle::Spheres => r * settings.atom_scale,
                AtomStyle::Sticks => stick,
                _ => (r * 0.25).max(stick * 1.2),
            };
            SphereInstance {
                centre: p.to_array(),
                radius,
                colour: colour(i),
            }
        })
        .collect();
    let mut cylinders = Vec::new();
    if style.has_bonds() {
        for &[a, b] in bonds {
            let (a, b) = (a as usize, b as usize);
            let (Some(pa), Some(pb)) = (positions.get(a), positions.get(b)) else {
                continue;
            };
            if !(pa.is_finite() && pb.is_finite()) {
                continue;
            }
            let mid = (*pa + *pb) * 0.5;
            for (from, idx) in [(*pa, a), (*pb, b)] {
                cylinders.push(CylinderInstance {
                    start: from.to_array(),
                    radius: stick,
                    end: [mid.x, mid.y, mid.z, 0.0],
                    colour: colour(idx),
                });
            }
        }
    }
    (spheres, cylinders)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bonds::guess_bonds;

    #[test]
    fn water_has_two_bonds_and_no_h_h_bond() {
        // O at origin, H at 0.96 Å, H-O-H 104.5 degrees; a second water 3 Å away.
        let a = 104.5f32.to_radians();
        let mut p = vec![
            Vec3::ZERO,
            Vec3::new(0.96, 0.0, 0.0),
            Vec3::new(0.96 * a.cos(), 0.96 * a.sin(), 0.0),
        ];
        let shift = Vec3::new(0.0, 0.0, 3.0);
        p.extend(p.clone().iter().map(|q| *q + shift));
        let r = [1.3, 1.0, 1.0, 1.3, 1.0, 1.0];
        assert_eq!(guess_bonds(&p, &r), vec![[0, 1], [0, 2], [3, 4], [3, 5]]);
    }

    #[test]
    fn sticks_make_two_halves_per_bond() {
        let p = [Vec3::ZERO, Vec3::X * 1.5];
        let s = RenderSettings {
            atom_style: AtomStyle::Sticks,
            ..Default::default()
        };
        let (sph, cyl) = atom_instances(&p, &[1.5, 1.5], None, &[[0, 1], [0, 7]], &s);
        assert_eq!(sph.len(), 2);
        assert_eq!(cyl.len(), 2);
        assert_eq!(cyl[0].end[0], 0.75);
    }
}
