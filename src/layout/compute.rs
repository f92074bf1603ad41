//! `compute`: the whole pure layout step for one dataset and one method, from a
//! validated dataset to the layout and its constraints. With a similarity the
//! dataset is first prepared (virtual nodes, aggregation; paper §4) and the
//! constraints built (method-reference §3); without one, only `plain` runs.
//! Given a previous layout that fits, the layout starts warm instead
//! ([`crate::layout::warm`], issue 6), whatever the method.

use std::sync::Arc;

use super::method::Method;
use super::neighbor::{layout_similar, projection_of, NeighborParams};
use super::previous::{Previous, WarmRefusal};
use super::warm::layout_warm;
use super::{treemap, Layout, LayoutError, Params, Report};
use crate::neighborhood::adjacency::level_adjacency;
use crate::neighborhood::similarity::similarity;
use crate::neighborhood::{build_constraints, prepare, Constraint, SimilarityKind};
use nptreemap_formats::Dataset;

/// A finished layout with everything needed to render or evaluate it.
#[derive(Clone, Debug)]
pub struct Computed {
    /// The dataset the layout is indexed by: the prepared one (with virtual
    /// nodes) when a similarity was used, else the input.
    pub dataset: Dataset,
    /// The layout.
    pub layout: Layout,
    /// How the optimisation went.
    pub report: Report,
    /// Constraints on every level (empty without a similarity).
    pub constraints: Vec<Constraint>,
    /// Per constraint: do the two cells share an edge in this layout?
    pub realized: Vec<bool>,
    /// The method that ran.
    pub method: Method,
    /// Whether the layout started cold or from the previous layout.
    pub start: Start,
}

/// How a layout started.
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// From scratch: no previous layout was given.
    Cold,
    /// From scratch, because the previous layout given did not fit.
    Refused(WarmRefusal),
    /// From the previous layout.
    Warm {
        /// Non-root nodes found there under the same parent.
        survivors: usize,
        /// Non-root nodes that are new (or moved to another parent).
        new: usize,
    },
}

/// What to compute.
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// Layout parameters.
    pub params: Params,
    /// The method; `None` picks `neighbor` when there is a similarity, else `plain`.
    pub method: Option<Method>,
    /// The similarity; `None` takes the dataset's own hint.
    pub similarity: Option<SimilarityKind>,
    /// Settings of the similarity-driven methods.
    pub neighbor: NeighborParams,
    /// The previous layout to start from (issue 6's warm start), or `None` for a
    /// cold start. Used only when it [fits](Previous::fits) the run; the
    /// outcome is in [`Computed::start`]. Shared, not copied, between runs.
    pub previous: Option<Arc<Previous>>,
}

/// Minimum shared boundary (share of the canvas diagonal) for a constraint to
/// count as realised: `shared/tools/check-layout`'s default, so our flags and
/// the checker agree.
pub(crate) const MIN_SHARED: f64 = 1e-6;

/// Runs the layout step.
pub fn compute(dataset: &Dataset, request: &Request) -> Result<Computed, LayoutError> {
    let kind = request
        .similarity
        .or_else(|| dataset.similarity_hint().map(SimilarityKind::from_hint));
    let method = request.method.unwrap_or(if kind.is_some() {
        Method::Neighbor
    } else {
        Method::Plain
    });
    let Some(kind) = kind else {
        if method.uses_similarity() {
            return Err(LayoutError::NoSimilarity {
                method: method.name(),
            });
        }
        let start = warm_start_for(dataset, request);
        let (layout, report) = match &request.previous {
            Some(previous) if matches!(start, Start::Warm { .. }) => {
                layout_warm(dataset, &request.params, previous, None)?
            }
            _ => treemap::layout(dataset, &request.params)?,
        };
        return Ok(Computed {
            dataset: dataset.clone(),
            layout,
            report,
            constraints: Vec::new(),
            realized: Vec::new(),
            method,
            start,
        });
    };
    let prepared = prepare(dataset);
    let constraints = build_constraints(&prepared, kind);
    // Survival is judged on the prepared dataset: virtual nodes have ids
    // derived from their parents', so they match their previous selves too.
    let start = warm_start_for(&prepared, request);
    let warm_from = request
        .previous
        .as_deref()
        .filter(|_| matches!(start, Start::Warm { .. }));
    let (layout, report) = if let Some(previous) = warm_from {
        let sim = |a: usize, b: usize| similarity(kind, &prepared, a, b);
        layout_warm(&prepared, &request.params, previous, Some(&sim))?
    } else if method == Method::Plain {
        treemap::layout(&prepared, &request.params)?
    } else {
        let projection = projection_of(&prepared, |a, b| similarity(kind, &prepared, a, b));
        layout_similar(
            &prepared,
            &constraints,
            &projection,
            method,
            &request.params,
            &request.neighbor,
        )?
    };
    let realized = realized_flags(&prepared, &layout, &constraints);
    Ok(Computed {
        dataset: prepared,
        layout,
        report,
        constraints,
        realized,
        method,
        start,
    })
}

/// Whether `request`'s previous layout (if any) fits a run on `dataset`.
fn warm_start_for(dataset: &Dataset, request: &Request) -> Start {
    let Some(previous) = &request.previous else {
        return Start::Cold;
    };
    match previous.fits(dataset, &request.params) {
        Ok(()) => {
            let survivors = previous.survivors(dataset);
            Start::Warm {
                survivors,
                new: dataset.len().saturating_sub(1) - survivors,
            }
        }
        Err(refusal) => Start::Refused(refusal),
    }
}

/// Whether each constraint's cells share an edge (checker semantics).
pub fn realized_flags(dataset: &Dataset, layout: &Layout, constraints: &[Constraint]) -> Vec<bool> {
    let mut by_depth: Vec<Vec<usize>> = vec![Vec::new(); dataset.max_depth() + 1];
    for (i, node) in dataset.nodes().iter().enumerate() {
        by_depth[node.depth].push(i);
    }
    let adjacency: Vec<_> = by_depth
        .iter()
        .map(|nodes| level_adjacency(layout, nodes, MIN_SHARED))
        .collect();
    constraints
        .iter()
        .map(|c| adjacency[dataset.node(c.a).depth].are_adjacent(c.a, c.b))
        .collect()
}
