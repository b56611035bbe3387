//! The rules every long study follows (a sweep's grid points, a tolerance
//! analysis's samples): its items are computed in parallel with a progress
//! bar and appended, as they finish, to a journal (`<table>.partial.csv`) in
//! the staging folder `.<name>.journal` beside the output folder, so a killed
//! study resumes where it stopped; an output folder holding items of the
//! same study (another shard, say) is taken up too (or recomputed whole with
//! `--no-resume`), while other work there is replaced only with `--force`. `--shard i/n` computes every n-th item
//! starting at i, and `--merge` joins shard folders of the same study,
//! refusing duplicates, other splits and rows holding non-finite numbers.
//! The finished table and everything drawn from it go into the staging
//! folder, which then replaces the output folder whole.

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, bail};
use fistage_analysis::assess::{MAX_THREADS, worker_threads};

use fistage_model::output::write_whole;

use crate::output::{OutputFolder, holds_files};
use crate::progress;
use crate::provenance::Provenance;

/// A study of numbered items whose rows are exact functions of the item.
pub trait Study: Sync {
    /// One item's result.
    type Row: Send;
    /// The finished table's file name (`points.csv`, `samples.csv`).
    const TABLE: &'static str;
    /// What the items are called (`points`, `samples`).
    const ITEMS: &'static str;
    /// Items in the whole study.
    fn len(&self) -> usize;
    /// The table's header line.
    fn header(&self) -> String;
    /// One row (no line end).
    fn row(&self, row: &Self::Row) -> String;
    /// The item a row is of.
    fn index(row: &Self::Row) -> usize;
    /// The row a line of the table holds, if it is a finished row of this
    /// study ([`read_table`] takes it only when [`Study::row`] writes it
    /// back as the same line).
    fn parse_row(&self, line: &str) -> Option<Self::Row>;
    /// Computes these items on `threads` threads, calling `done` with each.
    fn compute(
        &self,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&Self::Row, usize) + Sync),
    ) -> Vec<Self::Row>;
}

/// How a study is run: the shared flags of `sweep` and `robust`.
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
        self.shard.as_deref().map(parse_shard).transpose()
    }
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

/// The journal's file name beside the table's (`points.partial.csv`).
fn journal_name<S: Study>() -> String {
    match S::TABLE.strip_suffix(".csv") {
        Some(stem) => format!("{stem}.partial.csv"),
        None => format!("{}.partial", S::TABLE),
    }
}

/// The study's rows, computed or merged, and the staging folder that will
/// hold the result: write the table with [`write_table`] and everything
/// else into [`OutputFolder::path`], then commit it.
pub fn gather<S: Study>(
    study: &S,
    args: &StudyArgs,
    out_dir: &Path,
    provenance: &Provenance,
) -> anyhow::Result<(OutputFolder, Vec<S::Row>)> {
    if args.merge.is_empty() {
        let folder = OutputFolder::resumable(out_dir)?;
        let rows = compute(study, args, &folder, out_dir, provenance)?;
        Ok((folder, rows))
    } else {
        let folder = OutputFolder::begin(out_dir, args.force)?;
        let rows = merge(study, &args.merge, provenance)?;
        Provenance {
            shard: "merged".into(),
            ..provenance.clone()
        }
        .write(folder.path())?;
        Ok((folder, rows))
    }
}

/// Writes the finished table into the staging folder and drops the journal.
pub fn write_table<S: Study>(
    study: &S,
    rows: &[S::Row],
    folder: &OutputFolder,
) -> anyhow::Result<()> {
    let mut text = study.header() + "\n";
    for row in rows {
        text.push_str(&study.row(row));
        text.push('\n');
    }
    let path = folder.path().join(S::TABLE);
    std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
    // The journal is only a journal; the finished table replaces it.
    let _ = std::fs::remove_file(folder.path().join(journal_name::<S>()));
    Ok(())
}

