//! `fistage identify`: LuGre identification from lab CSV files.
//!
//! ```text
//! fistage identify stribeck DATA.csv [--robust] [--asymmetric] [--json] [--out DIR]
//! fistage identify frf DATA.csv [--mass M | --fit-mass] [--sigma2 S] [--json] [--out DIR]
//! ```
//!
//! Prints a table (or the JSON report with `--json`); with `--out DIR` also writes
//! `fit.json`, `override.toml` (a `[overrides.<element>]` block a scenario can
//! include) and `data_vs_fit.csv` / `fit_curve.csv` for plotting. Nothing is
//! written unless the fit succeeds.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use fistage_ident::report::{
    DEFAULT_ELEMENT, frf_curve_csv, frf_data_vs_fit_csv, stribeck_curve_csv,
    stribeck_data_vs_fit_csv,
};
use fistage_ident::{
    FrfOptions, FrfReport, Loss, MassOption, Quantity, Sigma2Input, StribeckOptions,
    StribeckReport, Unit, UnitOverrides, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
    frf_override, read_frf_csv, read_stribeck_csv, stribeck_override,
};

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
}

/// Output options shared by both fits.
#[derive(Args)]
struct OutputArgs {
    /// Print the JSON report instead of the table.
    #[arg(long)]
    json: bool,
    /// Write fit.json, override.toml, data_vs_fit.csv and fit_curve.csv into DIR.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Friction element that override.toml applies to.
    #[arg(long, value_name = "NAME", default_value = DEFAULT_ELEMENT)]
    element: String,
}

#[derive(Clone, Copy, ValueEnum)]
enum LossArg {
    L2,
    Huber,
    L1,
}

#[derive(Args)]
struct StribeckArgs {
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
struct FrfArgs {
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

/// Runs the identification command.
pub fn run(args: &IdentifyArgs) -> Result<()> {
    match &args.fit {
        IdentifyCommand::Stribeck(a) => run_stribeck(a),
        IdentifyCommand::Frf(a) => run_frf(a),
    }
}

fn run_stribeck(args: &StribeckArgs) -> Result<()> {
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
    if let Some(dir) = &args.output.out {
        write_outputs(
            dir,
            &json,
            &stribeck_override(&args.output.element, &report),
            &stribeck_data_vs_fit_csv(&data, &fit),
            &stribeck_curve_csv(&data, &fit, 400),
        )?;
    }
    print_report(args.output.json, &json, &report.table());
    Ok(())
}

fn run_frf(args: &FrfArgs) -> Result<()> {
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
    if let Some(dir) = &args.output.out {
        write_outputs(
            dir,
            &json,
            &frf_override(&args.output.element, &report, stribeck.as_ref()),
            &frf_data_vs_fit_csv(&data, &fit),
            &frf_curve_csv(&data, &fit, 400),
        )?;
    }
    print_report(args.output.json, &json, &report.table());
    Ok(())
}

fn print_report(json: bool, json_text: &str, table: &str) {
    if json {
        println!("{json_text}");
    } else {
        print!("{table}");
    }
}

/// The unit given by a `--*-unit` flag, checked against its quantity.
fn unit_flag(quantity: Quantity, flag: &Option<String>) -> Result<Option<Unit>> {
    let Some(text) = flag else {
        return Ok(None);
    };
    match Unit::parse(quantity, text) {
        Some(unit) => Ok(Some(unit)),
        None => bail!(
            "{}: '{text}' is not a {quantity} unit (known: {})",
            quantity.unit_flag(),
            quantity.known_units()
        ),
    }
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
    let text = std::fs::read_to_string(path)
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

/// Writes the result files into `dir` (created if needed).
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use fistage_ident::synth::{
        FrfCsvLayout, FrfSynth, StribeckSynth, frf_csv, stribeck_csv, unit,
    };
    use fistage_model::LugreParams;

    #[derive(Parser)]
    struct TestCli {
        #[command(subcommand)]
        command: TestCommand,
    }

    #[derive(Subcommand)]
    enum TestCommand {
        Identify(IdentifyArgs),
    }

    fn parse(line: &str) -> std::result::Result<IdentifyArgs, clap::Error> {
        let words = std::iter::once("fistage").chain(line.split_whitespace());
        TestCli::try_parse_from(words).map(|cli| match cli.command {
            TestCommand::Identify(args) => args,
        })
    }

    /// A fresh scratch folder for one test.
    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fistage-identify-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn flags_parse_and_conflict() {
        assert!(parse("identify stribeck d.csv --robust --asymmetric --json --element rl").is_ok());
        assert!(parse("identify frf d.csv --mass 1.5 --sigma2 14.2 --json").is_ok());
        assert!(parse("identify frf d.csv --fit-mass").is_ok());
        assert!(parse("identify frf d.csv --mass 1.5 --fit-mass").is_err());
        assert!(parse("identify stribeck d.csv --robust --loss l1").is_err());
        assert!(parse("identify stribeck d.csv --asymmetric --one-sided").is_err());
        assert!(parse("identify frf d.csv --sigma2-ci95 1,2").is_err());
    }

    #[test]
    fn stribeck_then_frf_write_their_files() {
        let dir = scratch("chain");
        let p = LugreParams::paper_table1();
        let fss = dir.join("fss.csv");
        let data = StribeckSynth::noisy(p, 5).generate();
        let text = stribeck_csv(
            &data,
            unit(Quantity::Velocity, "mm/s"),
            unit(Quantity::Force, "N"),
        );
        std::fs::write(&fss, text).unwrap();
        let out_s = dir.join("stribeck");
        let line = format!(
            "identify stribeck {} --asymmetric --out {}",
            fss.display(),
            out_s.display()
        );
        run(&parse(&line).unwrap()).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out_s.join("fit.json")).unwrap())
                .unwrap();
        let f_c = json["f_c"]["value"].as_f64().unwrap();
        assert!((f_c / p.f_c - 1.0).abs() < 0.02, "{json}");
        assert_eq!(json["asymmetry"]["significant"], false);
        for name in ["override.toml", "data_vs_fit.csv", "fit_curve.csv"] {
            assert!(out_s.join(name).is_file(), "{name}");
        }

