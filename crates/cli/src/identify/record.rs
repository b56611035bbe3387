//! `fistage identify record` and `fistage identify simulate-record`: all six
//! LuGre parameters (and the mass) from a recorded run, and lab-style
//! records from any stage.
//!
//! ```text
//! fistage identify record DATA [--mass M | --fit-mass] [--json] [--out DIR]
//!                              [--segments FILE] [--loss l2|huber] [--horizon S|whole]
//!                              [--closed-loop SCENARIO]
//! fistage identify record DATA... --stage SCENARIO --fit PATH[,PATH...] [--closed-loop]
//!                              [--allow-undetermined] [--json] [--out DIR]
//! fistage identify simulate-record ROBOT_OR_SCENARIO --out DATA.csv|DATA.mat [--seed N]
//!                              [--exact] [--quantum M] [--noise M] [--disturbance N]
//!                              [--closed-loop [--duration S]]
//! ```

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use fistage_analysis::lab::LabStage;
use fistage_analysis::record_lab::RecordLab;
use fistage_ident::record::{
    FitProgress, LabErrors, MassChoice, Record, RecordFit, RecordOptions, RecordReport,
    SegmentChoice, ServoLoop, fit_record, read_record, read_segments, record_fit_csv,
    record_override,
};
use fistage_ident::stage::{
    Loop, StageOptions, StagePlant, StageProgress, StageReport, fit_stage, stage_fit_csv,
};
use fistage_ident::{Loss, Quantity, UnitOverrides};

use super::shared::{
    OutputArgs, SimulateArgs, check_element, nothing_written, print_report, refuse_undetermined,
    unit_flag,
};
use fistage_model::output::ResultFolder;

/// The input conventions, for `--help`.
const CONVENTIONS: &str = "\
Input conventions: columns (CSV) or variables (MAT-file, version 6 or 7 as MATLAB's \
`save` writes by default) are found by name and unit suffix: time `t_s` (or `t_ms`), \
force `f_servo_N` (or `force_N`), position `x_nm` (or `x_um`, `x_mm`, `x_m`). \
The force is held over each sample interval (zero-order hold: f[k] acts on [t_k, t_k+1)); \
the position is sampled at t_k before f[k] acts; the stage starts at rest with relaxed \
bristles unless --start-velocity / --start-bristle say otherwise; encoders are quantised \
(1 nm is typical) and the fit expects that. \
With --closed-loop SCENARIO the record is a run of that scenario's servo (its reference, \
gains, compensation and observer, in continuous time): the plant's force is the servo's on \
the simulated encoder, and the logged force gives only the first estimates.";

#[derive(Clone, Copy, ValueEnum)]
enum RecordLoss {
    L2,
    Huber,
}

