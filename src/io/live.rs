//! Frames from a running simulation ([`imd`](super::imd)), served as a trajectory: a thread
//! receives every step the engine sends as soon as it arrives (so the simulation never waits on
//! us) into a ring of the last frames, and [`LiveFrames::read_frame`] hands frame `i` out when
//! it has arrived, waiting for it when it has not. Frames are numbered from 0 in the order they
//! arrive; frames older than the ring are gone (one line says so). When the connection ends
//! (the run finished, the engine was killed, the network dropped) the frames received stay
//! readable and the next one is [`IoError::LiveEnded`].

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use super::IoError;
use super::imd::{ImdClient, ImdError, cut, leave};
use super::native::NativeFrames;
use glam::Vec3;

use crate::model::Frame;

/// How long dropping a live source waits for the engine to close the connection after the
/// disconnect message (it does so at its next step; see [`leave`] for why we wait) before
/// closing it anyway.
const LEAVE_WAIT: Duration = Duration::from_secs(10);

/// How many frames a live trajectory claims to have when the run's length is not known: the
/// consumers' loops end at [`IoError::LiveEnded`] long before.
pub const LIVE_FRAMES_UNBOUNDED: usize = 1_000_000;

/// A source of frames that grows while it is read.
#[derive(Debug, Clone)]
pub enum LiveSource {
    /// A running simulation, over IMD.
    Imd(LiveOptions),
    /// A trajectory file an engine is writing.
    Follow(super::follow::FollowOptions),
}

impl LiveSource {
    /// Where the frames come from, for messages (`HOST:PORT`, or the file).
    pub fn describe(&self) -> String {
        match self {
            LiveSource::Imd(o) => o.address.clone(),
            LiveSource::Follow(o) => o.path.display().to_string(),
        }
    }
}

/// How to follow a simulation.
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// `HOST:PORT` of the engine's IMD socket.
    pub address: String,
    /// Frames kept for reading back (the oldest are dropped first); at least 1.
    pub ring_frames: usize,
    /// Ask the engine to send one frame every this many steps (`None`: its default).
    pub rate_steps: Option<u32>,
    /// How long to keep trying to connect (the engine may still be starting).
    pub connect_timeout: Duration,
    /// How long to wait for the next frame before giving up on the engine.
    pub frame_timeout: Duration,
    /// The simulation's time step in ps: with it, a frame's time is its step (from the energy
    /// record the engine sends before the coordinates) times this. IMD version 2 sends no time;
    /// without this, a version 3 engine's time record is used (in ps, or in fs when its time
    /// step is 0.1 or more: LAMMPS with `units real`).
    pub timestep_ps: Option<f64>,
}

impl LiveOptions {
    /// Defaults for `address`: a ring of 256 frames, the engine's rate, 30 s to connect and
    /// 10 minutes between frames (a large system on a slow machine may take that long).
    pub fn new(address: &str) -> LiveOptions {
        LiveOptions {
            address: address.to_string(),
            ring_frames: 256,
            rate_steps: None,
            connect_timeout: Duration::from_secs(30),
            frame_timeout: Duration::from_secs(600),
            timestep_ps: None,
        }
    }
}

/// What the receiving thread and the readers share.
#[derive(Default)]
struct Received {
    /// The last frames, oldest first.
    ring: VecDeque<Frame>,
    /// Frames received so far (the newest has index `count - 1`).
    count: usize,
    /// Set when the connection ended, with why.
    ended: Option<ImdError>,
    /// Set by the reader side to make the thread stop (it reads on, dropping what comes, until
    /// the engine closes the connection).
    stop: bool,
    /// Set by the thread when it has returned: the engine closed the connection, or it failed.
    finished: bool,
}

