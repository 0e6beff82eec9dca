//! Outputs kept apart from inputs: an output equal to or inside an input
//! would be written into it (and `import --frames F --out F --force`
//! deleted its own frames), and an input inside an output folder would be
//! deleted with the old output by `--force`.
//!
//! Paths are compared canonicalised (symbolic links, `.` and `..`
//! resolved; the part of a path that does not exist yet is taken as
//! written), component by component.
use crate::error::{Result, StoreError};
use std::path::{Component, Path, PathBuf};

/// An input a command reads: the option that named it and its path.
pub type Input<'a> = (&'static str, &'a Path);

/// Refuse an output folder `out` (named by `out_flag`) that is an input,
/// lies inside one, or holds one: the checks for an output `--force`
/// replaces whole.
pub fn check_output_apart(out_flag: &'static str, out: &Path, inputs: &[Input]) -> Result<()> {
    check_output_outside(out_flag, out, inputs)?;
    let out_real = resolve(out);
    for &(in_flag, input) in inputs {
        if resolve(input).starts_with(&out_real) {
            return Err(StoreError::InputInOutput {
                out_flag,
                out: out.to_path_buf(),
                in_flag,
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Refuse an output `out` (a file, or a folder whose named files are
/// written) that is an input or lies inside one.
pub fn check_output_outside(out_flag: &'static str, out: &Path, inputs: &[Input]) -> Result<()> {
    let out_real = resolve(out);
    for &(in_flag, input) in inputs {
        let in_real = resolve(input);
        if out_real.starts_with(&in_real) {
            return Err(StoreError::OutputInInput {
                out_flag,
                out: out.to_path_buf(),
                in_flag,
                input: input.to_path_buf(),
                equal: out_real == in_real,
            });
        }
    }
    Ok(())
}

/// `path` made absolute, its longest existing ancestor canonicalised and
/// the rest normalised as written.
fn resolve(path: &Path) -> PathBuf {
    let absolute = match std::env::current_dir() {
        Ok(cwd) if path.is_relative() => cwd.join(path),
        _ => path.to_path_buf(),
    };
    let normal = normalise(&absolute);
    let mut existing = normal.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(real) = existing.canonicalize() {
            let mut out = real;
            out.extend(rest.iter().rev());
            return out;
        }
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                existing = parent;
            }
            _ => return normal,
        }
    }
}

/// `.` dropped and `..` applied, lexically.
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn an_output_in_or_around_an_input_is_refused() {
        let root = tempfile::tempdir().unwrap();
        let frames = root.path().join("frames");
        fs::create_dir(&frames).unwrap();
        fs::write(frames.join("init_0.png"), "x").unwrap();
        let inputs: [Input; 1] = [("--frames", &frames)];
        let same = root.path().join("./frames/../frames");
        let err = check_output_apart("--out", &same, &inputs).unwrap_err();
        assert!(
            matches!(err, StoreError::OutputInInput { equal: true, .. }),
            "{err}"
        );
        assert!(err
            .to_string()
            .contains("is the same as the input --frames"));
        let inside = frames.join("new/ds");
        let err = check_output_apart("--out", &inside, &inputs).unwrap_err();
        assert!(
            err.to_string().contains("is inside the input --frames"),
            "{err}"
        );
        // An input inside the output folder that --force would replace.
        let reference = frames.join("init_0.png");
        let err = check_output_apart("--out", &frames, &[("--reference", &reference)]).unwrap_err();
        assert!(matches!(err, StoreError::InputInOutput { .. }), "{err}");
        // ... which a file output or a plots folder does not replace.
        check_output_outside("--plots", root.path(), &[("--data", &frames)]).unwrap();
        // Through a symbolic link.
        #[cfg(unix)]
        {
            let link = root.path().join("link");
            std::os::unix::fs::symlink(&frames, &link).unwrap();
            assert!(check_output_apart("--out", &link.join("x"), &inputs).is_err());
        }
        // Siblings with a common prefix are apart.
        let sibling = root.path().join("frames2");
        check_output_apart("--out", &sibling, &inputs).unwrap();
    }
}
