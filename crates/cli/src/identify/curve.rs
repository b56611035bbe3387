//! `fistage identify stribeck`, `frf`, `simulate-stribeck` and
//! `simulate-frf`: LuGre parameters from steady-state friction curves and
//! pre-motion FRFs, and such data made from a simulated stage.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use fistage_analysis::lab::{FrfLab, LabStage, MAX_LAB_POINTS, StribeckLab, log_spaced};
use fistage_ident::report::{
    frf_curve_csv, frf_data_vs_fit_csv, stribeck_curve_csv, stribeck_data_vs_fit_csv,
};
use fistage_ident::synth::{FrfCsvLayout, frf_csv, stribeck_csv};
use fistage_ident::{
    FrfOptions, FrfReport, Loss, MassOption, Quantity, Sigma2Input, StribeckOptions,
    StribeckReport, Unit, UnitOverrides, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
    frf_override, read_frf_csv, read_stribeck_csv, stribeck_override,
};

use super::shared::{
    OutputArgs, SimulateArgs, check_element, nothing_written, print_report, refuse_undetermined,
    unit_flag,
};
use fistage_model::output::ResultFolder;

#[derive(Args)]
pub(super) struct SimulateStribeckArgs {
    #[command(flatten)]
    common: SimulateArgs,
    /// Speeds per direction, log-spaced.
    #[arg(long, default_value_t = 20)]
    points: usize,
    /// Lowest speed, m/s.
    #[arg(long, value_name = "M_PER_S", default_value_t = 5e-4)]
    v_min: f64,
    /// Highest speed, m/s.
    #[arg(long, value_name = "M_PER_S", default_value_t = 0.4)]
    v_max: f64,
}

#[derive(Args)]
pub(super) struct SimulateFrfArgs {
    #[command(flatten)]
    common: SimulateArgs,
    /// Frequencies, log-spaced.
    #[arg(long, default_value_t = 30)]
    points: usize,
    /// Lowest frequency, Hz.
    #[arg(long, value_name = "HZ", default_value_t = 10.0)]
    f_min: f64,
    /// Highest frequency, Hz.
    #[arg(long, value_name = "HZ", default_value_t = 1000.0)]
    f_max: f64,
    /// Force amplitude, N (larger amplitudes bias the damping upwards: the
    /// contact is then not the linear spring-damper of the FRF model).
    #[arg(long, value_name = "N", default_value_t = 0.01)]
    amplitude: f64,
}

#[derive(Clone, Copy, ValueEnum)]
enum LossArg {
    L2,
    Huber,
    L1,
}

#[derive(Args)]
pub(super) struct StribeckArgs {
    /// CSV with velocity and force columns, e.g. `velocity_mm_per_s,force_N`.
    data: PathBuf,
    /// Robust fit (Huber loss) for data with outliers.
    #[arg(long, conflicts_with = "loss")]
    robust: bool,
    /// The loss to minimise.
    #[arg(long, value_enum)]
    loss: Option<LossArg>,
    /// Huber threshold, N (default: 1.345 robust residual scales of an L1 pilot fit).
    #[arg(long, value_name = "N")]
    huber_delta: Option<f64>,
    /// Also fit each velocity sign on its own and test whether they differ.
    #[arg(long)]
    asymmetric: bool,
    /// Accept data of one velocity sign only.
    #[arg(long, conflicts_with = "asymmetric")]
    one_sided: bool,
    /// An extra starting v_s, m/s (not needed: the search over v_s is global).
    #[arg(long, value_name = "M_PER_S")]
    v_s_start: Option<f64>,
    /// Unit of a velocity column named without one (m/s, mm/s, um/s).
    #[arg(long, value_name = "UNIT")]
    velocity_unit: Option<String>,
    /// Unit of a force column named without one (N, mN).
    #[arg(long, value_name = "UNIT")]
    force_unit: Option<String>,
    #[command(flatten)]
    output: OutputArgs,
}