struct Shared {
    received: Mutex<Received>,
    arrived: Condvar,
    /// A handle on the socket for pause and detach ([`LiveProgress::control`]).
    control: Mutex<Option<std::net::TcpStream>>,
    /// The session's IMD version (2 or 3).
    version: i32,
    /// True while we have the simulation paused.
    paused: std::sync::atomic::AtomicBool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Received> {
        self.received
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

/// How far a growing source has come, readable without waiting on its reader: a running
/// simulation ([`LiveFrames`]) or a file an engine is writing ([`super::follow`]).
pub(crate) trait LiveProgress: Send + Sync {
    /// Frames readable now.
    fn received(&self) -> usize;
    /// Why the source stopped growing, once it has (one line), else `None`.
    fn ended(&self) -> Option<String>;
    /// Pauses, resumes or detaches from a running simulation; only IMD sources can.
    fn control(&self, _action: LiveAction) -> Result<(), LiveControlError> {
        Err(LiveControlError::NotImd)
    }
    /// True while [`LiveProgress::control`] can reach the simulation (an IMD stream that has
    /// not ended).
    fn controllable(&self) -> bool {
        false
    }
}

/// What the viewer can ask of a running simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LiveAction {
    /// Pause the simulation, or resume it when paused.
    TogglePause,
    /// Leave the simulation running and stop receiving its frames (those received stay).
    Detach,
}

/// Why a [`LiveAction`] could not be sent.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LiveControlError {
    /// The frames do not come from a simulation over IMD.
    #[error("not a running simulation: only --imd sources can be paused or detached")]
    NotImd,
    /// The stream has ended (the run finished, was killed, or we detached).
    #[error("the simulation stream has ended")]
    Ended,
    /// The message could not be sent.
    #[error(transparent)]
    Imd(#[from] ImdError),
}

/// A shared handle on a [`LiveProgress`].
pub(crate) type LiveCount = Arc<dyn LiveProgress>;

impl LiveProgress for Shared {
    fn received(&self) -> usize {
        self.lock().count
    }

    fn ended(&self) -> Option<String> {
        self.lock().ended.as_ref().map(|e| e.to_string())
    }

    fn controllable(&self) -> bool {
        let control = self
            .control
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        control.is_some() && self.lock().ended.is_none()
    }

