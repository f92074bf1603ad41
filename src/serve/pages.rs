//! The pages the live preview served lately, by dataset and build key, so
//! that a page can ask for what changed since its own key (`GET
//! <page>?since=KEY`, issue 32) instead of fetching itself whole: the
//! answer is `render::page_patch` from the page it has to the page on disk.
//! Owns the memo (the last [`KEPT`] pages of each dataset) and its rule for
//! a key served with two texts: a page's key is taken before its file is
//! read (`events.rs`), so two pages stamped with one key can differ when a
//! rebuild lands between; such a key is forgotten, and its pages load whole.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

/// Pages kept per dataset: the one on disk and the one before it.
pub(crate) const KEPT: usize = 2;

/// Pages larger than this are not kept (they load whole): a bound on the
/// memo's memory, about four pages of 20,000 leaves.
pub(crate) const MAX_KEPT_BYTES: usize = 64 << 20;

/// The text served under a key, or `None` when two texts were.
type Entry = (String, Option<Arc<str>>);

/// The memo of served pages.
#[derive(Debug, Default)]
pub(crate) struct Pages {
    by_dataset: BTreeMap<String, VecDeque<Entry>>,
}

impl Pages {
    /// Notes that `text` was served (or read) as `dataset`'s page of `key`.
    pub(crate) fn remember(&mut self, dataset: &str, key: &str, text: &Arc<str>) {
        if text.len() > MAX_KEPT_BYTES {
            return;
        }
        let list = self.by_dataset.entry(dataset.to_string()).or_default();
        if let Some(entry) = list.iter_mut().find(|(k, _)| k == key) {
            if entry.1.as_ref().is_some_and(|t| t != text) {
                entry.1 = None;
            }
            return;
        }
        list.push_back((key.to_string(), Some(text.clone())));
        while list.len() > KEPT {
            list.pop_front();
        }
    }

    /// The page `dataset` was served with under `key`, if it is kept and
    /// unambiguous.
    pub(crate) fn get(&self, dataset: &str, key: &str) -> Option<Arc<str>> {
        self.by_dataset
            .get(dataset)?
            .iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, t)| t.clone())
    }
}

/// The key a page asks for changes since (`since=KEY` in the query), if any.
pub(crate) fn since(target: &str) -> Option<&str> {
    let query = target.split_once('?')?.1.split('#').next()?;
    query
        .split('&')
        .find_map(|pair| pair.strip_prefix("since="))
        .filter(|k| !k.is_empty() && k.len() <= 64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_pages_are_kept_and_an_ambiguous_key_is_forgotten() {
        let mut pages = Pages::default();
        let (a, b, c): (Arc<str>, Arc<str>, Arc<str>) = ("a".into(), "b".into(), "c".into());
        pages.remember("d", "k1", &a);
        pages.remember("d", "k2", &b);
        assert_eq!(pages.get("d", "k1").as_deref(), Some("a"));
        pages.remember("d", "k2", &b);
        assert_eq!(pages.get("d", "k2").as_deref(), Some("b"), "the same text again");
        pages.remember("d", "k2", &c);
        assert_eq!(pages.get("d", "k2"), None, "two texts under one key");
        pages.remember("d", "k3", &c);
        assert_eq!(pages.get("d", "k1"), None, "only {KEPT} kept");
        assert_eq!(pages.get("d", "k3").as_deref(), Some("c"));
        assert_eq!(pages.get("other", "k3"), None);
    }

    #[test]
    fn since_reads_the_query_only() {
        assert_eq!(since("/out/a.html?since=x.3"), Some("x.3"));
        assert_eq!(since("/out/a.html?b=1&since=x.3#f"), Some("x.3"));
        assert_eq!(since("/out/a.html"), None);
        assert_eq!(since("/out/since=x.html"), None);
        assert_eq!(since("/out/a.html?since="), None);
    }
}
