//! `fistage robust SCENARIO [--samples N] [--seed S] [--out DIR] [--shard i/n]
//! [--merge DIR ...]`: a tolerance analysis of the scenario's `[robust]`
//! table (see `fistage_analysis::robust`). Writes `samples.csv` (one row per
//! sample: every drawn value, then verdicts and metrics), `summary.json`
//! (`p_unstable_linear`, `p_oscillating` with Wilson 95% intervals, quantiles,
//! the sensitivity ranking) and plots: the histogram of the largest real part
//! with zero marked, the probability of instability against each parameter,
//! and the sensitivity ranking. Journal, resume, shards and merge follow
//! `fistage_analysis::study`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fistage_analysis::robust::{RobustSpec, RobustStudy, SampleResult, Summary};
use fistage_analysis::study::write_table;
use fistage_model::RobotSpec;
use fistage_plot::{Series, XyPlot, write_xy};

use crate::study::{self, StudyArgs};

/// Arguments of `fistage robust`.
#[derive(clap::Args)]
pub struct RobustArgs {
    /// Scenario file with a [robust] table.
    pub scenario: PathBuf,
    /// Samples (default: the table's `samples`, else 1000).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of the design (default: the table's `seed`, else 0).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output folder (default: out/<scenario>-robust).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Shards, merging, threads, resume.
    #[command(flatten)]
    pub study: StudyArgs,
}

/// Runs the command.
pub fn run(args: &RobustArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    let spec = RobustSpec::from_scenario(&loaded.scenario, &robot_file, args.samples, args.seed)?;
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| fistage_model::output::default_folder(&args.scenario, "robust"));
    let population = RobustStudy {
        loaded: &loaded,
        robot_file: &robot_file,
        spec: &spec,
    };
    let provenance = population.provenance(None, args.study.shard()?)?;
    let (folder, results) = study::gather(&population, &args.study, &out_dir, &provenance)?;
    write_table(&population, &results, &folder)?;
    let summary = Summary::of(&spec, &results);
    let json = folder.path().join("summary.json");
    std::fs::write(&json, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("cannot write {}", json.display()))?;
    draw(&spec, &results, &summary, folder.path())?;
    folder.commit()?;
    report(&summary, &out_dir);
    Ok(())
}

fn report(summary: &Summary, out_dir: &Path) {
    println!(
        "{} of {} samples in {}/samples.csv",
        summary.computed,
        summary.samples,
        out_dir.display()
    );
    let show = |name: &str, p: &fistage_analysis::robust::Probability| {
        println!(
            "{name}: {:.4} (95% interval {:.4} to {:.4}, n = {})",
            p.estimate, p.ci95[0], p.ci95[1], p.n
        );
    };
    if let Some(p) = &summary.p_unstable_linear {
        show("P(linearly unstable)", p);
    }
    if let Some(p) = &summary.p_oscillating {
        show("P(oscillating)", p);
    }
    if summary.undetermined_simulated > 0 {
        println!(
            "{} samples without a simulated verdict (still decaying after the longest run, or a failed run: see samples.csv)",
            summary.undetermined_simulated
        );
    }
    if summary.undetermined_linear + summary.refused > 0 {
        println!(
            "{} samples without a linear verdict the numerics back, {} stages the model refused (see samples.csv)",
            summary.undetermined_linear, summary.refused
        );
    }
    if let Some(top) = summary.sensitivity.first() {
        println!("matters most: {} (index {:.3})", top.parameter, top.index);
    }
}

/// A histogram as a step line: (edges, counts) drawn as x, y.
fn histogram(values: &[f64], bins: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let width = if hi > lo {
        (hi - lo) / bins as f64
    } else {
        1.0
    };
    let mut counts = vec![0.0; bins];
    for &v in values {
        counts[(((v - lo) / width) as usize).min(bins - 1)] += 1.0;
    }
    let (mut x, mut y) = (vec![lo], vec![0.0]);
    for (k, &c) in counts.iter().enumerate() {
        let (a, b) = (lo + k as f64 * width, lo + (k + 1) as f64 * width);
        x.extend([a, b]);
        y.extend([c, c]);
    }
    x.push(lo + bins as f64 * width);
    y.push(0.0);
    Some((x, y))
}

/// P(unstable) in ten equal-count bins of one parameter, against the bin's
/// mean deviation from the sample mean in sample standard deviations.
fn probability_curve(results: &[SampleResult], column: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let mut pairs: Vec<(f64, bool)> = results
        .iter()
        .filter_map(|r| {
            Some((
                r.values[column],
                r.outcome.stable_linear.or(r.outcome.stable_sim)?,
            ))
        })
        .collect();
    if pairs.len() < 20 {
        return None;
    }
    let n = pairs.len() as f64;
    let mean = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let sd = (pairs.iter().map(|p| (p.0 - mean).powi(2)).sum::<f64>() / n).sqrt();
    if sd == 0.0 {
        return None;
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let bins = 10;
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for chunk in pairs.chunks(pairs.len().div_ceil(bins)) {
        let m = chunk.len() as f64;
        x.push((chunk.iter().map(|p| p.0).sum::<f64>() / m - mean) / sd);
        y.push(chunk.iter().filter(|p| !p.1).count() as f64 / m);
    }
    Some((x, y))
}

fn draw(
    spec: &RobustSpec,
    results: &[SampleResult],
    summary: &Summary,
    out_dir: &Path,
) -> anyhow::Result<()> {
    let write = |plot: &XyPlot, stem: &str| -> anyhow::Result<()> {
        for extension in ["svg", "png"] {
            let name = format!("{stem}.{extension}");
            write_xy(plot, &out_dir.join(&name)).with_context(|| format!("cannot draw {name}"))?;
        }
        Ok(())
    };
    let eig: Vec<f64> = results
        .iter()
        .filter_map(|r| r.outcome.max_real_eig)
        .collect();
    if let Some((x, y)) = histogram(&eig, 40) {
        let top = y.iter().copied().fold(0.0, f64::max);
        let plot = XyPlot::new(
            format!("largest real part over {} samples", eig.len()),
            "max Re(lambda) [1/s]",
            "samples",
            vec![
                Series::line("samples", x, y),
                Series::line("zero: stable to the left", vec![0.0, 0.0], vec![0.0, top]),
            ],
        );
        write(&plot, "max_real_eig_histogram")?;
    }
    let columns = spec.columns();
    let curves: Vec<Series> = summary
        .sensitivity
        .iter()
        .take(8)
        .filter_map(|s| {
            let column = columns.iter().position(|t| t.path == s.parameter)?;
            let (x, y) = probability_curve(results, column)?;
            Some(Series::line_and_markers(s.parameter.clone(), x, y))
        })
        .collect();
    if !curves.is_empty() {
        let plot = XyPlot::new(
            "probability of instability against each parameter",
            "parameter's deviation from its sample mean [sample sd]",
            "P(unstable) in the bin",
            curves,
        );
        write(&plot, "probability_by_parameter")?;
    }
    let bars: Vec<Series> = summary
        .sensitivity
        .iter()
        .enumerate()
        .map(|(rank, s)| {
            let x = (rank + 1) as f64;
            Series::line_and_markers(s.parameter.clone(), vec![x, x], vec![0.0, s.index])
        })
        .collect();
    if !bars.is_empty() {
        let plot = XyPlot::new(
            "which tolerance matters most",
            "rank",
            summary.sensitivity_method,
            bars,
        );
        write(&plot, "sensitivity")?;
    }
    Ok(())
}
