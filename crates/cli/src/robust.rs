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
use fistage_analysis::robust::{RobustSpec, RobustStudy, Summary};
use fistage_analysis::study::write_table;
use fistage_model::RobotSpec;

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
    /// Skip the HTML page (report.html).
    #[arg(long)]
    pub no_report: bool,
}

/// Runs the command.
pub fn run(args: &RobustArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    let spec = RobustSpec::from_scenario(&loaded.scenario, &robot_file, args.samples, args.seed)?;
    if let Some(stages) = spec.fitted.as_ref().and_then(|f| f.distinct_stages()) {
        eprintln!(
            "warning: {}: from_fit_draw = \"replicates\" draws {stages} distinct stages (the fit's \
             replicates): P is resolved no finer than 1/{stages}, whatever the samples",
            args.scenario.display()
        );
    }
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
    fistage_plot::figures::robust::write(&spec, &results, &summary, folder.path())?;
    if !args.no_report {
        crate::report::write(folder.path(), || {
            fistage_report::sections::robust::section(&loaded, &spec, &results, &summary)
        })?;
    }
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
