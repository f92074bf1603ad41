//! The text of the config `init` writes: block-style YAML whose every scalar
//! (paths, dataset and column names) is emitted by the YAML crate's serializer,
//! so a file named with a newline, `: ` or `#` reads back exactly as named,
//! and comments in which no user text can end the comment's line.

use std::collections::BTreeMap;

use serde::Serialize;

use super::guess::{Fields, PageOffer};

/// Everything the config says, decided.
pub(super) struct Plan {
    /// The command as typed (for the first comment).
    pub(super) command_line: String,
    /// Why the format was chosen, and what was left out.
    pub(super) why: Vec<String>,
    /// The dataset's name.
    pub(super) name: String,
    /// The dataset's format.
    pub(super) format: &'static str,
    /// Its inputs by role, as the config names them.
    pub(super) files: Vec<(&'static str, String)>,
    /// The node table's field mapping.
    pub(super) fields: Fields,
    /// The pairs table's strength column.
    pub(super) strength: Option<String>,
    /// The output paths.
    pub(super) outputs: Vec<String>,
    /// Columns offered (commented out) for the HTML page.
    pub(super) page: PageOffer,
}

/// `text` on one line: characters that would end a comment's line or that
/// YAML does not allow in a stream (controls, line and paragraph separators,
/// a byte order mark) written as Rust escapes.
fn one_line(text: &str) -> String {
    let printable = |c: char| {
        c == '\t'
            || (' '..='~').contains(&c)
            || (('\u{A0}'..='\u{FFFD}').contains(&c)
                && !matches!(c, '\u{2028}' | '\u{2029}' | '\u{FEFF}'))
            || c >= '\u{10000}'
    };
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if printable(c) {
            out.push(c);
        } else {
            out.extend(c.escape_default());
        }
    }
    out
}

/// A config's text, line by line.
#[derive(Default)]
struct Writer {
    text: String,
}

impl Writer {
    /// A comment line at `indent`.
    fn comment(&mut self, indent: &str, text: &str) {
        self.text.push_str(indent);
        self.text.push_str("# ");
        self.text.push_str(&one_line(text));
        self.text.push('\n');
    }

    /// `key: value`, serialized by the YAML crate: its first line after
    /// `first`, any further lines (a block scalar, a sequence) after `rest`,
    /// with `note` as a comment after a one-line entry or above a longer one.
    fn entry<T: Serialize + ?Sized>(
        &mut self,
        (first, rest): (&str, &str),
        key: &str,
        value: &T,
        note: Option<&str>,
    ) -> Result<(), serde_yaml::Error> {
        let yaml = serde_yaml::to_string(&BTreeMap::from([(key, value)]))?;
        let lines: Vec<&str> = yaml.lines().collect();
        let inline = lines.len() == 1;
        if let (Some(note), false) = (note, inline) {
            self.comment(first.trim_end_matches("- "), note);
        }
        for (i, line) in lines.iter().enumerate() {
            self.text.push_str(if i == 0 { first } else { rest });
            self.text.push_str(line);
            if let (Some(note), true) = (note, inline) {
                self.text.push_str("  # ");
                self.text.push_str(&one_line(note));
            }
            self.text.push('\n');
        }
        Ok(())
    }

    /// [`Writer::entry`] at `indent`, further lines (a sequence's items) two
    /// spaces deeper.
    fn at<T: Serialize + ?Sized>(
        &mut self,
        indent: &str,
        key: &str,
        value: &T,
        note: Option<&str>,
    ) -> Result<(), serde_yaml::Error> {
        self.entry((indent, &format!("{indent}  ")), key, value, note)
    }
}

/// The dataset's `fields:` section: each column `init` chose, or a comment
/// saying what it looked for and found none of.
fn write_fields(w: &mut Writer, plan: &Plan, f: &str) -> Result<(), serde_yaml::Error> {
    w.text.push_str("    fields:\n");
    let fields = &plan.fields;
    w.at(f, "id", &fields.id, Some("unique per row"))?;
    match &fields.label {
        Some(label) => w.at(f, "label", label, None)?,
        None => w.comment(
            f,
            "label: COLUMN       # no short text column unique per row: labels show the id",
        ),
    }
    match &fields.weight {
        Some(weight) => w.at(f, "weight", weight, Some("cell areas"))?,
        None => w.comment(
            f,
            "weight: COLUMN      # no numeric column found: every leaf weighs 1",
        ),
    }
    if fields.groups.is_empty() {
        w.comment(
            f,
            "groups: [COLUMN]    # grouping columns, outermost first (none found)",
        );
    } else {
        w.at(f, "groups", &fields.groups, Some("outermost first"))?;
    }
    for note in &fields.notes {
        w.comment(f, note);
    }
    if let Some(genres) = fields
        .genres
        .as_ref()
        .filter(|_| plan.format == "genre-table")
    {
        w.at(
            f,
            "genres",
            genres,
            Some("several values per row, split at |"),
        )?;
    }
    if let Some(strength) = &plan.strength {
        w.at(f, "strength", strength, None)?;
    }
    Ok(())
}

