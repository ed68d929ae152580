//! Subcommands of the `mdsurf` binary, one file each.

pub mod bench;
pub mod render;
pub mod surface;
pub mod view;
