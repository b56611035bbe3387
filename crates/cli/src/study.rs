//! The flags every long study shares (`sweep`, `robust`, `compare`) and the
//! driver's face: [`gather`] computes (with a progress bar and the
//! journal of `fistage_analysis::study`) or merges the study's rows.

use std::path::{Path, PathBuf};

use fistage_analysis::assess::{MAX_THREADS, worker_threads};
use fistage_analysis::study::{Provenance, Study, StudyOptions, StudyRun, merge, parse_shard};
use fistage_model::output::ResultFolder;

use crate::progress;

/// How a study is run: the shared flags of `sweep`, `robust` and `compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct StudyArgs {
    /// Compute only shard i of n (items i, i + n, i + 2n, ...), as "i/n".
    #[arg(long)]
    pub shard: Option<String>,
    /// Merge the items of these shard folders instead of computing.
    #[arg(long)]
    pub merge: Vec<PathBuf>,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long, value_parser = threads_flag)]
    pub threads: Option<usize>,
    /// Recompute items already in the output folder or its journal.
    #[arg(long)]
    pub no_resume: bool,
    /// Replace an output folder that holds other work (or, with --no-resume,
    /// this study's items).
    #[arg(long)]
    pub force: bool,
}

impl StudyArgs {
    /// The shard, checked.
    pub fn shard(&self) -> anyhow::Result<Option<(usize, usize)>> {
        Ok(self.shard.as_deref().map(parse_shard).transpose()?)
    }

    fn options(&self) -> anyhow::Result<StudyOptions> {
        Ok(StudyOptions {
            shard: self.shard()?,
            no_resume: self.no_resume,
            force: self.force,
        })
    }
}

/// The study's rows, computed or merged, and the staging folder that will
/// hold the result: write the table with
/// [`fistage_analysis::study::write_table`] and everything else into
/// [`ResultFolder::path`], then commit it.
pub fn gather<S: Study>(
    study: &S,
    args: &StudyArgs,
    out_dir: &Path,
    provenance: &Provenance,
) -> anyhow::Result<(ResultFolder, Vec<S::Row>)> {
    if !args.merge.is_empty() {
        return Ok(merge(study, &args.merge, out_dir, args.force, provenance)?);
    }
    let threads = worker_threads(args.threads).map_err(|why| anyhow::anyhow!("--{why}"))?;
    let run = StudyRun::start(study, &args.options()?, out_dir, provenance)?;
    if run.not_taken() > 0 {
        eprintln!(
            "resuming: {} damaged or unfinished rows of the earlier work are computed again",
            run.not_taken()
        );
    }
    if run.already_done() > 0 {
        eprintln!(
            "resuming: {} {} already done, {} to go",
            run.already_done(),
            S::ITEMS,
            run.todo().len()
        );
    }
    let bar = progress::bar(&format!("{} {}", run.todo().len(), S::ITEMS));
    let total = run.todo().len().max(1);
    let computed = study.compute(run.todo(), threads, &|row, done| {
        run.record(row);
        progress::set_fraction(&bar, done as f64 / total as f64);
    });
    bar.finish_and_clear();
    Ok(run.finish(computed))
}

/// `--threads`: a whole number the library's rule admits.
fn threads_flag(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("must be a whole number from 1 to {MAX_THREADS}"))?;
    worker_threads(Some(n)).map(|_| n)
}