/// The page's own columns and link, commented out: written by the YAML
/// crate, then commented line by line, so removing the `# ` gives valid
/// YAML.
fn write_page(w: &mut Writer, plan: &Plan, d: &str) -> Result<(), serde_yaml::Error> {
    if !plan.page.fields.is_empty() || plan.page.link.is_some() {
        let mut page = Writer::default();
        page.text.push_str("page:\n");
        if !plan.page.fields.is_empty() {
            page.at("  ", "fields", &plan.page.fields, None)?;
        }
        if let Some(link) = &plan.page.link {
            page.at("  ", "link", link, None)?;
            page.at("  ", "link_target", "new-tab", None)?;
        }
        w.comment(
            d,
            "Your own columns in the HTML page's tooltip, and a link on click (remove the #):",
        );
        for line in page.text.lines() {
            w.comment(d, line);
        }
    }
    Ok(())
}

/// The commented config of `plan`.
pub(super) fn config_text(plan: &Plan) -> Result<String, serde_yaml::Error> {
    let mut w = Writer::default();
    w.comment("", &format!("Written by `{}`.", plan.command_line));
    w.comment(
        "",
        "Build with `nptreemap build`, keep current with `nptreemap watch`.",
    );
    w.comment(
        "",
        "Every key, with its default and what it does: `nptreemap config --defaults`.",
    );
    for line in &plan.why {
        w.comment("", line);
    }
    w.text.push_str("layout:\n");
    w.at(
        "  ",
        "seed",
        &1,
        Some("the same seed gives the same picture"),
    )?;
    if let Some(text) = &plan.fields.label_text {
        w.text.push_str("render:\n  labels:\n");
        w.at(
            "    ",
            "text",
            text,
            Some("the label column repeats: this is unique per row"),
        )?;
    }
    w.text.push_str("datasets:\n");
    let (item, d) = ("  - ", "    ");
    w.entry((item, d), "name", &plan.name, None)?;
    w.at(d, "format", plan.format, None)?;
    w.text.push_str("    files:\n");
    let f = "      ";
    for (role, path) in &plan.files {
        w.at(f, role, path, None)?;
    }
    write_fields(&mut w, plan, f)?;
    write_page(&mut w, plan, d)?;
    w.text.push_str("    outputs:\n");
    for path in &plan.outputs {
        w.entry(("      - ", "        "), "path", path, None)?;
    }
    Ok(w.text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(name: &str, path: &str, column: &str) -> Plan {
        Plan {
            command_line: format!("nptreemap init {path}"),
            why: vec![format!("column {column:?} lists several values")],
            name: name.to_owned(),
            format: "genre-table",
            files: vec![("nodes", path.to_owned())],
            page: PageOffer::default(),
            fields: Fields {
                id: "id".to_owned(),
                label: Some(column.to_owned()),
                weight: None,
                groups: vec![column.to_owned(), "b".to_owned()],
                genres: Some(column.to_owned()),
                label_text: None,
                notes: Vec::new(),
            },
            strength: None,
            outputs: vec![format!("out/{name}.svg")],
        }
    }

    #[test]
    fn awkward_names_read_back_as_written() {
        for text in [
            "plain.csv",
            "a: b.csv",
            "x #1.csv",
            "two\nlines.csv",
            "trailing \n",
            "yes",
            "null",
            "1.5",
            "- dash",
            "[bracket]",
            "{brace}",
            "'quote\"",
            "tab\there",
            "bell\u{7}",
            "line\u{2028}sep",
            "\u{feff}bom",
            "*star &amp !tag %pct @at `tick",
        ] {
            let yaml = config_text(&plan(text, text, text)).expect("serialize");
            let value: serde_yaml::Value =
                serde_yaml::from_str(&yaml).unwrap_or_else(|e| panic!("{text:?}: {e}\n{yaml}"));
            let d = &value["datasets"][0];
            assert_eq!(d["name"].as_str(), Some(text), "{yaml}");
            assert_eq!(d["files"]["nodes"].as_str(), Some(text), "{yaml}");
            assert_eq!(d["fields"]["label"].as_str(), Some(text), "{yaml}");
            assert_eq!(d["fields"]["groups"][0].as_str(), Some(text), "{yaml}");
            assert_eq!(d["fields"]["genres"].as_str(), Some(text), "{yaml}");
            assert_eq!(
                d["outputs"][0]["path"].as_str(),
                Some(format!("out/{text}.svg").as_str()),
                "{yaml}"
            );
            assert_eq!(value["layout"]["seed"].as_u64(), Some(1), "{yaml}");
        }
    }
}
