//! The options that take frames from a running simulation instead of a file (`--imd`), shared
//! by the commands that read frames as they arrive.

use std::time::Duration;

use anyhow::{Result, bail};
use mdsurf::io::LiveOptions;

/// Frames from a simulation running now, over IMD (GROMACS `mdrun -imdport`, NAMD, LAMMPS).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LiveArgs {
    /// Take the frames from the simulation listening at HOST:PORT (IMD version 2), frame i being
    /// the i-th step it sends, instead of from TRAJ. TOP must hold the atoms the engine sends
    /// (GROMACS: IMD-group = System). Without --frames the run goes on until the simulation ends.
    #[arg(long, value_name = "HOST:PORT")]
    pub imd: Option<String>,
    /// With --imd: ask the engine for one frame every N steps.
    #[arg(long, value_name = "N", requires = "imd",
          value_parser = clap::value_parser!(u32).range(1..))]
    pub imd_every: Option<u32>,
    /// With --imd: the simulation's time step in ps, so that frames get times (step x time
    /// step); IMD version 2 sends steps, not times.
    #[arg(long, value_name = "PS", requires = "imd", value_parser = parse_timestep)]
    pub imd_timestep: Option<f64>,
    /// With --imd: seconds to wait for the simulation to accept the connection.
    #[arg(long, value_name = "S", requires = "imd", default_value_t = 30,
          value_parser = clap::value_parser!(u64).range(1..=86_400))]
    pub imd_wait: u64,
}

/// A time step in ps: finite, above 0 and at most 1000 (1 ns).
fn parse_timestep(s: &str) -> Result<f64> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1000.0 => Ok(v),
        _ => bail!("expected a time step in ps above 0 and at most 1000"),
    }
}

impl LiveArgs {
    /// The connection to make, when --imd was given; fails on a time step out of range or a
    /// trajectory file given as well.
    pub fn options(&self, traj: Option<&std::path::Path>) -> Result<Option<LiveOptions>> {
        let Some(address) = &self.imd else {
            return Ok(None);
        };
        if let Some(traj) = traj {
            bail!(
                "--imd {address}: the frames come from the simulation, so give no trajectory file ({})",
                traj.display()
            );
        }
        let mut options = LiveOptions::new(address);
        options.rate_steps = self.imd_every;
        options.timestep_ps = self.imd_timestep;
        options.connect_timeout = Duration::from_secs(self.imd_wait);
        Ok(Some(options))
    }
}