    fn control(&self, action: LiveAction) -> Result<(), LiveControlError> {
        let control = self
            .control
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let socket = match (&*control, &self.lock().ended) {
            (Some(socket), None) => socket,
            _ => return Err(LiveControlError::Ended),
        };
        match action {
            LiveAction::TogglePause => {
                use std::sync::atomic::Ordering::SeqCst;
                let pause = !self.paused.load(SeqCst);
                super::imd::pause_on(socket, self.version, pause)?;
                self.paused.store(pause, SeqCst);
            }
            LiveAction::Detach => {
                // Marked first, so the receiver's end of stream reads as the detach it is.
                self.lock().ended = Some(ImdError::Detached);
                super::imd::leave(socket);
                self.arrived.notify_all();
            }
        }
        Ok(())
    }
}

/// A running simulation as a source of frames.
pub(crate) struct LiveFrames {
    /// `imd://HOST:PORT`, for messages.
    path: PathBuf,
    shared: Arc<Shared>,
    /// A handle on the socket, to unblock the receiving thread on drop.
    socket: Option<std::net::TcpStream>,
    thread: Option<JoinHandle<()>>,
    /// Frames kept.
    ring_frames: usize,
    /// Longest wait for a frame.
    frame_timeout: Duration,
}

impl LiveFrames {
    /// Connects to the engine (see [`ImdClient::connect`]) and starts receiving frames of
    /// `atoms` atoms. A version 3 engine may send each frame's box and time, which the frame
    /// then gets. IMD version 2 sends neither box nor time: every frame gets the box of
    /// `start`, the structure the run started from (exact at constant volume; under pressure
    /// coupling the box breathes and this is the starting one), and with a time step, the time
    /// of `start` plus the steps since the first frame (engines number steps differently:
    /// GROMACS 2022 reports step + 1 with the coordinates of step, so only differences count).
    pub(crate) fn connect(
        options: &LiveOptions,
        atoms: usize,
        start: &Frame,
    ) -> Result<LiveFrames, IoError> {
        let path = PathBuf::from(format!("imd://{}", options.address));
        let fail = |e: ImdError| IoError::unreadable(&path, e.to_string());
        let mut client = ImdClient::connect(
            &options.address,
            options.connect_timeout,
            options.frame_timeout,
        )
        .map_err(fail)?;
        if let Some(steps) = options.rate_steps {
            client.set_rate(steps).map_err(fail)?;
        }
        let socket = client.socket().ok();
        let shared = Arc::new(Shared {
            received: Mutex::new(Received::default()),
            arrived: Condvar::new(),
            control: Mutex::new(client.socket().ok()),
            version: client.version(),
            paused: Default::default(),
        });
        let ring_frames = options.ring_frames.max(1);
        let expected = Expected {
            atoms,
            cell: start.cell,
            timestep_ps: options.timestep_ps,
            start_ps: start.time_ps.unwrap_or(0.0),
        };
        let thread = {
            let shared = Arc::clone(&shared);
            std::thread::Builder::new()
                .name("mdsurf-imd".into())
                .spawn(move || receive(client, &expected, ring_frames, &shared))
                .map_err(|e| IoError::unreadable(&path, format!("cannot start a thread: {e}")))?
        };
        setup_delay_for_tests();
        Ok(LiveFrames {
            path,
            shared,
            socket,
            thread: Some(thread),
            ring_frames,
            frame_timeout: options.frame_timeout,
        })
    }
}

/// What every frame of a run has in common.
struct Expected {
    /// Atoms per frame.
    atoms: usize,
    /// The box every frame gets (Å).
    cell: Option<[Vec3; 3]>,
    /// Time step (ps), to turn steps into times.
    timestep_ps: Option<f64>,
    /// Time of the first frame (ps): the structure's.
    start_ps: f64,
}

/// Factor from a version 3 engine's time unit to ps, judged from its time step `dt` in that
/// unit: GROMACS sends ps, LAMMPS its own units, fs with `units real` (the usual units for
/// molecules) and ps with `units metal`. No MD time step is 0.1 ps or longer, so a step of 0.1 or
/// more is taken as fs; a shorter one as ps.
fn engine_time_to_ps(dt: f64) -> f64 {
    if dt >= 0.1 { 1e-3 } else { 1.0 }
}

/// The receiving thread: every step into the ring (of `ring_frames` frames) until the
/// connection ends. After a detach or a stop the steps still on their way are read and dropped
/// until the engine closes the connection (see [`leave`]).
fn receive(mut client: ImdClient, expected: &Expected, ring_frames: usize, shared: &Shared) {
    let mut first_step = None;
    loop {
        let result = client.next_step(expected.atoms);
        let mut received = shared.lock();
        match result {
            Ok(_) if received.stop || received.ended.is_some() => {}
            Ok(step) => {
                let index = received.count;
                let step_number =
                    (step.time.map(|t| t.step)).or(step.energies.map(|e| i64::from(e.step)));
                let first = *first_step.get_or_insert(step_number);
                // A given time step wins over the engine's time (LAMMPS sends its own units).
                let time_ps = match (step_number, first, expected.timestep_ps, step.time) {
                    (Some(now), Some(first), Some(dt), _) => {
                        Some(expected.start_ps + (now - first) as f64 * dt)
                    }
                    (.., Some(time)) => Some(time.time * engine_time_to_ps(time.dt)),
                    _ => None,
                };
                received.ring.push_back(Frame {
                    index,
                    time_ps,
                    positions: step.positions,
                    cell: step.cell.or(expected.cell),
                });
                while received.ring.len() > ring_frames {
                    received.ring.pop_front();
                }
                received.count += 1;
                shared.arrived.notify_all();
            }
            Err(error) => {
                // A detach already said why the stream ends.
                received.ended.get_or_insert(error);
                received.finished = true;
                shared.arrived.notify_all();
                return;
            }
        }
    }
}

/// The `test-hooks` build waits `MDSURF_TEST_LIVE_SETUP_DELAY_MS` ms after connecting, before
/// the caller reads its first frame: a slow machine's set-up, during which a fast engine fills
/// the ring (the tests that the first frame may be gone by then). Other builds do nothing.
fn setup_delay_for_tests() {
    #[cfg(feature = "test-hooks")]
    if let Some(ms) = std::env::var("MDSURF_TEST_LIVE_SETUP_DELAY_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(Duration::from_millis(ms));
    }
}

/// Reads frame `index` with `read`, or, when a running simulation has already pushed it out of
/// the frames kept (it sends faster than the reader sets up; `oldest` finds that in an error
/// and says the oldest frame still held), that oldest frame: for the frame a command or the
/// viewer sets up with, where any frame of the run serves. Returns the index of the frame read
/// with it. Other errors are returned as they are.
pub fn read_held<E>(
    index: usize,
    mut read: impl FnMut(usize) -> Result<Frame, E>,
    oldest: impl Fn(&E) -> Option<usize>,
) -> Result<(usize, Frame), E> {
    let mut index = index;
    loop {
        match read(index) {
            Ok(frame) => return Ok((index, frame)),
            Err(e) => match oldest(&e) {
                Some(held) if held > index => index = held,
                _ => return Err(e),
            },
        }
    }
}

impl LiveFrames {
    /// A handle on the count of frames received.
    pub(crate) fn count(&self) -> LiveCount {
        Arc::clone(&self.shared) as LiveCount
    }
}

impl NativeFrames for LiveFrames {
    fn path(&self) -> &Path {
        &self.path
    }

