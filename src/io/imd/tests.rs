//! The IMD client against fake engines on local ports (bytes as engines write them).

use super::*;
use std::net::TcpListener;

/// A fake engine on a local port that sends `messages` after the handshake (written
/// little-endian, as x86 engines do) and records what the client sent.
fn fake_engine(messages: Vec<u8>) -> (String, std::thread::JoinHandle<Vec<u8>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let handle = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let go = greet(&mut socket);
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

/// Sends a version 2 handshake as a little-endian engine does, and returns the client's answer
/// (8 bytes: `GO`).
pub(crate) fn greet(socket: &mut TcpStream) -> [u8; 8] {
    let mut hello = header(MessageType::Handshake as i32, 0);
    hello[4..].copy_from_slice(&IMD_VERSIONS[0].to_le_bytes());
    socket.write_all(&hello).unwrap();
    let mut go = [0u8; 8];
    socket.read_exact(&mut go).unwrap();
    go
}

/// A message header: type and length, big-endian.
pub(crate) fn header(kind: i32, length: i32) -> Vec<u8> {
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

/// A fake engine that sends `bytes` as they are (handshake included) and returns what the
/// client sent until it closed the connection.
pub(crate) fn replaying_engine(bytes: Vec<u8>) -> (String, std::thread::JoinHandle<Vec<u8>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let handle = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        socket.write_all(&bytes).unwrap();
        let mut sent = Vec::new();
        let _ = socket.set_read_timeout(Some(Duration::from_secs(5)));
        let _ = socket.read_to_end(&mut sent);
        sent
    });
    (address, handle)
}

/// The bytes LAMMPS 2025 sent in an IMD version 3 session (tests/data/README.md).
pub(crate) fn lammps_v3_session() -> Vec<u8> {
    std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/imd/lammps_argon_v3.bin"
    ))
    .unwrap()
}

/// The positions of `argon.xyz`, the structure LAMMPS wrote before the run (Å).
pub(crate) fn argon_start() -> Vec<Vec3> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/imd/argon.xyz"
    ))
    .unwrap();
    text.lines()
        .skip(2)
        .map(|l| {
            let v: Vec<f32> = l
                .split_whitespace()
                .skip(1)
                .map(|w| w.parse().unwrap())
                .collect();
            Vec3::new(v[0], v[1], v[2])
        })
        .collect()
}

#[test]
fn reads_a_version_3_session_as_lammps_sends_it() {
    let (address, engine) = replaying_engine(lammps_v3_session());
    let wait = Duration::from_secs(5);
    let mut client = ImdClient::connect(&address, wait, wait).unwrap();
    assert_eq!(client.version(), 3);
    // in.argon: time, box, coordinates (wrapped: `unwrap off`), velocities and forces.
    assert_eq!(
        client.session(),
        ImdSession {
            time: true,
            energies: false,
            cell: true,
            positions: true,
            wrapped: true,
            velocities: true,
            forces: true,
        }
    );
    let start = argon_start();
    // 4 x 4 x 4 fcc cells of 5.26 Å.
    let edge = 4.0 * 5.26f32;
    for step in 1..=3 {
        let frame = client.next_step(start.len()).unwrap();
        // LAMMPS sends its own units: real units have 2 fs steps, times in fs.
        let time = frame.time.unwrap();
        assert_eq!(
            (time.step, time.dt, time.time),
            (step, 2.0, 2.0 * step as f64)
        );
        assert_eq!(frame.energies, None);
        let cell = frame.cell.unwrap();
        for (k, v) in cell.iter().enumerate() {
            assert!((*v - Vec3::AXES[k] * edge).length() < 1e-4, "{cell:?}");
        }
        // At 90 K an argon atom moves about 0.004 Å per step; wrapped into the box.
        let worst = start
            .iter()
            .zip(&frame.positions)
            .map(|(a, b)| {
                let d = *b - *a;
                (d - (d / edge).round() * edge).length()
            })
            .fold(0.0f32, f32::max);
        assert!(worst < 0.05 * step as f32, "step {step}: moved {worst} Å");
        // Wrapped (LAMMPS wraps at each neighbour-list rebuild: at most the 2 Å skin out).
        let (lo, hi) = (Vec3::splat(-2.0), Vec3::splat(edge + 2.0));
        assert!(
            frame
                .positions
                .iter()
                .all(|p| p.cmpge(lo).all() && p.cmple(hi).all())
        );
    }
    drop(client);
    assert_eq!(
        engine.join().unwrap(),
        header(3, 0),
        "the client sent GO only"
    );
}

#[test]
fn a_version_3_session_without_coordinates_or_record_is_refused_in_one_line() {
    let mut bytes = lammps_v3_session();
    // The session record's coordinates flag (after 8 + 8 bytes of headers and 3 flags).
    bytes[19] = 0;
    let (address, engine) = replaying_engine(bytes);
    let wait = Duration::from_secs(5);
    let error = ImdClient::connect(&address, wait, wait).unwrap_err();
    assert!(
        error.to_string().contains("sends no coordinates"),
        "{error}"
    );
    engine.join().unwrap();

    let mut bytes = lammps_v3_session();
    bytes[11] = 9; // message type 9 where the session record belongs
    let (address, engine) = replaying_engine(bytes);
    let error = ImdClient::connect(&address, wait, wait).unwrap_err();
    assert!(
        error
            .to_string()
            .contains("message type 9 of length 7, not the session record"),
        "{error}"
    );
    engine.join().unwrap();
}

#[test]
fn pause_and_resume_are_one_toggle_in_version_2_and_two_messages_in_version_3() {
    let (address, engine) = fake_engine(Vec::new());
    let wait = Duration::from_secs(5);
    let client = ImdClient::connect(&address, wait, wait).unwrap();
    let socket = client.socket().unwrap();
    for (version, pause) in [(2, true), (2, false), (3, true), (3, false)] {
        pause_on(&socket, version, pause).unwrap();
    }
    leave(&socket);
    let sent = engine.join().unwrap();
    let expected: Vec<u8> = [(3, 0), (7, 0), (7, 0), (7, 0), (11, 0), (0, 0)]
        .iter()
        .flat_map(|&(k, l)| header(k, l))
        .collect();
    assert_eq!(sent, expected);
}

#[test]
fn a_velocity_record_of_another_atom_count_is_one_line() {
    let mut bytes = lammps_v3_session();
    // The first frame's velocity header: after the preamble (23), time (32), box (44) and
    // coordinates (8 + 256 * 12); its length field is 4 bytes in.
    let at = 23 + 32 + 44 + 8 + 256 * 12 + 4;
    assert_eq!(bytes[at - 4..at], 14i32.to_be_bytes(), "a velocity record");
    bytes[at..at + 4].copy_from_slice(&255i32.to_be_bytes());
    let (address, _engine) = replaying_engine(bytes);
    let wait = Duration::from_secs(5);
    let mut client = ImdClient::connect(&address, wait, wait).unwrap();
    client.next_step(256).unwrap();
    let error = client.next_step(256).unwrap_err();
    assert_eq!(
        error.to_string(),
        "bad message from the simulation: unexpected message type 14 (length 255)"
    );
}
