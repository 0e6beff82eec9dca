//! Where raw camera images come from, without linking any system library.
//!
//! [`CommandSource`] runs an external capture program (fswebcam, ffmpeg,
//! v4l2-ctl, ...) that writes one image file, then decodes that file.
//! [`FolderSource`] hands out the images of a folder in natural name order
//! (frame_2 before frame_10), for tests and replays.
//!
//! A camera kept open over V4L2 is the `v4l2` module's
//! `V4l2Source`.
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use image::DynamicImage;
use serde::{Deserialize, Serialize};

use crate::HwError;

/// A source of raw camera images.
pub trait FrameSource {
    /// The next image (any pixel format). Blocking behaviour is the
    /// source's: see each implementation.
    fn grab(&mut self) -> Result<DynamicImage, HwError>;
}

impl<S: FrameSource + ?Sized> FrameSource for Box<S> {
    /// The boxed source's frame.
    fn grab(&mut self) -> Result<DynamicImage, HwError> {
        (**self).grab()
    }
}

/// The placeholder in [`CommandSource`] arguments replaced by the output path.
pub const OUTPUT_PLACEHOLDER: &str = "{output}";

/// Runs `program args...` for every frame; the program must write the
/// image to `output` (PNG, JPEG or BMP).
///
/// Example: `ffmpeg -y -loglevel error -f v4l2 -i /dev/video0 -frames:v 1
/// {output}` with output `/tmp/tactip.png`.
#[derive(Debug, Clone)]
pub struct CommandSource {
    program: String,
    args: Vec<String>,
    output: PathBuf,
    timeout: Duration,
}

/// Serialisable settings of a [`CommandSource`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CommandSourceConfig {
    /// The capture program (looked up on PATH).
    pub program: String,
    /// Its arguments; [`OUTPUT_PLACEHOLDER`] becomes the output path.
    #[serde(default)]
    pub args: Vec<String>,
    /// The image file the program writes.
    pub output: PathBuf,
    /// Longest time one capture may take, s.
    #[serde(default = "default_capture_timeout")]
    pub timeout_s: f64,
}

fn default_capture_timeout() -> f64 {
    10.0
}

impl CommandSource {
    /// A source from its settings; fails on an empty program or a timeout
    /// that is not a positive number of seconds (at most an hour).
    pub fn from_config(config: &CommandSourceConfig) -> Result<Self, HwError> {
        if config.program.trim().is_empty() {
            return Err(HwError::Config {
                field: "program",
                reason: "empty".into(),
            });
        }
        if !(config.timeout_s > 0.0 && config.timeout_s <= 3600.0) {
            return Err(HwError::Config {
                field: "timeout_s",
                reason: format!("{} is not in (0, 3600]", config.timeout_s),
            });
        }
        let source = Self::new(
            config.program.clone(),
            config.args.clone(),
            config.output.clone(),
        );
        Ok(source.with_timeout(Duration::from_secs_f64(config.timeout_s)))
    }

    /// A source running `program` with `args` (where [`OUTPUT_PLACEHOLDER`]
    /// becomes `output`), with a 10 s timeout.
    pub fn new(program: impl Into<String>, args: Vec<String>, output: impl Into<PathBuf>) -> Self {
        Self {
            program: program.into(),
            args,
            output: output.into(),
            timeout: Duration::from_secs(10),
        }
    }

    /// Sets the longest time one capture may take.
    pub fn with_timeout(mut self, timeout: Duration) -> Self {
        self.timeout = timeout;
        self
    }

    fn command_line(&self) -> String {
        std::iter::once(self.program.as_str())
            .chain(self.args.iter().map(String::as_str))
            .collect::<Vec<_>>()
            .join(" ")
    }

    fn fail(&self, reason: impl Into<String>) -> HwError {
        HwError::Command {
            command: self.command_line(),
            reason: reason.into(),
        }
    }

