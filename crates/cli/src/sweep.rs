//! `fistage sweep SCENARIO [--out DIR] [--shard i/n] [--merge DIR ...]`: run the
//! scenario's `[sweep]` grid in parallel with a progress bar, write
//! `points.csv` (a column per axis, then `stable_linear`, `stable_sim`,
//! `amplitude`, `max_real_eig`, `bistable`), `points.json`, and a stability
//! map. Journal, resume, shards and merge follow `fistage_analysis::study`.

use std::path::PathBuf;

use anyhow::Context;
use fistage_analysis::study::write_table;
use fistage_analysis::sweep::{PointResult, SweepSpec, SweepStudy};
use fistage_model::RobotSpec;

use crate::study::{self, StudyArgs};

/// Arguments of `fistage sweep`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Scenario file with a [sweep] table.
    pub scenario: PathBuf,
    /// Output folder (default: out/<scenario>-sweep).
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
pub fn run(args: &SweepArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    let spec = SweepSpec::from_scenario(&loaded.scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    spec.check_against(&loaded.scenario, &robot_file)?;
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| fistage_model::output::default_folder(&args.scenario, "sweep"));
    let grid = SweepStudy {
        loaded: &loaded,
        robot_file: &robot_file,
        spec: &spec,
    };
    let provenance = grid.provenance(None, args.study.shard()?)?;
    let (folder, results) = study::gather(&grid, &args.study, &out_dir, &provenance)?;
    write_table(&grid, &results, &folder)?;
    let json_path = folder.path().join("points.json");
    std::fs::write(&json_path, grid.points_json(&results))
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    let pictures = fistage_plot::figures::sweep::write(
        &fistage_plot::figures::title(&loaded),
        &spec,
        &results,
        folder.path(),
    )?;
    if !args.no_report {
        crate::report::write(folder.path(), || {
            fistage_report::sections::sweep::section(&loaded, &spec, &results)
        })?;
    }
    folder.commit()?;
    let missing = spec.len() - results.len();
    println!(
        "{} of {} points in {}/points.csv{}{}",
        results.len(),
        spec.len(),
        out_dir.display(),
        if missing > 0 {
            format!(" ({missing} not computed here)")
        } else {
            String::new()
        },
        if pictures.is_empty() {
            String::new()
        } else {
            format!(", map in {}", pictures.join(", "))
        }
    );
    summarize(&results);
    Ok(())
}

fn summarize(results: &[PointResult]) {
    let count = |f: &dyn Fn(&PointResult) -> bool| results.iter().filter(|r| f(r)).count();
    println!(
        "linear: {} stable, {} unstable, {} undetermined; simulation: {} stable, {} oscillating; {} bistable",
        count(&|r| r.stable_linear == Some(true)),
        count(&|r| r.stable_linear == Some(false)),
        // Analysed (a largest real part exists) without a verdict the numerics back.
        count(&|r| r.stable_linear.is_none() && r.max_real_eig.is_some()),
        count(&|r| r.stable_sim == Some(true)),
        count(&|r| r.stable_sim == Some(false)),
        count(&|r| r.bistable == Some(true)),
    );
}
