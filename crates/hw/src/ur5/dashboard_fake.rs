//! A fake dashboard server on 127.0.0.1 for tests: it answers the
//! commands [`Dashboard`](super::Dashboard) sends with the replies of a
//! real controller, from a state the test sets, and records every command.
//! Clients are served one after the other; the thread stops on drop or
//! after its lifetime.
use std::io::{BufRead, BufReader, ErrorKind, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::HwError;

/// What the fake dashboard reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FakeDashboardState {
    /// `robotmode` (e.g. `RUNNING`).
    pub robot_mode: String,
    /// `safetystatus` (e.g. `NORMAL`, `PROTECTIVE_STOP`).
    pub safety_status: String,
    /// `PolyscopeVersion` reply.
    pub version: String,
    /// `is in remote control`; `None`: the command is unknown (CB3).
    pub remote_control: Option<bool>,
    /// Program files `load` finds.
    pub programs: Vec<String>,
    /// The loaded program.
    pub loaded: Option<String>,
    /// `PLAYING` after `play`, else `STOPPED`.
    pub playing: bool,
    /// The greeting never ends: bytes without a line end until the client
    /// hangs up (a flooding server).
    pub endless_greeting: bool,
}

impl Default for FakeDashboardState {
    fn default() -> Self {
        Self {
            robot_mode: "RUNNING".into(),
            safety_status: "NORMAL".into(),
            version: "URSoftware 5.11.1.108318 (Mar 22 2021)".into(),
            remote_control: Some(true),
            programs: vec!["tactrace.urp".into()],
            loaded: None,
            playing: false,
            endless_greeting: false,
        }
    }
}

#[derive(Default)]
struct Shared {
    state: FakeDashboardState,
    commands: Vec<String>,
}

/// A running fake dashboard server.
pub struct FakeDashboard {
    port: u16,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeDashboard {
    /// Serves `state` on an ephemeral port of 127.0.0.1 for at most
    /// `lifetime`.
    pub fn start(state: FakeDashboardState, lifetime: Duration) -> Result<Self, HwError> {
        let (listener, port) = super::fake_listener(0, "fake dashboard")?;
        let shared = Arc::new(Mutex::new(Shared {
            state,
            commands: Vec::new(),
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (s, f) = (shared.clone(), stop.clone());
        let deadline = Instant::now() + lifetime;
        let thread = std::thread::spawn(move || serve(&listener, &s, &f, deadline));
        Ok(Self {
            port,
            shared,
            stop,
            thread: Some(thread),
        })
    }

    /// The port it listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// The state reported now.
    pub fn state(&self) -> FakeDashboardState {
        lock(&self.shared).state.clone()
    }

    /// Every command received so far.
    pub fn commands(&self) -> Vec<String> {
        lock(&self.shared).commands.clone()
    }
}

impl Drop for FakeDashboard {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    shared.lock().unwrap_or_else(|p| p.into_inner())
}

fn serve(listener: &TcpListener, shared: &Mutex<Shared>, stop: &AtomicBool, deadline: Instant) {
    let done = || stop.load(Ordering::Relaxed) || Instant::now() >= deadline;
    while !done() {
        match listener.accept() {
            Ok((stream, _)) => serve_client(stream, shared, &done),
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(2));
            }
            Err(_) => return,
        }
    }
}

fn serve_client(mut stream: TcpStream, shared: &Mutex<Shared>, done: &dyn Fn() -> bool) {
    if lock(shared).state.endless_greeting {
        return flood(stream, done);
    }
    if stream.set_nonblocking(false).is_err()
        || stream
            .set_read_timeout(Some(Duration::from_millis(20)))
            .is_err()
        || stream
            .write_all(b"Connected: Universal Robots Dashboard Server\n")
            .is_err()
    {
        return;
    }
    let Ok(reader) = stream.try_clone() else {
        return;
    };
    let mut reader = BufReader::new(reader);
    let mut line = String::new();
    while !done() {
        match reader.read_line(&mut line) {
            Ok(0) => return,
            Ok(_) if line.ends_with('\n') => {
                let command = line.trim().to_string();
                line.clear();
                let reply = answer(&mut lock(shared), &command);
                if stream.write_all(format!("{reply}\n").as_bytes()).is_err() {
                    return;
                }
            }
            Ok(_) => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(_) => return,
        }
    }
}

/// Sends a greeting that never ends until the client hangs up.
fn flood(mut stream: TcpStream, done: &dyn Fn() -> bool) {
    let junk = vec![b'x'; 65536];
    if stream.set_nonblocking(false).is_err()
        || stream
            .set_write_timeout(Some(Duration::from_millis(50)))
            .is_err()
        || stream.write_all(b"Connected: ").is_err()
    {
        return;
    }
    while !done() {
        match stream.write(&junk) {
            Ok(0) => return,
            Ok(_) => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(_) => return,
        }
    }
}

/// The reply of a real controller in the fake's state.
fn answer(shared: &mut Shared, command: &str) -> String {
    shared.commands.push(command.to_string());
    let state = &mut shared.state;
    match command {
        "robotmode" => format!("Robotmode: {}", state.robot_mode),
        "safetystatus" => format!("Safetystatus: {}", state.safety_status),
        "safetymode" => format!("Safetymode: {}", state.safety_status),
        "PolyscopeVersion" => state.version.clone(),
        "is in remote control" => match state.remote_control {
            Some(on) => on.to_string(),
            None => format!("could not understand: '{command}'"),
        },
        "unlock protective stop" => {
            if state.safety_status == "PROTECTIVE_STOP" {
                state.safety_status = "NORMAL".into();
                "Protective stop releasing".into()
            } else {
                "Cannot unlock protective stop until 5s after occurrence. Always inspect \
                 cause of protective stop before unlocking"
                    .into()
            }
        }
        "close safety popup" => "closing safety popup".into(),
        "play" if state.loaded.is_some() && state.robot_mode == "RUNNING" => {
            state.playing = true;
            "Starting program".into()
        }
        "play" => "Failed to execute: play".into(),
        "programState" => format!(
            "{} {}",
            if state.playing { "PLAYING" } else { "STOPPED" },
            state.loaded.as_deref().unwrap_or("<unnamed>")
        ),
        _ => match command.strip_prefix("load ") {
            Some(file) if state.programs.iter().any(|p| p == file) => {
                state.loaded = Some(file.to_string());
                state.playing = false;
                format!("Loading program: {file}")
            }
            Some(file) => format!("File not found: {file}"),
            None => format!("could not understand: '{command}'"),
        },
    }
}
