//! `fistage tune SCENARIO`: servo gains (k, c) with the largest bandwidth
//! that keep every stage of the scenario's `[robust]` population linearly
//! stable with a margin (`--margin`, 1/s), or P(unstable) below a target
//! (`--p-target`, on the upper end of its Wilson interval); see
//! `fistage_analysis::robust::tune`. Prints the gains and the margin, and
//! writes `tune.json`, `region.csv` (the worst largest real part over the
//! population on the (k, c) grid) and the map of the admissible region.

use std::path::PathBuf;

use anyhow::{Context, bail};
use fistage_analysis::robust::RobustSpec;
use fistage_analysis::robust::tune::{Criterion, Population, TuneSettings, Tuning, tune};
use fistage_model::RobotSpec;

use crate::progress;
use fistage_model::output::ResultFolder;

/// Arguments of `fistage tune`.
#[derive(clap::Args)]
pub struct TuneArgs {
    /// Scenario file with a [robust] table (the population) and a [controller].
    pub scenario: PathBuf,
    /// Members of the population (the first of the table's design).
    #[arg(long, default_value_t = 256)]
    pub samples: usize,
    /// Seed of the design (default: the table's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Range of k searched, N/m, as LOW,HIGH.
    #[arg(long, value_delimiter = ',', default_values_t = [1e3, 1e7])]
    pub k_range: Vec<f64>,
    /// Range of c searched, N s/m, as LOW,HIGH.
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 1e4])]
    pub c_range: Vec<f64>,
    /// Grid values per gain.
    #[arg(long, default_value_t = 24)]
    pub points: usize,
    /// Every stage's largest real part at most -MARGIN, 1/s.
    #[arg(long, default_value_t = 0.0)]
    pub margin: f64,
    /// Instead of every stage: the upper 95% bound of P(unstable) at most this.
    #[arg(long)]
    pub p_target: Option<f64>,
    /// Output folder (default: out/<scenario>-tune).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Replace an output folder holding an earlier result.
    #[arg(long)]
    pub force: bool,
    /// Skip the HTML page (report.html).
    #[arg(long)]
    pub no_report: bool,
}

/// A gain range: LOW,HIGH with 0 < LOW < HIGH, each end a value the gains'
/// rule of the parameter table admits (so every gain searched, and the one
/// recommended, is one `fistage check` accepts).
fn range(name: &str, values: &[f64]) -> anyhow::Result<[f64; 2]> {
    let shown: Vec<String> = values
        .iter()
        .map(|v| fistage_model::rule::show(*v))
        .collect();
    let [lo, hi] = match values {
        [lo, hi] if lo.is_finite() && hi.is_finite() && *lo > 0.0 && hi > lo => [*lo, *hi],
        _ => bail!(
            "--{name} must be LOW,HIGH with 0 < LOW < HIGH, got {}",
            shown.join(",")
        ),
    };
    for end in [lo, hi] {
        if let Err(violation) = fistage_model::scenario::Gain::RULE.check(end) {
            bail!("--{name}: a gain {violation}");
        }
    }
    Ok([lo, hi])
}

fn settings(args: &TuneArgs) -> anyhow::Result<TuneSettings> {
    if !(2..=200).contains(&args.points) {
        bail!("--points must be from 2 to 200, got {}", args.points);
    }
    if !(args.margin.is_finite() && args.margin >= 0.0) {
        bail!(
            "--margin must be >= 0 (1/s), got {}",
            fistage_model::rule::show(args.margin)
        );
    }
    let criterion = match args.p_target {
        Some(p) if p > 0.0 && p < 1.0 => Criterion::Probability(p),
        Some(p) => bail!(
            "--p-target must be between 0 and 1, got {}",
            fistage_model::rule::show(p)
        ),
        None => Criterion::Margin(args.margin),
    };
    Ok(TuneSettings {
        k_range: range("k-range", &args.k_range)?,
        c_range: range("c-range", &args.c_range)?,
        points: args.points,
        criterion,
    })
}

/// Runs the command.
pub fn run(args: &TuneArgs) -> anyhow::Result<()> {
    let settings = settings(args)?;
    if args.samples == 0 {
        bail!("--samples must be at least 1");
    }
    let loaded = fistage_model::load(&args.scenario)?;
    if loaded.scenario.controller.is_none() {
        bail!("{}: tune needs a [controller]", args.scenario.display());
    }
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    let spec =
        RobustSpec::from_scenario(&loaded.scenario, &robot_file, Some(args.samples), args.seed)?;
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| fistage_model::output::default_folder(&args.scenario, "tune"));
    let folder = ResultFolder::begin(&out_dir, args.force)?;
    let population = Population::draw(&spec, &loaded, &robot_file, args.samples);
    if population.is_empty() {
        bail!(
            "{}: the model refused every drawn stage",
            args.scenario.display()
        );
    }
    let bar = progress::bar("tune: population on the (k, c) grid");
    let tuning = tune(&population, &loaded, &robot_file, &settings, &|f| {
        progress::set_fraction(&bar, f)
    });
    bar.finish_and_clear();
    write(&tuning, folder.path())?;
    if !args.no_report {
        crate::report::write(folder.path(), || {
            fistage_report::sections::tune::section(&loaded, &tuning)
        })?;
    }
    folder.commit()?;
    report(&tuning, &out_dir);
    Ok(())
}

fn write(tuning: &Tuning, dir: &std::path::Path) -> anyhow::Result<()> {
    let json = dir.join("tune.json");
    std::fs::write(&json, serde_json::to_string_pretty(tuning)? + "\n")
        .with_context(|| format!("cannot write {}", json.display()))?;
    let path = dir.join("region.csv");
    std::fs::write(&path, tuning.region_csv())
        .with_context(|| format!("cannot write {}", path.display()))?;
    fistage_plot::figures::tune::write(tuning, dir)?;
    Ok(())
}

fn report(tuning: &Tuning, out_dir: &std::path::Path) {
    let what = match tuning.criterion {
        Criterion::Margin(m) => format!(
            "every one of {} stages stable with margin {m} 1/s",
            tuning.members
        ),
        Criterion::Probability(p) => format!(
            "P(unstable) below {p} (95% upper bound) over {} stages",
            tuning.members
        ),
    };
    match (tuning.gains, tuning.standing, tuning.bandwidth_hz) {
        (Some([k, c]), Some(s), Some(bandwidth)) => {
            println!("gains for {what}: k = {k:.6e} N/m, c = {c:.6e} N s/m");
            if let Some(k_i) = tuning.k_i {
                println!("integral gain: up to k_i = {k_i:.6e} N/(m s) at these k and c");
            }
            println!(
                "bandwidth sqrt(k/M)/2pi = {bandwidth:.2} Hz (M = {:.4} kg); worst largest real part {:.4e} 1/s, {} of {} unstable",
                tuning.moving_mass, s.worst_max_real_eig, s.unstable, s.members
            );
        }
        _ => {
            println!("no gains in the searched range give {what}");
            for remedy in &tuning.remedies {
                match (remedy.factor, remedy.gains) {
                    (Some(f), Some([k, c])) => println!(
                        "  {} x {f:.3} would make it safe (at k = {k:.3e} N/m, c = {c:.3e} N s/m)",
                        remedy.what
                    ),
                    _ => println!("  {}: no factor from 1/64 to 1024 suffices", remedy.what),
                }
            }
        }
    }
    println!(
        "wrote tune.json, region.csv and region.svg/.png in {}",
        out_dir.display()
    );
}
