//! Which text a node's label shows (`render.labels.text`, issue 33 item 1):
//! the one function every output asks for a node's name ([`display_name`](crate::render::label_text::display_name):
//! the SVG and PNG labels, group names and legend, and the page's data, whose
//! script draws and lists what it is given). Owns the choice of text; may not
//! measure or place it.

use std::collections::BTreeMap;

use nptreemap_formats::{suggest, Dataset};

use super::chains::original;

/// The separators of a path-like id, strongest first: an id with `::` or `/`
/// is split there only (`src/render/labels.rs` ends in `labels.rs`), a dotted
/// one at its dots (`sympy.stats.rv`).
const SEPARATORS: [&str; 3] = ["::", "/", "."];

/// What a label says (`render.labels.text`).
#[derive(serde::Serialize, Clone, Debug, Default, PartialEq)]
pub enum LabelText {
    /// The label; but a path-like label whose leading segments repeat its
    /// group's name shows the rest (`sympy.stats.rv` in `sympy.stats`: `rv`).
    #[default]
    Auto,
    /// The label column as it is.
    Label,
    /// The node's id.
    Id,
    /// The last segment of a path-like id (`.`, `/`, `::`).
    Segment,
    /// The label without its group's name in front (`sympy.stats.rv` in
    /// group `sympy`: `stats.rv`); the label where it does not start so.
    Relative,
    /// A template over columns, such as `{name} {version}`.
    Template(Template),
}

/// The names of the fixed choices, as a config writes them.
pub const TEXT_NAMES: [&str; 5] = ["auto", "label", "id", "segment", "relative"];

impl LabelText {
    /// Parses a config value: one of [`TEXT_NAMES`], or a template (any
    /// value with a `{`). The error says what was expected, with a likely
    /// fix.
    pub fn parse(text: &str) -> Result<LabelText, String> {
        match text.trim() {
            "auto" => Ok(LabelText::Auto),
            "label" => Ok(LabelText::Label),
            "id" => Ok(LabelText::Id),
            "segment" => Ok(LabelText::Segment),
            "relative" => Ok(LabelText::Relative),
            _ if text.contains('{') || text.contains('}') => {
                Template::parse(text).map(LabelText::Template)
            }
            other => Err(format!(
                "unknown label text {other:?}, expected auto, label, id, segment, relative \
                 or a template over columns such as \"{{name}} {{version}}\"{}",
                suggest::did_you_mean(other, TEXT_NAMES)
            )),
        }
    }

    /// The columns a template reads (to be carried from the data), in
    /// order, each once; none for the fixed choices.
    pub fn columns(&self) -> Vec<&str> {
        let LabelText::Template(t) = self else {
            return Vec::new();
        };
        let mut out: Vec<&str> = Vec::new();
        for part in &t.parts {
            if let Part::Column(c) = part {
                if !BUILT_IN.contains(&c.as_str()) && !out.contains(&c.as_str()) {
                    out.push(c);
                }
            }
        }
        out
    }
}

/// Names a template may use without a column of that name: the node's own.
const BUILT_IN: [&str; 2] = ["id", "label"];

/// A label template: text with `{column}` places; `{{` and `}}` are braces.
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
pub struct Template {
    parts: Vec<Part>,
}

#[derive(serde::Serialize, Clone, Debug, PartialEq)]
enum Part {
    Text(String),
    Column(String),
}

impl Template {
    /// Parses `{name} {version}`; an unclosed or empty place is an error.
    pub fn parse(text: &str) -> Result<Template, String> {
        let mut parts = Vec::new();
        let mut literal = String::new();
        let mut chars = text.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '{' if chars.peek() == Some(&'{') => {
                    chars.next();
                    literal.push('{');
                }
                '}' if chars.peek() == Some(&'}') => {
                    chars.next();
                    literal.push('}');
                }
                '{' => {
                    let mut name = String::new();
                    loop {
                        match chars.next() {
                            Some('}') => break,
                            Some('{') | None => {
                                return Err(format!(
                                    "template {text:?}: a `{{` without its `}}` \
                                     (write `{{{{` for a brace)"
                                ))
                            }
                            Some(c) => name.push(c),
                        }
                    }
                    let name = name.trim();
                    if name.is_empty() {
                        return Err(format!("template {text:?}: `{{}}` names no column"));
                    }
                    if !literal.is_empty() {
                        parts.push(Part::Text(std::mem::take(&mut literal)));
                    }
                    parts.push(Part::Column(name.to_string()));
                }
                '}' => {
                    return Err(format!(
                        "template {text:?}: a `}}` without its `{{` (write `}}}}` for a brace)"
                    ))
                }
                c => literal.push(c),
            }
        }
        if !literal.is_empty() {
            parts.push(Part::Text(literal));
        }
        if !parts.iter().any(|p| matches!(p, Part::Column(_))) {
            return Err(format!("template {text:?} names no column"));
        }
        Ok(Template { parts })
    }

    /// The template filled from node `i`'s own values, `None` when it lacks
    /// one of the columns (group nodes carry no columns).
    fn fill(&self, dataset: &Dataset, i: usize) -> Option<String> {
        let node = dataset.node(i);
        let mut out = String::new();
        for part in &self.parts {
            match part {
                Part::Text(t) => out.push_str(t),
                Part::Column(c) => {
                    let value = node.fields.iter().find(|(name, _)| name == c).map(|f| &f.1);
                    match (value, c.as_str()) {
                        (Some(v), _) => out.push_str(v),
                        (None, "id") => out.push_str(&node.id),
                        (None, "label") => out.push_str(&node.label),
                        (None, _) => return None,
                    }
                }
            }
        }
        Some(out)
    }
}

