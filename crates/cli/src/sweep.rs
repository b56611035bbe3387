//! `fistage sweep SCENARIO [--out DIR] [--shard i/n] [--merge DIR ...]`: run the
//! scenario's `[sweep]` grid in parallel with a progress bar, write
//! `points.csv` (a column per axis, then `stable_linear`, `stable_sim`,
//! `amplitude`, `max_real_eig`, `bistable`), `points.json`, and a stability
//! map. The result is staged in `.<name>.journal` beside the output folder and
//! moved into place whole when complete. Finished points are appended to the
//! journal's `points.partial.csv` as they come, so a killed sweep resumes
//! where it stopped; so does a sweep into a folder holding points of the same
//! sweep (another shard, say). A folder holding other work is replaced only
//! with `--force`. `--shard i/n` computes every n-th point starting at i (for
//! batch job arrays) and `--merge` joins shard folders.

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, bail};
use fistage_analysis::sweep::{
    Analyses, PointResult, Spacing, SweepSpec, header, read_rows, row, run_points,
};
use fistage_model::RobotSpec;
use fistage_plot::{ColourScale, Heatmap, Series, XyPlot, write_heatmap, write_xy};

use crate::output::{OutputFolder, holds_files};
use crate::progress;
use crate::provenance::Provenance;

/// Arguments of `fistage sweep`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Scenario file with a [sweep] table.
    pub scenario: PathBuf,
    /// Output folder (default: out/<scenario>-sweep).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Compute only shard i of n (points i, i + n, i + 2n, ...), as "i/n".
    #[arg(long)]
    pub shard: Option<String>,
    /// Merge the points of these shard folders instead of computing.
    #[arg(long)]
    pub merge: Vec<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Recompute points already in the output folder or its journal.
    #[arg(long)]
    pub no_resume: bool,
    /// Replace an output folder that holds other work (or, with --no-resume,
    /// this sweep's points).
    #[arg(long)]
    pub force: bool,
}

fn parse_shard(text: &str) -> anyhow::Result<(usize, usize)> {
    let parsed = text.split_once('/').and_then(|(i, n)| {
        Some((
            i.trim().parse::<usize>().ok()?,
            n.trim().parse::<usize>().ok()?,
        ))
    });
    match parsed {
        Some((i, n)) if n > 0 && i < n => Ok((i, n)),
        _ => bail!("--shard must be i/n with 0 <= i < n, got \"{text}\""),
    }
}

