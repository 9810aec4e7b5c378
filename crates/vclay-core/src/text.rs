//! Locating places in source text for error messages (scenario and spec files): the 1-based
//! line (and column) of a byte offset, and the line of a `key = ...` entry inside a TOML table.

use std::ops::Range;

/// 1-based line of byte offset `at` in `text` (offsets past the end count as the end).
pub fn line_at(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// 1-based line and column (in characters) of byte offset `at` in `text`.
pub fn line_column(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line_at(text, at), col)
}

/// The line of `key = ...` in the TOML table whose span is `span` (searched from the span's
/// start up to the next table header after it, inline tables `{ key = ... }` included); the
/// span's first line when the key is not written there (a default, or an error about the
/// table as a whole).
pub fn key_line(text: &str, span: &Range<usize>, key: &str) -> usize {
    let start = span.start.min(text.len());
    let mut offset = start;
    for (k, line) in text[start..].split_inclusive('\n').enumerate() {
        let t = line.trim_start();
        if k > 0 && offset >= span.end && t.starts_with('[') {
            break;
        }
        if let Some(rest) = t.strip_prefix(key)
            && rest.trim_start().starts_with('=')
        {
            return line_at(text, offset);
        }
        if let Some(pos) = line.find(&format!(" {key} =")) {
            return line_at(text, offset + pos);
        }
        offset += line.len();
    }
    line_at(text, start)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_columns_and_keys() {
        let text =
            "[model]\nkind = \"x\"\n\n[[force]]\nk = 2\nspring = { at = 1, k = 3 }\n[out]\nk = 9\n";
        assert_eq!(line_at(text, 0), 1);
        assert_eq!(line_at(text, 8), 2);
        assert_eq!(line_at(text, 10_000), 9);
        assert_eq!(line_column(text, 10), (2, 3));
        let model = 0..8;
        assert_eq!(key_line(text, &model, "kind"), 2);
        assert_eq!(key_line(text, &model, "missing"), 1);
        let force = text.find("[[force]]").unwrap()..text.find("[out]").unwrap();
        assert_eq!(key_line(text, &force, "k"), 5);
        assert_eq!(key_line(text, &force, "at"), 6);
        // The next table's `k` is not this table's.
        let out = text.find("[out]").unwrap()..text.len();
        assert_eq!(key_line(text, &out, "k"), 8);
    }
}
