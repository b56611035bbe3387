//! The rules every long study follows (a sweep's grid points, a tolerance
//! analysis's samples, a comparison's runs), for the program and the Python
//! package alike. Its items are computed in parallel and appended, as they
//! finish, to a journal (`<table>.partial.csv`) in the staging folder
//! `.<name>.journal` beside the output folder, so a killed study resumes
//! where it stopped ([`StudyRun`]); an output folder holding items of the
//! same study (another shard, say) is taken up too (or recomputed whole with
//! `no_resume`), while other work there is replaced only with `force`. A
//! shard `i/n` computes every n-th item starting at i, and [`merge`] joins
//! shard folders of the same study, refusing duplicates, other splits and
//! damaged rows. Every folder holds its [`Provenance`]; the finished table
//! ([`write_table`]) and everything drawn from it go into the staging
//! folder, which then replaces the output folder whole
//! ([`ResultFolder::commit`]).
//!
//! ```no_run
//! use fistage_analysis::study::{Study, StudyOptions, StudyRun, write_table};
//! use fistage_analysis::sweep::{SweepSpec, SweepStudy};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let loaded = fistage_model::load("scenarios/paper/fig06b_fi_vp20.toml".as_ref())?;
//! let robot = fistage_model::RobotSpec::from_file(&loaded.scenario.robot)?;
//! let spec = SweepSpec::from_scenario(&loaded.scenario)?;
//! let grid = SweepStudy { loaded: &loaded, robot_file: &robot, spec: &spec };
//! let options = StudyOptions { shard: Some((0, 4)), ..StudyOptions::default() };
//! let out = std::path::Path::new("out/fig06b-shard0");
//! let run = StudyRun::start(&grid, &options, out, &grid.provenance(None, options.shard)?)?;
//! let new = grid.compute(run.todo(), 2, &|row, _| run.record(row));
//! let (folder, rows) = run.finish(new);
//! write_table(&grid, &rows, &folder)?;
//! folder.commit()?;
//! # Ok(())
//! # }
//! ```

mod provenance;
mod table;

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use fistage_model::output::{OutputError, ResultFolder, holds_files, write_whole};

pub use provenance::{PROVENANCE_FILE, Provenance};
use table::{Table, read_table};

/// A study of numbered items whose rows are exact functions of the item.
pub trait Study: Sync {
    /// One item's result.
    type Row: Send + Sync;
    /// The finished table's file name (`points.csv`, `samples.csv`).
    const TABLE: &'static str;
    /// What the items are called (`points`, `samples`).
    const ITEMS: &'static str;
    /// Items in the whole study.
    fn len(&self) -> usize;
    /// Whether the study has no items.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The table's header line.
    fn header(&self) -> String;
    /// One row (no line end).
    fn row(&self, row: &Self::Row) -> String;
    /// The item a row is of.
    fn index(row: &Self::Row) -> usize;
    /// The row a line of the table holds, if it is a finished row of this
    /// study (the study's reader takes it only when [`Study::row`] writes
    /// it back as the same line).
    fn parse_row(&self, line: &str) -> Option<Self::Row>;
    /// Computes these items on `threads` threads, calling `done` with each
    /// finished one and the count finished so far.
    fn compute(
        &self,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&Self::Row, usize) + Sync),
    ) -> Vec<Self::Row>;
}

/// How a study is run (the program's `--shard`, `--no-resume`, `--force`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StudyOptions {
    /// Only shard `i` of `n`: items i, i + n, i + 2n, ...
    pub shard: Option<(usize, usize)>,
    /// Recompute items already in the output folder or its journal.
    pub no_resume: bool,
    /// Replace an output folder that holds other work (or, with
    /// `no_resume`, this study's items).
    pub force: bool,
}

