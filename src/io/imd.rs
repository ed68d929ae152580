//! The Interactive Molecular Dynamics (IMD) protocol, version 2, as GROMACS, NAMD and LAMMPS
//! speak it: a client that connects to a running simulation, receives its coordinates (Å) and
//! energy records frame by frame, and can pause it, change how often it sends, detach or stop it.
//!
//! Every message is an 8-byte header (type and length, 32-bit big-endian integers) and a body.
//! The engine opens with a handshake whose length field is the protocol version written in the
//! engine's own byte order: read big-endian it is 2 on a big-endian engine, and 2 << 24 on a
//! little-endian one. The bodies (energy records, coordinates) come in that same engine order.
//! The client answers `GO`; from then on the engine sends an `ENERGIES` message (length 1, a step
//! number and nine 32-bit floats) and an `FCOORDS` message (length = atoms, then x, y, z per atom
//! as 32-bit floats in Å) every time it reports a step.
//!
//! Nothing the engine sends is trusted: a coordinate message is allocated only after its atom
//! count was checked against the topology's, unknown message types end the connection with a
//! one-line error, and every read has a time limit.

use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use glam::Vec3;

/// The IMD protocol version this client speaks.
pub(crate) const IMD_VERSION: i32 = 2;

/// Message types of IMD version 2.
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
    Forces = 6,
    /// The client toggles a pause of the simulation.
    Pause = 7,
    /// The client sets the transmission rate: one frame every `length` steps.
    Rate = 8,
    /// Either side reports an I/O error.
    IoError = 9,
}

