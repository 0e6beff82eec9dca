//! Progress bars on stderr (hidden when stderr is not a terminal).
use indicatif::{ProgressBar, ProgressStyle};

/// A bar for `len` items of `what`.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// Runs a follow run of at most `steps` steps under a bar named "follow":
/// `run` is given the bar (to move it as steps end, to print warnings over
/// it), which is cleared when the run returns, whichever way it ended.
pub fn follow_bar<T>(steps: usize, run: impl FnOnce(&ProgressBar) -> T) -> T {
    let pb = bar(steps as u64, "follow");
    let res = run(&pb);
    pb.finish_and_clear();
    res
}
