//! The two TCP connections to the UR controller, each with a reader thread.
//!
//! The controller pushes state continuously (125 Hz on the real-time port
//! for CB3, 500 Hz on e-series; 10 Hz on the secondary port). A client that
//! stops reading lets stale packets pile up in the socket, so both
//! connections get a background thread that keeps reading: the state thread
//! keeps only the newest parsed packet, the command thread discards what the
//! secondary interface sends (UR recommend always reading that socket).
//! The threads check a stop flag every read timeout and end on drop.
//!
//! Every state is checked ([`ArmState::check`]) as it is read: a state no
//! UR arm can be in fails the stream, with the reason, for every waiter.
//! What the reader keeps is bounded: the newest state, and at most one
//! packet's bytes (a declared length is checked before more is read).
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::realtime::{declared_length, parse_packet, RobotState};
use super::rtde::{start_state_stream, state_from_values, RtdeClient};
use super::state::ArmState;
use crate::HwError;

/// How often the reader threads look at their stop flag.
const READ_POLL: Duration = Duration::from_millis(50);

/// Opens a TCP connection with a connect timeout.
pub fn connect(host: &str, port: u16, timeout: Duration) -> Result<TcpStream, HwError> {
    let addr_text = format!("{host}:{port}");
    let io_err = |source| HwError::Connect {
        addr: addr_text.clone(),
        source,
    };
    let addrs = (host, port).to_socket_addrs().map_err(io_err)?;
    let mut last = std::io::Error::new(ErrorKind::NotFound, "no address resolved");
    for addr in addrs {
        match TcpStream::connect_timeout(&addr, timeout) {
            Ok(stream) => {
                stream.set_nodelay(true).map_err(io_err)?;
                return Ok(stream);
            }
            Err(e) => last = e,
        }
    }
    Err(io_err(last))
}

#[derive(Default)]
struct Latest {
    state: Option<ArmState>,
    seq: u64,
    failure: Option<HwError>,
}

type Shared = Arc<(Mutex<Latest>, Condvar)>;

fn lock(shared: &Shared) -> MutexGuard<'_, Latest> {
    // A poisoned lock only means a reader thread panicked mid-update; the
    // data is plain values, so keep using it.
    shared.0.lock().unwrap_or_else(|p| p.into_inner())
}

/// The real-time state connection and its reader thread.
pub struct StateStream {
    shared: Shared,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl StateStream {
    /// Starts reading real-time packets (port 30003) from `stream` in a
    /// background thread.
    pub fn start(stream: TcpStream) -> Result<Self, HwError> {
        stream
            .set_read_timeout(Some(READ_POLL))
            .map_err(|source| HwError::Io {
                what: "state socket".into(),
                source,
            })?;
        let mut reader = RealtimeReader {
            stream,
            buffer: Vec::with_capacity(8192),
        };
        Ok(Self::spawn(move || match reader.next_state()? {
            Some(raw) => ArmState::check(raw).map(Some),
            None => Ok(None),
        }))
    }

    /// Negotiates RTDE on `stream` (port 30004), sets up the state recipe,
    /// starts it and reads data packages in a background thread. Blocks
    /// up to `timeout` for each handshake reply.
    pub fn start_rtde(stream: TcpStream, timeout: Duration) -> Result<Self, HwError> {
        let mut client = RtdeClient::handshake(stream, timeout)?;
        start_state_stream(&mut client)?;
        Ok(Self::spawn(move || match client.poll_data()? {
            Some(values) => state_from_values(&values)
                .and_then(ArmState::check)
                .map(Some),
            None => Ok(None),
        }))
    }

    /// Runs `next` (one read, at most [`READ_POLL`]) in a thread until it
    /// fails or the stream is dropped, publishing every state.
    fn spawn<F>(mut next: F) -> Self
    where
        F: FnMut() -> Result<Option<ArmState>, HwError> + Send + 'static,
    {
        let shared: Shared = Arc::default();
        let stop = Arc::new(AtomicBool::new(false));
        let (s, f) = (shared.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            let failure = loop {
                if f.load(Ordering::Relaxed) {
                    return;
                }
                match next() {
                    Ok(Some(state)) => publish(&s, state),
                    Ok(None) => {}
                    Err(e) => break e,
                }
            };
            lock(&s).failure = Some(failure);
            s.1.notify_all();
        });
        Self {
            shared,
            stop,
            thread: Some(thread),
        }
    }

    /// The newest state and its sequence number; blocks until one arrives
    /// with a sequence number above `after`, or fails after `timeout`.
    pub fn wait_newer(&self, after: u64, timeout: Duration) -> Result<(u64, ArmState), HwError> {
        let deadline = Instant::now() + timeout;
        let mut latest = lock(&self.shared);
        loop {
            if let Some(failure) = &latest.failure {
                return Err(failure_again(failure));
            }
            if let (Some(state), true) = (latest.state, latest.seq > after) {
                return Ok((latest.seq, state));
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(HwError::NoState {
                    seconds: timeout.as_secs_f64(),
                });
            }
            let (guard, _) = self
                .shared
                .1
                .wait_timeout(latest, deadline - now)
                .unwrap_or_else(|p| p.into_inner());
            latest = guard;
        }
    }

