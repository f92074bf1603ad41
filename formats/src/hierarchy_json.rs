//! Reader for hierarchy JSON: the paper prototype's dataset files and d3-hierarchy
//! style trees (`{"name": .., "children": [..]}`). Owns bytes → [`Dataset`] for this
//! format; it never touches paths and never guesses similarity values.
//!
//! # The format
//!
//! The top level is the root node: an object whose `children` arrays nest the tree.
//! Per node:
//!
//! - **id**: `id` (a string, or a number written as text); else `name`; else `Name`;
//!   else the parent's id + `/` + the child's index. The root defaults to `root`.
//! - **label**: `name`, else `Name`, else the id.
//! - **weight**: the field named by [`HierarchyJsonOptions::weight_field`], else by the
//!   root's `weightAttribute` flag, else the first of `value`, `weight`, `size` that
//!   any leaf has. The name `none` means every node, internal nodes included, weighs
//!   1 (the prototype's quirk, method-reference §2.3). Every leaf must have the field;
//!   an internal node that has it keeps it as its own weight (d3's `hierarchy.sum`
//!   adds it too). With no weight field anywhere, every leaf weighs 1 (d3's `count`).
//! - **features**: the field named by the root's `simAttribute` (default `embeddings`):
//!   an array of numbers (a vector), possibly wrapped once as `[[..]]`, or an array of
//!   strings (a set: `["stdio.h", "string.h"]`, repeats counted once). Sets are
//!   numbered over the distinct strings of the whole file, sorted by bytes, and kept
//!   as those numbers ([`SparseVector::set`]): the same as 0/1 vectors over the sorted
//!   names, without a row per name. A file uses one kind: numbers on one node and
//!   strings on another is an error; an empty array is an empty set in a file of
//!   sets. Under `similarityMeasure: jaccard`, vectors are sets too (only their
//!   non-zero entries are kept, [`SparseVector::from_dense`], which loses nothing)
//!   and their length counts against `limits.max_set_members` instead of
//!   `max_dimensions`; so do the distinct strings of a file of sets.
//! - **relations**: `neighbors`, an array of ids. Ids that name no node in the file are
//!   dropped: the prototype's country file lists every real border (117 of the 153
//!   entries in `country_pop_50M_AUS.json` name countries that are not in the dataset,
//!   e.g. China's neighbour "AF"), and the prototype just never matches them.
//! - **color**: `#rgb` or `#rrggbb`.
//!
//! The similarity hint comes from root flags: `useNeighborLeafs: true` gives
//! [`SimilarityHint::NeighborList`]; else `similarityMeasure` (`cosine`, `jaccard`,
//! `binary`); without either flag, neighbour lists that name nodes of the file give
//! [`SimilarityHint::NeighborList`] (what an adapter printing them means); else
//! Jaccard for sets of strings and cosine for vectors. Neighbour lists left unused by a flag, or
//! chosen over feature vectors, are a warning. Other fields are ignored, but
//! for those asked for in [`HierarchyJsonOptions::carry`]: a string, number or
//! boolean there becomes the node's [`crate::Node::fields`] entry (other values
//! are skipped), and a field on no node at all is an error.
//!
//! # Error positions
//!
//! The bytes are parsed once with `serde_json` into a `Value`, which has no positions.
//! Syntax errors take serde_json's line and column. For any later error the reader
//! knows the JSON path of the offending value (`children[2].children[0].Population`)
//! and `locate` (`json_path.rs`) walks the raw bytes along that path to find its offset. The walk
//! runs only when an error is reported and only on text serde_json has accepted, so it
//! can stay a small skip-scanner; if it ever gets lost it returns no position rather
//! than a wrong one.

use std::collections::{BTreeMap, BTreeSet, HashSet};

use serde_json::{Map, Value};

use crate::color::Rgb;
use crate::dataset::{
    is_valid_weight, Dataset, DatasetBuilder, ModelError, NodeSpec, SimilarityHint,
};
use crate::error::FormatError;
use crate::features::{Features, SparseVector};
use crate::format::{Carry, Format, FormatOptions, InputError, Inputs, Role};
use crate::json_path::{extend, line_column, locate, skip_whitespace, syntax_error, Step};
use crate::limits::{Limit, Limits};
use crate::warning::{Warning, WarningKind};

