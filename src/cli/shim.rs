//! TEMPORARY stand-ins for library APIs other branches are landing (`io::open`, `CpuEngine`,
//! `GpuEngine`, `gpu::table1`), written against the agreed interfaces so the command line
//! compiles meanwhile. Each item fails with a clear error; this file is deleted when the real
//! ones are merged.

#![allow(dead_code)]

use std::path::Path;

use anyhow::{Result, bail};

use mdsurf::model::{Frame, Topology};
use mdsurf::surface::{AtomSet, SurfaceEngine, SurfaceError, SurfaceOutput, SurfaceParams};

/// Stand-in for `mdsurf::io`.
pub mod io {
    use super::*;

    /// Stand-in for `mdsurf::io::Trajectory`.
    pub struct Trajectory {
        topology: Topology,
    }

    impl Trajectory {
        pub fn topology(&self) -> &Topology {
            &self.topology
        }
        pub fn len(&self) -> usize {
            0
        }
        pub fn read_frame(&self, _index: usize) -> Result<Frame> {
            bail!("reading frames is not merged into this branch yet")
        }
    }

    /// Stand-in for `mdsurf::io::open`.
    pub fn open(top: &Path, _traj: Option<&Path>) -> Result<Trajectory> {
        bail!("{}: reading files is not merged into this branch yet", top.display())
    }
}

/// Stand-in for `mdsurf::surface::CpuEngine`.
pub struct CpuEngine;

impl CpuEngine {
    pub fn new() -> CpuEngine {
        CpuEngine
    }
}

impl SurfaceEngine for CpuEngine {
    fn name(&self) -> &str {
        "cpu"
    }
    fn compute(
        &mut self,
        _atoms: &AtomSet<'_>,
        _params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError> {
        Err(SurfaceError::EmptySystem)
    }
}

/// Stand-in for `mdsurf::gpu::GpuEngine`.
pub struct GpuEngine;

impl GpuEngine {
    pub fn new() -> Result<GpuEngine> {
        bail!("the GPU engine is not merged into this branch yet")
    }
}

impl SurfaceEngine for GpuEngine {
    fn name(&self) -> &str {
        "gpu"
    }
    fn compute(
        &mut self,
        _atoms: &AtomSet<'_>,
        _params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError> {
        Err(SurfaceError::EmptySystem)
    }
}

/// Stand-in for `mdsurf::gpu::table1`.
pub fn table1() -> Result<String> {
    bail!("--table1 needs the GPU engine, which is not merged into this branch yet")
}
