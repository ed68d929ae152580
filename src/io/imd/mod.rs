//! The Interactive Molecular Dynamics (IMD) protocol, versions 2 (GROMACS up to 2024, NAMD,
//! LAMMPS) and 3 (GROMACS 2025): a client that connects to a running simulation, receives its
//! coordinates (Å), box and time frame by frame, and can pause it, change how often it sends,
//! detach or stop it.
//!
//! Every message is an 8-byte header (type and length, 32-bit big-endian integers) and a body.
//! The engine opens with a handshake whose length field is the protocol version written in the
//! engine's own byte order: read big-endian it is 2 on a big-endian engine, and 2 << 24 on a
//! little-endian one. The bodies (energy records, coordinates) come in that same engine order.
//! Version 3 then sends a session record (7 one-byte flags: time, energies, box, coordinates,
//! coordinates wrapped into the box, velocities, forces) saying what each frame carries. The
//! client answers `GO`; from then on each frame the engine reports is, in this order and as the
//! session says: `TIME` (version 3: time step and time in ps as f64, step as i64), `ENERGIES`
//! (a step number and nine 32-bit floats), `BOX` (version 3: the three box vectors, nine 32-bit
//! floats in Å), `FCOORDS` (length = atoms, then x, y, z per atom as 32-bit floats in Å), and
//! `VELOCITIES` and `FORCES` (version 3, shaped as the coordinates; read past, not kept).
//! Version 2 has one `PAUSE` message that toggles; version 3 pauses with `PAUSE` and resumes
//! with `RESUME`.
//!
//! Nothing the engine sends is trusted: a coordinate message is allocated only after its atom
//! count was checked against the topology's, unknown message types end the connection with a
//! one-line error, and every read has a time limit.

use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use glam::Vec3;

/// The IMD protocol versions this client speaks, oldest first.
pub(crate) const IMD_VERSIONS: [i32; 2] = [2, 3];

/// Message types of IMD versions 2 and 3 (the last six are version 3's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub(crate) enum MessageType {
    /// Either side closes the connection; the simulation goes on.
    Disconnect = 0,
    /// Energy record of a step.
    Energies = 1,
    /// Coordinates of the IMD group (Å).
    Coordinates = 2,
    /// The client asks the engine to start sending.
    Go = 3,
    /// The engine's greeting, carrying the protocol version.
    Handshake = 4,
    /// The client asks the engine to stop the simulation.
    Kill = 5,
    /// The client applies forces (not used by this client).
    MdComm = 6,
    /// The client toggles a pause of the simulation (version 2), or pauses it (version 3).
    Pause = 7,
    /// The client sets the transmission rate: one frame every `length` steps.
    Rate = 8,
    /// Either side reports an I/O error.
    IoError = 9,
    /// The engine says what each frame carries (version 3).
    SessionInfo = 10,
    /// The client resumes a paused simulation (version 3).
    Resume = 11,
    /// A frame's time step, time and step (version 3).
    Time = 12,
    /// A frame's box vectors (version 3).
    Box = 13,
    /// A frame's velocities (version 3).
    Velocities = 14,
    /// A frame's forces (version 3).
    Forces = 15,
}

impl MessageType {
    /// The type with number `value`, if IMD version 2 or 3 has one.
    fn from_i32(value: i32) -> Option<MessageType> {
        use MessageType::*;
        [
            Disconnect,
            Energies,
            Coordinates,
            Go,
            Handshake,
            Kill,
            MdComm,
            Pause,
            Rate,
            IoError,
            SessionInfo,
            Resume,
            Time,
            Box,
            Velocities,
            Forces,
        ]
        .into_iter()
        .find(|t| *t as i32 == value)
    }
}

/// Why talking to the engine failed; each prints as one line (the caller adds the address).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImdError {
    /// No engine accepted the connection in time.
    #[error("cannot connect: {0}")]
    Connect(String),
    /// The engine is not an IMD engine, or speaks another version.
    #[error("not an IMD engine of version 2 or 3: {0}")]
    Handshake(String),
    /// The connection closed (the simulation ended, was killed, or detached us).
    #[error("the simulation closed the connection")]
    Closed,
    /// Nothing arrived within the time limit.
    #[error("no message from the simulation for {0} s")]
    Timeout(u64),
    /// The engine sent something this protocol does not allow.
    #[error("bad message from the simulation: {0}")]
    Protocol(String),
    /// The socket failed.
    #[error("network error: {0}")]
    Network(String),
    /// We left the simulation running and stopped receiving it.
    #[error("detached from the simulation (it goes on)")]
    Detached,
}

