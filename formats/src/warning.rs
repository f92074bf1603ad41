//! [`Warning`]: something in an input that is read but probably not what the
//! user meant (a header without rows, a repeated column name, a pair of a
//! node with itself, a pair repeated with another strength), and
//! [`Warnings`], the bounded list a dataset carries: the first few of each
//! kind verbatim, the rest counted in one line per kind. The dataset is still
//! valid; `check`, `build` and `watch` report the warnings it carries.

use std::fmt;

/// What a [`Warning`] is about: warnings of one kind in one input are
/// summarised together past the first few.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum WarningKind {
    /// A header names a column twice.
    RepeatedColumn,
    /// A table has a header but no rows.
    EmptyTable,
    /// A node table has no weight column.
    NoWeight,
    /// A pair, vector row or series column names an id no node has.
    UnknownId,
    /// A pair joins a node to itself.
    SelfPair,
    /// A pair repeats an earlier one with another strength.
    RepeatedPair,
    /// Neighbour lists of hierarchy JSON and what the similarity makes of them.
    Neighbors,
}

impl WarningKind {
    /// The kind in the plural, for "and N more ...".
    pub fn plural(self) -> &'static str {
        match self {
            WarningKind::RepeatedColumn => "repeated column names",
            WarningKind::EmptyTable => "tables without rows",
            WarningKind::NoWeight => "tables without a weight column",
            WarningKind::UnknownId => "unknown ids",
            WarningKind::SelfPair => "pairs of a node with itself",
            WarningKind::RepeatedPair => "pairs repeated with another strength",
            WarningKind::Neighbors => "notes on neighbour lists",
        }
    }
}

/// One warning about an input, with its role and line like an error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// What the warning is about.
    pub kind: WarningKind,
    /// The role of the input (a [`crate::Role::name`]); the caller maps it to a path.
    pub role: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// What looks wrong, and what the reader did about it.
    pub message: String,
}

impl Warning {
    /// A warning of `kind` about input `role` at `line`.
    pub fn new(
        kind: WarningKind,
        role: impl Into<String>,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        Warning {
            kind,
            role: role.into(),
            line,
            message: message.into(),
        }
    }
}

/// `line L: message` (or the message alone); the caller puts the file first.
impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "line {line}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

/// Warnings as a reader collects them: the first [`Warnings::KEPT`] of each
/// kind in each input verbatim, in the order they came, and a count of the
/// rest. A million repeated pairs gave 378,713 warning lines on every build
/// (and as many strings in memory); they now cost five lines and a number.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Warnings {
    kept: Vec<Warning>,
    /// How many warnings each (role, kind) had, in the order first seen; few
    /// entries (kinds times inputs), so a list is searched.
    seen: Vec<(String, WarningKind, usize)>,
}

impl Warnings {
    /// Warnings of one kind in one input kept verbatim; the rest are counted.
    pub const KEPT: usize = 5;

    /// No warnings yet.
    pub fn new() -> Self {
        Warnings::default()
    }

    /// Adds a warning: kept when fewer than [`Warnings::KEPT`] of its kind and
    /// input came before it, else counted.
    pub fn push(&mut self, warning: Warning) {
        let slot = self.slot(&warning.role, warning.kind);
        let before = self.seen[slot].2;
        self.seen[slot].2 = before.saturating_add(1);
        if before < Warnings::KEPT {
            self.kept.push(warning);
        }
    }

    /// The index in `seen` of (`role`, `kind`), added with a count of 0.
    fn slot(&mut self, role: &str, kind: WarningKind) -> usize {
        match self
            .seen
            .iter()
            .position(|(r, k, _)| *k == kind && r == role)
        {
            Some(slot) => slot,
            None => {
                self.seen.push((role.to_owned(), kind, 0));
                self.seen.len() - 1
            }
        }
    }

