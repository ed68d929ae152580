//! mdsurf: Gaussian density surfaces for molecular dynamics trajectories.
//!
//! Data flow: [`io`] reads a [`model::Topology`] and a stream of [`model::Frame`]s; the surface
//! engine ([`surface`] on the CPU, [`gpu`] on the GPU) turns atom positions, radii and colours into
//! a density map and a triangle [`surface::Mesh`]; [`render`] draws it and [`export`] writes it.
//! The desktop viewer in [`app`] sits on top of all of them; none of them imports the app.
//!
//! The `app` feature (on by default) adds the file readers ([`io`]), the viewer ([`app`]) and
//! the command line; without it the crate is the engine alone, as the Python package uses it.
//! `chemfiles` (on by default) adds the C++ chemfiles library for the formats our own readers
//! leave to it (TNG, ...); `readers` is [`io`] alone (what the fuzz targets build).

#[cfg(feature = "app")]
pub mod app;
pub mod export;
pub mod gpu;
#[cfg(feature = "readers")]
pub mod io;
pub mod measure;
pub mod model;
pub mod render;
pub mod scene;
pub mod selection;
pub mod surface;
pub mod synthetic;
pub mod transform;