/// Why a study could not start, merge or finish.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The output folder (its lock, staging or commit).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A shard that is not `i/n` with `0 <= i < n`.
    #[error("--shard must be i/n with 0 <= i < n, got \"{0}\"")]
    Shard(String),
    /// A folder without a provenance record.
    #[error(
        "{}: no {PROVENANCE_FILE}, so its {items} are of unknown origin; {advice}",
        folder.display()
    )]
    UnknownOrigin {
        /// The folder.
        folder: PathBuf,
        /// What its items are called.
        items: &'static str,
        /// What to do instead.
        advice: &'static str,
    },
    /// A provenance record that does not read.
    #[error("{}: not a provenance record ({why})", path.display())]
    BadProvenance {
        /// The file.
        path: PathBuf,
        /// The parser's reason.
        why: String,
    },
    /// A folder of another study.
    #[error("{}: made by another {kind} ({difference}); {advice}", folder.display())]
    OtherWork {
        /// The folder.
        folder: PathBuf,
        /// This study's kind in words ("sweep").
        kind: &'static str,
        /// The first item that differs.
        difference: String,
        /// What to do instead.
        advice: &'static str,
    },
    /// One shard given twice to a merge.
    #[error("{}: shard {shard} is given twice", folder.display())]
    ShardTwice {
        /// The folder.
        folder: PathBuf,
        /// The shard.
        shard: String,
    },
    /// Shards of different splits given to one merge.
    #[error("{}: shard {shard} splits the study otherwise than shard {first}", folder.display())]
    OtherSplit {
        /// The folder.
        folder: PathBuf,
        /// Its shard.
        shard: String,
        /// The first folder's shard.
        first: String,
    },
    /// A damaged row in a shard's finished table.
    #[error("{}: line {line}: {why}; not merged", table.display())]
    DamagedRow {
        /// The table.
        table: PathBuf,
        /// The line (the header is line 1).
        line: usize,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A shard's table without a row of this study.
    #[error("{}: no {items} of this study", table.display())]
    NoRows {
        /// The table.
        table: PathBuf,
        /// What the items are called.
        items: &'static str,
    },
}

/// `i/n`, checked.
pub fn parse_shard(text: &str) -> Result<(usize, usize), StudyError> {
    let parsed = text.split_once('/').and_then(|(i, n)| {
        Some((
            i.trim().parse::<usize>().ok()?,
            n.trim().parse::<usize>().ok()?,
        ))
    });
    match parsed {
        Some((i, n)) if n > 0 && i < n => Ok((i, n)),
        _ => Err(StudyError::Shard(text.to_string())),
    }
}

/// The journal's file name beside the table's (`points.partial.csv`).
fn journal_name<S: Study>() -> String {
    match S::TABLE.strip_suffix(".csv") {
        Some(stem) => format!("{stem}.partial.csv"),
        None => format!("{}.partial", S::TABLE),
    }
}

/// A study (or shard) being computed: what was found done, what is left
/// ([`StudyRun::todo`]), and the journal every finished item goes into
/// ([`StudyRun::record`]) until [`StudyRun::finish`].
pub struct StudyRun<'s, S: Study> {
    study: &'s S,
    folder: ResultFolder,
    finished: Vec<S::Row>,
    todo: Vec<usize>,
    not_taken: usize,
    journal: Mutex<File>,
}

impl<'s, S: Study> StudyRun<'s, S> {
    /// Takes the output folder (its lock and journal) and finds the items
    /// already done: those in the output folder (when it holds this study)
    /// and in the journal. The journal starts again from what was taken,
    /// written whole, so that no cut line of a killed run is continued.
    pub fn start(
        study: &'s S,
        options: &StudyOptions,
        out_dir: &Path,
        provenance: &Provenance,
    ) -> Result<Self, StudyError> {
        let folder = ResultFolder::resumable(out_dir)?;
        let journal = folder.path().to_path_buf();
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
                S::ITEMS,
                "give --force to replace it, or choose another --out",
            );
            match (earlier, options.force, options.no_resume) {
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
        if options.no_resume {
            clear(&journal)?;
        } else if partial_path.exists() {
            provenance.check_folder(
                &journal,
                S::ITEMS,
                "resume only the same study (--no-resume starts over, or choose another --out)",
            )?;
            take(read_table(study, &partial_path)?);
        }
        provenance.write(&journal)?;
        let mine = |index: usize| options.shard.is_none_or(|(i, n)| index % n == i);
        finished.retain(|r| mine(S::index(r)));
        finished.sort_by_key(|r| S::index(r));
        finished.dedup_by_key(|r| S::index(r));
        let todo: Vec<usize> = (0..study.len())
            .filter(|&k| mine(k) && finished.binary_search_by_key(&k, |r| S::index(r)).is_err())
            .collect();
        write_whole(&partial_path, table_text(study, &finished).as_bytes())
            .map_err(OutputError::io("write", &partial_path))?;
        let journal_file = OpenOptions::new()
            .append(true)
            .open(&partial_path)
            .map_err(OutputError::io("write", &partial_path))?;
        Ok(Self {
            study,
            folder,
            finished,
            todo,
            not_taken,
            journal: Mutex::new(journal_file),
        })
    }

