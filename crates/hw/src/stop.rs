//! Stopping a hardware run on SIGINT or SIGTERM.
//!
//! A [`StopFlag`] is shared between whoever asks for a stop (a signal
//! handler, a test) and the UR5 driver, whose blocking waits (move
//! arrival, state waits) poll it: on a request the driver sends `stopl`,
//! marks the flag halted and returns [`HwError::Interrupted`], so the run
//! stops between steps and keeps what it did.
//!
//! [`StopFlag::on_signals`] installs the handlers, for hardware runs only
//! (everything else keeps the default Ctrl-C): a thread of `signal-hook`
//! receives SIGINT and SIGTERM outside signal context. The first signal
//! sets the flag. A second one ends the process at once (exit 130 or 143),
//! but only once the flag is halted (the driver sent `stopl`, or no arm
//! was moving): never while a `movel` may still be running unstopped.
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;

use crate::HwError;

/// The signal that asked a hardware run to stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopSignal {
    /// SIGINT (Ctrl-C): exit code 130.
    Interrupt,
    /// SIGTERM: exit code 143.
    Terminate,
}

impl StopSignal {
    /// The shell's exit code for a process ended by this signal (128 + N).
    pub fn exit_code(self) -> u8 {
        match self {
            Self::Interrupt => 130,
            Self::Terminate => 143,
        }
    }

    fn code(self) -> u8 {
        match self {
            Self::Interrupt => 1,
            Self::Terminate => 2,
        }
    }

    fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(Self::Interrupt),
            2 => Some(Self::Terminate),
            _ => None,
        }
    }
}

impl std::fmt::Display for StopSignal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Interrupt => "SIGINT",
            Self::Terminate => "SIGTERM",
        })
    }
}

#[derive(Debug, Default)]
struct Shared {
    /// 0: no stop asked; else the first signal's code.
    signal: AtomicU8,
    /// The arm was halted after the request (or none was moving).
    halted: AtomicBool,
}

/// A stop request shared by clones; never set unless asked.
#[derive(Debug, Clone, Default)]
pub struct StopFlag(Arc<Shared>);

impl StopFlag {
    /// A flag no one has set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Ask for a stop; the first request's signal is the one kept.
    pub fn request(&self, signal: StopSignal) {
        let _ =
            self.0
                .signal
                .compare_exchange(0, signal.code(), Ordering::SeqCst, Ordering::SeqCst);
    }

    /// The signal of the first request, if a stop was asked.
    pub fn requested(&self) -> Option<StopSignal> {
        StopSignal::from_code(self.0.signal.load(Ordering::SeqCst))
    }

    /// Record that the arm is stopped after a request (`stopl` sent, or no
    /// arm moving): from now on a second signal may end the process.
    pub fn mark_halted(&self) {
        self.0.halted.store(true, Ordering::SeqCst);
    }

    /// Whether [`StopFlag::mark_halted`] was called.
    pub fn halted(&self) -> bool {
        self.0.halted.load(Ordering::SeqCst)
    }

    /// For a moment when no arm can be moving (before connecting): an
    /// [`HwError::Interrupted`] when a stop was asked (the flag is then
    /// halted), else `Ok`.
    pub fn check_idle(&self) -> Result<(), HwError> {
        match self.requested() {
            Some(signal) => {
                self.mark_halted();
                Err(HwError::Interrupted { signal })
            }
            None => Ok(()),
        }
    }

    /// A flag set by the process's SIGINT and SIGTERM from now on (the
    /// handlers stay for the life of the process; install them once, and
    /// only for a run that moves a real arm). A second signal after the
    /// arm was halted exits at once with the signal's exit code.
    pub fn on_signals() -> Result<Self, HwError> {
        use signal_hook::consts::signal::{SIGINT, SIGTERM};
        let io_err = |source| HwError::Io {
            what: "SIGINT/SIGTERM handlers".into(),
            source,
        };
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]).map_err(io_err)?;
        let flag = Self::new();
        let shared = flag.clone();
        std::thread::Builder::new()
            .name("tactrace-signals".into())
            .spawn(move || {
                for raw in signals.forever() {
                    let signal = if raw == SIGTERM {
                        StopSignal::Terminate
                    } else {
                        StopSignal::Interrupt
                    };
                    if shared.requested().is_some() && shared.halted() {
                        std::process::exit(i32::from(signal.exit_code()));
                    }
                    shared.request(signal);
                }
            })
            .map_err(io_err)?;
        Ok(flag)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_request_is_kept_and_idle_checks_halt() {
        let flag = StopFlag::new();
        assert_eq!(flag.requested(), None);
        assert!(flag.check_idle().is_ok());
        let other = flag.clone();
        other.request(StopSignal::Terminate);
        flag.request(StopSignal::Interrupt);
        assert_eq!(flag.requested(), Some(StopSignal::Terminate));
        assert!(!flag.halted());
        let err = flag.check_idle().unwrap_err();
        assert!(matches!(
            err,
            HwError::Interrupted {
                signal: StopSignal::Terminate
            }
        ));
        assert!(other.halted());
        assert_eq!(StopSignal::Interrupt.exit_code(), 130);
        assert_eq!(StopSignal::Terminate.exit_code(), 143);
        assert_eq!(StopSignal::Interrupt.to_string(), "SIGINT");
    }
}
