//! The lexer of the page's ES modules for the bundler
//! (`src/render/page/bundle.rs`): JavaScript's tokens (identifiers,
//! punctuation, strings, templates, regular expressions by the usual
//! previous-token rule, numbers), comments and white space left out, each
//! with its line. It knows tokens, not grammar.

/// What a token is; its text is the source between `start` and `end`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Ident,
    Punct,
    Str,
    Template,
    Regex,
    Number,
}

/// One token of a module, comments and white space left out.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Token {
    pub(crate) kind: Kind,
    pub(crate) start: usize,
    pub(crate) end: usize,
    pub(crate) line: usize,
}

/// Operators, longest first (so `>>>=` is not read as `>>` `>=`).
const PUNCT: &[&str] = &[
    ">>>=", "...", "===", "!==", "**=", "<<=", ">>=", ">>>", "&&=", "||=", "??=", "=>", "==", "!=",
    "<=", ">=", "&&", "||", "??", "?.", "++", "--", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=",
    "**", "<<", ">>",
];

/// Words after which a `/` starts a regular expression, not a division.
const BEFORE_REGEX: &[&str] = &[
    "return",
    "typeof",
    "instanceof",
    "in",
    "of",
    "new",
    "delete",
    "void",
    "throw",
    "case",
    "do",
    "else",
    "yield",
    "await",
];

/// The tokens of `text`, or the line and the reason it cannot be read.
pub(crate) fn tokens(text: &str) -> Result<Vec<Token>, (usize, String)> {
    let b = text.as_bytes();
    let mut out: Vec<Token> = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < b.len() {
        let c = b[i];
        let start = i;
        let at = line;
        if c == b'\n' {
            line += 1;
            i += 1;
            continue;
        }
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        if c == b'/' && b.get(i + 1) == Some(&b'*') {
            let end = text[i + 2..]
                .find("*/")
                .ok_or((at, "unterminated comment".to_string()))?;
            line += text[i..i + 2 + end].matches('\n').count();
            i += end + 4;
            continue;
        }
        let kind = if c == b'"' || c == b'\'' {
            i = string_end(b, i, &mut line).ok_or((at, "unterminated string".to_string()))?;
            Kind::Str
        } else if c == b'`' {
            i = template_end(b, i, &mut line).ok_or((at, "unterminated template".to_string()))?;
            Kind::Template
        } else if c == b'/' && regex_may_start(text, out.last()) {
            i = regex_end(b, i).ok_or((at, "unterminated regular expression".to_string()))?;
            Kind::Regex
        } else if c.is_ascii_digit() || (c == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            i = number_end(b, i);
            Kind::Number
        } else if c.is_ascii_alphabetic() || c == b'_' || c == b'$' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_' || b[i] == b'$') {
                i += 1;
            }
            Kind::Ident
        } else {
            let op = PUNCT.iter().find(|p| text[i..].starts_with(**p));
            let width = op.map_or_else(
                || text[i..].chars().next().map_or(1, char::len_utf8),
                |p| p.len(),
            );
            i += width;
            Kind::Punct
        };
        out.push(Token {
            kind,
            start,
            end: i,
            line: at,
        });
    }
    Ok(out)
}

/// Past the closing quote of the string opening at `i`.
fn string_end(b: &[u8], mut i: usize, line: &mut usize) -> Option<usize> {
    let quote = b[i];
    i += 1;
    while i < b.len() {
        match b[i] {
            b'\\' => {
                if b.get(i + 1) == Some(&b'\n') {
                    *line += 1;
                }
                i += 2;
            }
            b'\n' => return None,
            c if c == quote => return Some(i + 1),
            _ => i += 1,
        }
    }
    None
}

/// Past the closing backtick of the template opening at `i` (its `${…}`
/// parts skipped by their braces).
fn template_end(b: &[u8], mut i: usize, line: &mut usize) -> Option<usize> {
    i += 1;
    let mut depth = 0usize;
    while i < b.len() {
        match b[i] {
            b'\\' => i += 1,
            b'\n' => *line += 1,
            b'`' if depth == 0 => return Some(i + 1),
            b'$' if depth == 0 && b.get(i + 1) == Some(&b'{') => {
                depth = 1;
                i += 1;
            }
            b'{' if depth > 0 => depth += 1,
            b'}' if depth > 0 => depth -= 1,
            _ => {}
        }
        i += 1;
    }
    None
}

/// Past the flags of the regular expression opening at `i`.
fn regex_end(b: &[u8], mut i: usize) -> Option<usize> {
    i += 1;
    let mut class = false;
    while i < b.len() {
        match b[i] {
            b'\\' => i += 1,
            b'\n' => return None,
            b'[' => class = true,
            b']' => class = false,
            b'/' if !class => {
                i += 1;
                while i < b.len() && b[i].is_ascii_alphabetic() {
                    i += 1;
                }
                return Some(i);
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// Past the number starting at `i` (`1e-12` included).
fn number_end(b: &[u8], mut i: usize) -> usize {
    let hex = b.get(i + 1).is_some_and(|c| matches!(c, b'x' | b'X'));
    while i < b.len() {
        let c = b[i];
        let sign = matches!(c, b'+' | b'-') && !hex && matches!(b[i - 1], b'e' | b'E');
        if !(c.is_ascii_alphanumeric() || c == b'.' || c == b'_' || sign) {
            break;
        }
        i += 1;
    }
    i
}

/// Whether a `/` after `last` starts a regular expression.
fn regex_may_start(text: &str, last: Option<&Token>) -> bool {
    match last {
        None => true,
        Some(t) => {
            let s = &text[t.start..t.end];
            match t.kind {
                Kind::Punct => !matches!(s, ")" | "]" | "}"),
                Kind::Ident => BEFORE_REGEX.contains(&s),
                _ => false,
            }
        }
    }
}