/// Arguments of `fistage identify record`.
#[derive(Args)]
#[command(after_help = CONVENTIONS)]
pub struct RecordArgs {
    /// The records: CSV or `.mat` with time, force and position (and, for a
    /// stage fit, further sensors as `<sensor>_<unit>` columns). The
    /// one-mass fit takes one; a stage fit takes several, fitted jointly.
    #[arg(required = true, num_args = 1..)]
    data: Vec<PathBuf>,
    /// Fit a scenario's whole stage (any robot file) instead of the one-mass
    /// plant: the parameters named by --fit, the rest as the scenario has them.
    #[arg(long, value_name = "SCENARIO", requires = "fit")]
    stage: Option<PathBuf>,
    /// The parameters a stage fit estimates: paths of the parameter table
    /// (`overrides.isolator.k_x`, `overrides.friction_*.f_c`), comma separated.
    #[arg(
        long,
        value_name = "PATH[,PATH...]",
        value_delimiter = ',',
        requires = "stage"
    )]
    fit: Vec<String>,
    /// Known moving mass, kg.
    #[arg(long, value_name = "KG", conflicts_with = "fit_mass")]
    mass: Option<f64>,
    /// Fit the mass (the default when --mass is not given).
    #[arg(long)]
    fit_mass: bool,
    /// Segments table (CSV `start_s,end_s[,kind]`); without it, rests of zero
    /// force of 50 ms or more split the record.
    #[arg(long, value_name = "FILE")]
    segments: Option<PathBuf>,
    /// The loss.
    #[arg(long, value_enum, default_value = "l2")]
    loss: RecordLoss,
    /// How often the simulated position is re-anchored to the encoder, s, or
    /// `whole` for a pure output error (re-anchored only where a motion
    /// follows a rest). 10 ms keeps an unmeasured force from bending the fit
    /// and a closed-loop limit cycle from drifting out of phase; `whole`
    /// suits a smooth closed-loop run (the servo reads every re-anchored,
    /// quantised position). With --stage: how often the whole stage is
    /// translated onto the main sensor, or `whole` for a pure output error
    /// over growing horizons.
    #[arg(long, value_name = "S|whole", default_value = "0.01")]
    horizon: String,
    /// A closed-loop record: the scenario whose servo and reference drove
    /// the stage (its stage must be one mass on one contact). With --stage,
    /// give it without a value: the --stage scenario's servo drove it.
    #[arg(long, value_name = "SCENARIO", num_args = 0..=1, default_missing_value = "")]
    closed_loop: Option<PathBuf>,
    /// Relative tolerance of the plant simulation.
    #[arg(long, default_value_t = 1e-8)]
    rtol: f64,
    /// Velocity at the first sample, m/s.
    #[arg(long, value_name = "M_PER_S", default_value_t = 0.0)]
    start_velocity: f64,
    /// Bristle deflection at the first sample, m.
    #[arg(long, value_name = "M", default_value_t = 0.0)]
    start_bristle: f64,
    /// Unit of a time column named without one (s, ms, us).
    #[arg(long, value_name = "UNIT")]
    time_unit: Option<String>,
    /// Unit of a force column named without one (N, mN).
    #[arg(long, value_name = "UNIT")]
    force_unit: Option<String>,
    /// Unit of a position column named without one (m, mm, um, nm).
    #[arg(long, value_name = "UNIT")]
    position_unit: Option<String>,
    #[command(flatten)]
    output: OutputArgs,
}

/// Arguments of `fistage identify simulate-record`.
#[derive(Args)]
pub struct SimulateRecordArgs {
    #[command(flatten)]
    common: SimulateArgs,
    /// Encoder step, m.
    #[arg(long, value_name = "M", default_value_t = 1e-9)]
    quantum: f64,
    /// Standard deviation of white position noise, m.
    #[arg(long, value_name = "M", default_value_t = 0.0)]
    noise: f64,
    /// RMS of an unmeasured force disturbance (low-pass noise, 50 ms), N.
    #[arg(long, value_name = "N", default_value_t = 0.0)]
    disturbance: f64,
    /// Sample rate, Hz.
    #[arg(long, value_name = "HZ", default_value_t = 10_000.0)]
    rate: f64,
    /// Record a run of the scenario's own servo along its reference instead
    /// of the open-loop program (the stage must be a scenario with a
    /// [controller]); the disturbance acts unlogged.
    #[arg(long)]
    closed_loop: bool,
    /// Length of a closed-loop record, s (the scenario's duration by default).
    #[arg(long, value_name = "S", requires = "closed_loop")]
    duration: Option<f64>,
    /// A further sensor of the stage to record (a bearing encoder), as a
    /// column `<sensor>_m`; repeat for several.
    #[arg(long = "sensor", value_name = "NAME", conflicts_with = "closed_loop")]
    sensors: Vec<String>,
}