    /// Runs the command once, killing it after the timeout.
    fn run(&self) -> Result<(), HwError> {
        let output = self.output.to_string_lossy();
        let args = self
            .args
            .iter()
            .map(|a| a.replace(OUTPUT_PLACEHOLDER, &output));
        let mut child = Command::new(&self.program)
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| self.fail(format!("cannot start: {e}")))?;
        // Read stderr in a thread so a chatty program cannot block on a full pipe.
        let stderr = child.stderr.take().map(|mut pipe| {
            std::thread::spawn(move || {
                let mut text = String::new();
                let _ = pipe.read_to_string(&mut text);
                text
            })
        });
        let start = Instant::now();
        let status = loop {
            match child.try_wait() {
                Ok(Some(status)) => break status,
                Ok(None) if start.elapsed() < self.timeout => {
                    std::thread::sleep(Duration::from_millis(5))
                }
                Ok(None) => {
                    let _ = child.kill();
                    let _ = child.wait();
                    let secs = self.timeout.as_secs_f64();
                    return Err(self.fail(format!("timed out after {secs} s")));
                }
                Err(e) => return Err(self.fail(format!("wait failed: {e}"))),
            }
        };
        let message = stderr.and_then(|t| t.join().ok()).unwrap_or_default();
        if status.success() {
            Ok(())
        } else {
            let tail: String = message
                .chars()
                .rev()
                .take(400)
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            Err(self.fail(format!("{status}: {}", tail.trim())))
        }
    }
}

impl FrameSource for CommandSource {
    /// Deletes any old output file, runs the command (blocking up to the
    /// timeout) and decodes the new file.
    fn grab(&mut self) -> Result<DynamicImage, HwError> {
        match std::fs::remove_file(&self.output) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(HwError::Io {
                    what: format!("removing old frame {}", self.output.display()),
                    source: e,
                })
            }
            _ => {}
        }
        self.run()?;
        if !self.output.exists() {
            return Err(self.fail(format!("did not write {}", self.output.display())));
        }
        open_image(&self.output)
    }
}

/// Decodes an image file.
pub fn open_image(path: &Path) -> Result<DynamicImage, HwError> {
    image::open(path).map_err(|source| HwError::Image {
        path: path.to_path_buf(),
        source,
    })
}

/// Images of a folder, in natural name order.
#[derive(Debug, Clone)]
pub struct FolderSource {
    files: Vec<PathBuf>,
    next: usize,
    looping: bool,
}

impl FolderSource {
    /// Lists the `.png`, `.jpg`, `.jpeg` and `.bmp` files of `dir`.
    pub fn new(dir: impl AsRef<Path>) -> Result<Self, HwError> {
        let dir = dir.as_ref();
        let entries = std::fs::read_dir(dir).map_err(|source| HwError::Io {
            what: format!("listing {}", dir.display()),
            source,
        })?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_image_name(p))
            .collect();
        if files.is_empty() {
            return Err(HwError::EmptyFolder {
                dir: dir.to_path_buf(),
            });
        }
        files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
        Ok(Self::from_files(files))
    }

    /// A source over the given files, in the given order.
    pub fn from_files(files: Vec<PathBuf>) -> Self {
        Self {
            files,
            next: 0,
            looping: false,
        }
    }

    /// Start again from the first image after the last (default: no).
    pub fn looping(mut self, looping: bool) -> Self {
        self.looping = looping;
        self
    }

    /// The files, in the order they are handed out.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }
}

impl FrameSource for FolderSource {
    /// Decodes the next file; does not block beyond reading it. After the
    /// last file: wraps around when looping, else `HwError::Exhausted`.
    fn grab(&mut self) -> Result<DynamicImage, HwError> {
        if self.next >= self.files.len() {
            if !self.looping || self.files.is_empty() {
                return Err(HwError::Exhausted { count: self.next });
            }
            self.next = 0;
        }
        let image = open_image(&self.files[self.next])?;
        self.next += 1;
        Ok(image)
    }
}

fn is_image_name(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("png" | "jpg" | "jpeg" | "bmp"))
}

/// Compares names with digit runs as numbers: "f_2" < "f_10".
pub fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    let (mut a, mut b) = (a, b);
    loop {
        match (a.chars().next(), b.chars().next()) {
            (None, None) => return std::cmp::Ordering::Equal,
            (None, Some(_)) => return std::cmp::Ordering::Less,
            (Some(_), None) => return std::cmp::Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let (na, ra) = split_digits(a);
                let (nb, rb) = split_digits(b);
                let by_value = na
                    .trim_start_matches('0')
                    .len()
                    .cmp(&nb.trim_start_matches('0').len());
                let order = by_value
                    .then_with(|| na.trim_start_matches('0').cmp(nb.trim_start_matches('0')))
                    .then_with(|| na.len().cmp(&nb.len()));
                if order.is_ne() {
                    return order;
                }
                (a, b) = (ra, rb);
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(&y);
                }
                (a, b) = (&a[x.len_utf8()..], &b[y.len_utf8()..]);
            }
        }
    }
}

fn split_digits(s: &str) -> (&str, &str) {
    let end = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    s.split_at(end)
}
