//! Subcommands of the `mdsurf` binary, one file each, plus what they share ([`common`]) and the
//! benchmark table ([`bench_table`]).

pub(crate) mod arg_error;
pub(crate) mod bench;
pub(crate) mod bench_args;
pub(crate) mod bench_table;
pub(crate) mod bench_viewer;
pub(crate) mod chunk;
pub(crate) mod common;
pub(crate) mod interrupt;
pub(crate) mod live_args;
pub(crate) mod look_args;
pub(crate) mod measure_args;
pub(crate) mod merge;
pub(crate) mod progress;
pub(crate) mod render;
pub(crate) mod render_args;
pub(crate) mod render_output;
pub(crate) mod render_script;
pub(crate) mod scene_args;
pub(crate) mod select;
pub(crate) mod surface;
pub(crate) mod transform_args;
pub(crate) mod view;
