//! Issue 20: the SIGINT/SIGTERM handlers of a hardware run, in a process
//! of their own (this test binary): a signal sets the stop flag instead of
//! ending the process, and a second one does not end it either while the
//! arm has not been halted.
use std::time::{Duration, Instant};

use signal_hook::consts::signal::SIGINT;
use tactrace_hw::{StopFlag, StopSignal};

fn wait_for(flag: &StopFlag) -> Option<StopSignal> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        if let Some(s) = flag.requested() {
            return Some(s);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    None
}

#[test]
fn sigint_sets_the_stop_flag_and_a_second_waits_for_the_halt() {
    let flag = StopFlag::on_signals().unwrap();
    assert_eq!(flag.requested(), None);
    signal_hook::low_level::raise(SIGINT).unwrap();
    assert_eq!(wait_for(&flag), Some(StopSignal::Interrupt));
    // Not halted yet: a second SIGINT must not end the process.
    signal_hook::low_level::raise(SIGINT).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    assert!(!flag.halted());
    assert_eq!(flag.requested(), Some(StopSignal::Interrupt));
}
