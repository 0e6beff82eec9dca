//! [`Dashboard`]: the UR dashboard server (port 29999), the text interface
//! for the set-up steps of every session.
//!
//! Facts used (Universal Robots, "Dashboard server" articles for CB3 and
//! e-series): one command a line, terminated by `\n`, one reply line each;
//! on connection the server greets with `Connected: Universal Robots
//! Dashboard Server`. Replies used here: `Robotmode: RUNNING`,
//! `Safetystatus: NORMAL` (3.11 / 5.4 and later; `Safetymode: ...` before),
//! `Protective stop releasing`, `closing safety popup`, `Loading program:
//! <file>` (or `File not found: ...` / `Error while loading program: ...`),
//! `Starting program` (or `Failed to execute: play`), `<STATE> <program>`
//! for `programState`, `URSoftware 5.11.1.108318 (Mar 22 2021)` for
//! `PolyscopeVersion`, and `true`/`false` for `is in remote control`
//! (e-series 5.6 and later). A command the server does not know is
//! answered `could not understand: '<command>'`.
//!
//! Blocking: every call waits for its reply line up to the timeout.
//! Bounded: a reply longer than [`MAX_REPLY_LEN`] bytes without a line end
//! is an error ([`HwError::ReplyTooLong`]), not a growing buffer.
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};

use super::link::connect;
use crate::HwError;

/// The dashboard server's port.
pub const DASHBOARD_PORT: u16 = 29999;

/// Longest reply line accepted, bytes (real replies are under 200).
pub const MAX_REPLY_LEN: usize = 4096;

/// A connection to the dashboard server.
pub struct Dashboard {
    stream: std::net::TcpStream,
    pending: Vec<u8>,
    timeout: Duration,
    greeting: String,
}

/// The PolyScope version the dashboard reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PolyscopeVersion {
    /// 3 (CB3), 5 (e-series), ...
    pub major: u32,
    /// Minor version.
    pub minor: u32,
    /// The whole reply, e.g. `URSoftware 5.11.1.108318 (Mar 22 2021)`.
    pub text: String,
}

impl PolyscopeVersion {
    /// Reads `URSoftware MAJOR.MINOR...` out of a reply.
    pub fn parse(reply: &str) -> Option<Self> {
        let numbers = reply
            .split_whitespace()
            .find(|w| w.chars().next().is_some_and(|c| c.is_ascii_digit()))?;
        let mut parts = numbers.split('.').map(|p| p.parse::<u32>().ok());
        Some(Self {
            major: parts.next()??,
            minor: parts.next()??,
            text: reply.to_string(),
        })
    }

    /// Whether URScript sent over the network may need the robot in remote
    /// control: PolyScope 5 with the remote-control feature enabled
    /// refuses it in local control; CB3 (PolyScope 3) has no such mode.
    pub fn has_remote_control(&self) -> bool {
        self.major >= 5
    }
}

impl Dashboard {
    /// Connects and reads the greeting; blocks up to `timeout`.
    pub fn connect(host: &str, port: u16, timeout: Duration) -> Result<Self, HwError> {
        let stream = connect(host, port, timeout)?;
        stream
            .set_read_timeout(Some(Duration::from_millis(50)))
            .map_err(io_err)?;
        let mut dashboard = Self {
            stream,
            pending: Vec::new(),
            timeout,
            greeting: String::new(),
        };
        dashboard.greeting = dashboard.read_line("(greeting)")?;
        Ok(dashboard)
    }

    /// The greeting line.
    pub fn greeting(&self) -> &str {
        &self.greeting
    }

    /// Sends one command and returns its reply line (trimmed).
    pub fn command(&mut self, command: &str) -> Result<String, HwError> {
        self.stream
            .write_all(format!("{command}\n").as_bytes())
            .map_err(io_err)?;
        self.read_line(command)
    }

    /// The robot mode, e.g. `RUNNING`, `IDLE`, `POWER_OFF`.
    pub fn robot_mode(&mut self) -> Result<String, HwError> {
        let reply = self.command("robotmode")?;
        field(&reply, "Robotmode:", "robotmode")
    }

    /// The safety status, e.g. `NORMAL`, `PROTECTIVE_STOP`: `safetystatus`,
    /// or `safetymode` on controllers that do not know it.
    pub fn safety_status(&mut self) -> Result<String, HwError> {
        let reply = self.command("safetystatus")?;
        if let Ok(status) = field(&reply, "Safetystatus:", "safetystatus") {
            return Ok(status);
        }
        let reply = self.command("safetymode")?;
        field(&reply, "Safetymode:", "safetymode")
    }