    fn base(&self) -> &'static str {
        "IMD"
    }

    fn len(&self) -> usize {
        LIVE_FRAMES_UNBOUNDED
    }

    fn damage(&self) -> Option<&IoError> {
        None
    }

    fn read_frame(&mut self, index: usize) -> Result<Frame, IoError> {
        let mut received = self.shared.lock();
        loop {
            let oldest = received.count - received.ring.len();
            if index < oldest {
                return Err(IoError::LiveOverrun {
                    path: self.path.clone(),
                    frame: index,
                    oldest,
                    kept: self.ring_frames,
                });
            }
            if index < received.count {
                return Ok(received.ring[index - oldest].clone());
            }
            if let Some(reason) = &received.ended {
                return Err(IoError::LiveEnded {
                    path: self.path.clone(),
                    frames: received.count,
                    reason: reason.to_string(),
                });
            }
            let (guard, wait) = self
                .shared
                .arrived
                .wait_timeout(received, self.frame_timeout)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            received = guard;
            if wait.timed_out() && index >= received.count && received.ended.is_none() {
                return Err(IoError::bad_frame(
                    &self.path,
                    index,
                    format!(
                        "no frame from the simulation for {} s",
                        self.frame_timeout.as_secs()
                    ),
                ));
            }
        }
    }
}

impl Drop for LiveFrames {
    fn drop(&mut self) {
        let detached = {
            let mut received = self.shared.lock();
            received.stop = true;
            received.ended.is_some()
        };
        if let Some(socket) = &self.socket {
            // Tell the engine we leave (it goes on running), unless a detach or its own close
            // did already, and let the thread read on until the engine closes the connection.
            if !detached {
                leave(socket);
            }
            let received = self.shared.lock();
            let (received, _) = self
                .shared
                .arrived
                .wait_timeout_while(received, LEAVE_WAIT, |r| !r.finished)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            if !received.finished {
                cut(socket);
            }
        }
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::imd::tests::{greet, header};
    use std::io::{Read, Write};
    use std::net::TcpListener;

    /// One step of `atoms` atoms at `step` as an x86 engine writes it (bodies little-endian):
    /// the energy record, then the coordinates.
    fn step_message(step: i32, atoms: i32) -> Vec<u8> {
        let mut bytes = header(1, 1);
        bytes.extend(step.to_le_bytes());
        bytes.extend([0u8; 36]);
        bytes.extend(header(2, atoms));
        for i in 0..atoms * 3 {
            bytes.extend((i as f32).to_le_bytes());
        }
        bytes
    }

    /// A fake engine on a local port, as GROMACS behaves around a detach: it sends one step,
    /// waits for the client's next message, and when that is the disconnect, sends the steps
    /// it was already computing (`late`, 100 ms apart) before it reads the message and closes.
    /// Returns the address and what each late write did.
    fn engine_mid_step(late: i32) -> (String, JoinHandle<Vec<String>>) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let address = listener.local_addr().unwrap().to_string();
        let handle = std::thread::spawn(move || {
            let (mut socket, _) = listener.accept().unwrap();
            greet(&mut socket);
            socket.write_all(&step_message(0, 2)).unwrap();
            let mut header = [0u8; 8];
            socket.read_exact(&mut header).unwrap();
            assert_eq!(header, [0u8; 8], "the next message is the disconnect");
            (1..=late)
                .map(|step| {
                    std::thread::sleep(Duration::from_millis(100));
                    match socket.write_all(&step_message(step, 2)) {
                        Ok(()) => "written".to_string(),
                        Err(e) => e.to_string(),
                    }
                })
                .collect()
        });
        (address, handle)
    }

