//! What a section is made of: key-value facts, tables, interactive plots,
//! text, and the 3D mode view.

use serde::{Deserialize, Serialize};

use crate::Scene;

/// One block of a section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Block {
    /// Named values (provenance, settings).
    Facts {
        /// Heading of the block.
        title: String,
        /// Name and value, in reading order.
        rows: Vec<[String; 2]>,
    },
    /// A table of text cells.
    Table {
        /// Heading of the block.
        title: String,
        /// Column names.
        columns: Vec<String>,
        /// Rows, one cell per column.
        rows: Vec<Vec<String>>,
    },
    /// An interactive plot: Plotly traces and layout.
    Plot {
        /// Heading of the block.
        title: String,
        /// The traces (Plotly's trace objects).
        traces: Vec<serde_json::Value>,
        /// The layout (Plotly's layout object; the page adds margins and hover mode).
        layout: serde_json::Value,
        /// Height in pixels.
        height: u32,
    },
    /// A paragraph.
    Text {
        /// The paragraph.
        text: String,
        /// `note` or `warning` (styled), or empty.
        tone: String,
    },
    /// The stage in 3D with its modes animated.
    Scene(Box<Scene>),
}

impl Block {
    /// A facts block.
    pub fn facts(title: &str, rows: Vec<[String; 2]>) -> Self {
        Block::Facts {
            title: title.to_string(),
            rows,
        }
    }

    /// A warning paragraph.
    pub fn warning(text: impl Into<String>) -> Self {
        Block::Text {
            text: text.into(),
            tone: "warning".into(),
        }
    }

    /// A plain paragraph.
    pub fn note(text: impl Into<String>) -> Self {
        Block::Text {
            text: text.into(),
            tone: "note".into(),
        }
    }
}

/// A number as the page shows it: four significant digits.
pub fn number(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let magnitude = value.abs().log10();
    if (-3.0..5.0).contains(&magnitude) {
        let decimals = (3 - magnitude.floor() as i32).max(0) as usize;
        format!("{value:.decimals$}")
    } else {
        format!("{value:.3e}")
    }
}
