//! The representations a system gets when the user names none: proteins and nucleic acids as a
//! surface, ligands as ball-and-stick, lipids as a second, coarser and see-through surface, and
//! water and ions as a surface that exists but is hidden. A system with none of these classes
//! (argon, SPC/E with numeric LAMMPS types, a bare particle cloud) gets one surface of everything.

use crate::model::{ColorScheme, Frame, Topology};

use super::representation::{RepStyle, Representation};
use crate::selection::Selection;

/// Selection of the main representation (proteins and nucleic acids).
pub const MACROMOLECULE: &str = "protein or nucleic";
/// Selection of the ligand representation.
pub const LIGAND: &str = "ligand";
/// Selection of the membrane representation.
pub const LIPID: &str = "lipid";
/// Selection of the solvent representation (hidden by default).
pub const SOLVENT: &str = "water or ion";

/// How much coarser (in H) the lipid and solvent surfaces are than the main surface.
pub const COARSE_FACTOR: f32 = 2.0;
/// Opacity of the default lipid surface, so that a protein inside a membrane stays visible.
pub const LIPID_OPACITY: f32 = 0.45;
/// Colour of the default lipid surface (sRGB hex).
pub const LIPID_COLOUR: &str = "single:#d8c8a0";

/// Number of atoms of `topology` that `selection` (a static expression) picks in `frame`.
fn count(selection: &str, topology: &Topology, frame: &Frame) -> usize {
    Selection::parse(selection)
        .map(|s| s.bind(topology).indices(frame).len())
        .unwrap_or(0)
}

/// The default representations of `topology` (using `frame` for the class counts), each with
/// the surface parameters and colour scheme of `base`. `base.name`, `selection`, `style` and
/// `visible` are ignored.
pub fn default_representations(
    topology: &Topology,
    frame: &Frame,
    base: &Representation,
) -> Vec<Representation> {
    let with = |name: &str, selection: &str, style: RepStyle| Representation {
        name: name.into(),
        selection: selection.into(),
        style,
        visible: true,
        ..base.clone()
    };
    let coarse = |mut r: Representation| {
        r.spacing = base.spacing * COARSE_FACTOR;
        r
    };
    let macro_atoms = count(MACROMOLECULE, topology, frame);
    let ligand_atoms = count(LIGAND, topology, frame);
    let lipid_atoms = count(LIPID, topology, frame);
    let mut reps = Vec::new();
    if macro_atoms > 0 {
        reps.push(with("macromolecule", MACROMOLECULE, RepStyle::Surface));
    }
    if ligand_atoms > 0 && (macro_atoms > 0 || lipid_atoms > 0) {
        reps.push(Representation {
            opacity: 1.0,
            colour: ColorScheme::Element,
            ..with("ligand", LIGAND, RepStyle::BallAndStick)
        });
    }
    if lipid_atoms > 0 {
        let mut lipids = coarse(with("lipids", LIPID, RepStyle::Surface));
        lipids.opacity = LIPID_OPACITY.min(base.opacity);
        if let Ok(c) = LIPID_COLOUR.parse() {
            lipids.colour = c;
        }
        reps.push(lipids);
    }
    if reps.is_empty() {
        // No macromolecule, lipid or (alongside them) ligand: one surface of everything.
        return vec![with("all", "all", RepStyle::Surface)];
    }
    if count(SOLVENT, topology, frame) > 0 {
        let mut solvent = coarse(with("solvent", SOLVENT, RepStyle::Surface));
        solvent.visible = false;
        reps.push(solvent);
    }
    reps
}

/// One line per representation for stderr: name, style, selection, atom count, H and
/// visibility, e.g. `rep macromolecule: surface of 'protein or nucleic' (3,341 atoms), H 1 Å`.
pub fn describe(reps: &[Representation], topology: &Topology, frame: &Frame) -> Vec<String> {
    reps.iter()
        .map(|r| {
            let atoms = count(&r.selection, topology, frame);
            let detail = if r.style.is_surface() {
                format!(", H {} Å, I {}, {}", r.spacing, r.isovalue, r.quality)
            } else {
                String::new()
            };
            let hidden = if r.visible { "" } else { ", hidden" };
            let opacity = if r.opacity < 1.0 {
                format!(", opacity {}", r.opacity)
            } else {
                String::new()
            };
            format!(
                "rep {}: {} of '{}' ({atoms} atoms){detail}{opacity}{hidden}",
                r.name, r.style, r.selection
            )
        })
        .collect()
}
