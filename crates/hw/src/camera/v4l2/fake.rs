//! [`FakeDevice`]: a capture device that replays buffers a test made.
//!
//! Time is modelled by polls: `stale` buffers are filled already when the
//! source asks; each of the `incoming` buffers arrives on the second poll
//! that finds nothing waiting, so a source that drains the waiting
//! buffers and then waits gets the next incoming one. After `unplug_after`
//! dequeues the device reports itself unplugged.
use std::collections::VecDeque;

use super::{CaptureDevice, StreamFormat};
use crate::HwError;

/// A recorded camera.
#[derive(Debug, Clone)]
pub struct FakeDevice {
    format: StreamFormat,
    stale: VecDeque<Vec<u8>>,
    incoming: VecDeque<Vec<u8>>,
    empty_polls: usize,
    dequeued: usize,
    unplug_after: Option<usize>,
}

impl FakeDevice {
    /// A device of `format` with `stale` buffers waiting and `incoming`
    /// ones still to come.
    pub fn new(format: StreamFormat, stale: Vec<Vec<u8>>, incoming: Vec<Vec<u8>>) -> Self {
        Self {
            format,
            stale: stale.into(),
            incoming: incoming.into(),
            empty_polls: 0,
            dequeued: 0,
            unplug_after: None,
        }
    }

    /// Unplugged after `count` dequeues.
    pub fn unplug_after(mut self, count: usize) -> Self {
        self.unplug_after = Some(count);
        self
    }

    /// Buffers taken so far.
    pub fn dequeued(&self) -> usize {
        self.dequeued
    }

    fn check_plugged(&self) -> Result<(), HwError> {
        match self.unplug_after {
            Some(n) if self.dequeued >= n => Err(HwError::CameraUnplugged {
                device: self.name().to_string(),
            }),
            _ => Ok(()),
        }
    }
}

impl CaptureDevice for FakeDevice {
    fn name(&self) -> &str {
        "fake camera"
    }

    fn format(&self) -> StreamFormat {
        self.format
    }

    fn ready(&mut self) -> Result<bool, HwError> {
        self.check_plugged()?;
        if !self.stale.is_empty() {
            return Ok(true);
        }
        self.empty_polls += 1;
        if self.empty_polls >= 2 {
            if let Some(next) = self.incoming.pop_front() {
                self.stale.push_back(next);
                self.empty_polls = 0;
                return Ok(true);
            }
        }
        Ok(false)
    }

    fn dequeue(&mut self) -> Result<Vec<u8>, HwError> {
        self.check_plugged()?;
        let bytes = self.stale.pop_front().ok_or(HwError::FrameData {
            reason: "dequeue with no buffer filled".into(),
        })?;
        self.dequeued += 1;
        Ok(bytes)
    }
}