        let frf = dir.join("frf.csv");
        let data = FrfSynth::noisy(&p, 1.5, 5).generate();
        let layout = FrfCsvLayout::MagnitudePhase(
            unit(Quantity::Magnitude, "dB"),
            unit(Quantity::Phase, "deg"),
        );
        std::fs::write(
            &frf,
            frf_csv(&data, unit(Quantity::Frequency, "Hz"), layout),
        )
        .unwrap();
        let out_f = dir.join("frf");
        let line = format!(
            "identify frf {} --mass 1.5 --sigma2-from {} --element bearing_rl --out {}",
            frf.display(),
            out_s.join("fit.json").display(),
            out_f.display()
        );
        run(&parse(&line).unwrap()).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out_f.join("fit.json")).unwrap())
                .unwrap();
        let sigma1 = json["sigma1"]["value"].as_f64().unwrap();
        assert!((sigma1 / p.sigma1 - 1.0).abs() < 0.05, "{json}");
        let toml = std::fs::read_to_string(out_f.join("override.toml")).unwrap();
        assert!(toml.contains("[overrides.bearing_rl]"), "{toml}");
        for key in [
            "sigma0 =", "sigma1 =", "f_c =", "f_s =", "v_s =", "sigma2 =",
        ] {
            assert!(toml.contains(key), "{toml}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_failed_fit_writes_nothing() {
        let dir = scratch("fail");
        let bad = dir.join("bad.csv");
        std::fs::write(&bad, "velocity_mm_per_s,force_N\n1,6.4\n2,x\n").unwrap();
        let out = dir.join("out");
        let line = format!(
            "identify stribeck {} --out {}",
            bad.display(),
            out.display()
        );
        let message = run(&parse(&line).unwrap()).unwrap_err().to_string();
        assert!(
            message.contains("bad.csv: line 3 (data row 2), column 'force_N'"),
            "{message}"
        );
        assert!(!out.exists());
        let line = format!(
            "identify stribeck {} --velocity-unit furlong/s",
            bad.display()
        );
        let message = run(&parse(&line).unwrap()).unwrap_err().to_string();
        assert!(
            message.contains("--velocity-unit: 'furlong/s' is not a velocity unit"),
            "{message}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
