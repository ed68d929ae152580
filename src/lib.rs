//! mdsurf: Gaussian density surfaces for molecular dynamics trajectories.
//!
//! Data flow: [`io`] reads a [`model::Topology`] and a stream of [`model::Frame`]s; the surface
//! engine ([`surface`] on the CPU, [`gpu`] on the GPU) turns atom positions, radii and colours into
//! a density map and a triangle [`surface::Mesh`]; [`render`] draws it and [`export`] writes it.
//! The desktop viewer in [`app`] sits on top of all of them; none of them imports the app.
//!
//! The `app` feature (on by default) adds the file readers ([`io`]), the viewer ([`app`]) and
//! the command line; without it the crate is the engine alone, as the Python package uses it.

#[cfg(feature = "app")]
pub mod app;
pub mod export;
pub mod gpu;
#[cfg(feature = "app")]
pub mod io;
/// Stand-in for [`io`] without the `app` feature, for the one engine item that opens a file
/// (`gpu::table1::Structure::from_file`): opening fails with a message naming the feature.
#[cfg(not(feature = "app"))]
mod io {
    use std::path::Path;

    use crate::model::{Frame, Topology};

    /// A reader that cannot exist without the `app` feature.
    pub(crate) enum NoReader {}

    impl NoReader {
        pub(crate) fn read_frame(&self, _index: usize) -> Result<Frame, &'static str> {
            match *self {}
        }

        pub(crate) fn topology(&self) -> &Topology {
            match *self {}
        }
    }

    /// Always fails: there are no file readers without the `app` feature.
    pub(crate) fn open(_top: &Path, _traj: Option<&Path>) -> Result<NoReader, &'static str> {
        Err("reading files needs mdsurf's `app` feature")
    }
}
pub mod model;
pub mod render;
pub mod scene;
pub mod surface;
pub mod synthetic;
pub mod transform;
