//! `fistage compare CASE... [--baseline FILE] [--metric NAME] [--out DIR]`:
//! tracking of several scenarios over the `[sweep]` grid of the first,
//! against an optional baseline (the paper's Fig. 3 studies). Writes
//! `points.csv` (a row per case and point: `case`, a column per axis, then
//! `rms_error`, `peak_error`, `peak_error_std`, `settling_time`,
//! `settling_time_std`, `unsettled_steps`), `curves.csv` and `summary.json`
//! (per case and first-axis value: the metric's mean and spread, the
//! reduction against the baseline in percent), and plots of both. Journal,
//! resume, shards and merge follow `fistage_analysis::study`.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use fistage_analysis::compare::{Case, CompareRow, Comparison, Curve, Metric};
use fistage_analysis::sweep::SweepSpec;
use fistage_model::RobotSpec;

use fistage_analysis::study::{Provenance, write_table};

use crate::study::{self, StudyArgs};

/// Arguments of `fistage compare`.
#[derive(clap::Args)]
pub struct CompareArgs {
    /// Scenario files, one per case; the first one's [sweep] axes are the grid.
    #[arg(required = true)]
    pub cases: Vec<PathBuf>,
    /// The scenario every case is compared with (run on the axes it has).
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// What the curves show: peak_error (the reversal peak, default for
    /// circles and other references), settling_time (default for
    /// staircases) or rms_error.
    #[arg(long)]
    pub metric: Option<String>,
    /// Output folder (default: out/<first case>-compare).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Shards, merging, threads, resume.
    #[command(flatten)]
    pub study: StudyArgs,
    /// Skip the HTML page (report.html).
    #[arg(long)]
    pub no_report: bool,
}

/// The case of a scenario file.
fn case_of(
    path: &Path,
    grid: &[fistage_analysis::sweep::Axis],
    baseline: bool,
) -> anyhow::Result<Case> {
    let loaded = fistage_model::load(path)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().replace(',', "_"))
        .unwrap_or_default();
    Ok(Case::new(name, loaded, robot_file, grid, baseline)?)
}

/// Runs the command.
pub fn run(args: &CompareArgs) -> anyhow::Result<()> {
    let first = fistage_model::load(&args.cases[0])?;
    let axes = match first.scenario.sweep {
        Some(_) => {
            let spec = SweepSpec::from_scenario(&first.scenario)?;
            let robot_file = RobotSpec::from_file(&first.scenario.robot)?;
            spec.check_against(&first.scenario, &robot_file)?;
            spec.axes
        }
        None => Vec::new(),
    };
    let mut cases = Vec::new();
    if let Some(baseline) = &args.baseline {
        cases.push(case_of(baseline, &axes, true)?);
    }
    for path in &args.cases {
        cases.push(case_of(path, &axes, false)?);
    }
    for (i, case) in cases.iter().enumerate() {
        if let Some(other) = cases[..i].iter().find(|c| c.name == case.name) {
            bail!(
                "two cases are named \"{}\" (cases are named by their file names): rename one file",
                other.name
            );
        }
        if case.loaded.scenario.controller.is_none() {
            bail!(
                "{}: has no [controller], so it tracks nothing to compare",
                case.loaded.scenario.file.display()
            );
        }
    }
    let metric = match &args.metric {
        Some(name) => Metric::from_name(name).with_context(|| {
            format!("--metric must be peak_error, settling_time or rms_error, got \"{name}\"")
        })?,
        None => Metric::for_reference(&first.scenario.reference),
    };
    let comparison = Comparison {
        axes,
        cases,
        has_baseline: args.baseline.is_some(),
        metric,
    };
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| fistage_model::output::default_folder(&args.cases[0], "compare"));
    let mut provenance = Provenance::of_study(
        "compare",
        (&first.scenario.file, None),
        &first.scenario.robot,
        &format!("{:?}", comparison.axes),
        &format!("metric {}", metric.name()),
        args.study.shard()?,
    )?;
    for case in &comparison.cases {
        provenance = provenance
            .with_file(
                &format!("case {} scenario", case.name),
                &case.loaded.scenario.file,
            )?
            .with_file(
                &format!("case {} robot", case.name),
                &case.loaded.scenario.robot,
            )?;
    }
    let (folder, rows) = study::gather(&comparison, &args.study, &out_dir, &provenance)?;
    write_table(&comparison, &rows, &folder)?;
    let curves = comparison.curves(&rows);
    write_curves(&comparison, &curves, folder.path())?;
    let pictures = fistage_plot::figures::compare::write(&comparison, &curves, folder.path())?;
    if !args.no_report {
        crate::report::write(folder.path(), || {
            fistage_report::sections::compare::section(&comparison, &curves)
        })?;
    }
    folder.commit()?;
    report(&comparison, &rows, &curves, &out_dir, &pictures);
    let missing: usize = curves.iter().flat_map(|c| &c.missing).sum();
    if missing > 0 {
        bail!(
            "{missing} of {} points gave no {} (a failed run, no velocity reversal, or a step that never settled): the curve values they belong to are left empty",
            rows.len(),
            comparison.metric.name()
        );
    }
    Ok(())
}

fn write_curves(comparison: &Comparison, curves: &[Curve], out_dir: &Path) -> anyhow::Result<()> {
    let path = out_dir.join("curves.csv");
    std::fs::write(&path, comparison.curves_csv(curves))
        .with_context(|| format!("cannot write {}", path.display()))?;
    let path = out_dir.join("summary.json");
    let summary = serde_json::to_string_pretty(&comparison.curves_summary(curves))? + "\n";
    std::fs::write(&path, summary).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

fn report(
    comparison: &Comparison,
    rows: &[CompareRow],
    curves: &[Curve],
    out_dir: &Path,
    pictures: &[String],
) {
    let failed: Vec<&CompareRow> = rows.iter().filter(|r| r.metrics.is_none()).collect();
    println!(
        "{} of {} points in {}/points.csv, curves in curves.csv, plots {}",
        rows.len(),
        comparison.len(),
        out_dir.display(),
        pictures.join(", ")
    );
    for row in failed.iter().take(5) {
        println!(
            "  {} at {:?}: no metrics ({})",
            comparison.cases[row.case].name,
            row.values,
            row.failure.as_deref().unwrap_or("not computed")
        );
    }
    let metric = comparison.metric;
    for curve in curves {
        let is_baseline = comparison.has_baseline && curve.case == 0;
        println!(
            "{}{}:",
            comparison.cases[curve.case].name,
            if is_baseline { " (baseline)" } else { "" }
        );
        for i in 0..curve.x.len() {
            let reduction = (curve.reduction_mean.get(i))
                .filter(|_| !is_baseline)
                .map(|r| match curve.reduction_std[i] {
                    s if s.is_finite() => format!(", reduction {r:.1} +- {s:.1} %"),
                    _ if r.is_finite() => format!(", reduction {r:.1} %"),
                    _ => ", no reduction (baseline 0 or missing)".into(),
                })
                .unwrap_or_default();
            let missing = if curve.missing[i] > 0 {
                format!(
                    " ({} of {} points without a value)",
                    curve.missing[i],
                    curve.missing[i] + curve.points[i]
                )
            } else {
                String::new()
            };
            println!(
                "  {} = {:.4e}: {} {:.4e} +- {:.2e} {}{reduction}{missing}",
                comparison.x_label(),
                curve.x[i],
                metric.name(),
                curve.mean[i],
                curve.std[i],
                metric.unit()
            );
        }
    }
}
