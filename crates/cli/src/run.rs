//! `fistage run SCENARIO [--out DIR]`: simulate a scenario, write the trajectory
//! (CSV, a MAT-file or both), `summary.json` and plots, and print the
//! steady-state summary.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::Context;
use fistage_model::EngineKind;
use fistage_sim::RunOutput;

use crate::progress;
use fistage_model::output::ResultFolder;

/// Arguments of `fistage run`.
#[derive(clap::Args)]
pub struct RunArgs {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
    /// Output folder (default: out/<scenario name>).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Override the scenario's relative tolerance.
    #[arg(long)]
    pub rtol: Option<f64>,
    /// Skip the plots.
    #[arg(long)]
    pub no_plots: bool,
    /// Skip the HTML page (report.html).
    #[arg(long)]
    pub no_report: bool,
    /// Engine to use instead of the scenario's (`auto`, `native`, `imex`,
    /// `dop853`, `rk4`, `rosenbrock` or `rapier`).
    #[arg(long)]
    pub engine: Option<EngineKind>,
    /// Fixed step of the rapier engine, s (instead of `rapier.dt`).
    #[arg(long)]
    pub dt: Option<f64>,
    /// Trajectory files to write: csv (trajectory.csv), mat (trajectory.mat,
    /// a version 7 MAT-file: one variable per signal, `signals` a cell array
    /// of variable names, signal names and units) or both; instead of
    /// `output.format`.
    #[arg(long)]
    pub format: Option<fistage_model::OutputFormat>,
    /// Replace an earlier result in the output folder (as a whole).
    #[arg(long)]
    pub force: bool,
}

/// Runs the command.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let mut loaded = fistage_model::load(&args.scenario)?;
    for note in loaded.model.notes() {
        eprintln!("warning: {}: {note}", args.scenario.display());
    }
    if let Some(rtol) = args.rtol {
        fistage_model::SolverSettings::check_rtol(rtol)
            .map_err(|why| anyhow::anyhow!("--rtol {why}"))?;
        loaded.scenario.solver.rtol = rtol;
    }
    if let Some(engine) = args.engine {
        loaded.scenario.solver.engine = engine;
    }
    if let Some(dt) = args.dt {
        anyhow::ensure!(
            dt > 0.0 && dt.is_finite(),
            "--dt must be positive, got {}",
            fistage_model::rule::show(dt)
        );
        loaded.scenario.rapier.dt = Some(dt);
    }
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&args.scenario));
    let folder = ResultFolder::begin(&out_dir, args.force)?;
    let bar = progress::bar(&format!("run {}", args.scenario.display()));
    let output = fistage_sim::run_scenario(&loaded, &mut |f| {
        progress::set_fraction(&bar, f);
        std::ops::ControlFlow::Continue(())
    })?;
    bar.finish_and_clear();
    let staging = folder.path();
    let format = args.format.unwrap_or(loaded.scenario.output_format);
    let mut written = Vec::new();
    if format.csv() {
        write_csv(&output, &staging.join("trajectory.csv"))?;
        written.push("trajectory.csv".to_string());
    }
    if format.mat() {
        write_mat(&output, &staging.join("trajectory.mat"))?;
        written.push("trajectory.mat".to_string());
    }
    write_summary(&loaded, &output, &staging.join("summary.json"))?;
    written.push("summary.json".to_string());
    if !args.no_plots {
        written.extend(fistage_plot::figures::run::write(
            &loaded, &output, staging,
        )?);
    }
    if !args.no_report {
        written.extend(crate::report::write(staging, || {
            fistage_report::sections::run::section(&loaded, &output)
        })?);
    }
    let out_dir = folder.commit()?;
    print_summary(&loaded, &output);
    println!("wrote {} in {}", written.join(", "), out_dir.display());
    Ok(())
}

/// `out/<file stem>` next to the working directory.
pub fn default_out_dir(scenario: &Path) -> PathBuf {
    let stem = scenario
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    PathBuf::from("out").join(stem)
}

fn write_csv(output: &RunOutput, path: &Path) -> anyhow::Result<()> {
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut writer = BufWriter::new(file);
    output
        .signals
        .write_csv(&mut writer)
        .with_context(|| format!("cannot write {}", path.display()))
}

fn write_mat(output: &RunOutput, path: &Path) -> anyhow::Result<()> {
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut writer = BufWriter::new(file);
    output
        .signals
        .write_mat(&mut writer)
        .and_then(|()| std::io::Write::flush(&mut writer))
        .with_context(|| format!("cannot write {}", path.display()))
}

fn write_summary(
    loaded: &fistage_model::Loaded,
    output: &RunOutput,
    path: &Path,
) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(&fistage_sim::summary::document(loaded, output))?;
    std::fs::write(path, text + "\n").with_context(|| format!("cannot write {}", path.display()))
}

fn print_summary(loaded: &fistage_model::Loaded, output: &RunOutput) {
    let scenario = &loaded.scenario;
    if !scenario.title.is_empty() {
        println!("{}", scenario.title);
    }
    println!(
        "steady-state window {:.3} s to {:.3} s",
        scenario.window[0], scenario.window[1]
    );
    let width = output
        .summary
        .iter()
        .map(|s| s.name.len() + s.unit.len() + 3)
        .max()
        .unwrap_or(10)
        .max(10);
    println!(
        "{:<width$} {:>13} {:>13} {:>13} {:>13} {:>13}",
        "signal", "mean", "peak-to-peak", "rms", "min", "max"
    );
    for s in &output.summary {
        let label = format!("{} [{}]", s.name, s.unit);
        println!(
            "{label:<width$} {:>13.5e} {:>13.5e} {:>13.5e} {:>13.5e} {:>13.5e}",
            s.stats.mean, s.stats.peak_to_peak, s.stats.rms, s.stats.min, s.stats.max
        );
    }
    let stats = &output.trajectory.stats;
    // The fixed-step engine names its step in place of a tolerance.
    let setting = if !scenario.solver.engine.is_adaptive() {
        String::new()
    } else {
        format!(" rtol {:e}", scenario.solver.rtol)
    };
    println!(
        "solver {}{setting}: {} steps, {} rejected, {} rhs evaluations, {:.3} s wall",
        stats.engine,
        stats.counts.steps,
        stats.counts.rejected,
        stats.counts.rhs_evaluations,
        stats.wall_time_s
    );
}
