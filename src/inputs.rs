//! The inputs a command reads, by option, so that its output can be kept
//! apart from them (`tactrace_store::overlap`): an `--out` equal to or
//! inside an input, or (for a folder `--force` replaces) holding one, is
//! refused before anything runs.
use std::path::Path;
use tactrace_store::overlap::Input;

/// The paths a command reads, each with the option that gave it.
#[derive(Default)]
pub struct Inputs<'a>(Vec<Input<'a>>);

impl<'a> Inputs<'a> {
    /// No input yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// An input given by `flag`.
    pub fn add(mut self, flag: &'static str, path: &'a Path) -> Self {
        self.0.push((flag, path));
        self
    }

    /// An optional input given by `flag`.
    pub fn opt(self, flag: &'static str, path: Option<&'a Path>) -> Self {
        match path {
            Some(p) => self.add(flag, p),
            None => self,
        }
    }

    /// Every input of a repeatable `flag` (`--train A --train B`).
    pub fn all(self, flag: &'static str, paths: &'a [std::path::PathBuf]) -> Self {
        paths.iter().fold(self, |inputs, p| inputs.add(flag, p))
    }

    /// A `--shape`-like value: an input when it names a file (a contour
    /// CSV), nothing when it is a built-in or parametric shape.
    pub fn file_arg(self, flag: &'static str, value: &'a str) -> Self {
        let path = Path::new(value);
        let file = path.is_file().then_some(path);
        self.opt(flag, file)
    }

    /// Refuse an output folder `out` (given by `out_flag`) that is one of
    /// these inputs, lies inside one or holds one.
    pub fn check_apart(&self, out_flag: &'static str, out: &Path) -> tactrace_store::Result<()> {
        tactrace_store::check_output_apart(out_flag, out, &self.0)
    }

    /// Refuse an output file, or a folder whose named files are written,
    /// that is one of these inputs or lies inside one.
    pub fn check_outside(&self, out_flag: &'static str, out: &Path) -> tactrace_store::Result<()> {
        tactrace_store::check_output_outside(out_flag, out, &self.0)
    }
}
