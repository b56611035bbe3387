//! A page: a title and sections, each section a heading, the result folder it
//! came from, and its blocks. This is the data the page carries as JSON and
//! its script renders.

use serde::{Deserialize, Serialize};

use crate::Block;

/// One report page.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Page {
    /// The page's title.
    pub title: String,
    /// The program and version that wrote it.
    pub generator: String,
    /// The sections, in reading order.
    pub sections: Vec<Section>,
}

/// The part of a page that one result made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Section {
    /// Heading, e.g. `run: fig05b_fi` .
    pub heading: String,
    /// The scenario or records the result came from.
    pub source: String,
    /// The blocks, in reading order.
    pub blocks: Vec<Block>,
}

impl Page {
    /// A page of one section, titled by it.
    pub fn single(section: Section) -> Self {
        Page {
            title: section.heading.clone(),
            generator: generator(),
            sections: vec![section],
        }
    }
}

/// `fistage <version>`.
pub fn generator() -> String {
    format!("fistage {}", env!("CARGO_PKG_VERSION"))
}