    /// Sequence number of the newest state (0 before the first).
    pub fn seq(&self) -> u64 {
        lock(&self.shared).seq
    }
}

impl Drop for StateStream {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The real-time interface's byte stream and its unparsed rest.
struct RealtimeReader {
    stream: TcpStream,
    buffer: Vec<u8>,
}

impl RealtimeReader {
    /// One read; the newest complete packet's state, if any.
    fn next_state(&mut self) -> Result<Option<RobotState>, HwError> {
        let mut chunk = [0u8; 4096];
        match self.stream.read(&mut chunk) {
            Ok(0) => Err(stream_failed("connection closed by the controller")),
            Ok(n) => {
                self.buffer.extend_from_slice(&chunk[..n]);
                take_packets(&mut self.buffer)
            }
            Err(e) if is_poll_timeout(&e) => Ok(None),
            Err(e) => Err(stream_failed(&format!("read failed: {e}"))),
        }
    }
}

fn stream_failed(reason: &str) -> HwError {
    HwError::StateStream {
        reason: reason.to_string(),
    }
}

/// Removes every complete packet from the front of `buffer`; returns the
/// newest parsed state.
fn take_packets(buffer: &mut Vec<u8>) -> Result<Option<RobotState>, HwError> {
    let mut newest = None;
    while buffer.len() >= 4 {
        let len = declared_length([buffer[0], buffer[1], buffer[2], buffer[3]])?;
        if buffer.len() < len {
            break;
        }
        newest = Some(parse_packet(&buffer[..len])?);
        buffer.drain(..len);
    }
    Ok(newest)
}

/// The reader's failure, for one more waiter: typed for an impossible
/// state, else as the stream's failure with the reason.
fn failure_again(failure: &HwError) -> HwError {
    match failure {
        HwError::ImplausibleState { field, reason } => HwError::ImplausibleState {
            field,
            reason: reason.clone(),
        },
        HwError::StateStream { reason } => HwError::StateStream {
            reason: reason.clone(),
        },
        other => HwError::StateStream {
            reason: other.to_string(),
        },
    }
}

fn publish(shared: &Shared, state: ArmState) {
    let mut latest = lock(shared);
    latest.state = Some(state);
    latest.seq += 1;
    drop(latest);
    shared.1.notify_all();
}

fn is_poll_timeout(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
    )
}

/// The secondary-interface connection: URScript goes out, replies are read
/// and dropped by a background thread.
pub struct CommandChannel {
    stream: TcpStream,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl CommandChannel {
    /// Starts draining `stream` in a background thread.
    pub fn start(stream: TcpStream) -> Result<Self, HwError> {
        let io_err = |source| HwError::Io {
            what: "command socket".into(),
            source,
        };
        let mut reader = stream.try_clone().map_err(io_err)?;
        reader.set_read_timeout(Some(READ_POLL)).map_err(io_err)?;
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || drain(&mut reader, &flag));
        Ok(Self {
            stream,
            stop,
            thread: Some(thread),
        })
    }

    /// Sends URScript text; blocks only until the bytes are handed to the OS.
    pub fn send(&mut self, script: &str) -> Result<(), HwError> {
        self.stream
            .write_all(script.as_bytes())
            .and_then(|()| self.stream.flush())
            .map_err(|source| HwError::Io {
                what: "command socket".into(),
                source,
            })
    }
}

impl Drop for CommandChannel {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn drain(reader: &mut TcpStream, stop: &AtomicBool) {
    let mut sink = [0u8; 4096];
    while !stop.load(Ordering::Relaxed) {
        match reader.read(&mut sink) {
            Ok(0) => return,
            Ok(_) => {}
            Err(e) if is_poll_timeout(&e) => {}
            Err(_) => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ur5::realtime::encode_packet;
    use crate::ur5::rtde::resting_state;

    #[test]
    fn the_realtime_reader_keeps_at_most_one_packet() {
        let packet = encode_packet(&resting_state());
        let stream: Vec<u8> = packet
            .iter()
            .copied()
            .cycle()
            .take(packet.len() * 500 + 17)
            .collect();
        let mut buffer = Vec::new();
        for chunk in stream.chunks(4096) {
            buffer.extend_from_slice(chunk);
            assert!(take_packets(&mut buffer).unwrap().is_some());
            assert!(buffer.len() < packet.len(), "{} bytes kept", buffer.len());
        }
        // A header declaring more than the largest packet is refused before
        // anything more is read for it.
        let mut bogus = i32::MAX.to_be_bytes().to_vec();
        bogus.extend([0u8; 100]);
        assert!(matches!(
            take_packets(&mut bogus),
            Err(HwError::PacketLength { .. })
        ));
    }
}
