//! `tactrace`: the command-line front end. Arguments are parsed here (no
//! I/O), turned into run configurations, and handed to `tactrace-lab`.
//! Exit codes: 0 success, 1 a run failed, 2 bad input (arguments, files,
//! configuration).

mod cmd_data;
mod cmd_follow;
mod cmd_learn;
mod cmd_twin;
mod progress;

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
    /// Turn real TacTip frames (Bristol layout) into a dataset.
    Import(cmd_data::ImportArgs),
    /// Simulate a real labelled data set's taps (the simulator judged by real frames).
    Twin(cmd_twin::TwinArgs),
    /// Train a pose model (report ch. 4.2).
    Train(cmd_learn::TrainArgs),
    /// Mean absolute errors of a model on a dataset (report ch. 4.3).
    Validate(cmd_learn::ValidateArgs),
    /// Predict edge position and angle for one frame or a dataset.
    Predict(cmd_learn::PredictArgs),
    /// Follow a contour with the simulated rig (report ch. 5).
    Follow(cmd_follow::FollowArgs),
    /// Regenerate the report's tables and figures end to end.
    Reproduce(cmd_follow::ReproduceArgs),
    /// Time simulated taps and the control loop (figures in docs/results.md, "Speed").
    Bench(cmd_follow::BenchArgs),
    /// Inspect the sensor: render a simulated tap, detect pins in a frame.
    #[command(subcommand)]
    Sensor(cmd_data::SensorCommand),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Collect(a) => cmd_data::collect(a),
        Command::Import(a) => cmd_data::import(a),
        Command::Twin(a) => cmd_twin::twin(a),
        Command::Train(a) => cmd_learn::train(a),
        Command::Validate(a) => cmd_learn::validate(a),
        Command::Predict(a) => cmd_learn::predict(a),
        Command::Follow(a) => cmd_follow::follow(a),
        Command::Reproduce(a) => cmd_follow::reproduce(a),
        Command::Sensor(c) => cmd_data::sensor(c),
        Command::Bench(a) => cmd_follow::bench(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            let input_error = err.chain().any(|e| {
                e.downcast_ref::<tactrace_lab::LabError>()
                    .is_some_and(tactrace_lab::LabError::is_bad_input)
                    || e.downcast_ref::<toml::de::Error>().is_some()
            });
            ExitCode::from(if input_error { 2 } else { 1 })
        }
    }
}