/// `render.labels.names`: display names for ids or labels (`AS: Asia`), in
/// the config's order (the legend's `names` order). A key given twice keeps
/// its last name, at its last place, as a YAML reader that keeps the last
/// value would.
#[derive(serde::Serialize, Clone, Debug, Default, PartialEq)]
pub struct DisplayNames {
    /// (key, name) in the config's order.
    pairs: Vec<(String, String)>,
    /// The same, for lookup.
    #[serde(skip)]
    map: BTreeMap<String, String>,
}

impl DisplayNames {
    /// The names of `pairs`, in order; a repeated key keeps its last.
    pub fn new(pairs: impl IntoIterator<Item = (String, String)>) -> Self {
        let mut out: Vec<(String, String)> = Vec::new();
        for (k, v) in pairs {
            out.retain(|(key, _)| *key != k);
            out.push((k, v));
        }
        let map = out.iter().cloned().collect();
        DisplayNames { pairs: out, map }
    }

    /// The name given for `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.map.get(key).map(String::as_str)
    }

    /// Where `key` stands in the config's order.
    pub fn rank(&self, key: &str) -> Option<usize> {
        self.pairs.iter().position(|(k, _)| k == key)
    }

    /// (key, name) in the config's order.
    pub fn pairs(&self) -> &[(String, String)] {
        &self.pairs
    }
}

impl<'de> serde::Deserialize<'de> for DisplayNames {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = DisplayNames;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a map from ids or labels to display names")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Self::Value, A::Error> {
                let mut pairs = Vec::new();
                while let Some(pair) = map.next_entry::<String, String>()? {
                    pairs.push(pair);
                }
                Ok(DisplayNames::new(pairs))
            }
        }
        d.deserialize_map(Visitor)
    }
}

/// The name shown for node `i`: its entry in `names` (by id, then by label),
/// else the text `text` chooses, with control characters removed and runs
/// of white space made one space (as SVG renderers show text), trimmed.
///
/// A virtual copy (uniform depth) shows its original's text, and a node's
/// group is its nearest real ancestor, so copies change no label.
pub fn display_name(dataset: &Dataset, i: usize, names: &DisplayNames, text: &LabelText) -> String {
    let i = original(dataset, i);
    let node = dataset.node(i);
    if let Some(name) = names.get(&node.id).or_else(|| names.get(&node.label)) {
        return clean(name);
    }
    let group = node.parent.map(|p| dataset.node(original(dataset, p)));
    let group = group.filter(|g| g.parent.is_some());
    let chosen = match text {
        LabelText::Label => None,
        LabelText::Id => Some(node.id.clone()),
        LabelText::Segment => Some(last_segment(&node.id).to_string()),
        LabelText::Relative => group
            .and_then(|g| after_prefix(&node.label, &g.label))
            .map(str::to_string),
        LabelText::Auto => group
            .and_then(|g| own_segment(&node.label, &g.label))
            .map(str::to_string),
        LabelText::Template(t) => t.fill(dataset, i).or_else(|| {
            group
                .and_then(|g| own_segment(&node.label, &g.label))
                .map(str::to_string)
        }),
    };
    let shown = clean(chosen.as_deref().unwrap_or(&node.label));
    if shown.is_empty() {
        clean(&node.label)
    } else {
        shown
    }
}

/// The last segment of `id` at its strongest separator, or `id`.
fn last_segment(id: &str) -> &str {
    SEPARATORS
        .iter()
        .find_map(|sep| {
            let (_, last) = id.rsplit_once(sep)?;
            (!last.is_empty()).then_some(last)
        })
        .unwrap_or(id)
}

/// `label` without `prefix` and the separator after it (`sympy.stats.rv`,
/// `sympy`: `stats.rv`), when it starts so and something is left.
fn after_prefix<'a>(label: &'a str, prefix: &str) -> Option<&'a str> {
    if prefix.is_empty() {
        return None;
    }
    let rest = label.strip_prefix(prefix)?;
    SEPARATORS.iter().find_map(|sep| {
        let own = rest.strip_prefix(sep)?;
        (!own.is_empty()).then_some(own)
    })
}