impl MessageType {
    /// The type with number `value`, if IMD version 2 has one.
    fn from_i32(value: i32) -> Option<MessageType> {
        use MessageType::*;
        [
            Disconnect,
            Energies,
            Coordinates,
            Go,
            Handshake,
            Kill,
            Forces,
            Pause,
            Rate,
            IoError,
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
    #[error("not an IMD version 2 engine: {0}")]
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

/// What one step brings: its energies (when the engine sent them first) and the coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct ImdStep {
    /// The energy record sent before these coordinates, if any.
    pub energies: Option<ImdEnergies>,
    /// Positions of the IMD group's atoms, in Å.
    pub positions: Vec<Vec3>,
}

/// A connection to a running simulation, after the handshake.
#[derive(Debug)]
pub struct ImdClient {
    stream: TcpStream,
    /// True when the engine writes its bodies little-endian.
    little_endian: bool,
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
        client.little_endian = match version {
            IMD_VERSION => false,
            v if v.swap_bytes() == IMD_VERSION => true,
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
        client.read_timeout = read_timeout;
        client.send(MessageType::Go, 0)?;
        Ok(client)
    }

    /// Waits for the next coordinates and returns them with the energy record sent before them.
    /// `atoms` is the number the topology expects: another count is refused before anything is
    /// allocated.
    pub fn next_step(&mut self, atoms: usize) -> Result<ImdStep, ImdError> {
        let mut energies = None;
        loop {
            let (kind, length) = self.read_header()?;
            match MessageType::from_i32(kind) {
                Some(MessageType::Energies) => energies = Some(self.read_energies()?),
                Some(MessageType::Coordinates) => {
                    if usize::try_from(length).ok() != Some(atoms) {
                        return Err(ImdError::Protocol(format!(
                            "coordinates of {length} atoms, the topology has {atoms}"
                        )));
                    }
                    let positions = self.read_positions(atoms)?;
                    return Ok(ImdStep {
                        energies,
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

    /// Reads an energy record body: the step, then nine floats (T, Etot, Epot, ...).
    fn read_energies(&mut self) -> Result<ImdEnergies, ImdError> {
        let mut body = [0u8; 40];
        self.read_exact(&mut body)?;
        let word = |i: usize| {
            let b = [
                body[4 * i],
                body[4 * i + 1],
                body[4 * i + 2],
                body[4 * i + 3],
            ];
            if self.little_endian {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            }
        };
        Ok(ImdEnergies {
            step: word(0) as i32,
            temperature: f32::from_bits(word(1)),
            total: f32::from_bits(word(2)),
            potential: f32::from_bits(word(3)),
        })
    }

    /// Reads `atoms` positions (x, y, z as floats in Å).
    fn read_positions(&mut self, atoms: usize) -> Result<Vec<Vec3>, ImdError> {
        let mut body = vec![0u8; atoms * 12];
        self.read_exact(&mut body)?;
        let value = |c: &[u8]| {
            let b = [c[0], c[1], c[2], c[3]];
            f32::from_bits(if self.little_endian {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            })
        };
        Ok(body
            .chunks_exact(12)
            .map(|p| Vec3::new(value(&p[0..4]), value(&p[4..8]), value(&p[8..12])))
            .collect())
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

/// Pauses a running simulation, or resumes a paused one, through `socket` (a handle from
/// [`ImdClient::socket`]), while the client receives on another thread.
pub(crate) fn toggle_pause_on(socket: &TcpStream) -> Result<(), ImdError> {
    send_header(socket, MessageType::Pause, 0)
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
mod tests {
    use super::*;
    use std::net::TcpListener;

    /// A fake engine on a local port that sends `messages` after the handshake (written
    /// little-endian, as x86 engines do) and records what the client sent.
    fn fake_engine(messages: Vec<u8>) -> (String, std::thread::JoinHandle<Vec<u8>>) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let address = listener.local_addr().unwrap().to_string();
        let handle = std::thread::spawn(move || {
            let (mut socket, _) = listener.accept().unwrap();
            let mut hello = (MessageType::Handshake as i32).to_be_bytes().to_vec();
            hello.extend(IMD_VERSION.to_le_bytes());
            socket.write_all(&hello).unwrap();
            let mut go = [0u8; 8];
            socket.read_exact(&mut go).unwrap();
            socket.write_all(&messages).unwrap();
            let mut rest = go.to_vec();
            let _ = socket.set_read_timeout(Some(Duration::from_millis(300)));
            let mut buf = [0u8; 64];
            while let Ok(n) = socket.read(&mut buf) {
                if n == 0 {
                    break;
                }
                rest.extend(&buf[..n]);
            }
            rest
        });
        (address, handle)
    }

    fn header(kind: i32, length: i32) -> Vec<u8> {
        let mut h = kind.to_be_bytes().to_vec();
        h.extend(length.to_be_bytes());
        h
    }

    #[test]
    fn reads_energies_and_little_endian_coordinates() {
        let mut msg = header(1, 1);
        msg.extend(7i32.to_le_bytes());
        for v in [300.0f32, -10.0, -20.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0] {
            msg.extend(v.to_le_bytes());
        }
        msg.extend(header(2, 2));
        for v in [1.0f32, 2.0, 3.0, -4.5, 5.25, 6.0] {
            msg.extend(v.to_le_bytes());
        }
        let (address, engine) = fake_engine(msg);
        let wait = Duration::from_secs(5);
        let mut client = ImdClient::connect(&address, wait, wait).unwrap();
        let step = client.next_step(2).unwrap();
        assert_eq!(step.energies.unwrap().step, 7);
        assert_eq!(step.energies.unwrap().temperature, 300.0);
        assert_eq!(
            step.positions,
            vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.5, 5.25, 6.0)]
        );
        client.set_rate(10).unwrap();
        leave(&client.socket().unwrap());
        let sent = engine.join().unwrap();
        let mut expected = header(3, 0);
        expected.extend(header(8, 10));
        expected.extend(header(0, 0));
        assert_eq!(sent, expected);
    }

    #[test]
    fn refuses_a_wrong_atom_count_and_a_closed_stream() {
        let (address, engine) = fake_engine(header(2, 1_000_000_000));
        let wait = Duration::from_secs(5);
        let mut client = ImdClient::connect(&address, wait, wait).unwrap();
        let error = client.next_step(3).unwrap_err();
        assert!(error.to_string().contains("1000000000 atoms"), "{error}");
        drop(client);
        engine.join().unwrap();

        let (address, engine) = fake_engine(Vec::new());
        let mut client = ImdClient::connect(&address, wait, wait).unwrap();
        engine.join().unwrap();
        assert_eq!(client.next_step(3).unwrap_err(), ImdError::Closed);
    }

    #[test]
    fn nothing_listening_is_one_line() {
        let port = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let error = ImdClient::connect(
            &format!("127.0.0.1:{port}"),
            Duration::from_millis(300),
            Duration::from_secs(1),
        )
        .unwrap_err();
        assert!(
            error
                .to_string()
                .starts_with("cannot connect: nothing listens"),
            "{error}"
        );
        let error = ImdClient::connect("no-port", Duration::ZERO, Duration::ZERO).unwrap_err();
        assert!(error.to_string().contains("not HOST:PORT"), "{error}");
    }
}
