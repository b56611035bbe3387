//! `fistage identify`: LuGre identification from lab CSV files.
//!
//! ```text
//! fistage identify stribeck DATA.csv [--robust] [--asymmetric] [--json] [--out DIR]
//! fistage identify frf DATA.csv [--mass M | --fit-mass] [--sigma2 S] [--json] [--out DIR]
//! fistage identify simulate-stribeck ROBOT_OR_SCENARIO --out DATA.csv [--points N] [--exact]
//! fistage identify simulate-frf ROBOT_OR_SCENARIO --out DATA.csv [--amplitude N] [--exact]
//! fistage identify record DATA [--mass M | --fit-mass] [--json] [--out DIR] (see `record.rs`)
//! fistage identify simulate-record ROBOT_OR_SCENARIO --out DATA.csv|DATA.mat
//! ```
//!
//! Prints a table (or the JSON report with `--json`); with `--out DIR` also writes
//! `fit.json`, `override.toml` (a `[overrides.<element>]` block a scenario can
//! include), `data_vs_fit.csv` / `fit_curve.csv`, and the plot of data against
//! fit as `fit.svg` and `fit.png`: f_ss against v (measured points as markers,
//! the points a fit flags as outliers as markers of their own, the fitted curve
//! as a line, and with `--asymmetric` the curve of each branch), or the Bode
//! plot of the FRF (magnitude, and phase when the data have it; measured points
//! as markers, the fitted response as a line). Nothing is written unless the fit
//! succeeds.
//!
//! The `simulate-*` commands make such data files from fistage's own simulation
//! of a stage (see `fistage_analysis::lab`): f_ss(v) from constant-velocity servo
//! runs, the FRF from a stepped sine on the open-loop stage, with the sensor
//! errors of a lab unless `--exact`; they print the stage's true parameters.
//!
//! The subcommands live one family a file: `curve.rs` (steady-state curves
//! and FRFs: `stribeck`, `frf` and their `simulate-*`), `record.rs` (`record`,
//! `simulate-record`); `shared.rs` holds the arguments and checks they share.

mod curve;
mod record;
mod shared;
#[cfg(test)]
mod tests;

use anyhow::Result;
use clap::{Args, Subcommand};

use curve::{
    FrfArgs, SimulateFrfArgs, SimulateStribeckArgs, StribeckArgs, run_frf, run_stribeck,
    simulate_frf, simulate_stribeck,
};
use record::{RecordArgs, SimulateRecordArgs, run_record, simulate_record};

/// Arguments of `fistage identify`.
#[derive(Args)]
pub struct IdentifyArgs {
    #[command(subcommand)]
    fit: IdentifyCommand,
}

#[derive(Subcommand)]
enum IdentifyCommand {
    /// Fit f_C, f_S, v_s and sigma2 to a steady-state friction curve f_ss(v).
    Stribeck(StribeckArgs),
    /// Fit sigma0 and sigma1 + sigma2 (and the mass) to the pre-motion FRF.
    Frf(FrfArgs),
    /// Measure f_ss(v) on the simulated stage (servoed constant-velocity runs)
    /// and write it as a lab CSV (velocity_mm_per_s, force_N).
    SimulateStribeck(SimulateStribeckArgs),
    /// Measure the pre-motion FRF on the simulated open-loop stage (stepped
    /// sine) and write it as a lab CSV (freq_Hz, mag_dB, phase_deg).
    SimulateFrf(SimulateFrfArgs),
    /// Fit all six LuGre parameters (and the mass) to a recorded run (force
    /// command and encoder position) by output error.
    Record(RecordArgs),
    /// Make a lab-style record (chirps, breakaway ramps, holds, steps,
    /// rests) on the simulated open-loop stage and write it as CSV or MAT.
    SimulateRecord(SimulateRecordArgs),
}

/// Runs the identification command.
pub fn run(args: &IdentifyArgs) -> Result<()> {
    match &args.fit {
        IdentifyCommand::Stribeck(a) => run_stribeck(a),
        IdentifyCommand::Frf(a) => run_frf(a),
        IdentifyCommand::SimulateStribeck(a) => simulate_stribeck(a),
        IdentifyCommand::SimulateFrf(a) => simulate_frf(a),
        IdentifyCommand::Record(a) => run_record(a),
        IdentifyCommand::SimulateRecord(a) => simulate_record(a),
    }
}
