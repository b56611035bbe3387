//! `fistage lyapunov SCENARIO`: the largest Lyapunov exponent of the
//! scenario's motion (two-trajectory renormalisation), to tell a limit cycle
//! (about 0) from chaos (clearly positive) or a stable equilibrium (negative).

use std::path::PathBuf;

use fistage_analysis::lyapunov::{LyapunovSettings, largest_lyapunov};

/// Arguments of `fistage lyapunov`.
#[derive(clap::Args)]
pub struct LyapunovArgs {
    /// Scenario file (TOML) with a constant reference.
    pub scenario: PathBuf,
    /// Transient discarded first, s.
    #[arg(long, default_value_t = 2.0)]
    pub transient: f64,
    /// Measuring time, s.
    #[arg(long, default_value_t = 20.0)]
    pub duration: f64,
    /// Renormalisation interval, s.
    #[arg(long, default_value_t = 0.02)]
    pub interval: f64,
}

/// Renormalisation intervals a run may have.
const MAX_INTERVALS: f64 = 1e6;
/// Simulated seconds of the transient, and of the measurement.
const MAX_SPAN: f64 = 1e5;

/// Runs the command.
pub fn run(args: &LyapunovArgs) -> anyhow::Result<()> {
    for (name, value) in [
        ("--transient", args.transient),
        ("--duration", args.duration),
        ("--interval", args.interval),
    ] {
        anyhow::ensure!(
            value.is_finite() && value >= 0.0,
            "{name} must be >= 0, got {}",
            fistage_model::rule::show(value)
        );
    }
    anyhow::ensure!(
        args.interval > 0.0 && args.duration >= args.interval,
        "--interval must be > 0 and at most --duration"
    );
    anyhow::ensure!(
        args.duration / args.interval <= MAX_INTERVALS,
        "--duration / --interval is {:.3e} renormalisations; at most {MAX_INTERVALS:e}",
        args.duration / args.interval
    );
    for (name, value) in [
        ("--transient", args.transient),
        ("--duration", args.duration),
    ] {
        anyhow::ensure!(
            value <= MAX_SPAN,
            "{name} must be at most {MAX_SPAN:e} s, got {value:e}"
        );
    }
    let loaded = fistage_model::load(&args.scenario)?;
    let settings = LyapunovSettings {
        transient: args.transient,
        duration: args.duration,
        interval: args.interval,
        ..LyapunovSettings::default()
    };
    let exponent = largest_lyapunov(&loaded, &settings)?;
    let verdict = if exponent > 1.0 {
        "chaotic (nearby trajectories separate)"
    } else if exponent > -1.0 {
        "periodic or quasi-periodic (limit cycle)"
    } else {
        "converging (stable equilibrium)"
    };
    println!(
        "largest Lyapunov exponent {exponent:.4} 1/s over {} s: {verdict}",
        args.duration
    );
    Ok(())
}
