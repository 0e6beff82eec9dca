//! `tactrace`: the command-line front end. Arguments are parsed here (no
//! I/O), turned into run configurations, and handed to `tactrace-lab`.
//! Exit codes: 0 success, 1 a run failed (lost contact, unreachable
//! contour, diverged, a fault, an output that could not be written), 2 bad
//! input (arguments, files, configuration, data), 130 / 143 a hardware run
//! stopped by SIGINT / SIGTERM (the arm sent `stopl`). A closed standard
//! output (`tactrace predict ... | head`) ends the command quietly with 0.

mod cmd_completions;
mod cmd_data;
mod cmd_ensemble;
mod cmd_follow;
mod cmd_image;
mod cmd_inspect;
mod cmd_learn;
mod cmd_pin_init;
mod cmd_rig;
mod cmd_search;
mod cmd_task3d;
mod cmd_tune;
mod cmd_twin;
#[cfg(test)]
mod doc_commands;
mod inputs;
mod progress;
mod views;

/// Print a line on standard output; a closed pipe becomes an error that
/// `main` turns into a quiet exit, never a panic.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Tactile contour following: a simulated (or real) TacTip on a UR5-class
/// arm, dendritic networks trained by equilibrium propagation, PBTS control.
#[derive(Parser)]
#[command(name = "tactrace", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Collect taps on an edge with the simulated rig (report ch. 4.1).
    Collect(cmd_data::CollectArgs),
    /// Turn real TacTip frames (any TacTip; Bristol column defaults) into a dataset.
    Import(cmd_data::ImportArgs),
    /// Simulate a real labelled data set's taps (the simulator judged by real frames).
    Twin(cmd_twin::TwinArgs),
    /// Fit the simulated TacTip to your own labelled taps on a straight edge.
    Calibrate(cmd_twin::CalibrateArgs),
    /// Fit the simulator's physics by what a model trained on it makes of your real frames.
    SimFit(cmd_twin::SimFitArgs),
    /// Train a pose model (report ch. 4.2).
    Train(cmd_learn::TrainArgs),
    /// Bayesian search (TPE) of a pose model's settings on an inner validation part of the training data.
    Search(cmd_search::SearchArgs),
    /// Join pin models trained apart on the same rows into one ensemble, their predictions averaged.
    Ensemble(cmd_ensemble::EnsembleArgs),
    /// Mean absolute errors of a model on a dataset (report ch. 4.3).
    Validate(cmd_learn::ValidateArgs),
    /// Predict a model's targets (the edge pose by default) for one frame or a dataset.
    Predict(cmd_learn::PredictArgs),
    /// Follow a contour with the simulated rig, on real frames (--replay) or a real rig (report ch. 5).
    Follow(cmd_follow::FollowArgs),
    /// Tune the controller by CMA-ES over simulated runs; judge it on held-out contours.
    Tune(cmd_tune::TuneArgs),
    /// Score simulated follow runs on a set of contours (in memory, in parallel), with throughput.
    Evaluate(cmd_tune::EvaluateArgs),
    /// Regenerate the report's tables and figures end to end.
    Reproduce(cmd_follow::ReproduceArgs),
    /// Time simulated taps and the control loop (figures in docs/results.md, "Speed").
    Bench(cmd_follow::BenchArgs),
    /// Inspect the sensor: render a simulated tap, detect pins in a frame.
    #[command(subcommand)]
    Sensor(cmd_data::SensorCommand),
    /// Set up a real rig: check the arm, safety, camera and reference before a run.
    #[command(subcommand)]
    Rig(cmd_rig::RigCommand),
    /// Set up the TacTip camera: list V4L2 devices, grab a frame.
    #[command(subcommand)]
    Camera(cmd_rig::CameraCommand),
    /// Print a shell completion script (bash, zsh or fish) for every command and option.
    Completions(cmd_completions::CompletionsArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Collect(a) => cmd_data::collect(a),
        Command::Import(a) => cmd_data::import(a),
        Command::Twin(a) => cmd_twin::twin(a),
        Command::Calibrate(a) => cmd_twin::calibrate(a),
        Command::SimFit(a) => cmd_twin::sim_fit(a),
        Command::Train(a) => cmd_learn::train(a),
        Command::Search(a) => cmd_search::search(a),
        Command::Ensemble(a) => cmd_ensemble::ensemble(a),
        Command::Validate(a) => cmd_learn::validate(a),
        Command::Predict(a) => cmd_learn::predict(a),
        Command::Follow(a) => cmd_follow::follow(a),
        Command::Reproduce(a) => cmd_follow::reproduce(a),
        Command::Tune(a) => cmd_tune::tune(a),
        Command::Evaluate(a) => cmd_tune::evaluate(a),
        Command::Sensor(c) => cmd_data::sensor(c),
        Command::Bench(a) => cmd_follow::bench(a),
        Command::Rig(c) => cmd_rig::rig(c),
        Command::Camera(c) => cmd_rig::camera(c),
        Command::Completions(a) => {
            cmd_completions::completions(a, <Cli as clap::CommandFactory>::command())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            let cause: &(dyn std::error::Error + 'static) = err.as_ref();
            eprintln!("error: {}", tactrace_lab::error::error_chain(cause));
            ExitCode::from(exit_code(&err))
        }
    }
}

/// Standard output was closed by the reader.
fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|e| {
        e.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// 2 for bad input, 1 for a run that failed: decided by the first typed
/// error in the chain.
fn exit_code(err: &anyhow::Error) -> u8 {
    for e in err.chain() {
        if let Some(lab) = e.downcast_ref::<tactrace_lab::LabError>() {
            if let Some(code) = lab.signal_exit_code() {
                return code;
            }
            return if lab.is_bad_input() { 2 } else { 1 };
        }
        if let Some(store) = e.downcast_ref::<tactrace_store::StoreError>() {
            return if store.is_bad_input() { 2 } else { 1 };
        }
        if e.downcast_ref::<toml::de::Error>().is_some()
            || e.downcast_ref::<toml::ser::Error>().is_some()
        {
            return 2;
        }
    }
    1
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    /// Every argument of every (sub)command, with the path to it, that has
    /// no help line.
    fn undocumented(cmd: &clap::Command, path: &str, out: &mut Vec<String>) {
        for arg in cmd.get_arguments() {
            let builtin = matches!(arg.get_id().as_str(), "help" | "version");
            if !builtin && arg.get_help().is_none() && arg.get_long_help().is_none() {
                out.push(format!("{path} --{}", arg.get_id()));
            }
            // Values listed with help, some without: clap shows them blank.
            let values = arg.get_possible_values();
            if values.iter().any(|v| v.get_help().is_some()) {
                for v in values.iter().filter(|v| v.get_help().is_none()) {
                    out.push(format!("{path} --{} {}", arg.get_id(), v.get_name()));
                }
            }
        }
        for sub in cmd.get_subcommands() {
            if sub.get_about().is_none() && sub.get_name() != "help" {
                out.push(format!("{path} {} (no about)", sub.get_name()));
            }
            undocumented(sub, &format!("{path} {}", sub.get_name()), out);
        }
    }

    /// Issue 10: options such as `collect --samples`, `import --out` and the
    /// `sensor render` options had no help line.
    #[test]
    fn every_option_of_every_subcommand_has_a_help_line() {
        let mut missing = Vec::new();
        undocumented(&Cli::command(), "tactrace", &mut missing);
        assert!(missing.is_empty(), "no help line: {missing:#?}");
    }

    #[test]
    fn the_cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
