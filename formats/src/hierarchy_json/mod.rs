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

use std::collections::HashSet;

use serde_json::Value;

use crate::dataset::{Dataset, DatasetBuilder, ModelError, NodeSpec, SimilarityHint};
use crate::error::FormatError;
use crate::format::{Carry, Format, FormatOptions, InputError, Inputs, Role};
use crate::json_path::{line_column, skip_whitespace, syntax_error};
use crate::limits::{Limit, Limits};
use crate::warning::{Warning, WarningKind};

/// The root's flags, resolved with the options.
mod flags;
/// One node object, read field by field.
mod node;
/// The raw text, positions and errors at a JSON path.
mod reader;
/// Feature arrays into vectors or numbered sets.
mod sets;
/// The depth-first walk of node objects into specs.
mod walk;

use flags::Flags;
use reader::{kind, Reader};
use walk::Walk;

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

    let flags = reader.read_flags(root_object, options.weight_field.as_deref())?;
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
    check_carried(&specs, &options.carry)?;
    let relations = known_relations(&specs);

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

/// A property asked for that no node has is a misspelt name, not data: an
/// error naming what asked for it.
fn check_carried(specs: &[NodeSpec], carry: &[Carry]) -> Result<(), FormatError> {
    for carry in carry {
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
    Ok(())
}

/// Each node's relations without the ids that are not in the file (see the
/// module docs).
fn known_relations(specs: &[NodeSpec]) -> Vec<Vec<String>> {
    let ids: HashSet<&str> = specs.iter().map(|spec| spec.id.as_str()).collect();
    specs
        .iter()
        .map(|spec| {
            spec.relations
                .iter()
                .filter(|target| ids.contains(target.as_str()))
                .cloned()
                .collect()
        })
        .collect()
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