/// One step's energy record, as the engine sends it (GROMACS: kJ/mol and K).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImdEnergies {
    /// The simulation step.
    pub step: i32,
    /// Temperature (K).
    pub temperature: f32,
    /// Total energy.
    pub total: f32,
    /// Potential energy.
    pub potential: f32,
}

/// A frame's time record (IMD version 3).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImdTime {
    /// The simulation's time step, in the engine's time unit (GROMACS: ps; LAMMPS: its own
    /// units, fs with `units real`).
    pub dt: f64,
    /// The frame's time, in that unit.
    pub time: f64,
    /// The frame's step.
    pub step: i64,
}

/// What each frame of a session carries (IMD version 3 says so in its session record; a
/// version 2 engine sends energies and coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImdSession {
    /// A time record.
    pub time: bool,
    /// An energy record.
    pub energies: bool,
    /// The box.
    pub cell: bool,
    /// The coordinates.
    pub positions: bool,
    /// The coordinates are wrapped into the box.
    pub wrapped: bool,
    /// Velocities.
    pub velocities: bool,
    /// Forces.
    pub forces: bool,
}

impl ImdSession {
    /// What a version 2 engine sends.
    const VERSION_2: ImdSession = ImdSession {
        time: false,
        energies: true,
        cell: false,
        positions: true,
        wrapped: false,
        velocities: false,
        forces: false,
    };
}

/// What one frame brings: the records the engine sent before its coordinates (when it sent
/// them), and the coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct ImdStep {
    /// The time record (version 3), if any.
    pub time: Option<ImdTime>,
    /// The energy record, if any.
    pub energies: Option<ImdEnergies>,
    /// The box vectors a, b, c in Å (version 3), if any.
    pub cell: Option<[Vec3; 3]>,
    /// Positions of the IMD group's atoms, in Å.
    pub positions: Vec<Vec3>,
}

/// A connection to a running simulation, after the handshake.
#[derive(Debug)]
pub struct ImdClient {
    stream: TcpStream,
    /// True when the engine writes its bodies little-endian.
    little_endian: bool,
    /// The protocol version of the session (2 or 3).
    version: i32,
    /// What each frame carries.
    session: ImdSession,
    /// Longest wait for the next message.
    read_timeout: Duration,
}

impl ImdClient {
    /// Connects to the engine at `address` (`host:port`), retrying until `connect_timeout`
    /// passes (an engine started a moment ago may not listen yet), reads the handshake and
    /// answers `GO`. `read_timeout` bounds the wait for each later message.
    pub fn connect(
        address: &str,
        connect_timeout: Duration,
        read_timeout: Duration,
    ) -> Result<ImdClient, ImdError> {
        let deadline = Instant::now() + connect_timeout;
        let stream = loop {
            let tried = address
                .to_socket_addrs()
                .map_err(|e| ImdError::Connect(format!("'{address}' is not HOST:PORT ({e})")))?
                .find_map(|a| TcpStream::connect_timeout(&a, Duration::from_secs(2)).ok());
            match tried {
                Some(stream) => break stream,
                None if Instant::now() >= deadline => {
                    return Err(ImdError::Connect(format!(
                        "nothing listens at {address} (waited {} s)",
                        connect_timeout.as_secs()
                    )));
                }
                None => std::thread::sleep(Duration::from_millis(200)),
            }
        };
        stream.set_nodelay(true).map_err(network)?;
        let mut client = ImdClient {
            stream,
            little_endian: false,
            version: IMD_VERSIONS[0],
            session: ImdSession::VERSION_2,
            read_timeout: connect_timeout.max(read_timeout),
        };
        let (kind, version) = client.read_header().map_err(|e| match e {
            ImdError::Closed | ImdError::Timeout(_) => {
                ImdError::Handshake(format!("no handshake ({e})"))
            }
            e => e,
        })?;
        if kind != MessageType::Handshake as i32 {
            return Err(ImdError::Handshake(format!(
                "the first message has type {kind}, not the handshake"
            )));
        }
        (client.version, client.little_endian) = match version {
            v if IMD_VERSIONS.contains(&v) => (v, false),
            v if IMD_VERSIONS.contains(&v.swap_bytes()) => (v.swap_bytes(), true),
            v => {
                let v = if v.swap_bytes().unsigned_abs() < v.unsigned_abs() {
                    v.swap_bytes()
                } else {
                    v
                };
                return Err(ImdError::Handshake(format!(
                    "the engine speaks IMD version {v}"
                )));
            }
        };
        if client.version >= 3 {
            client.session = client.read_session()?;
        }
        client.read_timeout = read_timeout;
        client.send(MessageType::Go, 0)?;
        Ok(client)
    }

    /// The protocol version of the session (2 or 3).
    pub fn version(&self) -> i32 {
        self.version
    }