/// Options for [`parse_hierarchy_json`]. The defaults honour the file's own flags.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HierarchyJsonOptions {
    /// The field holding each leaf's weight, overriding the root's `weightAttribute`
    /// flag; `"none"` means every node weighs 1, as for the flag. Default: `None`
    /// (use the flag, else the first of `value`, `weight`, `size` found on leaves).
    pub weight_field: Option<String>,
    /// How many nodes, how deep and how long feature vectors may be. Default:
    /// [`Limits::default`].
    pub limits: Limits,
    /// Node properties to carry into [`crate::Node::fields`].
    pub carry: Vec<Carry>,
}

/// Reads a hierarchy JSON document (see the module docs for the format).
///
/// A UTF-8 byte order mark is accepted. Every error carries the line and column of
/// the offending value when it can be found.
pub fn parse_hierarchy_json(
    bytes: &[u8],
    options: &HierarchyJsonOptions,
) -> Result<Dataset, FormatError> {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let root: Value = serde_json::from_slice(text).map_err(|error| {
        if error.to_string().starts_with("recursion limit exceeded") {
            return too_deep(text, &error, &options.limits);
        }
        syntax_error(text, &error)
    })?;
    let reader = Reader { text };
    let Some(root_object) = root.as_object() else {
        let (line, column) = line_column(text, skip_whitespace(text, 0));
        return Err(FormatError::Structure {
            line: Some(line),
            column: Some(column),
            message: format!(
                "expected the root node, an object with \"children\", found {}",
                kind(&root)
            ),
        });
    };

    let flags = reader.read_flags(root_object, options)?;
    let mut walk = Walk {
        reader: &reader,
        flags: &flags,
        specs: Vec::new(),
        origins: Vec::new(),
        features: Vec::new(),
        limits: options.limits,
        carry: &options.carry,
    };
    walk.visit(&root, None, 0)?;
    let Walk {
        mut specs,
        origins,
        features,
        ..
    } = walk;
    let sets = reader.set_features(&mut specs, features, &flags, &origins, &options.limits)?;
    // A property asked for that no node has is a misspelt name, not data.
    for carry in &options.carry {
        if !specs
            .iter()
            .any(|spec| spec.fields.iter().any(|(name, _)| *name == carry.column))
        {
            return Err(FormatError::Structure {
                line: None,
                column: None,
                message: format!(
                    "no node has a field {:?} ({}) with a string, number or boolean value",
                    carry.column, carry.asked_by
                ),
            });
        }
    }

    // Drop relations to ids that are not in the file (see the module docs).
    let ids: HashSet<&str> = specs.iter().map(|spec| spec.id.as_str()).collect();
    let relations: Vec<Vec<String>> = specs
        .iter()
        .map(|spec| {
            spec.relations
                .iter()
                .filter(|target| ids.contains(target.as_str()))
                .cloned()
                .collect()
        })
        .collect();

    let listing = relations.iter().filter(|r| !r.is_empty()).count();
    let has_features = specs.iter().any(|spec| spec.features.is_some());
    let (hint, note) = similarity_hint(&flags, listing, has_features, sets);

    let node_ids: Vec<String> = specs.iter().map(|spec| spec.id.clone()).collect();
    let mut builder = DatasetBuilder::new();
    builder.limits(options.limits);
    if let Some(note) = note {
        builder.warn(Warning::new(
            WarningKind::Neighbors,
            HIERARCHY_ROLES[0].name,
            None,
            note,
        ));
    }
    for (mut spec, relations) in specs.into_iter().zip(relations) {
        spec.relations = relations;
        builder.add(spec);
    }
    if let Some(hint) = hint {
        builder.similarity_hint(hint);
    }
    builder
        .build()
        .map_err(|source| reader.model_error(source, &node_ids, &origins))
}