/// Runs the command.
pub fn run(args: &SweepArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    let spec = SweepSpec::from_scenario(&loaded.scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    spec.check_against(&loaded.scenario, &robot_file)?;
    let out_dir = args.out.clone().unwrap_or_else(|| {
        let stem = args
            .scenario
            .file_stem()
            .map_or("sweep".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(format!("{stem}-sweep"))
    });
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let provenance = Provenance::of_sweep(
        &loaded.scenario.file,
        &loaded.scenario.robot,
        &format!("{:?}", spec.axes),
        &format!(
            "{:?}, duration {:?}, oscillation threshold {:?}",
            spec.analysis, spec.duration, spec.oscillation_threshold
        ),
        shard,
    )?;
    let (folder, results) = if args.merge.is_empty() {
        let folder = OutputFolder::resumable(&out_dir)?;
        let results = compute(
            args,
            &loaded,
            &robot_file,
            &spec,
            shard,
            &folder,
            &out_dir,
            &provenance,
        )?;
        (folder, results)
    } else {
        let folder = OutputFolder::begin(&out_dir, args.force)?;
        let all = merge(&args.merge, &spec, &provenance)?;
        Provenance {
            shard: "merged".into(),
            ..provenance
        }
        .write(folder.path())?;
        (folder, all)
    };
    write_points(&spec, &results, folder.path())?;
    let pictures = draw(
        &crate::figures::figure_title(&loaded),
        &spec,
        &results,
        folder.path(),
    )?;
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

/// The points of shard folders made by this very sweep: each must carry the
/// same provenance, no shard may come twice, all must split the grid alike,
/// and no row may hold a non-finite number.
fn merge(
    folders: &[PathBuf],
    spec: &SweepSpec,
    provenance: &Provenance,
) -> anyhow::Result<Vec<PointResult>> {
    let mut all: Vec<PointResult> = Vec::new();
    let mut shards: Vec<String> = Vec::new();
    for dir in folders {
        let theirs = provenance.check_folder(dir, "merge only shards of this sweep")?;
        if shards.contains(&theirs.shard) {
            bail!("{}: shard {} is given twice", dir.display(), theirs.shard);
        }
        let parts = |s: &str| s.split_once('/').map(|(_, n)| n.to_string());
        if let Some(first) = shards.first()
            && parts(first) != parts(&theirs.shard)
        {
            bail!(
                "{}: shard {} splits the grid otherwise than shard {first}",
                dir.display(),
                theirs.shard
            );
        }
        shards.push(theirs.shard.clone());
        let points = dir.join("points.csv");
        refuse_non_finite_rows(&points)?;
        let rows = read_rows(&points, spec);
        anyhow::ensure!(
            !rows.is_empty(),
            "{}: no points of this sweep",
            points.display()
        );
        all.extend(rows);
    }
    all.sort_by_key(|r| r.index);
    all.dedup_by_key(|r| r.index);
    Ok(all)
}

/// A row with a NaN or infinite cell is damaged work: refuse it, naming it.
fn refuse_non_finite_rows(points: &Path) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(points)
        .with_context(|| format!("cannot read {}", points.display()))?;
    for (line, row) in text.lines().enumerate().skip(1) {
        if row
            .split(',')
            .any(|cell| cell.parse::<f64>().is_ok_and(|v| !v.is_finite()))
        {
            bail!(
                "{}: line {}: a non-finite number ({row}); not merged",
                points.display(),
                line + 1
            );
        }
    }
    Ok(())
}

/// The points of the sweep (or shard): those already in the output folder
/// (when it holds this sweep) and in the journal, then the rest, computed
/// with every finished one appended to the journal as it comes.
#[allow(clippy::too_many_arguments)]
fn compute(
    args: &SweepArgs,
    loaded: &fistage_model::Loaded,
    robot_file: &RobotSpec,
    spec: &SweepSpec,
    shard: Option<(usize, usize)>,
    folder: &OutputFolder,
    out_dir: &Path,
    provenance: &Provenance,
) -> anyhow::Result<Vec<PointResult>> {
    let mut finished: Vec<PointResult> = Vec::new();
    if holds_files(out_dir) {
        let earlier = provenance.check_folder(
            out_dir,
            "give --force to replace it, or choose another --out",
        );
        match (earlier, args.force, args.no_resume) {
            (_, true, _) => {}
            (Ok(_), false, false) => {
                // Points of any shard of the same sweep are points of this one.
                finished.extend(read_rows(&out_dir.join("points.csv"), spec));
                finished.extend(read_rows(&out_dir.join("points.partial.csv"), spec));
            }
            (Ok(_), false, true) => bail!(
                "{}: holds points of this sweep; give --force with --no-resume to recompute them",
                out_dir.display()
            ),
            (Err(refused), false, _) => return Err(refused),
        }
    }
    let journal = folder.path();
    let partial_path = journal.join("points.partial.csv");
    if args.no_resume {
        clear(journal)?;
    } else if partial_path.exists() {
        provenance.check_folder(
            journal,
            "resume only the same sweep (--no-resume starts over, or choose another --out)",
        )?;
        finished.extend(read_rows(&partial_path, spec));
    }
    provenance.write(journal)?;
    let mine = |index: usize| shard.is_none_or(|(i, n)| index % n == i);
    finished.retain(|r| mine(r.index));
    finished.sort_by_key(|r| r.index);
    finished.dedup_by_key(|r| r.index);
    let todo: Vec<usize> = (0..spec.len())
        .filter(|&k| mine(k) && finished.binary_search_by_key(&k, |r| r.index).is_err())
        .collect();
    if !finished.is_empty() {
        eprintln!(
            "resuming: {} points already done, {} to go",
            finished.len(),
            todo.len()
        );
    }
    let fresh = !partial_path.exists();
    let mut partial = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&partial_path)
        .with_context(|| format!("cannot write {}", partial_path.display()))?;
    if fresh {
        writeln!(partial, "{}", header(spec))?;
    }
    let partial = Mutex::new(partial);
    let bar = progress::bar(&format!("sweep {} points", todo.len()));
    let total = todo.len().max(1);
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let new = run_points(loaded, robot_file, spec, &todo, threads, &|result, done| {
        if let Ok(mut file) = partial.lock() {
            // A failed write only costs the resume of this point.
            let _ = writeln!(file, "{}", row(result)).and_then(|_| file.flush());
        }
        progress::set_fraction(&bar, done as f64 / total as f64);
    });
    bar.finish_and_clear();
    finished.extend(new);
    finished.sort_by_key(|r| r.index);
    Ok(finished)
}

/// Empties the journal folder (`--no-resume`).
fn clear(journal: &Path) -> anyhow::Result<()> {
    for entry in
        std::fs::read_dir(journal).with_context(|| format!("cannot read {}", journal.display()))?
    {
        let path = entry?.path();
        std::fs::remove_file(&path).with_context(|| format!("cannot remove {}", path.display()))?;
    }
    Ok(())
}

fn write_points(spec: &SweepSpec, results: &[PointResult], out_dir: &Path) -> anyhow::Result<()> {
    let mut text = header(spec) + "\n";
    for result in results {
        text.push_str(&row(result));
        text.push('\n');
    }
    let path = out_dir.join("points.csv");
    std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
    let json: Vec<serde_json::Value> = results
        .iter()
        .map(|r| {
            let mut object = serde_json::Map::new();
            for (axis, value) in spec.axes.iter().zip(&r.parameters) {
                object.insert(axis.parameter.clone(), serde_json::json!(value));
            }
            object.insert("stable_linear".into(), serde_json::json!(r.stable_linear));
            object.insert("stable_sim".into(), serde_json::json!(r.stable_sim));
            object.insert("amplitude".into(), serde_json::json!(r.amplitude));
            object.insert("max_real_eig".into(), serde_json::json!(r.max_real_eig));
            object.insert("bistable".into(), serde_json::json!(r.bistable));
            serde_json::Value::Object(object)
        })
        .collect();
    let json_path = out_dir.join("points.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)? + "\n")
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    // The partial file is only a journal; the finished table replaces it.
    let _ = std::fs::remove_file(out_dir.join("points.partial.csv"));
    Ok(())
}

/// 0 stable, 1 oscillating (or linearly unstable), 2 bistable; NaN not computed.
fn category(result: &PointResult) -> f64 {
    if result.bistable == Some(true) {
        2.0
    } else if let Some(stable) = result.stable_sim.or(result.stable_linear) {
        if stable { 0.0 } else { 1.0 }
    } else {
        f64::NAN
    }
}

fn draw(
    title: &str,
    spec: &SweepSpec,
    results: &[PointResult],
    out_dir: &Path,
) -> anyhow::Result<Vec<String>> {
    let mut written = Vec::new();
    match spec.axes.as_slice() {
        [x_axis, y_axis] => {
            let (xs, ys) = (x_axis.values(), y_axis.values());
            let mut values = vec![f64::NAN; xs.len() * ys.len()];
            let mut linear = vec![None; xs.len() * ys.len()];
            for result in results {
                values[result.index] = category(result);
                linear[result.index] = result.stable_linear;
            }
            let (mut bx, mut by) = (Vec::new(), Vec::new());
            let mid = |a: f64, b: f64, log: bool| if log { (a * b).sqrt() } else { 0.5 * (a + b) };
            for row in 0..ys.len() {
                for col in 0..xs.len() {
                    let here = linear[row * xs.len() + col];
                    if col + 1 < xs.len()
                        && here.is_some()
                        && linear[row * xs.len() + col + 1].is_some_and(|v| Some(v) != here)
                    {
                        bx.push(mid(xs[col], xs[col + 1], x_axis.spacing == Spacing::Log));
                        by.push(ys[row]);
                    }
                    if row + 1 < ys.len()
                        && here.is_some()
                        && linear[(row + 1) * xs.len() + col].is_some_and(|v| Some(v) != here)
                    {
                        bx.push(xs[col]);
                        by.push(mid(ys[row], ys[row + 1], y_axis.spacing == Spacing::Log));
                    }
                }
            }
            let mut map = Heatmap::new(
                if title.is_empty() {
                    "stability map".to_string()
                } else {
                    title.to_string()
                },
                x_axis.parameter.clone(),
                y_axis.parameter.clone(),
                xs,
                ys,
                values,
                ColourScale::Categorical {
                    labels: if matches!(spec.analysis, Analyses::Linear) {
                        vec!["stable".into(), "unstable".into(), "bistable".into()]
                    } else {
                        vec!["stable".into(), "oscillating".into(), "bistable".into()]
                    },
                },
            );
            map.x_log = x_axis.spacing == Spacing::Log;
            map.y_log = y_axis.spacing == Spacing::Log;
            map.value_label = "verdict".into();
            if !bx.is_empty() {
                map.overlay
                    .push(Series::markers("linear stability boundary", bx, by));
            }
            for extension in ["svg", "png"] {
                let name = format!("map.{extension}");
                write_heatmap(&map, &out_dir.join(&name))
                    .with_context(|| format!("cannot draw {name}"))?;
                written.push(name);
            }
        }
        [axis] => {
            let xs: Vec<f64> = results.iter().map(|r| r.parameters[0]).collect();
            let mut series = Vec::new();
            let amplitude: Vec<f64> = results
                .iter()
                .map(|r| r.amplitude.unwrap_or(f64::NAN))
                .collect();
            if amplitude.iter().any(|v| v.is_finite()) {
                series.push(Series::line_and_markers(
                    "steady peak-to-peak [m]",
                    xs.clone(),
                    amplitude,
                ));
            }
            let eig: Vec<f64> = results
                .iter()
                .map(|r| r.max_real_eig.unwrap_or(f64::NAN))
                .collect();
            if eig.iter().any(|v| v.is_finite()) {
                series.push(Series::line_and_markers("max Re(lambda) [1/s]", xs, eig));
            }
            let mut plot = XyPlot::new(title.to_string(), axis.parameter.clone(), "value", series);
            plot.x_log = axis.spacing == Spacing::Log;
            for extension in ["svg", "png"] {
                let name = format!("sweep.{extension}");
                write_xy(&plot, &out_dir.join(&name))
                    .with_context(|| format!("cannot draw {name}"))?;
                written.push(name);
            }
        }
        _ => {}
    }
    Ok(written)
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
