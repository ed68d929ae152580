//! What scientists publish about a surface (issue 32): area per atom and per residue, the
//! exposure of each residue, the area buried between two groups, and cavities tracked from frame
//! to frame, with CSV writers. It sits after the surface engine in the data flow: it reads a
//! [`Mesh`](crate::surface::Mesh) (or a [`SurfaceOutput`](crate::surface::SurfaceOutput)), the
//! [`AtomSet`](crate::surface::AtomSet) and [`SurfaceParams`](crate::surface::SurfaceParams) it
//! was computed from, and the [`Topology`](crate::model::Topology) for residue names; it never
//! imports the app or the command line. Units: lengths in Å, areas in Å², volumes in Å³.
//!
//! The rules (docs/measure.md gives the reasons):
//!
//! - **Area per atom** ([`atom_areas`]): each triangle's area goes one third to each of its
//!   three vertices; a vertex's share goes to the atoms in proportion to each atom's Gaussian
//!   `exp(-|v - p_i|^2 / (2 alpha_i^2))` at the vertex, over the atoms with
//!   `|v - p_i| < q alpha_i` (the density's own terms and cutoff, DESIGN section 2; the
//!   exponential is the analytic engine's polynomial one, relative error below 1e-6). A vertex
//!   no atom reaches (impossible on a surface the engine made) goes to the atom nearest it. The
//!   per-atom areas sum to the mesh's area ([`Mesh::area`](crate::surface::Mesh::area)), in
//!   f64. [`atom_areas_of`] rescales them to [`SurfaceOutput::area`], which differs from the flat
//!   triangles' area with refined vertices. Pass the parameters the engine used: with refined
//!   vertices, `engine.vertices().effective(&params)`.
//! - **Area per residue** ([`residue_areas`]): the sum over the residue's atoms in the set.
//! - **Exposure** ([`ExposureTable`]): a residue's area over the largest area that a residue of
//!   the same name has alone (its atoms only, same radii and parameters), over up to
//!   [`ExposureTable::SAMPLES`] residues of that name in the structure the table is built from.
//!   1 is as exposed as an isolated residue; values a little above 1 are possible.
//! - **Buried area** ([`interface()`]): `(area(A) + area(B) - area(A and B)) / 2`, the three
//!   surfaces on the union's grid ([`SurfaceEngine::set_grid`](crate::surface::SurfaceEngine::set_grid)).
//!   Contact residues ([`contact_residues`]) lose more than a threshold (default 1 Å²) of area
//!   from alone to the complex.
//! - **Cavities** ([`cavities()`]): the mesh's connected components (triangles sharing a vertex);
//!   a component whose signed volume is negative (its triangles wind towards the void) is an
//!   enclosed void when it lies inside a component of positive volume (ray parity). Volume
//!   (positive), area, centroid of the enclosed region, and the atoms lining it: at some vertex
//!   of the void's wall, the atom's Gaussian is at least half the largest Gaussian there
//!   ([`CavityOptions::lining_fraction`]).
//! - **Probe cavities** ([`probe_cavities`]): voids where a probe sphere fits but which it
//!   cannot reach from outside (the SES's inner components), with Bondi's radii
//!   ([`ses_probe_cavities`]); the same [`Cavity`] rows, so tracking and CSVs are shared.
//! - **Tracking** ([`CavityTracker`]): a cavity keeps its id while its centroid and its previous
//!   self's are within the larger of their bounding radii (by nearest images in a periodic
//!   cell); births, deaths, merges and splits are reported as [`CavityEvent`]s.
//! - **Periodic surfaces** ([`periodic`]): per-atom areas over the atoms' periodic images, per
//!   cell; cavities of the mesh welded across the cell faces (finite sheets of negative volume);
//!   the interface's three surfaces periodic in the frame's cell. [`atom_areas_of`] and
//!   [`cavities_of`] choose by the output.

pub(crate) mod areas;
pub(crate) mod cavities;
mod cells;
pub(crate) mod csv;
mod grid_balls;
mod grid_flood;
pub mod interface;
mod lanes;
pub(crate) mod periodic;
pub(crate) mod probe_cavities;
mod probe_small_voids;
pub(crate) mod probe_surface;
pub(crate) mod residues;
pub(crate) mod tracking;

pub use areas::{atom_areas, atom_areas_of, scaled_atom_areas, vertex_areas};
pub use cavities::{Cavity, CavityOptions, Component, cavities, cavities_of, components};
pub use csv::{
    AtomCsv, CavityCsv, CavityEventCsv, ContactCsv, InterfaceCsv, ResidueCsv, lining_residues,
};
pub use interface::{
    CONTACT_THRESHOLD, ContactResidue, InterfaceResult, Side, TakenFromComplex, contact_residues,
    interface, interface_on, interface_with,
};
pub use periodic::{
    periodic_atom_areas, periodic_cavities, periodic_cavity_walls, periodic_interface,
};
pub use probe_cavities::{
    ProbeOptions, probe_cavities, probe_cavity_walls, ses_probe_cavities, ses_probe_cavity_walls,
    ses_radius,
};
pub use probe_surface::{ProbeSurface, probe_interface, probe_surface, ses_probe_interface};
pub use residues::{
    ExposureTable, ResidueArea, ResidueNames, names_residues, residue_areas, residue_label,
};
pub use tracking::{CavityEvent, CavityTracker, TrackUpdate, TrackedCavity};

use crate::surface::SurfaceError;

/// Why a measurement could not be made.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    /// The atoms or parameters were invalid, or a surface could not be computed.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// Two inputs that must have one entry per atom differ in length.
    #[error("{got} {what} given for {expected} atoms")]
    LengthMismatch {
        /// What was given (`atom areas`, `atom indices`).
        what: &'static str,
        /// Number of atoms.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// An index points past the end of what it indexes.
    #[error("{what} {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// What the index is (`mesh vertex`, `topology atom`).
        what: &'static str,
        /// The index.
        index: usize,
        /// Number of items.
        len: usize,
    },
    /// The engine measured the surface without keeping its mesh.
    #[error("the surface was measured without keeping its mesh; per-atom areas need the mesh")]
    NoMesh,
    /// A probe's surface or cavities were asked for on a periodic surface.
    #[error(
        "the probe's cavities and surface are found in open space, not in a periodic cell: turn off the probe or the periodic surface"
    )]
    PeriodicProbe,
    /// The probe cavities' grid would not fit in memory.
    #[error(
        "the cavity probe's {}x{}x{} grid at {spacing} Å needs {:.1} GB but only {:.1} GB is \
         available; select fewer atoms (the grid covers the selection's box)",
        dims[0], dims[1], dims[2], *bytes_needed as f64 / 1e9, *bytes_available as f64 / 1e9
    )]
    ProbeGridTooLarge {
        /// Grid points along x, y, z.
        dims: [u64; 3],
        /// Grid spacing in Å.
        spacing: f32,
        /// Bytes the grid would need.
        bytes_needed: u64,
        /// Bytes available.
        bytes_available: u64,
    },
    /// A threshold or option was not a finite non-negative number.
    #[error("{name} must be a finite non-negative number, got {value}")]
    InvalidOption {
        /// Which option.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// An option was not a finite number within its range.
    #[error("{name} must be a number from {low} to {high}, got {value}")]
    OptionOutOfRange {
        /// Which option, with its unit.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The least value allowed.
        low: f64,
        /// The largest value allowed.
        high: f64,
    },
}
