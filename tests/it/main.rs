//! All integration tests in one binary (each test binary links chemfiles, wgpu and eframe; one
//! binary instead of 29 saves most of the link time and disk). One module per former test file.

mod cli_common;
mod data_support;
mod gpu_support;
mod surface_common;

mod app_gpu_worker;
mod app_panels;
mod app_smoke;
mod app_stream_source;
mod app_window;
mod cli_bench;
mod cli_errors;
mod cli_gpu;
mod cli_surface;
mod export_atomic;
mod export_formats;
mod gpu_frames;
mod gpu_parity;
mod gpu_stages;
mod gpu_steady;
mod gpu_table1;
mod io_bad;
mod io_data;
mod io_hostile;
mod io_model;
mod io_roundtrip;
mod io_stream;
mod io_xdr;
mod render_cli;
mod render_gpu_surface;
mod render_images;
mod render_stereo;
mod scene_reps;
mod scene_selection;
mod shaders_validate;
mod surface_analytic;
mod surface_bricks;
mod surface_density;
mod surface_errors;
mod surface_invariance;
mod surface_periodic;
mod surface_real;
mod surface_refine;
mod surface_ses;
mod transform;
