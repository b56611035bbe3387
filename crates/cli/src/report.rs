//! `report.html` beside a result's other files, and `fistage report DIR...
//! -o FILE`: the pages of several result folders of one study on one page.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fistage_report::{FILE_NAME, Page, Section};

/// Arguments of `fistage report`.
#[derive(clap::Args)]
pub struct ReportArgs {
    /// Result folders (each with its report.html) or report files, in the
    /// order their sections go on the page.
    #[arg(required = true)]
    pub results: Vec<PathBuf>,
    /// The page to write.
    #[arg(long, short)]
    pub out: PathBuf,
    /// The page's title (default: the sections' headings).
    #[arg(long)]
    pub title: Option<String>,
}

/// Writes the page of one section into the staging folder `dir`; returns the
/// file name written, or nothing (with a warning) where this build has no
/// report.
pub fn write(dir: &Path, section: impl FnOnce() -> Section) -> anyhow::Result<Vec<String>> {
    if let Err(why) = fistage_report::available() {
        eprintln!("warning: {FILE_NAME} not written: {why}");
        return Ok(Vec::new());
    }
    let path = dir.join(FILE_NAME);
    fistage_report::write(&Page::single(section()), &path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(vec![FILE_NAME.to_string()])
}

/// Runs `fistage report`.
pub fn run(args: &ReportArgs) -> anyhow::Result<()> {
    let mut pages = Vec::new();
    for result in &args.results {
        let file = if result.is_dir() {
            result.join(FILE_NAME)
        } else {
            result.clone()
        };
        anyhow::ensure!(
            file.exists(),
            "{}: no {FILE_NAME} (was the result written with --no-report? run its command again without it)",
            result.display()
        );
        pages.push(fistage_report::read(&file)?);
    }
    let title = args.title.clone().unwrap_or_else(|| {
        pages
            .iter()
            .flat_map(|p| p.sections.iter().map(|s| s.heading.as_str()))
            .collect::<Vec<_>>()
            .join("; ")
    });
    fistage_report::available()?;
    let page = fistage_report::combine(&title, pages);
    fistage_report::write(&page, &args.out)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    println!(
        "wrote {} ({} sections from {} results)",
        args.out.display(),
        page.sections.len(),
        args.results.len()
    );
    Ok(())
}
