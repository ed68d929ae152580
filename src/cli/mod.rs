//! Subcommands of the `mdsurf` binary, one file each, plus what they share ([`common`]) and the
//! benchmark table ([`bench_table`]).

pub mod arg_error;
pub mod bench;
pub mod bench_args;
pub mod bench_table;
pub mod bench_viewer;
pub mod chunk;
pub mod common;
pub mod interrupt;
pub mod live_args;
pub mod look_args;
pub mod measure_args;
pub mod merge;
pub mod progress;
pub mod render;
pub mod render_args;
pub mod render_output;
pub mod render_script;
pub mod scene_args;
pub mod select;
pub mod surface;
pub mod transform_args;
pub mod view;
