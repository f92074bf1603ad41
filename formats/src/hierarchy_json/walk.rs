//! The depth-first walk of a hierarchy JSON document: node objects into
//! [`NodeSpec`]s in a fixed order, within the node and depth limits.

use serde_json::{Map, Value};

use crate::dataset::NodeSpec;
use crate::error::FormatError;
use crate::format::Carry;
use crate::json_path::{extend, Step};
use crate::limits::{Limit, Limits};

use super::flags::Flags;
use super::node::{text_field, NodeObject};
use super::reader::{kind, node_path, over_limit, Origin, Reader};
use super::sets::RawFeatures;

/// State of the depth-first walk that turns node objects into [`NodeSpec`]s.
pub(super) struct Walk<'r, 't> {
    pub(super) reader: &'r Reader<'t>,
    pub(super) flags: &'r Flags,
    pub(super) specs: Vec<NodeSpec>,
    pub(super) origins: Vec<Origin>,
    /// Parallel to `specs`: the feature array as read, turned into
    /// [`crate::Features`] once the whole file is known ([`Reader::set_features`]).
    pub(super) features: Vec<Option<RawFeatures>>,
    pub(super) limits: Limits,
    pub(super) carry: &'r [Carry],
}

impl Walk<'_, '_> {
    /// Turns the node object `value` (and, depth-first, its subtree) into specs.
    /// `parent` is the parent's spec index and this node's index among its children.
    /// The steps run in a fixed order (limits, identity, then the fields), so the
    /// same input always reports the same error.
    pub(super) fn visit(
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
        let jaccard = self.flags.jaccard();
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
