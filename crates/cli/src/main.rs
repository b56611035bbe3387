//! The `fistage` command-line program: a thin face over the library crates.

// The doc comments of the argument structs are the program's --help texts,
// written for a terminal (`out/<scenario>`, `[sweep]`), not for rustdoc.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

#[cfg(any(not(feature = "bench"), not(feature = "fmu")))]
mod absent;
mod check;
mod compare;
mod fmu;
mod identify;

mod lyapunov;
mod modes;

mod progress;
mod report;

mod robust;
mod run;
mod shell;
mod ssp;
mod study;
mod sweep;
mod tune;

use clap::{CommandFactory, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "fistage",
    version,
    about = "Precision motion stages with friction isolators"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scenario; write trajectory.csv, summary.json and plots.
    Run(run::RunArgs),
    /// Load and validate a scenario and its robot; print the assembled model.
    Check(check::CheckArgs),
    /// Measure engine speed and accuracy (Markdown tables for BENCHMARKS.md).
    #[cfg(feature = "bench")]
    Bench(fistage_bench::BenchArgs),
    /// Measure engine speed and accuracy (not in this build: the `bench` feature).
    #[cfg(not(feature = "bench"))]
    Bench(absent::AbsentArgs),
    /// Equilibria, eigenvalues and mode shapes (table, modes.json, top-view pictures).
    Modes(modes::ModesArgs),
    /// Stability over a grid of one or two parameters (points.csv, points.json, map).
    Sweep(sweep::SweepArgs),
    /// Tracking of several scenarios over a grid against a baseline (curves.csv, plots).
    Compare(compare::CompareArgs),
    /// Tolerance analysis of a population of stages (samples.csv, summary.json, plots).
    Robust(robust::RobustArgs),
    /// Servo gains with the largest bandwidth that keep a whole population stable.
    Tune(tune::TuneArgs),
    /// Largest Lyapunov exponent: limit cycle (about 0) or chaos (positive).
    Lyapunov(lyapunov::LyapunovArgs),
    /// Identify LuGre parameters from measured stage data.
    Identify(identify::IdentifyArgs),
    /// Package a scenario as an FMI 2.0 or 3.0 FMU (Model Exchange and Co-Simulation).
    Fmu(fmu::FmuArgs),
    /// Package the plant's FMU with controller FMUs as an SSP 1.0 system (connections, parameters).
    Ssp(ssp::SspArgs),
    /// Put the pages of several result folders of one study on one HTML page.
    Report(report::ReportArgs),
    /// Print the completion script of a shell (bash, zsh, fish, elvish, powershell).
    Completions(shell::CompletionsArgs),
    /// Write man pages: fistage.1 and one per command.
    Man(shell::ManArgs),
}

/// Runs the command; an error is printed as its chain of causes (never a
/// backtrace, whatever `RUST_BACKTRACE` says: the message is for the user)
/// and the program exits with status 1.
fn main() -> std::process::ExitCode {
    match run_command() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("Error: {}", error_text(&error));
            std::process::ExitCode::FAILURE
        }
    }
}

/// An error and its causes as anyhow prints them, without the backtrace.
fn error_text(error: &anyhow::Error) -> String {
    let mut text = error.to_string();
    let causes: Vec<String> = error.chain().skip(1).map(ToString::to_string).collect();
    match causes.as_slice() {
        [] => {}
        [cause] => text.push_str(&format!("\n\nCaused by:\n    {cause}")),
        _ => {
            text.push_str("\n\nCaused by:");
            for (i, cause) in causes.iter().enumerate() {
                text.push_str(&format!("\n    {i}: {cause}"));
            }
        }
    }
    text
}

fn run_command() -> anyhow::Result<()> {
    // Written into a pipe that closes early (`fistage check x.toml | head -1`),
    // end quietly as other Unix programs do instead of panicking on EPIPE.
    // SAFETY: restoring the default disposition of SIGPIPE before any thread
    // starts touches no Rust state.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    match cli.command {
        Command::Run(args) => run::run(&args),
        Command::Identify(args) => identify::run(&args),
        #[cfg(feature = "bench")]
        Command::Bench(args) => fistage_bench::run(&args),
        #[cfg(not(feature = "bench"))]
        Command::Bench(_) => absent::refuse("bench", "bench"),
        Command::Check(args) => check::run(&args),
        Command::Modes(args) => modes::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Robust(args) => robust::run(&args),
        Command::Tune(args) => tune::run(&args),
        Command::Lyapunov(args) => lyapunov::run(&args),
        Command::Fmu(args) => fmu::run(&args),
        Command::Ssp(args) => ssp::run(&args),
        Command::Report(args) => report::run(&args),
        Command::Completions(args) => shell::completions(&args, Cli::command()),
        Command::Man(args) => shell::man(&args, Cli::command()),
    }
}