    /// What each frame of the session carries (the reader needs only [`ImdStep`]'s options).
    #[cfg(test)]
    pub fn session(&self) -> ImdSession {
        self.session
    }

    /// Reads version 3's session record; refuses a session without coordinates.
    fn read_session(&mut self) -> Result<ImdSession, ImdError> {
        let (kind, length) = self.read_header()?;
        if kind != MessageType::SessionInfo as i32 || length != 7 {
            return Err(ImdError::Handshake(format!(
                "after a version 3 handshake came message type {kind} of length {length}, not \
                 the session record"
            )));
        }
        let mut flags = [0u8; 7];
        self.read_exact(&mut flags)?;
        let [time, energies, cell, positions, wrapped, velocities, forces] = flags.map(|f| f != 0);
        if !positions {
            return Err(ImdError::Handshake(
                "the engine sends no coordinates in this session (LAMMPS: `fix imd ... \
                 coordinates on`)"
                    .into(),
            ));
        }
        Ok(ImdSession {
            time,
            energies,
            cell,
            positions,
            wrapped,
            velocities,
            forces,
        })
    }

    /// Waits for the next coordinates and returns them with the energy record sent before them.
    /// `atoms` is the number the topology expects: another count is refused before anything is
    /// allocated.
    pub fn next_step(&mut self, atoms: usize) -> Result<ImdStep, ImdError> {
        let (mut time, mut energies, mut cell) = (None, None, None);
        loop {
            let (kind, length) = self.read_header()?;
            match MessageType::from_i32(kind) {
                Some(MessageType::Time) if length == 1 => time = Some(self.read_time()?),
                Some(MessageType::Energies) => energies = Some(self.read_energies()?),
                Some(MessageType::Box) if length == 1 => cell = Some(self.read_cell()?),
                Some(MessageType::Velocities | MessageType::Forces)
                    if usize::try_from(length).ok() == Some(atoms) =>
                {
                    self.skip(atoms * 12)?;
                }
                Some(MessageType::Coordinates) => {
                    if usize::try_from(length).ok() != Some(atoms) {
                        return Err(ImdError::Protocol(format!(
                            "coordinates of {length} atoms, the topology has {atoms}"
                        )));
                    }
                    let positions = self.read_positions(atoms)?;
                    return Ok(ImdStep {
                        time,
                        energies,
                        cell,
                        positions,
                    });
                }
                Some(MessageType::Disconnect | MessageType::Kill) => return Err(ImdError::Closed),
                Some(MessageType::IoError) => {
                    return Err(ImdError::Protocol(
                        "the engine reported an I/O error".into(),
                    ));
                }
                _ => {
                    return Err(ImdError::Protocol(format!(
                        "unexpected message type {kind} (length {length})"
                    )));
                }
            }
        }
    }

    /// Asks the engine to send one frame every `steps` steps (at least 1).
    pub fn set_rate(&mut self, steps: u32) -> Result<(), ImdError> {
        let steps = i32::try_from(steps.max(1)).unwrap_or(i32::MAX);
        self.send(MessageType::Rate, steps)
    }

    /// A second handle on the socket, for [`leave`] from another thread while this client
    /// waits for a message.
    pub(crate) fn socket(&self) -> std::io::Result<TcpStream> {
        self.stream.try_clone()
    }

    /// Sends a header-only message.
    fn send(&mut self, kind: MessageType, length: i32) -> Result<(), ImdError> {
        send_header(&self.stream, kind, length)
    }

    /// Reads a header: (type, length), both big-endian.
    fn read_header(&mut self) -> Result<(i32, i32), ImdError> {
        let mut header = [0u8; 8];
        self.read_exact(&mut header)?;
        let word =
            |i: usize| i32::from_be_bytes([header[i], header[i + 1], header[i + 2], header[i + 3]]);
        Ok((word(0), word(4)))
    }

