//! The list of input formats, by name. Adding a format is one line here (see
//! `formats/README.md`).

use crate::border_list::BorderList;
use crate::embedding::EmbeddingMatrix;
use crate::format::Format;
use crate::hierarchy_json::HierarchyJson;

/// Every format, one line each, in the order they are listed to users.
// Kept one format per line (rustfmt would join them) so adding one is a one-line diff.
#[rustfmt::skip]
static FORMATS: &[&dyn Format] = &[
    &HierarchyJson,
    &BorderList,
    &EmbeddingMatrix,
    &crate::genre_table::GenreTable,
    &crate::time_series::TimeSeries,
];

/// Every known format.
pub fn formats() -> &'static [&'static dyn Format] {
    FORMATS
}

/// The format called `name`, if any.
pub fn find(name: &str) -> Option<&'static dyn Format> {
    FORMATS.iter().copied().find(|format| format.name() == name)
}

/// The names of all formats, for error messages ("expected one of ...").
pub fn names() -> Vec<&'static str> {
    FORMATS.iter().map(|format| format.name()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_found() {
        let names = names();
        assert_eq!(
            names,
            [
                "hierarchy-json",
                "border-list",
                "embedding-matrix",
                "genre-table",
                "time-series"
            ]
        );
        for name in &names {
            assert_eq!(find(name).map(|f| f.name()), Some(*name));
        }
        assert!(find("nope").is_none());
        assert!(formats().iter().all(|f| !f.roles().is_empty()));
    }
}