/// The similarity the file asks for, and a note when its neighbour lists
/// (`listing` nodes have some that name nodes of the file) go unused or win
/// over its feature vectors. An explicit flag decides; without one, neighbour
/// lists are what an adapter that prints them means (issue 21: they were
/// silently ignored without the paper's `useNeighborLeafs`), else vectors give
/// cosine. The paper's files set the flag wherever they list neighbours.
fn similarity_hint(
    flags: &Flags,
    listing: usize,
    has_features: bool,
    sets: bool,
) -> (Option<SimilarityHint>, Option<String>) {
    let measure = flags.measure.map(|(hint, _)| hint);
    match (flags.neighbor_lists, measure) {
        (Some(true), _) => (Some(SimilarityHint::NeighborList), None),
        (None, None) if listing > 0 => {
            let note = has_features.then(|| {
                "nodes carry both neighbor lists and feature vectors: the neighbor lists are \
                 the similarity (\"useNeighborLeafs\": false, or a \"similarityMeasure\", on \
                 the root uses the vectors instead)"
                    .to_owned()
            });
            (Some(SimilarityHint::NeighborList), note)
        }
        (flag, _) => {
            let natural = if sets {
                SimilarityHint::Jaccard
            } else {
                SimilarityHint::Cosine
            };
            let hint = measure.or(has_features.then_some(natural));
            let why = match (flag, flags.measure) {
                (Some(false), _) => "\"useNeighborLeafs\" is false".to_owned(),
                (_, Some((_, name))) => format!("\"similarityMeasure\" is {name:?}"),
                _ => String::new(),
            };
            let note = (listing > 0).then(|| {
                format!(
                    "the neighbor lists of {listing} node(s) are not used: {why} on the root \
                     (\"useNeighborLeafs\": true uses them)"
                )
            });
            (hint, note)
        }
    }
}

/// How weights are read, decided once from the options and the root's flags.
#[derive(Debug)]
enum WeightRule {
    /// `weightAttribute: "none"`: every node, internal ones too, weighs 1.
    EveryNodeOne,
    /// Leaves must have this numeric field; internal nodes may.
    Field(String),
    /// No weight field anywhere: every leaf weighs 1.
    LeafOne,
}

/// The root's flags, resolved.
#[derive(Debug)]
struct Flags {
    weight: WeightRule,
    feature_field: String,
    /// `useNeighborLeafs`, when given.
    neighbor_lists: Option<bool>,
    /// `similarityMeasure`, when given, with its name.
    measure: Option<(SimilarityHint, &'static str)>,
}

/// Where a node sits: its parent's spec index and its index in the parent's
/// `children` array. Enough to rebuild its JSON path for error positions.
#[derive(Clone, Copy, Debug)]
struct Origin {
    parent: Option<(usize, usize)>,
}

/// The raw text, kept to turn JSON paths into positions.
struct Reader<'t> {
    text: &'t [u8],
}

/// State of the depth-first walk that turns node objects into [`NodeSpec`]s.
struct Walk<'r, 't> {
    reader: &'r Reader<'t>,
    flags: &'r Flags,
    specs: Vec<NodeSpec>,
    origins: Vec<Origin>,
    /// Parallel to `specs`: the feature array as read, turned into
    /// [`Features`] once the whole file is known ([`Reader::set_features`]).
    features: Vec<Option<RawFeatures>>,
    limits: Limits,
    carry: &'r [Carry],
}

/// The weight-field names tried on leaves when neither the options nor the file say.
const WEIGHT_FIELD_GUESSES: [&str; 3] = ["value", "weight", "size"];

/// A node's feature array as read, before the file's kind is known.
#[derive(Debug)]
enum RawFeatures {
    /// Numbers: a vector (an empty array is this too).
    Numbers(Vec<f64>),
    /// Strings: the names of a set's members.
    Names(Vec<String>),
}