#[derive(Args)]
pub(super) struct FrfArgs {
    /// CSV with a frequency column and re/im parts of G, or magnitude (and phase).
    data: PathBuf,
    /// Known moving mass m_t + m_b, kg.
    #[arg(long, value_name = "KG", conflicts_with = "fit_mass")]
    mass: Option<f64>,
    /// Fit the mass (the default when --mass is not given).
    #[arg(long)]
    fit_mass: bool,
    /// sigma2 from the Stribeck fit, N s/m: gives sigma1 = (sigma1 + sigma2) - sigma2.
    #[arg(long, value_name = "N_S_PER_M", conflicts_with = "sigma2_from")]
    sigma2: Option<f64>,
    /// 95% interval of --sigma2, as LO,HI (N s/m).
    #[arg(long, value_name = "LO,HI", requires = "sigma2")]
    sigma2_ci95: Option<String>,
    /// Take sigma2 and its interval from the fit.json of `identify stribeck`; the
    /// override then holds all six LuGre parameters.
    #[arg(long, value_name = "FIT_JSON")]
    sigma2_from: Option<PathBuf>,
    /// Fit the magnitude only, even if the file has a phase.
    #[arg(long)]
    magnitude_only: bool,
    /// Unit of a frequency column named without one (Hz, rad/s).
    #[arg(long, value_name = "UNIT")]
    freq_unit: Option<String>,
    /// Unit of a magnitude column named without one (m/N, um/N, nm/N, dB).
    #[arg(long, value_name = "UNIT")]
    mag_unit: Option<String>,
    /// Unit of a phase column named without one (deg, rad).
    #[arg(long, value_name = "UNIT")]
    phase_unit: Option<String>,
    /// Unit of real/imaginary part columns named without one (m/N, um/N, nm/N).
    #[arg(long, value_name = "UNIT")]
    response_unit: Option<String>,
    #[command(flatten)]
    output: OutputArgs,
}

/// `lo < hi`, both positive and finite, at least two points.
fn check_range(name: &str, lo: f64, hi: f64, points: usize) -> Result<()> {
    if !(lo > 0.0 && lo.is_finite() && hi.is_finite() && lo < hi) {
        bail!(
            "--{name}-min and --{name}-max must satisfy 0 < min < max, got {} and {}",
            fistage_model::rule::show(lo),
            fistage_model::rule::show(hi)
        );
    }
    if !(2..=MAX_LAB_POINTS).contains(&points) {
        bail!("--points must be from 2 to {MAX_LAB_POINTS}, got {points}");
    }
    Ok(())
}

pub(super) fn simulate_stribeck(args: &SimulateStribeckArgs) -> Result<()> {
    check_range("v", args.v_min, args.v_max, args.points)?;
    let common = &args.common;
    let stage = LabStage::load(&common.stage)?;
    let mut lab = StribeckLab::paper_like(args.points, common.seed);
    lab.speeds = log_spaced(args.v_min, args.v_max, args.points);
    if common.exact {
        lab = lab.exact();
    }
    let measured = lab.measure(&stage)?;
    let text = stribeck_csv(
        &measured.data,
        known_unit(Quantity::Velocity, "mm/s"),
        known_unit(Quantity::Force, "N"),
    );
    write_file(&common.out, &text)?;
    let p = stage.friction();
    println!(
        "wrote {} constant-velocity runs ({} to {} m/s, both directions) to {}",
        measured.data.len(),
        args.v_min,
        args.v_max,
        common.out.display()
    );
    println!(
        "true f_ss parameters of {} ({}): f_c = {} N, f_s = {} N, v_s = {} m/s, sigma2 = {} N s/m",
        stage.friction_name(),
        stage.source(),
        p.f_c,
        p.f_s,
        p.v_s,
        p.sigma2
    );
    Ok(())
}

