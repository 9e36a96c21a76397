//! Byte offsets in a scenario file to 1-based line:column positions.

use std::fmt;

/// A position in a scenario file: 1-based line and 1-based column, the
/// column counted in characters (not bytes).
///
/// Every validated cable, body, joint, winch and probe keeps the location of
/// its table header so that later errors (a diverging cable, say) can point
/// at it with [`ScenarioError::at`](super::ScenarioError::at).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Location {
    /// Line, starting at 1 (0 means "no position", e.g. an unreadable file).
    pub line: usize,
    /// Column in characters, starting at 1.
    pub col: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

/// Line starts of a source text, for offset → line:col conversion.
pub(crate) struct LineIndex<'a> {
    src: &'a str,
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    /// Index the line starts of `src`.
    pub(crate) fn new(src: &'a str) -> Self {
        let mut starts = vec![0];
        starts.extend(src.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { src, starts }
    }

    /// Largest char boundary ≤ `byte` (clamped to the text).
    fn boundary(&self, byte: usize) -> usize {
        let mut b = byte.min(self.src.len());
        while b > 0 && !self.src.is_char_boundary(b) {
            b -= 1;
        }
        b
    }

    /// Line and column of byte offset `byte`.
    pub(crate) fn location(&self, byte: usize) -> Location {
        let b = self.boundary(byte);
        let line0 = self.starts.partition_point(|&s| s <= b).saturating_sub(1);
        let start = self.starts.get(line0).copied().unwrap_or(0);
        let col = self.src.get(start..b).map_or(0, |s| s.chars().count()) + 1;
        Location { line: line0 + 1, col }
    }

    /// Text of 1-based line `line` without its line terminator.
    pub(crate) fn line_text(&self, line: usize) -> &'a str {
        line_of(self.src, line)
    }

    /// Number of characters of `start..end` that lie on the line of `start`
    /// (at least 1), for the underline.
    pub(crate) fn underline_len(&self, start: usize, end: usize) -> usize {
        let a = self.boundary(start);
        let b = self.boundary(end.max(start));
        let piece = self.src.get(a..b).unwrap_or("");
        let first_line = piece.split('\n').next().unwrap_or("");
        first_line.trim_end_matches('\r').chars().count().max(1)
    }
}

/// Text of 1-based line `line` of `src` without its terminator ("" if none).
pub(crate) fn line_of(src: &str, line: usize) -> &str {
    if line == 0 {
        return "";
    }
    src.split('\n').nth(line - 1).map(|l| l.trim_end_matches('\r')).unwrap_or("")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_span_offsets_to_line_col() {
        let src = "ab\nçd = 1\r\n\nx";
        let ix = LineIndex::new(src);
        assert_eq!(ix.location(0), Location { line: 1, col: 1 });
        assert_eq!(ix.location(3), Location { line: 2, col: 1 });
        // 'ç' is two bytes: "d" is the second character.
        assert_eq!(ix.location(5), Location { line: 2, col: 2 });
        // Inside a multi-byte character: snaps back.
        assert_eq!(ix.location(4), Location { line: 2, col: 1 });
        assert_eq!(ix.location(src.len()), Location { line: 4, col: 2 });
        assert_eq!(ix.location(10_000), Location { line: 4, col: 2 });
        assert_eq!(ix.line_text(2), "çd = 1");
        assert_eq!(ix.line_text(9), "");
        assert_eq!(ix.underline_len(3, 7), 3);
        assert_eq!(ix.underline_len(3, 3), 1);
    }
}