/// The items of shard folders made by this very study: each must carry the
/// same provenance, no shard may come twice, all must split the study alike,
/// and no row may hold a non-finite number.
fn merge<S: Study>(
    study: &S,
    folders: &[PathBuf],
    provenance: &Provenance,
) -> anyhow::Result<Vec<S::Row>> {
    let mut all: Vec<S::Row> = Vec::new();
    let mut shards: Vec<String> = Vec::new();
    for dir in folders {
        let theirs = provenance.check_folder(dir, "merge only shards of this study")?;
        if shards.contains(&theirs.shard) {
            bail!("{}: shard {} is given twice", dir.display(), theirs.shard);
        }
        let parts = |s: &str| s.split_once('/').map(|(_, n)| n.to_string());
        if let Some(first) = shards.first()
            && parts(first) != parts(&theirs.shard)
        {
            bail!(
                "{}: shard {} splits the study otherwise than shard {first}",
                dir.display(),
                theirs.shard
            );
        }
        shards.push(theirs.shard.clone());
        let table = dir.join(S::TABLE);
        let Table { rows, refused } = read_table(study, &table)?;
        if let Some(first) = refused.first() {
            bail!(
                "{}: line {}: {}; not merged",
                table.display(),
                first.line,
                first.why
            );
        }
        anyhow::ensure!(
            !rows.is_empty(),
            "{}: no {} of this study",
            table.display(),
            S::ITEMS
        );
        all.extend(rows);
    }
    all.sort_by_key(|r| S::index(r));
    all.dedup_by_key(|r| S::index(r));
    Ok(all)
}

/// The rows of a study's table or journal, as [`read_table`] found them.
struct Table<R> {
    /// The finished rows of this study, in file order.
    rows: Vec<R>,
    /// The lines not taken, each with why.
    refused: Vec<RefusedLine>,
}

/// A line of a table that is not a finished row of its study.
struct RefusedLine {
    /// Line number in the file (the header is line 1).
    line: usize,
    why: &'static str,
}

/// The one reader of every study's tables and journals. A line is taken
/// only when it is whole (ends with a line end: a killed run can leave a
/// cut last line), holds no non-finite number, and is exactly the line
/// [`Study::row`] writes for the row [`Study::parse_row`] reads from it (so
/// a cell cut to "fa" is not read as a missing verdict). A missing file
/// holds no rows; a file whose header is another study's is refused.
fn read_table<S: Study>(study: &S, path: &Path) -> anyhow::Result<Table<S::Row>> {
    let mut table = Table {
        rows: Vec::new(),
        refused: Vec::new(),
    };
    let text = match std::fs::read(path) {
        Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(table),
        Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
    };
    let mut lines = text.split_inclusive('\n');
    match lines.next() {
        None => return Ok(table),
        Some(header) if header.trim_end_matches(['\n', '\r']) == study.header() => {}
        Some(_) => {
            table.refused.push(RefusedLine {
                line: 1,
                why: "not this study's header",
            });
            return Ok(table);
        }
    }
    for (number, line) in lines.enumerate().map(|(k, line)| (k + 2, line)) {
        let Some(line) = line.strip_suffix('\n') else {
            table.refused.push(RefusedLine {
                line: number,
                why: "cut short (no line end)",
            });
            continue;
        };
        let line = line.strip_suffix('\r').unwrap_or(line);
        match take_row(study, line) {
            Ok(row) => table.rows.push(row),
            Err(why) => table.refused.push(RefusedLine { line: number, why }),
        }
    }
    Ok(table)
}

/// One line as a finished row of the study, or why not.
fn take_row<S: Study>(study: &S, line: &str) -> Result<S::Row, &'static str> {
    if line
        .split(',')
        .any(|cell| cell.parse::<f64>().is_ok_and(|v| !v.is_finite()))
    {
        return Err("a non-finite number");
    }
    match study.parse_row(line) {
        Some(row) if study.row(&row) == line => Ok(row),
        _ => Err("damaged, or not a finished row of this study"),
    }
}

