//! The scenario error: a message with file:line:col and the offending line.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::span::{line_of, LineIndex, Location};

/// An invalid (or unreadable) scenario file.
///
/// `Display` renders it like rustc:
///
/// ```text
/// error: cable `main`: `segments` must be between 1 and 100000, found 0
///  --> crane.toml:12:12
///   |
/// 12 | segments = 0
///   |            ^
/// ```
#[derive(Debug, thiserror::Error)]
#[error("{}", self.render())]
pub struct ScenarioError {
    /// The scenario file as given to [`load`](super::load) or
    /// [`parse`](super::parse).
    pub file: PathBuf,
    /// 1-based line; 0 when the error has no position (unreadable file).
    pub line: usize,
    /// 1-based column in characters; 0 when the error has no position.
    pub col: usize,
    /// Number of characters to underline (at least 1).
    pub len: usize,
    /// What is wrong, without position.
    pub message: String,
    /// The text of line `line` (empty when there is none).
    pub source_line: String,
    /// The I/O error when the file could not be read.
    #[source]
    pub io: Option<std::io::Error>,
}

impl ScenarioError {
    /// An error at byte range `span` of `source` (the text of `file`).
    pub fn new(file: impl Into<PathBuf>, source: &str, span: Range<usize>, message: impl Into<String>) -> Self {
        let index = LineIndex::new(source);
        let loc = index.location(span.start);
        ScenarioError {
            file: file.into(),
            line: loc.line,
            col: loc.col,
            len: index.underline_len(span.start, span.end),
            message: message.into(),
            source_line: index.line_text(loc.line).to_string(),
            io: None,
        }
    }

    /// An error at `location` of `file`, for problems found after
    /// validation (e.g. a cable that diverges). The source line is read back
    /// from the file if it is still readable; the underline runs from the
    /// column to the end of the line.
    pub fn at(file: impl Into<PathBuf>, location: Location, message: impl Into<String>) -> Self {
        let file = file.into();
        let source_line = std::fs::read_to_string(&file).map(|s| line_of(&s, location.line).to_string()).unwrap_or_default();
        let rest = source_line.chars().skip(location.col.saturating_sub(1)).collect::<String>();
        ScenarioError {
            file,
            line: location.line,
            col: location.col,
            len: rest.trim_end().chars().count().max(1),
            message: message.into(),
            source_line,
            io: None,
        }
    }

    /// The file `file` could not be read.
    pub fn io(file: &Path, error: std::io::Error) -> Self {
        ScenarioError {
            file: file.to_path_buf(),
            line: 0,
            col: 0,
            len: 1,
            message: format!("cannot read {}: {error}", file.display()),
            source_line: String::new(),
            io: Some(error),
        }
    }

    /// The position of the error.
    pub fn location(&self) -> Location {
        Location { line: self.line, col: self.col }
    }

    /// The rustc-style rendering used by `Display`.
    fn render(&self) -> String {
        let mut out = format!("error: {}", self.message);
        if self.line == 0 {
            let _ = write!(out, "\n --> {}", self.file.display());
            return out;
        }
        let num = self.line.to_string();
        let pad = " ".repeat(num.len());
        let _ = write!(out, "\n{pad}--> {}:{}:{}\n{pad} |", self.file.display(), self.line, self.col);
        if !self.source_line.is_empty() || self.col <= 1 {
            let (shown, col) = window(&self.source_line, self.col);
            // Keep tabs so that the caret lines up under the source text.
            let lead: String = shown.chars().take(col.saturating_sub(1)).map(|c| if c == '\t' { '\t' } else { ' ' }).collect();
            let room = shown.chars().count().saturating_sub(col.saturating_sub(1)).max(1);
            let _ = write!(out, "\n{num} | {shown}\n{pad} | {lead}{}", "^".repeat(self.len.clamp(1, room)));
        }
        out
    }
}

/// Longest source line shown in full, in characters.
const MAX_LINE: usize = 120;

/// The part of `line` shown around 1-based column `col` (long lines are cut
/// with `…`), and the column within it.
fn window(line: &str, col: usize) -> (String, usize) {
    let n = line.chars().count();
    if n <= MAX_LINE {
        return (line.to_string(), col);
    }
    let half = MAX_LINE / 2;
    let from = col.saturating_sub(1).saturating_sub(half).min(n.saturating_sub(MAX_LINE));
    let mut shown: String = line.chars().skip(from).take(MAX_LINE).collect();
    let mut col = col - from;
    if from > 0 {
        shown.insert(0, '…');
        col += 1;
    }
    if from + MAX_LINE < n {
        shown.push('…');
    }
    (shown, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_error_renders_like_rustc() {
        let src = "a = 1\n\n\n\n\n\n\n\n\n\n\nsegments = 0\n";
        let at = src.find("0\n").unwrap_or(0);
        let e = ScenarioError::new("x.toml", src, at..at + 1, "bad");
        assert_eq!((e.line, e.col), (12, 12));
        assert_eq!(e.to_string(), "error: bad\n  --> x.toml:12:12\n   |\n12 | segments = 0\n   |            ^");
    }

    #[test]
    fn scenario_error_cuts_long_lines() {
        let line = format!("{}X{}", "a".repeat(500), "b".repeat(500));
        let (shown, col) = window(&line, 501);
        assert_eq!(shown.chars().nth(col - 1), Some('X'));
        assert!(shown.starts_with('…') && shown.ends_with('…'));
        assert_eq!(window("short", 3), ("short".to_string(), 3));
        let (shown, col) = window(&line, 1000);
        assert_eq!((shown.chars().nth(col - 1), shown.ends_with('…')), (Some('b'), false));
    }
}