    fn connect(address: &str) -> LiveFrames {
        connect_with(address, 2, None)
    }

    /// A live source of `atoms` atoms on the engine at `address`, with `timestep_ps`.
    fn connect_with(address: &str, atoms: usize, timestep_ps: Option<f64>) -> LiveFrames {
        let mut options = LiveOptions::new(address);
        options.connect_timeout = Duration::from_secs(5);
        options.frame_timeout = Duration::from_secs(20);
        options.timestep_ps = timestep_ps;
        let start = Frame {
            index: 0,
            time_ps: Some(10.0),
            positions: vec![Vec3::ZERO; atoms],
            cell: None,
        };
        LiveFrames::connect(&options, atoms, &start).unwrap()
    }

    /// A version 3 engine's box and time go to the frames (LAMMPS sends fs here: its 2.0 time
    /// step says so); a time step given wins over the engine's time.
    #[test]
    fn version_3_frames_take_the_engines_box_and_time() {
        use crate::io::imd::tests::{argon_start, lammps_v3_session, replaying_engine};
        let atoms = argon_start().len();
        for (timestep_ps, times) in [
            (None, [0.002, 0.004, 0.006]),
            (Some(0.002), [10.0, 10.002, 10.004]),
        ] {
            let (address, _engine) = replaying_engine(lammps_v3_session());
            let mut live = connect_with(&address, atoms, timestep_ps);
            for (i, want) in times.into_iter().enumerate() {
                let frame = live.read_frame(i).unwrap();
                let time = frame.time_ps.unwrap();
                assert!(
                    (time - want).abs() < 1e-9,
                    "frame {i}: {time} ps, not {want}"
                );
                assert_eq!(frame.cell.unwrap()[2], Vec3::new(0.0, 0.0, 21.04));
            }
        }
    }

    /// A detach must not reset the connection while the engine still sends: GROMACS writes
    /// with SIGPIPE at its default, so its second write to a reset connection kills the run
    /// (this failed with both halves shut at the detach: "Broken pipe").
    #[test]
    fn a_detach_reads_the_steps_on_their_way_and_keeps_only_those_before_it() {
        let (address, engine) = engine_mid_step(3);
        let mut live = connect(&address);
        assert_eq!(
            live.read_frame(0).unwrap().positions[1],
            Vec3::new(3.0, 4.0, 5.0)
        );
        live.count().control(LiveAction::Detach).unwrap();
        let writes = engine.join().unwrap();
        assert_eq!(writes, vec!["written"; 3], "late writes of the engine");
        match live.read_frame(1).unwrap_err() {
            IoError::LiveEnded { frames, reason, .. } => {
                assert_eq!(frames, 1);
                assert!(reason.contains("detached"), "{reason}");
            }
            other => panic!("{other}"),
        }
        assert_eq!(live.count().received(), 1);
    }

    /// Dropping a live source (the end of `surface --imd --frames :N`, a closed window) leaves
    /// the engine the same way.
    #[test]
    fn dropping_a_live_source_lets_the_engine_finish_its_writes() {
        let (address, engine) = engine_mid_step(3);
        let mut live = connect(&address);
        live.read_frame(0).unwrap();
        drop(live);
        assert_eq!(engine.join().unwrap(), vec!["written"; 3]);
    }
}