/// The default: `label` without its group's name in front (as
/// [`after_prefix`]), or its last segment when the segments before it end
/// with the group's name (`sympy.stats.rv` in a group named `stats`) or the
/// last segment is the group's name (a package's own module, `xml.dom` in
/// `dom`).
fn own_segment<'a>(label: &'a str, group: &str) -> Option<&'a str> {
    after_prefix(label, group).or_else(|| {
        SEPARATORS.iter().find_map(|sep| {
            let (head, last) = label.rsplit_once(sep)?;
            let repeats =
                head == group || head.ends_with(&format!("{sep}{group}")) || last == group;
            (repeats && !group.is_empty() && !last.is_empty()).then_some(last)
        })
    })
}

/// `text` with control characters dropped and white space collapsed.
pub(crate) fn clean(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for word in text
        .split(|c: char| c.is_whitespace())
        .filter(|w| !w.is_empty())
    {
        if !out.is_empty() {
            out.push(' ');
        }
        out.extend(word.chars().filter(|c| !c.is_control()));
    }
    out.trim().to_owned()
}

#[cfg(test)]
mod tests {
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    use super::*;

    /// root > `sympy` > `sympy.stats` > leaves, ids dotted, labels the ids.
    fn dotted() -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        b.add(NodeSpec::new("sympy").parent("root"));
        b.add(NodeSpec::new("sympy.core").parent("sympy").weight(2.0));
        b.add(NodeSpec::new("sympy.stats").parent("sympy"));
        let mut rv = NodeSpec::new("sympy.stats.rv")
            .parent("sympy.stats")
            .weight(1.0);
        rv.fields = vec![
            ("name".to_string(), "rv".to_string()),
            ("version".to_string(), "1.2".to_string()),
        ];
        b.add(rv);
        b.add(NodeSpec::new("other").parent("sympy.stats").weight(1.0));
        b.build().expect("valid")
    }

    fn shown(d: &Dataset, id: &str, text: &LabelText) -> String {
        let i = d.find(id).expect("node");
        display_name(d, i, &DisplayNames::default(), text)
    }

    #[test]
    fn each_choice_on_dotted_ids() {
        let d = dotted();
        let text = |t: &str| LabelText::parse(t).expect("valid");
        assert_eq!(shown(&d, "sympy.stats.rv", &text("auto")), "rv");
        assert_eq!(shown(&d, "sympy.stats", &text("auto")), "stats");
        // A top-level group's group is the root: nothing to drop.
        assert_eq!(shown(&d, "sympy", &text("auto")), "sympy");
        assert_eq!(shown(&d, "other", &text("auto")), "other");
        assert_eq!(
            shown(&d, "sympy.stats.rv", &text("label")),
            "sympy.stats.rv"
        );
        assert_eq!(shown(&d, "sympy.stats.rv", &text("id")), "sympy.stats.rv");
        assert_eq!(shown(&d, "sympy.stats.rv", &text("segment")), "rv");
        assert_eq!(shown(&d, "sympy.stats.rv", &text("relative")), "rv");
        assert_eq!(
            shown(&d, "sympy.stats.rv", &text("{name} {version}")),
            "rv 1.2"
        );
        // Groups carry no columns: they keep the default text.
        assert_eq!(shown(&d, "sympy.stats", &text("{name} {version}")), "stats");
    }

    #[test]
    fn separators_strongest_first() {
        assert_eq!(last_segment("src/render/labels.rs"), "labels.rs");
        assert_eq!(last_segment("crate::render::Style"), "Style");
        assert_eq!(last_segment("a.b.c"), "c");
        assert_eq!(last_segment("plain"), "plain");
        assert_eq!(last_segment("trailing/"), "trailing/");
        assert_eq!(after_prefix("src/render/x.rs", "src/render"), Some("x.rs"));
        assert_eq!(after_prefix("sympystats", "sympy"), None);
        assert_eq!(own_segment("sympy.stats.rv", "stats"), Some("rv"));
        assert_eq!(own_segment("sympy.mystats.rv", "stats"), None);
        assert_eq!(own_segment("xml.dom", "dom"), Some("dom"));
        assert_eq!(own_segment("dom", "dom"), None);
        assert_eq!(own_segment("a::b::C", "a::b"), Some("C"));
    }

    #[test]
    fn names_win_and_bad_values_say_why() {
        let d = dotted();
        let names = DisplayNames::new([("sympy.stats.rv".to_string(), "Random".to_string())]);
        let i = d.find("sympy.stats.rv").expect("node");
        assert_eq!(display_name(&d, i, &names, &LabelText::Segment), "Random");
        let e = LabelText::parse("segmnet").expect_err("unknown");
        assert!(e.contains("did you mean \"segment\""), "{e}");
        for bad in ["{name", "name}", "{}", "{{literal}}"] {
            assert!(LabelText::parse(bad).is_err(), "{bad}");
        }
        let t = LabelText::parse("{name} {{v{version}}} {id}").expect("valid");
        assert_eq!(t.columns(), vec!["name", "version"]);
    }
}
