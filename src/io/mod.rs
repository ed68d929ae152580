//! Reading structures and trajectories: the first stage of the data flow. [`open`] turns a
//! topology file (and optionally a separate trajectory file) into a [`Trajectory`]: a constant
//! [`Topology`](crate::model::Topology) plus random access to [`Frame`](crate::model::Frame)s,
//! one at a time (the whole trajectory is never loaded; the models of an mmCIF file are read at
//! once, with the topology). [`FrameStreamer`] wraps a trajectory in
//! a reader thread with a bounded cache for the viewer.
//!
//! mmCIF files (`.cif`, `.mmcif`, also compressed) are read by our own reader (`mmcif`, on the
//! tokens of `cif_lexer`): no C++ parser sees their bytes (chemfiles' mmCIF reader crashed on
//! tabs in an `_atom_site` row and stopped at a blank line inside the loop). Large plain PDB and
//! XYZ files take a fast path (`fast`): read once, in Rust, giving exactly what the chemfiles
//! path gives. Every other format goes through chemfiles (PDB, GRO, XTC, TRR, DCD, LAMMPS dump,
//! XYZ, TNG, Amber NetCDF, with `.gz`/`.bz2`/`.xz` compression); PDB files are additionally
//! read column by column for element columns, B-factors and chains (`wwpdb`). All failures are
//! [`IoError`]s that print as one line naming the file (and frame, and atom, or line); chemfiles'
//! own warnings are captured (see [`take_warnings`]) rather than printed. No byte of a file
//! reaches the C++ readers unchecked: text is made valid UTF-8 and `.gz`/`.bz2` decompressed in
//! Rust (`prepare`), XTC/TRR frame headers (`xdr`), TNG blocks (`tng`) and DCD headers (`dcd`)
//! are walked first, and a damaged part ends the readable frames as [`Damage`]. chemfiles itself
//! runs in a reader process (`contained`: the same executable, started as `mdsurf
//! __read-frames`; see [`reader_main`]), never in the process that holds the user's work: a file
//! that still crashes it costs the frame it crashed on (a one-line error naming the file and the
//! frame), and its libraries' text never reaches the terminal.
//!
//! Without the `chemfiles` cargo feature there is no C++ reader: every format above is read by
//! our own readers (GRO, LAMMPS dump, DCD, Amber NetCDF in `native`; XTC/TRR; mmCIF; PDB and
//! XYZ, also compressed, when a fast reader takes the file), and a file only chemfiles reads
//! (TNG, a multi-model PDB) fails to open with one line saying so (`without_chemfiles`).
//! [`read_whole_file`] opens a file and reads every frame (the fuzz targets' entry point).

#[cfg(feature = "chemfiles")]
mod chem;
mod cif_lexer;
mod cif_residues;
mod conect;
#[cfg(feature = "chemfiles")]
mod contained;
#[cfg(not(feature = "chemfiles"))]
#[path = "without_chemfiles.rs"]
mod contained;
mod copy_room;
mod dcd;
mod dcd_frames;
mod decoders;
pub(crate) mod error;
mod fast;
mod fast_pdb;
mod fast_xyz;
mod follow;
pub(crate) mod format;
mod frame_checks;
mod gro;
#[cfg(feature = "app")]
mod http;
#[cfg(feature = "app")]
mod http_prefetch;
pub(crate) mod imd;
mod lammps;
mod lammps_header;
mod line_ends;
mod live;
mod mmcif;
mod mmcif_bonds;
mod native;
mod netcdf;
mod pdb_models;
mod pdb_templates;
mod positioned;
mod positioned_frames;
mod prepare;
mod quiet;
mod reader_errors;
pub(crate) mod stream;
mod text_clean;
mod text_scan;
mod tng;
mod trajectory;
mod type_masses;
mod unit_cell;
mod warnings;
pub mod whole_file;
mod wwpdb;
mod xdr;
mod xdr_error;
mod xdr_reader;
mod xyz_frames;

#[cfg(feature = "chemfiles")]
pub use contained::READER_ARG;
pub use contained::reader_main;
pub use error::IoError;
pub use follow::FollowOptions;
pub use format::{FileFormat, WwFormat, detect};
pub use live::{
    LIVE_FRAMES_UNBOUNDED, LiveAction, LiveControlError, LiveOptions, LiveSource, read_held,
};
pub use stream::{
    FrameHook, FrameHookError, FrameResult, FrameStatus, FrameStreamer, ReadyCallback,
    StreamerOptions,
};
#[doc(hidden)]
pub use tng::check_chain as check_tng_chain;
pub use trajectory::{
    Damage, Trajectory, open, open_following, open_growing, open_live, reads_fast,
};
#[cfg(feature = "chemfiles")]
pub use trajectory::{open_via_chemfiles, open_via_reader_process};
pub use warnings::take_warnings;
pub use whole_file::{WholeFile, read_whole_file};