/// Runs `fistage identify record`.
pub fn run_record(args: &RecordArgs) -> Result<()> {
    if let Some(stage) = &args.stage {
        return run_stage(args, stage);
    }
    let [data] = args.data.as_slice() else {
        bail!(
            "the one-mass fit takes one record ({} given); fit several jointly with --stage \
             SCENARIO --fit PATHS",
            args.data.len()
        );
    };
    if args
        .closed_loop
        .as_ref()
        .is_some_and(|p| p.as_os_str().is_empty())
    {
        bail!("--closed-loop needs the scenario whose servo drove the record (or --stage)");
    }
    check_element(&args.output)?;
    let units = record_units(args)?;
    let mut record = read_record(data, &units)?;
    record.start.velocity = args.start_velocity;
    record.start.bristle = args.start_bristle;
    record.check()?;
    let segments = match &args.segments {
        Some(path) => SegmentChoice::Given(read_segments(path, &record)?),
        None => SegmentChoice::Detect,
    };
    let closed_loop = match &args.closed_loop {
        Some(path) => Some(ServoLoop::from_scenario(path)?),
        None => None,
    };
    let horizon = horizon(args)?;
    let options = RecordOptions {
        mass: args.mass.map_or(MassChoice::Fit, MassChoice::Known),
        loss: match args.loss {
            RecordLoss::L2 => Loss::L2,
            RecordLoss::Huber => Loss::Huber,
        },
        rtol: args.rtol,
        segments,
        horizon,
        closed_loop,
        ..RecordOptions::default()
    };
    let folder = (args.output.out.as_ref())
        .map(|target| ResultFolder::begin(target, args.output.force))
        .transpose()?;
    let bar = crate::progress::bar("fitting the record");
    let mut iterations = 0usize;
    let fit = fit_record(&record, &options, &mut |p: &FitProgress| {
        iterations += usize::from(p.iteration > 0);
        // The fraction of the most iterations a fit of this kind has needed.
        crate::progress::set_fraction(&bar, iterations as f64 / 30.0);
        if p.rms.is_finite() {
            bar.set_message(format!(
                "fitting: iteration {iterations}, rms {:.3e} m",
                p.rms
            ));
        }
        true
    })?;
    bar.finish_and_clear();
    let report = RecordReport::new(&record, &fit).for_element(&args.output.element);
    let json = serde_json::to_string_pretty(&report)?;
    let verdict = refuse_undetermined(&args.output, &report.not_identifiable);
    if let (Some(folder), true) = (folder, verdict.is_ok()) {
        write_record_outputs(folder.path(), &record, &fit, &report, &json, &args.output)?;
        folder.commit()?;
    }
    print_report(args.output.json, &json, &report.table());
    verdict.map_err(|e| nothing_written(e, &args.output))
}

/// `--horizon`: a positive number of s, or None for `whole`.
fn horizon(args: &RecordArgs) -> Result<Option<f64>> {
    Ok(match args.horizon.as_str() {
        "whole" => None,
        text => Some(
            text.parse::<f64>()
                .ok()
                .filter(|h| h.is_finite() && *h > 0.0)
                .with_context(|| {
                    format!("--horizon: '{text}' is neither a positive number of s nor 'whole'")
                })?,
        ),
    })
}

/// The one-mass fit's flags a stage fit has no use for, refused by name
/// rather than ignored.
fn refuse_one_mass_flags(args: &RecordArgs) -> Result<()> {
    let masses =
        "the stage's masses are its robot file's (fit one with --fit overrides.<link>.mass)";
    let refusals = [
        (args.mass.is_some(), "--mass", masses),
        (args.fit_mass, "--fit-mass", masses),
        (
            args.segments.is_some(),
            "--segments",
            "a stage fit uses each record whole, re-anchored every --horizon",
        ),
        (
            args.start_velocity != 0.0,
            "--start-velocity",
            "a stage fit starts each record from the scenario's start state",
        ),
        (
            args.start_bristle != 0.0,
            "--start-bristle",
            "a stage fit starts each record from the scenario's start state",
        ),
        (
            args.output.element != fistage_ident::report::DEFAULT_ELEMENT,
            "--element",
            "a stage fit's override.toml names each fitted path itself",
        ),
        (
            args.closed_loop
                .as_ref()
                .is_some_and(|p| !p.as_os_str().is_empty()),
            "--closed-loop SCENARIO",
            "with --stage, give --closed-loop without a value: the --stage scenario's servo",
        ),
    ];
    match refusals.iter().find(|(given, _, _)| *given) {
        Some((_, flag, why)) => bail!("{flag} is the one-mass fit's: {why}"),
        None => Ok(()),
    }
}

/// The record units of the `--*-unit` flags.
fn record_units(args: &RecordArgs) -> Result<UnitOverrides> {
    Ok(UnitOverrides {
        time: unit_flag(Quantity::Time, &args.time_unit)?,
        force: unit_flag(Quantity::Force, &args.force_unit)?,
        position: unit_flag(Quantity::Position, &args.position_unit)?,
        ..UnitOverrides::default()
    })
}