    /// Releases a protective stop (the cause must be gone; UR require
    /// waiting 5 s after it occurred).
    pub fn unlock_protective_stop(&mut self) -> Result<(), HwError> {
        self.expect("unlock protective stop", "Protective stop releasing")
    }

    /// Closes the safety pop-up on the pendant.
    pub fn close_safety_popup(&mut self) -> Result<(), HwError> {
        self.expect("close safety popup", "closing safety popup")
    }

    /// Loads a program file (`.urp`) on the controller.
    pub fn load(&mut self, program: &str) -> Result<(), HwError> {
        self.expect(&format!("load {program}"), "Loading program")
    }

    /// Starts the loaded program.
    pub fn play(&mut self) -> Result<(), HwError> {
        self.expect("play", "Starting program")
    }

    /// The program state (`STOPPED`, `PLAYING`, `PAUSED`) and the loaded
    /// program's name.
    pub fn program_state(&mut self) -> Result<(String, String), HwError> {
        let reply = self.command("programState")?;
        let (state, program) = reply.split_once(' ').unwrap_or((reply.as_str(), ""));
        if !matches!(state, "STOPPED" | "PLAYING" | "PAUSED") {
            return Err(refused("programState", &reply));
        }
        Ok((state.to_string(), program.trim().to_string()))
    }

    /// The PolyScope version.
    pub fn polyscope_version(&mut self) -> Result<PolyscopeVersion, HwError> {
        let reply = self.command("PolyscopeVersion")?;
        PolyscopeVersion::parse(&reply).ok_or_else(|| refused("PolyscopeVersion", &reply))
    }

    /// Whether the robot is in remote control; `None` on controllers that
    /// do not know the command (CB3, e-series before 5.6).
    pub fn is_in_remote_control(&mut self) -> Result<Option<bool>, HwError> {
        let reply = self.command("is in remote control")?;
        Ok(match reply.to_ascii_lowercase().as_str() {
            "true" => Some(true),
            "false" => Some(false),
            _ => None,
        })
    }

    fn expect(&mut self, command: &str, start: &str) -> Result<(), HwError> {
        let reply = self.command(command)?;
        if reply.starts_with(start) {
            Ok(())
        } else {
            Err(refused(command, &reply))
        }
    }

    fn read_line(&mut self, command: &str) -> Result<String, HwError> {
        let deadline = Instant::now() + self.timeout;
        let mut chunk = [0u8; 1024];
        loop {
            if let Some(end) = self.pending.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=end).collect();
                return Ok(String::from_utf8_lossy(&line).trim().to_string());
            }
            if self.pending.len() > MAX_REPLY_LEN {
                self.pending.clear();
                return Err(HwError::ReplyTooLong {
                    what: format!("dashboard reply to `{command}`"),
                    limit: MAX_REPLY_LEN,
                });
            }
            if Instant::now() >= deadline {
                return Err(refused(
                    command,
                    &format!("no reply within {:.1} s", self.timeout.as_secs_f64()),
                ));
            }
            match self.stream.read(&mut chunk) {
                Ok(0) => return Err(refused(command, "connection closed by the controller")),
                Ok(n) => self.pending.extend_from_slice(&chunk[..n]),
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(io_err(e)),
            }
        }
    }
}

fn field(reply: &str, prefix: &str, command: &str) -> Result<String, HwError> {
    reply
        .strip_prefix(prefix)
        .map(|v| v.trim().to_string())
        .ok_or_else(|| refused(command, reply))
}

fn refused(command: &str, reply: &str) -> HwError {
    HwError::Dashboard {
        command: command.to_string(),
        reply: reply.to_string(),
    }
}

fn io_err(source: std::io::Error) -> HwError {
    HwError::Io {
        what: "dashboard socket".into(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polyscope_versions_parse() {
        let e = PolyscopeVersion::parse("URSoftware 5.11.1.108318 (Mar 22 2021)").unwrap();
        assert_eq!((e.major, e.minor), (5, 11));
        assert!(e.has_remote_control());
        let cb3 = PolyscopeVersion::parse("URSoftware 3.15.7.106331 (Sep 21 2021)").unwrap();
        assert_eq!((cb3.major, cb3.minor), (3, 15));
        assert!(!cb3.has_remote_control());
        assert_eq!(PolyscopeVersion::parse("could not understand"), None);
    }
}