impl Reader<'_> {
    /// Turns every node's feature array into [`Features`] on its spec: sets
    /// when the file lists strings (numbered over all its distinct strings,
    /// sorted) or declares Jaccard, dense vectors otherwise. Returns whether
    /// the file lists strings. A file mixing numbers and strings is an error
    /// at the first node whose kind differs from the first node's.
    fn set_features(
        &self,
        specs: &mut [NodeSpec],
        raw: Vec<Option<RawFeatures>>,
        flags: &Flags,
        origins: &[Origin],
        limits: &Limits,
    ) -> Result<bool, FormatError> {
        let field = flags.feature_field.as_str();
        let is_names = |r: &RawFeatures| matches!(r, RawFeatures::Names(_));
        let non_empty = |r: &&RawFeatures| match r {
            RawFeatures::Numbers(v) => !v.is_empty(),
            RawFeatures::Names(v) => !v.is_empty(),
        };
        let mut kinds = raw.iter().enumerate().filter_map(|(i, r)| {
            r.as_ref()
                .filter(|r| non_empty(r))
                .map(|r| (i, is_names(r)))
        });
        let first = kinds.next();
        let names = first.is_some_and(|(_, names)| names);
        if let (Some((first, _)), Some((other, _))) = (first, kinds.find(|&(_, n)| n != names)) {
            let what = |n: bool| {
                if n {
                    "strings (a set)"
                } else {
                    "numbers (a vector)"
                }
            };
            let path = extend(&node_path(other, origins), Step::Key(field));
            return Err(self.field_error(
                Some(&specs[other].id),
                &path,
                field,
                format!(
                    "{} here, but node {:?} has {}: a file's features are all vectors or all sets",
                    what(!names),
                    specs[first].id,
                    what(names)
                ),
            ));
        }
        let jaccard = matches!(flags.measure, Some((SimilarityHint::Jaccard, _)));
        if !names {
            for (spec, raw) in specs.iter_mut().zip(raw) {
                spec.features = raw.map(|raw| match raw {
                    RawFeatures::Numbers(v) if jaccard => SparseVector::from_dense(&v).into(),
                    RawFeatures::Numbers(v) => v.into(),
                    // Only empty name lists reach here, in a file of vectors.
                    RawFeatures::Names(_) => Vec::new().into(),
                });
            }
            return Ok(false);
        }
        let all: BTreeSet<&str> = raw
            .iter()
            .flatten()
            .filter_map(|r| match r {
                RawFeatures::Names(names) => Some(names.iter().map(String::as_str)),
                RawFeatures::Numbers(_) => None,
            })
            .flatten()
            .collect();
        let too_many = |what: String| FormatError::Model {
            line: None,
            column: None,
            source: ModelError::TooLarge(limits.exceeded(Limit::SetMembers, what)),
        };
        let count = all.len();
        let described = format!("field {field:?}: {count} distinct names in lists");
        limits
            .check_set_members(count, &format!("names in the lists of field {field:?}"))
            .map_err(|e| FormatError::Model {
                line: None,
                column: None,
                source: ModelError::TooLarge(e),
            })?;
        let len = u32::try_from(count).map_err(|_| too_many(described))?;
        let number: BTreeMap<&str, u32> = all
            .iter()
            .enumerate()
            .map(|(i, &name)| (name, i as u32))
            .collect();
        let sets: Vec<Option<Features>> = raw
            .iter()
            .map(|r| {
                r.as_ref().map(|r| {
                    let members: Vec<u32> = match r {
                        RawFeatures::Names(names) => names
                            .iter()
                            .filter_map(|n| number.get(n.as_str()).copied())
                            .collect(),
                        RawFeatures::Numbers(_) => Vec::new(),
                    };
                    // Every number is below `len`: the fallback is never taken.
                    SparseVector::set(len, members)
                        .unwrap_or_else(|| SparseVector::from_dense(&[]))
                        .into()
                })
            })
            .collect();
        for (spec, features) in specs.iter_mut().zip(sets) {
            spec.features = features;
        }
        Ok(true)
    }

    /// Resolves the root flags that steer the whole read.
    fn read_flags(
        &self,
        root: &Map<String, Value>,
        options: &HierarchyJsonOptions,
    ) -> Result<Flags, FormatError> {
        let flag_error = |field: &str, message: String| {
            self.field_error(None, &[Step::Key(field)], field, message)
        };
        let string_flag = |field: &str| -> Result<Option<&str>, FormatError> {
            match root.get(field) {
                None | Some(Value::Null) => Ok(None),
                Some(Value::String(s)) => Ok(Some(s.as_str())),
                Some(other) => Err(flag_error(
                    field,
                    format!("expected a string, found {}", kind(other)),
                )),
            }
        };

        let weight_field = match &options.weight_field {
            Some(field) => Some(field.clone()),
            None => string_flag("weightAttribute")?.map(str::to_owned),
        };
        let weight = match weight_field {
            Some(field) if field == "none" => WeightRule::EveryNodeOne,
            Some(field) => WeightRule::Field(field),
            None => WEIGHT_FIELD_GUESSES
                .iter()
                .find(|field| any_leaf_has(root, field))
                .map_or(WeightRule::LeafOne, |field| {
                    WeightRule::Field((*field).to_owned())
                }),
        };

        let feature_field = string_flag("simAttribute")?
            .unwrap_or("embeddings")
            .to_owned();

        let neighbor_lists = match root.get("useNeighborLeafs") {
            None | Some(Value::Null) => None,
            Some(Value::Bool(b)) => Some(*b),
            Some(other) => {
                return Err(flag_error(
                    "useNeighborLeafs",
                    format!("expected true or false, found {}", kind(other)),
                ))
            }
        };
        // Checked even when `useNeighborLeafs` wins, so a typo never goes unnoticed.
        let measure = match string_flag("similarityMeasure")? {
            None => None,
            Some("cosine") => Some((SimilarityHint::Cosine, "cosine")),
            Some("jaccard") => Some((SimilarityHint::Jaccard, "jaccard")),
            Some("binary") => Some((SimilarityHint::Binary, "binary")),
            Some(other) => {
                return Err(flag_error(
                    "similarityMeasure",
                    format!("unknown similarity measure {other:?}; expected \"cosine\", \"jaccard\" or \"binary\""),
                ))
            }
        };
        Ok(Flags {
            weight,
            feature_field,
            neighbor_lists,
            measure,
        })
    }

    /// A field error at the value `path` leads to.
    fn field_error(
        &self,
        node: Option<&str>,
        path: &[Step<'_>],
        field: &str,
        message: String,
    ) -> FormatError {
        let (line, column) = self.position(path);
        FormatError::Field {
            line,
            column,
            node: node.map(str::to_owned),
            field: field.to_owned(),
            message,
        }
    }

    /// A structure error (a node that is not an object) at the value `path` leads to.
    fn structure_error(&self, path: &[Step<'_>], message: String) -> FormatError {
        let (line, column) = self.position(path);
        FormatError::Structure {
            line,
            column,
            message,
        }
    }

    /// Line and column of the value at `path`, if the scanner finds it.
    fn position(&self, path: &[Step<'_>]) -> (Option<usize>, Option<usize>) {
        match locate(self.text, path) {
            Some(offset) => {
                let (line, column) = line_column(self.text, offset);
                (Some(line), Some(column))
            }
            None => (None, None),
        }
    }

    /// Wraps a model error with the position of the node it names. For a duplicate
    /// id that is the second node with the id (the first one is not the problem).
    fn model_error(&self, source: ModelError, ids: &[String], origins: &[Origin]) -> FormatError {
        let skip = usize::from(matches!(source, ModelError::DuplicateId { .. }));
        let node = source
            .node_id()
            .and_then(|id| ids.iter().enumerate().filter(|(_, x)| *x == id).nth(skip))
            .map(|(index, _)| index);
        let (line, column) = match node {
            Some(index) => self.position(&node_path(index, origins)),
            None => (None, None),
        };
        FormatError::Model {
            line,
            column,
            source,
        }
    }
}

impl Walk<'_, '_> {
    /// Turns the node object `value` (and, depth-first, its subtree) into specs.
    /// `parent` is the parent's spec index and this node's index among its children.
    /// The steps run in a fixed order (limits, identity, then the fields), so the
    /// same input always reports the same error.
    fn visit(
        &mut self,
        value: &Value,
        parent: Option<(usize, usize)>,
        depth: usize,
    ) -> Result<(), FormatError> {
        let index = self.specs.len();
        self.origins.push(Origin { parent });
        let path = node_path(index, &self.origins);
        self.check_size(index, depth, &path)?;
        let Some(object) = value.as_object() else {
            return Err(self.reader.structure_error(
                &path,
                format!("expected a node object, found {}", kind(value)),
            ));
        };
        let parent_id = parent.map(|(p, _)| self.specs[p].id.clone());
        // Identity first, so later errors can name the node.
        let id = node_id(self.reader, object, &path, parent_id.as_deref(), parent)?;
        let node = NodeObject {
            reader: self.reader,
            object,
            path,
            id,
        };
        let label = node.label()?;
        let children = node.children()?;
        let weight = node.weight(&self.flags.weight, children.is_empty())?;
        let jaccard = matches!(self.flags.measure, Some((SimilarityHint::Jaccard, _)));
        let features = node.features(&self.flags.feature_field, &self.limits, jaccard)?;
        let relations = node.relations()?;
        let color = node.color()?;
        let fields = self
            .carry
            .iter()
            .filter_map(|c| node.carried(&c.column))
            .collect();
        self.specs.push(NodeSpec {
            id: node.id,
            label,
            parent: parent_id,
            weight,
            color,
            features: None,
            relations,
            fields,
        });
        self.features.push(features);
        for (child_index, child) in children.iter().enumerate() {
            self.visit(child, Some((index, child_index)), depth + 1)?;
        }
        Ok(())
    }

    /// The node count and depth limits, checked before a node is read.
    fn check_size(&self, index: usize, depth: usize, path: &[Step<'_>]) -> Result<(), FormatError> {
        let limits = &self.limits;
        if index >= limits.max_nodes {
            return Err(over_limit(
                self.reader,
                path,
                limits,
                Limit::Nodes,
                format!("more than {} nodes", limits.max_nodes),
            ));
        }
        if depth > limits.max_depth {
            return Err(over_limit(
                self.reader,
                path,
                limits,
                Limit::Depth,
                format!("a node at depth {depth}"),
            ));
        }
        Ok(())
    }
}

/// A refusal by `limit`, at the node `path` leads to.
fn over_limit(
    reader: &Reader<'_>,
    path: &[Step<'_>],
    limits: &Limits,
    limit: Limit,
    what: String,
) -> FormatError {
    let (line, column) = reader.position(path);
    FormatError::Model {
        line,
        column,
        source: ModelError::TooLarge(limits.exceeded(limit, what)),
    }
}

/// A node's id: `id`, else `name`, else `Name`; else the parent's id + `/` +
/// its index among the children; the root defaults to `root`.
fn node_id(
    reader: &Reader<'_>,
    object: &Map<String, Value>,
    path: &[Step<'static>],
    parent_id: Option<&str>,
    parent: Option<(usize, usize)>,
) -> Result<String, FormatError> {
    for field in ["id", "name", "Name"] {
        let found = text_field(object, field).map_err(|found| {
            reader.field_error(None, &extend(path, Step::Key(field)), field, found)
        })?;
        if let Some(text) = found {
            return Ok(text);
        }
    }
    Ok(match parent {
        Some((_, child_index)) => format!("{}/{child_index}", parent_id.unwrap_or("")),
        None => "root".to_owned(),
    })
}

/// One node object being read, once its id is known: each field has its own
/// step, and every error names the node and points at the field.
struct NodeObject<'a, 't> {
    reader: &'a Reader<'t>,
    object: &'a Map<String, Value>,
    path: Vec<Step<'static>>,
    id: String,
}

impl<'a> NodeObject<'a, '_> {
    /// The property `name` as a carried field: strings as they are, numbers
    /// and booleans as their JSON text; `None` when absent, null, empty or
    /// structured.
    fn carried(&self, name: &str) -> Option<(String, String)> {
        let text = match self.object.get(name)? {
            Value::Bool(b) => b.to_string(),
            value => id_text(value)?,
        };
        (!text.is_empty()).then(|| (name.to_owned(), text))
    }

    /// The path to `field` of this node.
    fn at<'f>(&self, field: &'f str) -> Vec<Step<'f>> {
        extend(&self.path, Step::Key(field))
    }

    /// A field error of this node at `steps`.
    fn error(&self, field: &str, steps: &[Step<'_>], message: String) -> FormatError {
        self.reader
            .field_error(Some(&self.id), steps, field, message)
    }

    /// `name`, else `Name` (else the id, later).
    fn label(&self) -> Result<Option<String>, FormatError> {
        for field in ["name", "Name"] {
            let found = text_field(self.object, field)
                .map_err(|found| self.error(field, &self.at(field), found))?;
            if found.is_some() {
                return Ok(found);
            }
        }
        Ok(None)
    }

    /// The `children` array (absent or null: none).
    fn children(&self) -> Result<&'a [Value], FormatError> {
        match self.object.get("children") {
            None | Some(Value::Null) => Ok(&[]),
            Some(Value::Array(children)) => Ok(children.as_slice()),
            Some(other) => Err(self.error(
                "children",
                &self.at("children"),
                format!("expected an array of nodes, found {}", kind(other)),
            )),
        }
    }

    /// The node's own weight by `rule`; a leaf must have one.
    fn weight(&self, rule: &WeightRule, is_leaf: bool) -> Result<Option<f64>, FormatError> {
        let field = match rule {
            WeightRule::EveryNodeOne => return Ok(Some(1.0)),
            WeightRule::LeafOne => return Ok(is_leaf.then_some(1.0)),
            WeightRule::Field(field) => field.as_str(),
        };
        match self.object.get(field) {
            None | Some(Value::Null) if is_leaf => Err(self.error(
                field,
                &self.path,
                "missing; every leaf needs a weight".to_owned(),
            )),
            None | Some(Value::Null) => Ok(None),
            Some(Value::Number(number)) => {
                let weight = number.as_f64().unwrap_or(f64::NAN);
                if is_valid_weight(weight) {
                    return Ok(Some(weight));
                }
                let problem = if weight < 0.0 {
                    "is negative"
                } else {
                    "is not a finite number"
                };
                Err(self.error(field, &self.at(field), format!("weight {number} {problem}")))
            }
            Some(other) => Err(self.error(
                field,
                &self.at(field),
                format!("expected a number, found {}", kind(other)),
            )),
        }
    }

    /// The feature array in `field`: numbers (possibly wrapped once as `[[..]]`)
    /// or strings, at most `limits.max_dimensions` numbers (`max_set_members`
    /// when they are a Jaccard file's sets).
    fn features(
        &self,
        field: &str,
        limits: &Limits,
        jaccard: bool,
    ) -> Result<Option<RawFeatures>, FormatError> {
        let outer = match self.object.get(field) {
            None | Some(Value::Null) => return Ok(None),
            Some(Value::Array(outer)) => outer,
            Some(other) => {
                return Err(self.error(
                    field,
                    &self.at(field),
                    format!(
                        "expected an array of numbers or of strings, found {}",
                        kind(other)
                    ),
                ))
            }
        };
        let mut steps = self.at(field);
        // The prototype unwraps a one-element list holding a list (`[[..]]`).
        let entries = match outer.as_slice() {
            [Value::Array(inner)] => {
                steps.push(Step::Index(0));
                inner
            }
            _ => outer,
        };
        if entries.first().is_some_and(Value::is_string) {
            let mut names = Vec::with_capacity(entries.len());
            for (k, entry) in entries.iter().enumerate() {
                let Some(name) = entry.as_str() else {
                    return Err(self.error(
                        field,
                        &extend(&steps, Step::Index(k)),
                        format!(
                            "entry {k}: expected a string like the entries before it, found {}",
                            kind(entry)
                        ),
                    ));
                };
                names.push(name.to_owned());
            }
            return Ok(Some(RawFeatures::Names(names)));
        }
        let (limit, allowed) = if jaccard {
            (Limit::SetMembers, limits.max_set_members)
        } else {
            (Limit::Dimensions, limits.max_dimensions)
        };
        if entries.len() > allowed {
            return Err(over_limit(
                self.reader,
                &self.path,
                limits,
                limit,
                format!(
                    "node {:?}: a feature vector of {} values",
                    self.id,
                    entries.len()
                ),
            ));
        }
        let mut features = Vec::with_capacity(entries.len());
        for (k, entry) in entries.iter().enumerate() {
            let Some(x) = entry.as_f64() else {
                return Err(self.error(
                    field,
                    &extend(&steps, Step::Index(k)),
                    format!("entry {k}: expected a number, found {}", kind(entry)),
                ));
            };
            features.push(x);
        }
        Ok(Some(RawFeatures::Numbers(features)))
    }

    /// The ids listed in `neighbors`.
    fn relations(&self) -> Result<Vec<String>, FormatError> {
        let entries = match self.object.get("neighbors") {
            None | Some(Value::Null) => return Ok(Vec::new()),
            Some(Value::Array(entries)) => entries,
            Some(other) => {
                return Err(self.error(
                    "neighbors",
                    &self.at("neighbors"),
                    format!("expected an array of ids, found {}", kind(other)),
                ))
            }
        };
        entries
            .iter()
            .enumerate()
            .map(|(k, entry)| {
                id_text(entry).ok_or_else(|| {
                    self.error(
                        "neighbors",
                        &extend(&self.at("neighbors"), Step::Index(k)),
                        format!("entry {k}: expected an id, found {}", kind(entry)),
                    )
                })
            })
            .collect()
    }

    /// `color`, a `#rgb` or `#rrggbb` string.
    fn color(&self) -> Result<Option<Rgb>, FormatError> {
        match self.object.get("color") {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(text)) => Rgb::from_hex(text).map(Some).ok_or_else(|| {
                self.error(
                    "color",
                    &self.at("color"),
                    format!("{text:?} is not a hex color like #rgb or #rrggbb"),
                )
            }),
            Some(other) => Err(self.error(
                "color",
                &self.at("color"),
                format!("expected a hex color string, found {}", kind(other)),
            )),
        }
    }
}

/// The JSON path of node `index`: `children`, i, `children`, j, ... from the root.
fn node_path(index: usize, origins: &[Origin]) -> Vec<Step<'static>> {
    let mut steps = Vec::new();
    let mut current = origins.get(index).and_then(|origin| origin.parent);
    // Parents always have smaller indices than their children, so this ends.
    while let Some((parent, child_index)) = current {
        steps.push(Step::Index(child_index));
        steps.push(Step::Key("children"));
        current = origins.get(parent).and_then(|origin| origin.parent);
    }
    steps.reverse();
    steps
}