/// `fistage identify record DATA... --stage SCENARIO --fit PATHS`.
fn run_stage(args: &RecordArgs, stage: &Path) -> Result<()> {
    refuse_one_mass_flags(args)?;
    let units = record_units(args)?;
    let records = (args.data.iter())
        .map(|path| read_record(path, &units))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let scenario = fistage_model::Scenario::from_file(stage)?;
    let robot = fistage_model::RobotSpec::from_file(&scenario.robot)?;
    let drive = if args.closed_loop.is_some() {
        Loop::Closed
    } else {
        Loop::Open
    };
    let plant = StagePlant::new(&scenario, &robot, &args.fit, drive)?;
    let options = StageOptions {
        rtol: args.rtol.max(1e-12),
        loss: match args.loss {
            RecordLoss::L2 => Loss::L2,
            RecordLoss::Huber => Loss::Huber,
        },
        anchor_every: horizon(args)?,
        ..StageOptions::default()
    };
    // The folder is taken before the work, so a held or earlier result is
    // refused at once; it is written only when the fit is accepted.
    let folder = (args.output.out.as_ref())
        .map(|target| ResultFolder::begin(target, args.output.force))
        .transpose()?;
    let bar = crate::progress::bar("fitting the stage");
    let fit = fit_stage(&plant, &records, &options, &mut |p: &StageProgress| {
        crate::progress::set_fraction(&bar, p.horizon_fraction);
        if p.rms.is_finite() {
            bar.set_message(format!(
                "{}: iteration {}, rms {:.3e} noise levels",
                p.stage, p.iterations, p.rms
            ));
        }
        true
    })?;
    bar.finish_and_clear();
    let report = StageReport::new(&stage.display().to_string(), &fit);
    let json = serde_json::to_string_pretty(&report)?;
    let undetermined = report.undetermined.clone();
    let refused = !undetermined.is_empty() && !args.output.allow_undetermined;
    if let (Some(folder), false) = (folder, refused) {
        let dir = folder.path();
        for (name, text) in [
            ("fit.json", format!("{json}\n")),
            ("override.toml", report.override_toml()),
            ("data_vs_fit.csv", stage_fit_csv(&records, &fit)),
        ] {
            let path = dir.join(name);
            std::fs::write(&path, text)
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
        if !args.output.no_report {
            crate::report::write(dir, || {
                fistage_report::sections::identify::stage_section(&records, &fit, &report)
            })?;
        }
        folder.commit()?;
    }
    print_report(args.output.json, &json, &report.table());
    if refused {
        return Err(nothing_written(
            anyhow::anyhow!(
                "not determined by these records: {} (left at the scenario's values; \
                 --allow-undetermined accepts the fit as it is)",
                undetermined.join(", ")
            ),
            &args.output,
        ));
    }
    Ok(())
}

fn write_record_outputs(
    dir: &Path,
    record: &Record,
    fit: &RecordFit,
    report: &RecordReport,
    json: &str,
    output: &OutputArgs,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for (name, text) in [
        ("fit.json", format!("{json}\n")),
        ("override.toml", record_override(&output.element, report)),
        ("data_vs_fit.csv", record_fit_csv(record, fit)),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    fistage_plot::figures::record::write(record, fit, dir)?;
    if !output.no_report {
        crate::report::write(dir, || {
            fistage_report::sections::identify::record_section(record, fit, report)
        })?;
    }
    Ok(())
}

/// Runs `fistage identify simulate-record`.
pub fn simulate_record(args: &SimulateRecordArgs) -> Result<()> {
    for (flag, value) in [
        ("--quantum", args.quantum),
        ("--noise", args.noise),
        ("--disturbance", args.disturbance),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            bail!(
                "{flag} must be a number >= 0, got {}",
                fistage_model::rule::show(value)
            );
        }
    }
    if !(args.rate.is_finite() && args.rate > 0.0 && args.rate <= 1e7) {
        bail!(
            "--rate must be in (0, 1e7] Hz, got {}",
            fistage_model::rule::show(args.rate)
        );
    }
    let common = &args.common;
    let stage = LabStage::load(&common.stage)?;
    let mut lab = RecordLab::new(common.seed);
    lab.dt = 1.0 / args.rate;
    lab.further_sensors = args.sensors.clone();
    lab.errors = if common.exact {
        LabErrors::exact()
    } else {
        LabErrors {
            quantum: args.quantum,
            position_noise: args.noise,
            disturbance_rms: args.disturbance,
            seed: common.seed,
            ..LabErrors::exact()
        }
    };
    if let Some(d) = args.duration
        && !(d.is_finite() && d > 0.0)
    {
        bail!(
            "--duration must be a positive number of s, got {}",
            fistage_model::rule::show(d)
        );
    }
    let (record, segments) = if args.closed_loop {
        (
            lab.measure_closed_loop(&common.stage, args.duration)?,
            Vec::new(),
        )
    } else {
        lab.measure(&stage)?
    };
    write_record(&common.out, &record)?;
    if args.closed_loop {
        println!(
            "wrote {} samples ({:.2} s at {} Hz, closed loop) to {}",
            record.len(),
            record.duration(),
            args.rate,
            common.out.display()
        );
        print_truth(&stage);
        return Ok(());
    }
    let segments_path = common.out.with_extension("segments.csv");
    let mut table = String::from("start_s,end_s,kind\n");
    for s in segments.iter().filter(|s| !s.is_rest()) {
        let end = record
            .time
            .get(s.end)
            .copied()
            .unwrap_or(record.time[record.len() - 1]);
        table += &format!("{},{},{}\n", record.time[s.start], end, s.kind);
    }
    fistage_model::output::write_whole(&segments_path, table.as_bytes())
        .with_context(|| format!("{}: cannot write", segments_path.display()))?;
    println!(
        "wrote {} samples ({:.2} s at {} Hz) to {} and its segments to {}",
        record.len(),
        record.duration(),
        args.rate,
        common.out.display(),
        segments_path.display()
    );
    print_truth(&stage);
    Ok(())
}

/// Prints the stage's true parameters as JSON (every contact's for a
/// stage with several).
fn print_truth(stage: &LabStage) {
    if let [_, _, ..] = stage.contacts() {
        let contacts: serde_json::Map<String, serde_json::Value> = (stage.contacts().iter())
            .map(|(name, p)| {
                let values = serde_json::json!({
                    "f_c": p.f_c, "f_s": p.f_s, "v_s": p.v_s, "sigma0": p.sigma0,
                    "sigma1": p.sigma1, "sigma2": p.sigma2,
                });
                (name.clone(), values)
            })
            .collect();
        println!(
            "true friction of {} contacts ({}), moving mass {} kg: {}",
            contacts.len(),
            stage.source(),
            stage.moving_mass(),
            serde_json::Value::Object(contacts)
        );
        return;
    }
    let p = stage.friction();
    let truth = serde_json::json!({
        "f_c": p.f_c, "f_s": p.f_s, "v_s": p.v_s, "sigma0": p.sigma0,
        "sigma1": p.sigma1, "sigma2": p.sigma2, "mass": stage.moving_mass(),
    });
    println!(
        "true parameters of {} ({}): {truth}",
        stage.friction_name(),
        stage.source()
    );
}

/// Writes a record as CSV (`t_s,f_servo_N,x_m`) or, for a `.mat` name, as a
/// version 7 MAT-file with the same variable names.
fn write_record(path: &Path, record: &Record) -> Result<()> {
    let is_mat = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"));
    let result = if is_mat {
        let mut bytes = Vec::new();
        let mut columns: Vec<(&str, &[f64])> = vec![
            ("t_s", &record.time),
            ("f_servo_N", &record.force),
            ("x_m", &record.position),
        ];
        for s in &record.sensors {
            columns.push((&s.column, &s.values));
        }
        fistage_model::mat::write_columns(&mut bytes, &columns)
            .and_then(|()| fistage_model::output::write_whole(path, &bytes))
    } else {
        let mut text = String::from("t_s,f_servo_N,x_m");
        for s in &record.sensors {
            text += &format!(",{}", s.column);
        }
        text.push('\n');
        for k in 0..record.len() {
            text += &format!(
                "{},{},{}",
                record.time[k], record.force[k], record.position[k]
            );
            for s in &record.sensors {
                text += &format!(",{}", s.values[k]);
            }
            text.push('\n');
        }
        fistage_model::output::write_whole(path, text.as_bytes())
    };
    result.with_context(|| format!("{}: cannot write", path.display()))
}