pub(super) fn simulate_frf(args: &SimulateFrfArgs) -> Result<()> {
    check_range("f", args.f_min, args.f_max, args.points)?;
    if !(args.amplitude > 0.0 && args.amplitude.is_finite()) {
        bail!(
            "--amplitude must be a positive number, got {}",
            fistage_model::rule::show(args.amplitude)
        );
    }
    let common = &args.common;
    let stage = LabStage::load(&common.stage)?;
    let mut lab = FrfLab::paper_like(args.points, common.seed);
    lab.frequencies_hz = log_spaced(args.f_min, args.f_max, args.points);
    // Absolute tolerances follow the response amplitude.
    lab.tolerance.atol_scale *= args.amplitude / lab.force_amplitude;
    lab.force_amplitude = args.amplitude;
    if common.exact {
        lab = lab.exact();
    }
    let measured = lab.measure(&stage)?;
    let layout = FrfCsvLayout::MagnitudePhase(
        known_unit(Quantity::Magnitude, "dB"),
        known_unit(Quantity::Phase, "deg"),
    );
    let text = frf_csv(
        &measured.data,
        known_unit(Quantity::Frequency, "Hz"),
        layout,
    );
    write_file(&common.out, &text)?;
    let p = stage.friction();
    println!(
        "wrote {} frequencies ({} to {} Hz, force amplitude {} N) to {}",
        measured.data.len(),
        args.f_min,
        args.f_max,
        args.amplitude,
        common.out.display()
    );
    println!(
        "true pre-motion parameters of {} ({}): sigma0 = {} N/m, sigma1 = {} N s/m, \
         sigma2 = {} N s/m, moving mass = {} kg",
        stage.friction_name(),
        stage.source(),
        p.sigma0,
        p.sigma1,
        p.sigma2,
        stage.moving_mass()
    );
    Ok(())
}

/// A unit this program names itself.
fn known_unit(quantity: Quantity, name: &str) -> Unit {
    Unit::parse(quantity, name).unwrap_or_else(|| panic!("{name} is a {quantity} unit"))
}

/// Writes a data file whole or not at all (an earlier file stays on failure).
fn write_file(path: &Path, text: &str) -> Result<()> {
    fistage_model::output::write_whole(path, text.as_bytes())
        .with_context(|| format!("{}: cannot write", path.display()))
}

pub(super) fn run_stribeck(args: &StribeckArgs) -> Result<()> {
    check_element(&args.output)?;
    let units = UnitOverrides {
        velocity: unit_flag(Quantity::Velocity, &args.velocity_unit)?,
        force: unit_flag(Quantity::Force, &args.force_unit)?,
        ..UnitOverrides::default()
    };
    let data = read_stribeck_csv(&args.data, &units)?;
    let loss = match (args.robust, args.loss) {
        (true, _) => Loss::Huber,
        (false, Some(LossArg::Huber)) => Loss::Huber,
        (false, Some(LossArg::L1)) => Loss::L1,
        (false, Some(LossArg::L2) | None) => Loss::L2,
    };
    let options = StribeckOptions {
        loss,
        huber_delta: args.huber_delta,
        two_sided: !args.one_sided,
        v_s_start: args.v_s_start,
        ..StribeckOptions::default()
    };
    let source = data.source.clone();
    let (fit, asymmetric) = if args.asymmetric {
        let a = fit_stribeck_asymmetric(&data, &options)?;
        (a.symmetric.clone(), Some(a))
    } else {
        (fit_stribeck(&data, &options)?, None)
    };
    let report = StribeckReport::new(&source, &fit, asymmetric.as_ref());
    let json = serde_json::to_string_pretty(&report)?;
    let verdict = refuse_undetermined(&args.output, &report.not_identifiable);
    if let (Some(target), true) = (&args.output.out, verdict.is_ok()) {
        let folder = ResultFolder::begin(target, args.output.force)?;
        let dir = folder.path();
        write_outputs(
            dir,
            &json,
            &stribeck_override(&args.output.element, &report),
            &stribeck_data_vs_fit_csv(&data, &fit),
            &stribeck_curve_csv(&data, &fit, 400),
        )?;
        fistage_plot::figures::curve::write_stribeck(&data, &fit, asymmetric.as_ref(), dir)?;
        if !args.output.no_report {
            crate::report::write(dir, || {
                let plot =
                    fistage_plot::figures::curve::stribeck_plot(&data, &fit, asymmetric.as_ref());
                let plots = vec![fistage_report::plot::from_xy(&plot)];
                fistage_report::sections::identify::curve_section(
                    "identify stribeck",
                    &report,
                    plots,
                )
            })?;
        }
        folder.commit()?;
    }
    print_report(args.output.json, &json, &report.table());
    verdict.map_err(|e| nothing_written(e, &args.output))
}

