//! The page as one HTML file: the style, the page's data as JSON, the
//! bundled script (the report's own code with Plotly and three.js), and the
//! embedded libraries' licences. It loads nothing: it opens from `file://`
//! with no network.

use std::path::Path;

use crate::{Page, ReportError};

/// The bundle made at build time (see `build.rs`).
const SCRIPT: &str = include_str!(concat!(env!("OUT_DIR"), "/report.js"));
/// The embedded libraries' licences, gathered at build time.
const LICENCES: &str = include_str!(concat!(env!("OUT_DIR"), "/licences.txt"));
/// Why the bundle is missing, or empty.
const UNAVAILABLE: &str = include_str!(concat!(env!("OUT_DIR"), "/unavailable.txt"));
/// The page's style.
const STYLE: &str = include_str!("../web/style.css");

/// Where the page keeps its data.
const DATA_OPEN: &str = r#"<script type="application/json" id="fistage-report-data">"#;
const DATA_CLOSE: &str = "</script>";

/// Whether this build can write pages.
pub fn available() -> Result<(), ReportError> {
    if SCRIPT.is_empty() {
        Err(ReportError::Unavailable(UNAVAILABLE.trim().to_string()))
    } else {
        Ok(())
    }
}

/// The whole HTML text of `page`.
pub fn render(page: &Page) -> Result<String, ReportError> {
    available()?;
    let data = serde_json::to_string(page).map_err(|source| ReportError::Data {
        path: "(page)".into(),
        source,
    })?;
    // JSON may carry "</" inside strings; "<\/" is the same string to JSON and
    // cannot close the script element.
    let data = data.replace("</", r"<\/");
    let title = escape(&page.title);
    let licences = escape(LICENCES);
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"{generator}\">\n<title>{title}</title>\n\
         <style>\n{STYLE}</style>\n</head>\n<body>\n<main id=\"fistage-report\"></main>\n\
         {DATA_OPEN}{data}{DATA_CLOSE}\n<script>{SCRIPT}</script>\n\
         <footer><details><summary>Licences of the libraries embedded in this page</summary>\
         <pre>{licences}</pre></details></footer>\n</body>\n</html>\n",
        generator = escape(&page.generator),
    ))
}

/// Writes `page` to `path` whole or not at all (a temporary file beside it,
/// then renamed over it).
pub fn write(page: &Page, path: &Path) -> Result<(), ReportError> {
    let text = render(page)?;
    let io = |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file_name = path.file_name().map_or_else(
        || "report.html".into(),
        |n| n.to_string_lossy().into_owned(),
    );
    let partial = path.with_file_name(format!(".{file_name}.partial-{}", std::process::id()));
    std::fs::write(&partial, text).map_err(io)?;
    std::fs::rename(&partial, path).map_err(|e| {
        let _ = std::fs::remove_file(&partial);
        io(e)
    })
}

/// The page data of a report file written by [`write`].
pub fn read(path: &Path) -> Result<Page, ReportError> {
    let text = std::fs::read_to_string(path).map_err(|source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let not_a_report = || ReportError::NotAReport {
        path: path.to_path_buf(),
        hint: String::new(),
    };
    let start = text.find(DATA_OPEN).ok_or_else(not_a_report)? + DATA_OPEN.len();
    let length = text[start..].find(DATA_CLOSE).ok_or_else(not_a_report)?;
    serde_json::from_str(&text[start..start + length]).map_err(|source| ReportError::Data {
        path: path.to_path_buf(),
        source,
    })
}

/// `text` with the characters HTML gives meaning escaped.
fn escape(text: &str) -> String {
    let mut escaped = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => escaped.push_str("&amp;"),
            '<' => escaped.push_str("&lt;"),
            '>' => escaped.push_str("&gt;"),
            '"' => escaped.push_str("&quot;"),
            _ => escaped.push(c),
        }
    }
    escaped
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Block, Section};

    fn page_with(text: &str) -> Page {
        Page::single(Section {
            heading: "run: <b>".into(),
            source: "a & b".into(),
            blocks: vec![Block::note(text)],
        })
    }

    #[test]
    fn a_page_reads_back_as_written_even_with_markup_in_its_strings() {
        if available().is_err() {
            eprintln!("SKIPPED: this build has no report bundle");
            return;
        }
        let page = page_with("</script><script>alert(1)</script> & \"quoted\"");
        let dir = std::env::temp_dir().join(format!("fistage-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("page.html");
        write(&page, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        // The data block is closed once, by its own tag: the string's markup
        // cannot end it.
        let start = text.find(DATA_OPEN).unwrap() + DATA_OPEN.len();
        assert!(!text[start..].starts_with("</script>"));
        assert!(!text[start..start + text[start..].find(DATA_CLOSE).unwrap()].contains("</"));
        assert_eq!(read(&path).unwrap(), page);
        assert!(text.contains("<title>run: &lt;b&gt;</title>"));
        // Nothing is left beside it.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_file_without_report_data_is_named() {
        let dir = std::env::temp_dir().join(format!("fistage-report-none-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("other.html");
        std::fs::write(&path, "<html><body>hello</body></html>").unwrap();
        let error = read(&path).unwrap_err().to_string();
        assert!(
            error.contains("other.html") && error.contains("not a fistage report"),
            "{error}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
