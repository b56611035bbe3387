//! fistage-report: the HTML page of a fistage result, one self-contained file
//! that opens from `file://` with nothing but a browser.
//!
//! A page is data ([`Page`]: sections of [`Block`]s) that the page's own
//! script renders: interactive plots with Plotly (zoom, pan, hover values,
//! signals switched on and off in the legend), tables, and the stage in 3D
//! with three.js, its modes animated ([`Scene`]). Both libraries are pinned
//! in `web/package-lock.json`, fetched from the npm registry and bundled at
//! build time (`build.rs`), and embedded in every page with their licences.
//! Time signals are reduced for the browser to per-column envelopes that keep
//! every extremum. A result folder's `report.html` is written with the other
//! files; [`combine`] puts the sections of several pages on one.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let loaded = fistage_model::load("scenarios/paper/fig05b_fi.toml".as_ref())?;
//! let output = fistage_sim::run_scenario(&loaded, &mut |_| std::ops::ControlFlow::Continue(()))?;
//! let page = fistage_report::Page::single(fistage_report::sections::run::section(&loaded, &output));
//! fistage_report::write(&page, "report.html".as_ref())?;
//! // Later, several results on one page:
//! let pages = [fistage_report::read("out/a/report.html".as_ref())?,
//!              fistage_report::read("out/b/report.html".as_ref())?];
//! fistage_report::write(&fistage_report::combine("my study", pages), "study.html".as_ref())?;
//! # Ok(()) }
//! ```

mod block;
mod error;
mod html;
mod page;
pub mod plot;
mod scene;
pub mod sections;

pub use block::{Block, number};
pub use error::ReportError;
pub use html::{available, read, render, write};
pub use page::{Page, Section, generator};
pub use scene::{BodyMotion, Rail, Scene, SceneBody, SceneIsolator, SceneMode, Shape};

/// The file name of a result folder's page.
pub const FILE_NAME: &str = "report.html";

/// One page holding every section of `pages`, in order, under `title`.
pub fn combine(title: &str, pages: impl IntoIterator<Item = Page>) -> Page {
    Page {
        title: title.to_string(),
        generator: generator(),
        sections: pages.into_iter().flat_map(|p| p.sections).collect(),
    }
}