    /// A 32-bit word of a body, in the engine's byte order.
    fn word(&self, b: &[u8]) -> u32 {
        let b = [b[0], b[1], b[2], b[3]];
        if self.little_endian {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    }

    /// A 64-bit word of a body, in the engine's byte order.
    fn dword(&self, b: &[u8]) -> u64 {
        let b = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
        if self.little_endian {
            u64::from_le_bytes(b)
        } else {
            u64::from_be_bytes(b)
        }
    }

    /// Reads an energy record body: the step, then nine floats (T, Etot, Epot, ...).
    fn read_energies(&mut self) -> Result<ImdEnergies, ImdError> {
        let mut body = [0u8; 40];
        self.read_exact(&mut body)?;
        let word = |i: usize| self.word(&body[4 * i..]);
        Ok(ImdEnergies {
            step: word(0) as i32,
            temperature: f32::from_bits(word(1)),
            total: f32::from_bits(word(2)),
            potential: f32::from_bits(word(3)),
        })
    }

    /// Reads a time record body: time step and time (f64, the engine's unit), then the step
    /// (i64).
    fn read_time(&mut self) -> Result<ImdTime, ImdError> {
        let mut body = [0u8; 24];
        self.read_exact(&mut body)?;
        Ok(ImdTime {
            dt: f64::from_bits(self.dword(&body[0..])),
            time: f64::from_bits(self.dword(&body[8..])),
            step: self.dword(&body[16..]) as i64,
        })
    }

    /// Reads a box body: vectors a, b, c (Å), three floats each.
    fn read_cell(&mut self) -> Result<[Vec3; 3], ImdError> {
        let mut body = [0u8; 36];
        self.read_exact(&mut body)?;
        let value = |i: usize| f32::from_bits(self.word(&body[4 * i..]));
        Ok([0, 3, 6].map(|k| Vec3::new(value(k), value(k + 1), value(k + 2))))
    }

    /// Reads `atoms` positions (x, y, z as floats in Å).
    fn read_positions(&mut self, atoms: usize) -> Result<Vec<Vec3>, ImdError> {
        let mut body = vec![0u8; atoms * 12];
        self.read_exact(&mut body)?;
        let value = |c: &[u8]| f32::from_bits(self.word(c));
        Ok(body
            .chunks_exact(12)
            .map(|p| Vec3::new(value(&p[0..4]), value(&p[4..8]), value(&p[8..12])))
            .collect())
    }

    /// Reads past `bytes` bytes of a body this client does not keep, 64 KiB at a time.
    fn skip(&mut self, mut bytes: usize) -> Result<(), ImdError> {
        let mut chunk = vec![0u8; bytes.min(1 << 16)];
        while bytes > 0 {
            let n = bytes.min(chunk.len());
            self.read_exact(&mut chunk[..n])?;
            bytes -= n;
        }
        Ok(())
    }

    /// Fills `buf`, waiting at most the read timeout for each piece.
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ImdError> {
        self.stream
            .set_read_timeout(Some(self.read_timeout))
            .map_err(network)?;
        self.stream.read_exact(buf).map_err(|e| match e.kind() {
            std::io::ErrorKind::UnexpectedEof
            | std::io::ErrorKind::ConnectionReset
            | std::io::ErrorKind::ConnectionAborted
            | std::io::ErrorKind::BrokenPipe => ImdError::Closed,
            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => {
                ImdError::Timeout(self.read_timeout.as_secs())
            }
            _ => network(e),
        })
    }
}

/// Writes a header-only message to `stream`.
fn send_header(mut stream: &TcpStream, kind: MessageType, length: i32) -> Result<(), ImdError> {
    let mut header = [0u8; 8];
    header[..4].copy_from_slice(&(kind as i32).to_be_bytes());
    header[4..].copy_from_slice(&length.to_be_bytes());
    stream.write_all(&header).map_err(network)
}

/// Pauses a running simulation (`pause`), or resumes a paused one, through `socket` (a handle
/// from [`ImdClient::socket`]) while the client receives on another thread; `version` is the
/// session's ([`ImdClient::version`]): version 2's one message toggles, so the caller keeps
/// track of which it is.
pub(crate) fn pause_on(socket: &TcpStream, version: i32, pause: bool) -> Result<(), ImdError> {
    let kind = if version >= 3 && !pause {
        MessageType::Resume
    } else {
        MessageType::Pause
    };
    send_header(socket, kind, 0)
}

/// Detaches from the engine through `socket` (a handle from [`ImdClient::socket`]; the
/// simulation goes on): sends the disconnect message and closes our sending half only. The
/// engine closes the connection when it reads the message, at its next step; a frame it was
/// already sending still arrives, and the receiver must read it (and drop it) until the engine
/// closes. Closing our receiving half as well would make the kernel answer that frame with a
/// reset, and an engine that writes again to a reset connection may die of it: GROMACS 2022
/// writes with `write()` and keeps the default SIGPIPE, so a detach that raced a frame killed
/// the simulation.
pub(crate) fn leave(socket: &TcpStream) {
    let _ = send_header(socket, MessageType::Disconnect, 0);
    let _ = socket.shutdown(std::net::Shutdown::Write);
}

/// Closes both halves of `socket`, which ends any wait of the client for a message at once:
/// only for an engine that did not close the connection after [`leave`] (see there why).
pub(crate) fn cut(socket: &TcpStream) {
    let _ = socket.shutdown(std::net::Shutdown::Both);
}

/// A socket error as one line.
fn network(e: std::io::Error) -> ImdError {
    ImdError::Network(e.to_string())
}

#[cfg(test)]
pub(crate) mod tests;
