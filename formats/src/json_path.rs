//! Positions in JSON text: the path to a value ([`Step`]s of keys and indices),
//! the byte offset that path leads to in text serde_json has accepted
//! ([`locate`]), and line and character column of an offset. serde_json's
//! `Value` keeps no positions, so the hierarchy JSON reader finds them here,
//! only when it reports an error.

use std::borrow::Cow;

use crate::error::FormatError;

/// One step of a JSON path.
#[derive(Clone, Debug)]
pub(crate) enum Step<'a> {
    /// The value of this key of an object.
    Key(&'a str),
    /// The element at this index of an array.
    Index(usize),
}

/// `path` followed by one more step.
pub(crate) fn extend<'a>(path: &[Step<'a>], step: Step<'a>) -> Vec<Step<'a>> {
    let mut steps = Vec::with_capacity(path.len() + 1);
    steps.extend_from_slice(path);
    steps.push(step);
    steps
}

/// Turns a serde_json error into [`FormatError::Syntax`], converting its byte column
/// into a character column.
pub(crate) fn syntax_error(text: &[u8], error: &serde_json::Error) -> FormatError {
    let line = error.line();
    let byte_column = error.column();
    // serde_json's Display appends " at line L column C"; the position has its own fields.
    let full = error.to_string();
    let suffix = format!(" at line {line} column {byte_column}");
    let message = full.strip_suffix(&suffix).unwrap_or(&full).to_owned();
    let line_start = text
        .split_inclusive(|&b| b == b'\n')
        .take(line.saturating_sub(1))
        .map(<[u8]>::len)
        .sum::<usize>();
    let line_end = line_start.saturating_add(byte_column).min(text.len());
    let column = text
        .get(line_start..line_end)
        .map_or(byte_column, count_chars);
    FormatError::Syntax {
        line,
        column,
        message,
    }
}

/// Number of UTF-8 characters in `bytes` (continuation bytes are not counted).
fn count_chars(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b & 0xC0 != 0x80).count()
}

/// 1-based line and character column of byte `offset`.
pub(crate) fn line_column(text: &[u8], offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    (line, 1 + count_chars(&before[line_start..]))
}

/// Byte offset of the value reached by following `path` from the top-level value.
/// Expects text that serde_json has accepted; returns `None` instead of guessing if
/// the path is absent. When an object repeats a key, the last one counts, as in
/// serde_json's `Value`.
pub(crate) fn locate(text: &[u8], path: &[Step<'_>]) -> Option<usize> {
    let mut pos = skip_whitespace(text, 0);
    for step in path {
        match step {
            Step::Key(key) => {
                if text.get(pos) != Some(&b'{') {
                    return None;
                }
                pos = skip_whitespace(text, pos + 1);
                let mut found = None;
                while text.get(pos) == Some(&b'"') {
                    let key_end = skip_string(text, pos)?;
                    let name = key_text(text.get(pos..key_end)?)?;
                    pos = skip_whitespace(text, key_end);
                    if text.get(pos) != Some(&b':') {
                        return None;
                    }
                    pos = skip_whitespace(text, pos + 1);
                    if name == *key {
                        found = Some(pos);
                    }
                    pos = skip_whitespace(text, skip_value(text, pos)?);
                    if text.get(pos) == Some(&b',') {
                        pos = skip_whitespace(text, pos + 1);
                    }
                }
                pos = found?;
            }
            Step::Index(index) => {
                if text.get(pos) != Some(&b'[') {
                    return None;
                }
                pos = skip_whitespace(text, pos + 1);
                for _ in 0..*index {
                    if text.get(pos) == Some(&b']') {
                        return None;
                    }
                    pos = skip_whitespace(text, skip_value(text, pos)?);
                    if text.get(pos) != Some(&b',') {
                        return None;
                    }
                    pos = skip_whitespace(text, pos + 1);
                }
                if matches!(text.get(pos), None | Some(&b']')) {
                    return None;
                }
            }
        }
    }
    Some(pos)
}

/// The first non-whitespace offset at or after `pos`.
pub(crate) fn skip_whitespace(text: &[u8], mut pos: usize) -> usize {
    while matches!(text.get(pos), Some(b' ' | b'\t' | b'\n' | b'\r')) {
        pos += 1;
    }
    pos
}

/// The offset just past the string starting at `pos` (which holds its opening quote).
fn skip_string(text: &[u8], pos: usize) -> Option<usize> {
    let mut i = pos + 1;
    loop {
        match text.get(i)? {
            b'\\' => i += 2,
            b'"' => return Some(i + 1),
            _ => i += 1,
        }
    }
}

/// The offset just past the value starting at `pos`.
fn skip_value(text: &[u8], pos: usize) -> Option<usize> {
    match text.get(pos)? {
        b'"' => skip_string(text, pos),
        b'{' | b'[' => {
            let mut depth = 0usize;
            let mut i = pos;
            loop {
                match text.get(i)? {
                    b'"' => {
                        i = skip_string(text, i)?;
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth = depth.checked_sub(1)?;
                        if depth == 0 {
                            return Some(i + 1);
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
        }
        // Numbers, true, false, null: run to the next delimiter.
        _ => {
            let mut i = pos;
            while !matches!(
                text.get(i),
                None | Some(b',' | b']' | b'}' | b' ' | b'\t' | b'\n' | b'\r')
            ) {
                i += 1;
            }
            Some(i)
        }
    }
}

/// The text of a quoted key, unescaping only when it holds escapes.
fn key_text(quoted: &[u8]) -> Option<Cow<'_, str>> {
    if quoted.contains(&b'\\') {
        serde_json::from_slice::<String>(quoted)
            .ok()
            .map(Cow::Owned)
    } else {
        let inner = quoted.get(1..quoted.len().checked_sub(1)?)?;
        std::str::from_utf8(inner).ok().map(Cow::Borrowed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn position_of(text: &str, path: &[Step<'_>]) -> Option<(usize, usize)> {
        locate(text.as_bytes(), path).map(|offset| line_column(text.as_bytes(), offset))
    }

    #[test]
    fn locate_follows_keys_and_indices() {
        let text = "{\"a\": 1,\n \"k\\\"ey\": {\"x\": [10, {\"y\": \"]}\"}, 30]},\n \"children\": [ {\"id\": \"é\"}, {\"id\": 2} ]}";
        assert_eq!(position_of(text, &[]), Some((1, 1)));
        assert_eq!(position_of(text, &[Step::Key("a")]), Some((1, 7)));
        assert_eq!(
            position_of(text, &[Step::Key("k\"ey"), Step::Key("x"), Step::Index(2)]),
            Some((2, 35))
        );
        assert_eq!(
            position_of(
                text,
                &[Step::Key("children"), Step::Index(1), Step::Key("id")]
            ),
            Some((3, 36))
        );
        assert_eq!(position_of(text, &[Step::Key("missing")]), None);
        assert_eq!(
            position_of(text, &[Step::Key("children"), Step::Index(2)]),
            None
        );
    }

    #[test]
    fn locate_takes_the_last_of_repeated_keys() {
        let text = r#"{"w": 1, "w": 2}"#;
        assert_eq!(position_of(text, &[Step::Key("w")]), Some((1, 15)));
    }
}