    /// Adds every warning of `other`, the ones it only counted included.
    pub fn append(&mut self, other: Warnings) {
        let Warnings { kept, seen } = other;
        let counted: Vec<(String, WarningKind, usize)> = seen
            .into_iter()
            .map(|(role, kind, total)| {
                let listed = kept
                    .iter()
                    .filter(|w| w.kind == kind && w.role == role)
                    .count();
                (role, kind, total - listed)
            })
            .collect();
        // The listed ones first, so they are kept where there is room.
        self.extend(kept);
        for (role, kind, more) in counted {
            let slot = self.slot(&role, kind);
            self.seen[slot].2 = self.seen[slot].2.saturating_add(more);
        }
    }

    /// The same warnings, all about input `role` (a table's reader does not
    /// know which input it reads).
    pub fn with_role(mut self, role: &str) -> Self {
        for warning in &mut self.kept {
            role.clone_into(&mut warning.role);
        }
        for (r, _, _) in &mut self.seen {
            role.clone_into(r);
        }
        self
    }

    /// The warnings kept verbatim, in order.
    pub fn iter(&self) -> impl Iterator<Item = &Warning> {
        self.kept.iter()
    }

    /// True when nothing was added.
    pub fn is_empty(&self) -> bool {
        self.kept.is_empty()
    }

    /// The warnings kept, then one line per kind and input that had more:
    /// "and N more `<kind>` (the first 5 are listed)", without a line.
    pub fn into_vec(self) -> Vec<Warning> {
        let mut summaries = Vec::new();
        for (role, kind, total) in self.seen {
            let listed = self
                .kept
                .iter()
                .filter(|w| w.kind == kind && w.role == role)
                .count();
            if total > listed {
                let message = format!(
                    "and {} more {} (the first {listed} are listed)",
                    total - listed,
                    kind.plural(),
                );
                summaries.push(Warning::new(kind, role, None, message));
            }
        }
        let mut out = self.kept;
        out.extend(summaries);
        out
    }
}

impl Extend<Warning> for Warnings {
    fn extend<I: IntoIterator<Item = Warning>>(&mut self, warnings: I) {
        for warning in warnings {
            self.push(warning);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(line: usize) -> Warning {
        Warning::new(WarningKind::RepeatedPair, "pairs", Some(line), "again")
    }

    #[test]
    fn the_first_few_of_each_kind_are_kept_and_the_rest_counted() {
        let mut w = Warnings::new();
        for line in 1..=8 {
            w.push(pair(line));
        }
        w.push(Warning::new(
            WarningKind::SelfPair,
            "pairs",
            Some(9),
            "self",
        ));
        // The same kind in another input is counted apart.
        w.push(Warning::new(
            WarningKind::RepeatedPair,
            "other",
            Some(1),
            "x",
        ));
        let lines: Vec<String> = w
            .into_vec()
            .iter()
            .map(|w| format!("{}: {w}", w.role))
            .collect();
        assert_eq!(
            lines,
            [
                "pairs: line 1: again",
                "pairs: line 2: again",
                "pairs: line 3: again",
                "pairs: line 4: again",
                "pairs: line 5: again",
                "pairs: line 9: self",
                "other: line 1: x",
                "pairs: and 3 more pairs repeated with another strength (the first 5 are listed)",
            ]
        );
    }

    #[test]
    fn appending_keeps_the_counts() {
        // 7 in one collection and 4 in another: 11 in all, 5 kept.
        let (mut a, mut b) = (Warnings::new(), Warnings::new());
        (1..=7).for_each(|l| a.push(pair(l)));
        (8..=11).for_each(|l| b.push(pair(l)));
        let mut all = Warnings::new();
        all.append(a);
        all.append(b);
        let out = all.into_vec();
        assert_eq!(out.len(), 6);
        assert_eq!(out[4].line, Some(5));
        assert!(
            out[5].message.starts_with("and 6 more pairs"),
            "{:?}",
            out[5]
        );
    }
}