pub(super) fn run_frf(args: &FrfArgs) -> Result<()> {
    check_element(&args.output)?;
    let units = UnitOverrides {
        frequency: unit_flag(Quantity::Frequency, &args.freq_unit)?,
        magnitude: unit_flag(Quantity::Magnitude, &args.mag_unit)?,
        phase: unit_flag(Quantity::Phase, &args.phase_unit)?,
        response: unit_flag(Quantity::RealPart, &args.response_unit)?,
        ..UnitOverrides::default()
    };
    let data = read_frf_csv(&args.data, &units)?;
    let stribeck = match &args.sigma2_from {
        Some(path) => Some(read_stribeck_report(path)?),
        None => None,
    };
    let options = FrfOptions {
        mass: match args.mass {
            Some(m) => MassOption::Known(m),
            None => MassOption::Fit,
        },
        sigma2: sigma2_input(args, stribeck.as_ref())?,
        use_phase: !args.magnitude_only,
        start: None,
    };
    let fit = fit_frf(&data, &options)?;
    let report = FrfReport::new(&data.source, &fit);
    let json = serde_json::to_string_pretty(&report)?;
    let verdict = refuse_undetermined(&args.output, &report.not_identifiable);
    if let (Some(target), true) = (&args.output.out, verdict.is_ok()) {
        let folder = ResultFolder::begin(target, args.output.force)?;
        let dir = folder.path();
        write_outputs(
            dir,
            &json,
            &frf_override(&args.output.element, &report, stribeck.as_ref()),
            &frf_data_vs_fit_csv(&data, &fit),
            &frf_curve_csv(&data, &fit, 400),
        )?;
        fistage_plot::figures::curve::write_frf(&data, &fit, dir)?;
        if !args.output.no_report {
            crate::report::write(dir, || {
                let (title, freq_hz, series) = fistage_plot::figures::curve::frf_bode(&data, &fit);
                let plots = fistage_report::plot::from_bode(&title, &freq_hz, &series);
                fistage_report::sections::identify::curve_section("identify frf", &report, plots)
            })?;
        }
        folder.commit()?;
    }
    print_report(args.output.json, &json, &report.table());
    verdict.map_err(|e| nothing_written(e, &args.output))
}

fn sigma2_input(args: &FrfArgs, stribeck: Option<&StribeckReport>) -> Result<Option<Sigma2Input>> {
    if let Some(report) = stribeck {
        return Ok(Some(Sigma2Input {
            value: report.sigma2.value,
            ci95: report.sigma2.ci95,
        }));
    }
    let Some(value) = args.sigma2 else {
        return Ok(None);
    };
    let ci95 = match &args.sigma2_ci95 {
        Some(text) => Some(parse_interval(text).context("--sigma2-ci95")?),
        None => None,
    };
    Ok(Some(Sigma2Input { value, ci95 }))
}

fn parse_interval(text: &str) -> Result<[f64; 2]> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [lo, hi] = parts.as_slice() else {
        bail!("expected LO,HI, got '{text}'");
    };
    let number = |s: &str| {
        s.parse::<f64>()
            .with_context(|| format!("'{s}' is not a number"))
    };
    Ok([number(lo)?, number(hi)?])
}

/// The fit.json written by `identify stribeck --out`.
fn read_stribeck_report(path: &Path) -> Result<StribeckReport> {
    let text = fistage_model::input::read_text(path, fistage_model::input::MAX_DESCRIPTION_BYTES)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let report: StribeckReport = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not the fit.json of `fistage identify stribeck`",
            path.display()
        )
    })?;
    if report.kind != "stribeck" {
        bail!(
            "{}: a '{}' report, not the fit.json of `fistage identify stribeck`",
            path.display(),
            report.kind
        );
    }
    Ok(report)
}

/// Writes the result files into `dir` (a staging folder of [`ResultFolder`]).
fn write_outputs(
    dir: &Path,
    json: &str,
    override_toml: &str,
    data_csv: &str,
    curve_csv: &str,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for (name, text) in [
        ("fit.json", format!("{json}\n")),
        ("override.toml", override_toml.to_string()),
        ("data_vs_fit.csv", data_csv.to_string()),
        ("fit_curve.csv", curve_csv.to_string()),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}