/// A string or a number as text (ids may be written either way); `Err` describes
/// any other value, `Ok(None)` means absent or null.
fn text_field(object: &Map<String, Value>, field: &str) -> Result<Option<String>, String> {
    match object.get(field) {
        None | Some(Value::Null) => Ok(None),
        Some(value) => id_text(value)
            .map(Some)
            .ok_or_else(|| format!("expected a string or a number, found {}", kind(value))),
    }
}

/// A string as is, a number as its JSON text; `None` for other values.
fn id_text(value: &Value) -> Option<String> {
    match value {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    }
}

/// True when any leaf below (or at) `node` has a non-null `field`. Malformed
/// `children` are ignored here; the walk reports them with a position.
fn any_leaf_has(node: &Map<String, Value>, field: &str) -> bool {
    match node.get("children") {
        Some(Value::Array(children)) if !children.is_empty() => children
            .iter()
            .filter_map(Value::as_object)
            .any(|child| any_leaf_has(child, field)),
        _ => node.get(field).is_some_and(|value| !value.is_null()),
    }
}

/// "a string", "an array", ... for error messages.
fn kind(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// The error for JSON nested deeper than serde_json reads (128 levels: a node
/// is an object and its `children` an array, so nodes down to depth 63). With
/// a smaller `limits.max_depth` the limit is what the user can change.
fn too_deep(text: &[u8], error: &serde_json::Error, limits: &Limits) -> FormatError {
    let FormatError::Syntax { line, column, .. } = syntax_error(text, error) else {
        unreachable!("syntax_error makes a syntax error")
    };
    if limits.max_depth < JSON_MAX_NODE_DEPTH {
        return FormatError::Model {
            line: Some(line),
            column: Some(column),
            source: ModelError::TooLarge(limits.exceeded(
                Limit::Depth,
                format_args!("nodes nested deeper than depth {}", limits.max_depth),
            )),
        };
    }
    FormatError::Syntax {
        line,
        column,
        message: format!(
            "nested deeper than the JSON reader's 128 levels: hierarchy JSON holds nodes down to \
             depth {JSON_MAX_NODE_DEPTH} (`limits.max_depth` cannot raise this)"
        ),
    }
}

/// The deepest node serde_json's nesting limit of 128 lets through.
const JSON_MAX_NODE_DEPTH: usize = 63;

/// The hierarchy JSON [`Format`] (name `hierarchy-json`, one input `hierarchy`):
/// [`parse_hierarchy_json`] with [`FormatOptions::weight`] as the weight field.
/// Other options do not apply and are ignored.
#[derive(Clone, Copy, Debug, Default)]
pub struct HierarchyJson;

/// The one input of [`HierarchyJson`].
const HIERARCHY_ROLES: &[Role] = &[Role {
    name: "hierarchy",
    required: true,
    description: "the hierarchy JSON document (paper prototype or d3-hierarchy style)",
}];

impl Format for HierarchyJson {
    fn name(&self) -> &'static str {
        "hierarchy-json"
    }

    fn roles(&self) -> &'static [Role] {
        HIERARCHY_ROLES
    }

    fn parse(&self, inputs: &Inputs<'_>, options: &FormatOptions) -> Result<Dataset, InputError> {
        let bytes = inputs.require("hierarchy")?;
        let json_options = HierarchyJsonOptions {
            weight_field: options.weight.clone(),
            limits: options.limits,
            carry: options.carry.clone(),
        };
        parse_hierarchy_json(bytes, &json_options)
            .map_err(|error| InputError::new("hierarchy", error))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_paths_are_rebuilt_from_origins() {
        let origins = [
            Origin { parent: None },
            Origin {
                parent: Some((0, 0)),
            },
            Origin {
                parent: Some((1, 3)),
            },
        ];
        let path = node_path(2, &origins);
        let rendered: Vec<String> = path
            .iter()
            .map(|step| match step {
                Step::Key(key) => (*key).to_owned(),
                Step::Index(i) => i.to_string(),
            })
            .collect();
        assert_eq!(rendered, ["children", "0", "children", "3"]);
    }
}