/// The items of the study (or shard): those already in the output folder
/// (when it holds this study) and in the journal, then the rest, computed
/// with every finished one appended to the journal as it comes.
fn compute<S: Study>(
    study: &S,
    args: &StudyArgs,
    folder: &OutputFolder,
    out_dir: &Path,
    provenance: &Provenance,
) -> anyhow::Result<Vec<S::Row>> {
    let shard = args.shard()?;
    let journal = folder.path();
    let partial_path = journal.join(journal_name::<S>());
    let mut finished: Vec<S::Row> = Vec::new();
    let mut not_taken = 0;
    let mut take = |table: Table<S::Row>| {
        not_taken += table.refused.len();
        finished.extend(table.rows);
    };
    if holds_files(out_dir) {
        let earlier = provenance.check_folder(
            out_dir,
            "give --force to replace it, or choose another --out",
        );
        match (earlier, args.force, args.no_resume) {
            (_, true, _) => {}
            (Ok(_), false, false) => {
                // Items of any shard of the same study are items of this one.
                take(read_table(study, &out_dir.join(S::TABLE))?);
                take(read_table(study, &out_dir.join(journal_name::<S>()))?);
            }
            // The same study recomputed: its result is replaced whole.
            (Ok(_), false, true) => {}
            (Err(refused), false, _) => return Err(refused),
        }
    }
    if args.no_resume {
        clear(journal)?;
    } else if partial_path.exists() {
        provenance.check_folder(
            journal,
            "resume only the same study (--no-resume starts over, or choose another --out)",
        )?;
        take(read_table(study, &partial_path)?);
    }
    provenance.write(journal)?;
    let mine = |index: usize| shard.is_none_or(|(i, n)| index % n == i);
    finished.retain(|r| mine(S::index(r)));
    finished.sort_by_key(|r| S::index(r));
    finished.dedup_by_key(|r| S::index(r));
    let todo: Vec<usize> = (0..study.len())
        .filter(|&k| mine(k) && finished.binary_search_by_key(&k, |r| S::index(r)).is_err())
        .collect();
    if not_taken > 0 {
        eprintln!(
            "resuming: {not_taken} damaged or unfinished rows of the earlier work are computed again"
        );
    }
    if !finished.is_empty() {
        eprintln!(
            "resuming: {} {} already done, {} to go",
            finished.len(),
            S::ITEMS,
            todo.len()
        );
    }
    // The journal starts again from what was taken, written whole, so that
    // no cut line of a killed run is continued by the next row.
    let mut text = study.header() + "\n";
    for row in &finished {
        text.push_str(&study.row(row));
        text.push('\n');
    }
    write_whole(&partial_path, text.as_bytes())
        .with_context(|| format!("cannot write {}", partial_path.display()))?;
    let partial = OpenOptions::new()
        .append(true)
        .open(&partial_path)
        .with_context(|| format!("cannot write {}", partial_path.display()))?;
    let partial = Mutex::new(partial);
    let bar = progress::bar(&format!("{} {}", todo.len(), S::ITEMS));
    let total = todo.len().max(1);
    let threads = worker_threads(args.threads).map_err(|why| anyhow::anyhow!("--{why}"))?;
    let new = study.compute(&todo, threads, &|row, done| {
        if let Ok(mut file) = partial.lock() {
            // A failed write only costs the resume of this item.
            let _ = writeln!(file, "{}", study.row(row)).and_then(|_| file.flush());
        }
        progress::set_fraction(&bar, done as f64 / total as f64);
    });
    bar.finish_and_clear();
    finished.extend(new);
    finished.sort_by_key(|r| S::index(r));
    Ok(finished)
}

/// Empties the journal folder (`--no-resume`).
fn clear(journal: &Path) -> anyhow::Result<()> {
    let entries =
        std::fs::read_dir(journal).with_context(|| format!("cannot read {}", journal.display()))?;
    for entry in entries {
        let path = entry?.path();
        std::fs::remove_file(&path).with_context(|| format!("cannot remove {}", path.display()))?;
    }
    Ok(())
}

/// `--threads`: a whole number the library's rule admits.
fn threads_flag(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("must be a whole number from 1 to {MAX_THREADS}"))?;
    worker_threads(Some(n)).map(|_| n)
}