    /// The items left to compute, in order.
    pub fn todo(&self) -> &[usize] {
        &self.todo
    }

    /// Items found done (in the output folder or the journal).
    pub fn already_done(&self) -> usize {
        self.finished.len()
    }

    /// Rows of the earlier work not taken (damaged, cut short or
    /// unfinished): computed again.
    pub fn not_taken(&self) -> usize {
        self.not_taken
    }

    /// Appends a finished item to the journal (from any thread). A failed
    /// write only costs the resume of this item.
    pub fn record(&self, row: &S::Row) {
        if let Ok(mut file) = self.journal.lock() {
            let line = self.study.row(row) + "\n";
            let _ = file.write_all(line.as_bytes()).and_then(|_| file.flush());
        }
    }

    /// The staging folder and every row of the study (or shard), those
    /// found done and `computed`, in item order.
    pub fn finish(self, computed: Vec<S::Row>) -> (ResultFolder, Vec<S::Row>) {
        let mut rows = self.finished;
        rows.extend(computed);
        rows.sort_by_key(|r| S::index(r));
        rows.dedup_by_key(|r| S::index(r));
        (self.folder, rows)
    }
}

/// The table's text as [`write_table`] writes it: header and rows, each
/// line ended.
pub fn table_text<S: Study>(study: &S, rows: &[S::Row]) -> String {
    let mut text = study.header() + "\n";
    for row in rows {
        text.push_str(&study.row(row));
        text.push('\n');
    }
    text
}

/// Writes the finished table into the staging folder and drops the journal.
pub fn write_table<S: Study>(
    study: &S,
    rows: &[S::Row],
    folder: &ResultFolder,
) -> Result<(), StudyError> {
    let path = folder.path().join(S::TABLE);
    std::fs::write(&path, table_text(study, rows)).map_err(OutputError::io("write", &path))?;
    // The journal is only a journal; the finished table replaces it.
    let _ = std::fs::remove_file(folder.path().join(journal_name::<S>()));
    Ok(())
}

/// The items of shard folders made by this very study, staged for
/// `out_dir`: each folder must carry the same provenance, no shard may come
/// twice, all must split the study alike, and no row may be damaged.
pub fn merge<S: Study>(
    study: &S,
    folders: &[PathBuf],
    out_dir: &Path,
    force: bool,
    provenance: &Provenance,
) -> Result<(ResultFolder, Vec<S::Row>), StudyError> {
    let folder = ResultFolder::begin(out_dir, force)?;
    let mut all: Vec<S::Row> = Vec::new();
    let mut shards: Vec<String> = Vec::new();
    for dir in folders {
        let theirs = provenance.check_folder(dir, S::ITEMS, "merge only shards of this study")?;
        if shards.contains(&theirs.shard) {
            return Err(StudyError::ShardTwice {
                folder: dir.clone(),
                shard: theirs.shard,
            });
        }
        let parts = |s: &str| s.split_once('/').map(|(_, n)| n.to_string());
        if let Some(first) = shards.first()
            && parts(first) != parts(&theirs.shard)
        {
            return Err(StudyError::OtherSplit {
                folder: dir.clone(),
                shard: theirs.shard,
                first: first.clone(),
            });
        }
        shards.push(theirs.shard.clone());
        let table = dir.join(S::TABLE);
        let Table { rows, refused } = read_table(study, &table)?;
        if let Some(first) = refused.first() {
            return Err(StudyError::DamagedRow {
                table,
                line: first.line,
                why: first.why,
            });
        }
        if rows.is_empty() {
            return Err(StudyError::NoRows {
                table,
                items: S::ITEMS,
            });
        }
        all.extend(rows);
    }
    all.sort_by_key(|r| S::index(r));
    all.dedup_by_key(|r| S::index(r));
    Provenance {
        shard: "merged".into(),
        ..provenance.clone()
    }
    .write(folder.path())?;
    Ok((folder, all))
}

/// Empties the journal folder (`no_resume`).
fn clear(journal: &Path) -> Result<(), StudyError> {
    let entries = std::fs::read_dir(journal).map_err(OutputError::io("read", journal))?;
    for entry in entries {
        let path = entry.map_err(OutputError::io("read", journal))?.path();
        std::fs::remove_file(&path).map_err(OutputError::io("remove", &path))?;
    }
    Ok(())
}
