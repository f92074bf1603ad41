//! "Did you mean": the known name closest to a misspelt one, for error
//! messages about columns, formats, roles and config keys. Similarity is
//! strsim's Jaro–Winkler (a maintained crate, the one clap suggests
//! subcommands with), compared without case.

/// Jaro–Winkler similarity from which a name counts as a likely misspelling
/// (clap's own threshold for "a similar subcommand exists" is 0.7 on plain
/// Jaro; Winkler's prefix bonus lifts scores, hence a little higher).
const LIKELY: f64 = 0.8;

/// The candidate most like `word` (ignoring case), if any is likely meant;
/// never `word` itself.
pub fn closest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let word = word.to_lowercase();
    candidates
        .into_iter()
        .filter(|c| c.to_lowercase() != word)
        .map(|c| (strsim::jaro_winkler(&word, &c.to_lowercase()), c))
        .filter(|(score, _)| *score >= LIKELY)
        // The first of equally close candidates, so the hint is deterministic.
        .fold(None, |best: Option<(f64, &str)>, (score, c)| match best {
            Some((b, _)) if b >= score => best,
            _ => Some((score, c)),
        })
        .map(|(_, c)| c)
}

/// `"; did you mean \"population\"?"` for a likely misspelling of a
/// candidate, else empty: ready to append to an error message.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    closest(word, candidates).map_or_else(String::new, |c| format!("; did you mean {c:?}?"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn misspellings_find_their_name() {
        let header = ["iso", "name", "population", "continent"];
        assert_eq!(closest("populaton", header), Some("population"));
        assert_eq!(closest("Continet", header), Some("continent"));
        assert_eq!(closest("weigth", ["id", "label", "weight"]), Some("weight"));
        assert_eq!(
            did_you_mean("border_list", ["border-list", "genre-table"]),
            "; did you mean \"border-list\"?"
        );
    }

    #[test]
    fn unrelated_words_get_no_hint() {
        assert_eq!(closest("zzz", ["iso", "name", "population"]), None);
        assert_eq!(did_you_mean("colour_by", ["id", "weight"]), "");
        // The word itself (another case) is not a suggestion.
        assert_eq!(closest("Name", ["name"]), None);
    }
}
