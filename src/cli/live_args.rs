//! The options that take frames from a running simulation (`--imd`) or from a file an engine
//! is still writing (`--follow`), shared by the commands that read frames as they arrive.

use std::time::Duration;

use anyhow::{Result, bail};
use mdsurf::io::{FollowOptions, IoError, LiveOptions, LiveSource};
use mdsurf::model::Frame;

/// Frames from a simulation running now, over IMD (GROMACS `mdrun -imdport`, NAMD, LAMMPS).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LiveArgs {
    /// Take the frames from the simulation listening at HOST:PORT (IMD version 2 or 3), frame i being
    /// the i-th step it sends, instead of from TRAJ. TOP must hold the atoms the engine sends
    /// (GROMACS: IMD-group = System). Without --frames the run goes on until the simulation ends.
    #[arg(long, value_name = "HOST:PORT")]
    pub imd: Option<String>,
    /// With --imd: ask the engine for one frame every N steps.
    #[arg(long, value_name = "N", requires = "imd",
          value_parser = clap::value_parser!(u32).range(1..))]
    pub imd_every: Option<u32>,
    /// With --imd: the simulation's time step in ps, so that frames get times (step x time
    /// step); IMD version 2 sends steps, not times (version 3 engines' own times are used
    /// without it).
    #[arg(long, value_name = "PS", requires = "imd", value_parser = parse_timestep)]
    pub imd_timestep: Option<f64>,
    /// With --imd: seconds to wait for the simulation to accept the connection.
    #[arg(long, value_name = "S", requires = "imd", default_value_t = 30,
          value_parser = clap::value_parser!(u64).range(1..=86_400))]
    pub imd_wait: u64,
    /// Keep reading TRAJ while an engine writes it: frames appended later appear as they are
    /// completed (a frame still being written is waited for); the run ends when the file has
    /// not grown for --follow-idle seconds.
    #[arg(long, conflicts_with = "imd")]
    pub follow: bool,
    /// With --follow: seconds without growth that end the run.
    #[arg(long, value_name = "S", requires = "follow", default_value_t = 60,
          value_parser = clap::value_parser!(u64).range(1..=604_800))]
    pub follow_idle: u64,
}

/// A time step in ps: finite, above 0 and at most 1000 (1 ns).
fn parse_timestep(s: &str) -> Result<f64> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1000.0 => Ok(v),
        _ => bail!("expected a time step in ps above 0 and at most 1000"),
    }
}

impl LiveArgs {
    /// Where growing frames come from: the simulation (--imd), or TRAJ followed as it grows
    /// (--follow); `None` for an ordinary file. Fails on --imd with a trajectory file, or
    /// --follow without one.
    pub fn options(&self, traj: Option<&std::path::Path>) -> Result<Option<LiveSource>> {
        if self.follow {
            let Some(traj) = traj else {
                bail!(
                    "--follow: give the trajectory file the engine is writing (mdsurf TOP TRAJ --follow)"
                );
            };
            let mut options = FollowOptions::new(traj);
            options.idle = Duration::from_secs(self.follow_idle);
            return Ok(Some(LiveSource::Follow(options)));
        }
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
        Ok(Some(LiveSource::Imd(options)))
    }
}

/// The frames a command's loop skipped because a running simulation sent them faster than they
/// were read (they left the ring of frames kept before being read). Only the frames the command
/// was asked for count (`--frames` may take one in N, or stop before the simulation does).
#[derive(Default)]
pub struct OverrunSkips {
    /// Frames asked for and skipped so far.
    frames: usize,
    /// The last frame asked for, if the run has one: the skip line names no frame after it.
    last: Option<usize>,
}

impl OverrunSkips {
    /// Skips of a loop over frames up to `last` (the last frame asked for, if known).
    pub fn up_to(last: Option<usize>) -> OverrunSkips {
        OverrunSkips { frames: 0, last }
    }

    /// When `error` says frames were lost that way: counts the frame asked for, says so in one
    /// line the first time (unless `quiet`), and returns the oldest frame still held, where the
    /// loop goes on (the frames asked for before it are counted by [`OverrunSkips::pass_over`]).
    pub fn skip(&mut self, error: &anyhow::Error, quiet: bool) -> Option<usize> {
        let IoError::LiveOverrun {
            path,
            frame,
            oldest,
            ..
        } = error.downcast_ref::<IoError>()?
        else {
            return None;
        };
        if self.frames == 0 && !quiet {
            let to = self.last.map_or(oldest - 1, |last| last.min(oldest - 1));
            eprintln!(
                "{}: frames {frame} to {to} skipped: the simulation sends frames faster than \
                 they are measured (--imd-every N asks for one frame in N steps; later skips \
                 are counted at the end)",
                path.display(),
            );
        }
        self.frames += 1;
        Some(*oldest)
    }

    /// Counts a frame asked for that the loop passes over because it left the ring with the
    /// one [`OverrunSkips::skip`] was told about (it comes before the returned frame).
    pub fn pass_over(&mut self) {
        self.frames += 1;
    }

    /// Says in one line how many frames were skipped in all, if any.
    pub fn finish(&self, quiet: bool) {
        if self.frames > 0 && !quiet {
            eprintln!("{} frames of the simulation skipped in all", self.frames);
        }
    }
}

/// [`mdsurf::io::read_held`] for the commands' readers: frame `index`, or the oldest frame a
/// running simulation still holds when it has already pushed `index` out, with its index.
pub fn read_held(index: usize, read: impl FnMut(usize) -> Result<Frame>) -> Result<(usize, Frame)> {
    mdsurf::io::read_held(index, read, |e: &anyhow::Error| {
        e.downcast_ref::<IoError>().and_then(IoError::oldest_held)
    })
}

/// The end of a growing source (a simulation that finished, a file that stopped growing) when
/// `error` is one: the end of the run, not a failure, for the commands' frame loops.
pub fn end_of_stream(error: &anyhow::Error) -> Option<&IoError> {
    error
        .downcast_ref::<IoError>()
        .filter(|e| matches!(e, IoError::LiveEnded { .. }))
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    /// A source whose frames before `oldest` were pushed out of the ring, as [`IoError`]s say.
    fn held_from(oldest: usize) -> impl FnMut(usize) -> Result<Frame> {
        move |index| {
            if index < oldest {
                return Err(IoError::LiveOverrun {
                    path: PathBuf::from("imd://localhost:8888"),
                    frame: index,
                    oldest,
                    kept: 4,
                }
                .into());
            }
            Ok(Frame {
                index,
                ..Frame::default()
            })
        }
    }

    #[test]
    fn the_set_up_frame_is_the_oldest_held_when_the_first_was_pushed_out() {
        let (index, frame) = read_held(0, held_from(7)).unwrap();
        assert_eq!((index, frame.index), (7, 7));
        assert_eq!(read_held(9, held_from(7)).unwrap().0, 9);
    }

    #[test]
    fn other_errors_are_returned_as_they_are() {
        let gone = |index| -> Result<Frame> {
            Err(IoError::LiveEnded {
                path: PathBuf::from("imd://localhost:8888"),
                frames: index,
                reason: "the engine closed the connection".into(),
            }
            .into())
        };
        let err = read_held(3, gone).unwrap_err();
        assert!(err.to_string().contains("imd://localhost:8888"), "{err}");
        assert!(end_of_stream(&err).is_some());
    }
}
