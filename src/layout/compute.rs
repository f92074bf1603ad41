//! `compute`: the whole pure layout step for one dataset and one method, from a
//! validated dataset to the layout and its constraints. With a similarity the
//! dataset is first prepared (virtual nodes, aggregation; paper §4) and the
//! constraints built (method-reference §3); without one, only `plain` runs.
//! Given a previous layout that fits, the layout starts warm instead
//! (`layout::warm`, issue 6), whatever the method. Before all of it, items of
//! weight 0 are hidden or kept for the floor (`layout::zero`, issue 34).

use std::sync::{Arc, OnceLock};

use super::method::Method;
use super::previous::{Previous, WarmRefusal};
use super::progress::{Monitor, ProgressSink};
use super::similar::{layout_similar_with, projection_of, NeighborParams};
use super::warm::layout_warm_with;
use super::zero::{self, ZeroItems, ZeroWeights};
use super::{treemap, Layout, LayoutError, Params, Report};
use crate::geom::{ConvexPolygon, LevelAdjacency};
use crate::neighborhood::similarity::similarity;
use crate::neighborhood::{build_constraints, prepare, Constraint, SimilarityKind};
use nptreemap_formats::Dataset;

/// A finished layout with everything needed to render or evaluate it.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Computed {
    /// The dataset the layout is indexed by: the prepared one (with virtual
    /// nodes) when a similarity was used, else the input. Shared: a build
    /// keeps the prepared dataset of its similarity inputs between runs.
    pub dataset: Arc<Dataset>,
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
    /// The settings it was laid out with ([`Request::settings`]).
    pub settings: LayoutSettings,
    /// What became of the input's items of weight 0 (hidden before the
    /// layout, or drawn at the floor): for the legend, the tooltips, the
    /// layout JSON and the status lines.
    pub zero: Arc<ZeroItems>,
    /// Each depth level's adjacency in `layout` (index = depth), computed at
    /// most once: by [`compute`] when there are constraints to flag, else on
    /// first use ([`Computed::adjacency`]).
    /// Shared with the next warm start's previous layout (no copy).
    adjacency: OnceLock<Arc<Vec<LevelAdjacency>>>,
}

impl Computed {
    /// Which cells of each depth level share an edge (index = depth), by the
    /// checker's definition (`geom::shared_edge`). Renderers, measurements and
    /// the constraints' `realized` flags all read this one computation.
    pub fn adjacency(&self) -> &[LevelAdjacency] {
        self.shared_adjacency()
    }

    /// Its adjacency per level when something asked for it already (it is
    /// not computed here): what the state folder keeps beside the stored
    /// layout for the next process's warm start.
    pub fn known_adjacency(&self) -> Option<Arc<Vec<LevelAdjacency>>> {
        self.adjacency.get().cloned()
    }

    fn shared_adjacency(&self) -> &Arc<Vec<LevelAdjacency>> {
        self.adjacency
            .get_or_init(|| Arc::new(levels_adjacency(&self.dataset, &self.layout)))
    }

    /// The previous layout this computation becomes for the next warm start:
    /// every node's id, parent, weight, site, power weight and cell, and the
    /// id pairs of its realised constraints.
    pub fn previous(&self) -> Arc<Previous> {
        Arc::new(self.make_previous())
    }

    fn make_previous(&self) -> Previous {
        let ds = &self.dataset;
        let realized = self
            .constraints
            .iter()
            .zip(&self.realized)
            .filter(|(_, r)| **r)
            .map(|(c, _)| (ds.node(c.a).id.clone(), ds.node(c.b).id.clone()))
            .collect();
        Previous::from_layout(ds, &self.layout)
            .with_realized(realized)
            .with_levels(Arc::clone(self.shared_adjacency()))
    }

    /// Every node's weight as the picture promises it, when that is not its
    /// value: with `zero_weights: floor`, an item of weight 0 is drawn at
    /// the floor (`treemap::drawn_weights`); `None` when every node is
    /// drawn at its value (nothing floored, or hidden instead).
    pub fn drawn_weights(&self) -> Option<Vec<f64>> {
        (self.zero.mode == ZeroWeights::Floor && self.zero.items > 0)
            .then(|| treemap::drawn_weights(&self.dataset, &self.settings.params))
    }
}

/// How a layout started.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
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
#[non_exhaustive]
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
    /// Called with the run's [`Progress`](super::Progress) (level, diagram,
    /// tick) as it goes, possibly from several threads at once; when it
    /// returns `ControlFlow::Break(())` the run stops at its next check and
    /// [`compute`] returns [`LayoutError::Cancelled`] (a signal handler, a
    /// user's Ctrl-C). Reporting never changes the layout: with or without a
    /// callback the bytes are the same. `None`: no reports.
    pub progress: Option<ProgressSink>,
    /// Compute the constraints, and so the realised flags, even for the
    /// `plain` method, which never uses them (issue 34: `eval` and `bench
    /// --realized` count what a plain treemap realises). Other methods always
    /// compute them. Not a layout setting: the layout is the same either way.
    pub realized: bool,
}

/// The settings of a request that shape the picture: everything but the
/// previous layout and the progress callback. A layout is a function of the
/// dataset, these settings and the previous layout it started from; the
/// build records them beside a stored layout so that a warm start from a
/// layout made with other settings (another seed, say) is never taken.
#[derive(serde::Serialize, Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct LayoutSettings {
    /// Layout parameters.
    pub params: Params,
    /// The method asked for (`None`: chosen by the data).
    pub method: Option<Method>,
    /// The similarity asked for (`None`: the data's own).
    pub similarity: Option<SimilarityKind>,
    /// Settings of the similarity-driven methods.
    pub neighbor: NeighborParams,
}

impl Request {
    /// The settings of this request that shape the picture.
    pub fn settings(&self) -> LayoutSettings {
        LayoutSettings {
            params: self.params.clone(),
            method: self.method,
            similarity: self.similarity,
            neighbor: self.neighbor.clone(),
        }
    }
}

/// What a run on a dataset does: the similarity it uses (none for a plain
/// treemap) and the method, as [`compute`] resolves them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Plan {
    /// The similarity, from the request or the data's hint.
    pub(crate) kind: Option<SimilarityKind>,
    /// The method, from the request or chosen by the similarity.
    pub(crate) method: Method,
    /// Whether the run needs the constraints: a similarity-driven method, or
    /// a realised count asked for ([`Request::realized`]). `plain` alone
    /// computes none.
    pub(crate) constraints: bool,
}

/// Checks the parameters and resolves the similarity and the method of a
/// run; a similarity-driven method without a similarity is an error.
pub(crate) fn plan(dataset: &Dataset, request: &Request) -> Result<Plan, LayoutError> {
    // Every method relies on a canvas in range; check before any of them runs.
    request.params.validate()?;
    let kind = request
        .similarity
        .or_else(|| dataset.similarity_hint().map(SimilarityKind::from_hint));
    let method = request.method.unwrap_or(if kind.is_some() {
        Method::Neighbor
    } else {
        Method::Plain
    });
    if kind.is_none() && method.uses_similarity() {
        return Err(LayoutError::NoSimilarity {
            method: method.name(),
        });
    }
    let constraints = kind.is_some() && (method != Method::Plain || request.realized);
    Ok(Plan {
        kind,
        method,
        constraints,
    })
}

/// Runs the layout step: items of weight 0 hidden or kept
/// (`request.params.zero_weights`), then the plan's preparation,
/// constraints and layout.
pub fn compute(dataset: &Dataset, request: &Request) -> Result<Computed, LayoutError> {
    let (dataset, zero) = zero::apply(&Arc::new(dataset.clone()), request.params.zero_weights);
    let plan = plan(&dataset, request)?;
    let input = match plan.kind {
        None => Prepared::Plain(dataset),
        Some(kind) => {
            let prepared = prepare(&dataset);
            let constraints = if plan.constraints {
                build_constraints(&prepared, kind)
            } else {
                Vec::new()
            };
            Prepared::Similar(Arc::new(prepared), constraints)
        }
    };
    lay_out_planned(input, plan, request, zero)
}

/// What the layout of a planned run starts from.
#[derive(Debug)]
pub(crate) enum Prepared {
    /// A plan without a similarity: the dataset as it is.
    Plain(Arc<Dataset>),
    /// A plan with a similarity: the prepared dataset ([`prepare`]) and its
    /// constraints ([`build_constraints`] with the plan's similarity; none
    /// when the plan needs none, [`Plan::constraints`]), which
    /// the caller may have kept from an earlier run on the same similarity
    /// inputs (the build's stage graph does).
    Similar(Arc<Dataset>, Vec<Constraint>),
}

/// The layout of a planned run (see [`plan`]) from its [`Prepared`] input,
/// made from a dataset whose items of weight 0 became `zero`
/// ([`zero::apply`]).
pub(crate) fn lay_out_planned(
    input: Prepared,
    plan: Plan,
    request: &Request,
    zero: Arc<ZeroItems>,
) -> Result<Computed, LayoutError> {
    let monitor = Monitor::new(request.progress.as_ref());
    let method = plan.method;
    let (kind, prepared, constraints) = match (plan.kind, input) {
        (Some(kind), Prepared::Similar(prepared, constraints)) => (kind, prepared, constraints),
        (_, Prepared::Plain(dataset) | Prepared::Similar(dataset, _)) => {
            return lay_out_plain(dataset, method, request, &monitor, zero)
        }
    };
    // Survival is judged on the prepared dataset: virtual nodes have ids
    // derived from their parents', so they match their previous selves too.
    let start = warm_start_for(&prepared, request);
    let warm_from = request
        .previous
        .as_deref()
        .filter(|_| matches!(start, Start::Warm { .. }));
    let (layout, report) = if let Some(previous) = warm_from {
        let sim = |a: usize, b: usize| similarity(kind, &prepared, a, b);
        layout_warm_with(&prepared, &request.params, previous, Some(&sim), &monitor)?
    } else if method == Method::Plain
        // Nothing to preserve, nothing to pay (issue 23): what the method
        // would give level by level without constraints, minus the projection.
        || (constraints.is_empty() && method == Method::Neighbor && !request.neighbor.prototype)
    {
        treemap::layout_with(&prepared, &request.params, &monitor)?
    } else {
        let projection = projection_of(&prepared, |a, b| similarity(kind, &prepared, a, b));
        layout_similar_with(
            &prepared,
            &constraints,
            &projection,
            method,
            &request.params,
            &request.neighbor,
            &monitor,
        )?
    };
    let adjacency = match warm_from.and_then(|p| p.levels_of(&prepared)) {
        Some((before, cells)) => levels_adjacency_after(&prepared, &layout, before, &cells),
        None => levels_adjacency(&prepared, &layout),
    };
    let realized = constraints
        .iter()
        .map(|c| adjacency[prepared.node(c.a).depth].are_adjacent(c.a, c.b))
        .collect();
    Ok(Computed {
        dataset: prepared,
        layout,
        report,
        constraints,
        realized,
        method,
        start,
        settings: request.settings(),
        zero,
        adjacency: OnceLock::from(Arc::new(adjacency)),
    })
}

/// The plain treemap of `dataset` (no similarity), warm when the request's
/// previous layout fits.
fn lay_out_plain(
    dataset: Arc<Dataset>,
    method: Method,
    request: &Request,
    monitor: &Monitor<'_>,
    zero: Arc<ZeroItems>,
) -> Result<Computed, LayoutError> {
    let start = warm_start_for(&dataset, request);
    let warm_from = request
        .previous
        .as_deref()
        .filter(|_| matches!(start, Start::Warm { .. }));
    let (layout, report) = match warm_from {
        Some(previous) => layout_warm_with(&dataset, &request.params, previous, None, monitor)?,
        None => treemap::layout_with(&dataset, &request.params, monitor)?,
    };
    // Made now only when the previous layout's adjacency makes it cheap;
    // else on first use, as nothing here needs it.
    let adjacency = match warm_from.and_then(|p| p.levels_of(&dataset)) {
        Some((before, cells)) => OnceLock::from(Arc::new(levels_adjacency_after(
            &dataset, &layout, before, &cells,
        ))),
        None => OnceLock::new(),
    };
    Ok(Computed {
        dataset,
        layout,
        report,
        constraints: Vec::new(),
        realized: Vec::new(),
        method,
        start,
        settings: request.settings(),
        zero,
        adjacency,
    })
}

/// Whether `request`'s previous layout (if any) fits a run on `dataset`:
/// the layout core's half of the warm-or-cold decision (the data side:
/// canvas, outline, survivors). Which previous layout a build offers is
/// decided in one place, `graph::start`.
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

/// Each depth level's node indices, in order (index = depth).
fn by_depth(dataset: &Dataset) -> Vec<Vec<usize>> {
    let mut by_depth: Vec<Vec<usize>> = vec![Vec::new(); dataset.max_depth() + 1];
    for (i, node) in dataset.nodes().iter().enumerate() {
        by_depth[node.depth].push(i);
    }
    by_depth
}

/// Each depth level's adjacency in `layout` (index = depth), the levels on
/// every core (they share nothing; at 6,000 C headers, ten levels, this
/// was 40 ms of one core after every edit).
fn levels_adjacency(dataset: &Dataset, layout: &Layout) -> Vec<LevelAdjacency> {
    use rayon::prelude::*;
    by_depth(dataset)
        .par_iter()
        .map(|nodes| layout.level_adjacency(nodes))
        .collect()
}

/// [`levels_adjacency`] of a layout made warm from one of the same nodes
/// whose cells were `cells` and adjacency `before`: a pair of two cells
/// that did not move (bit for bit) is taken over, since whether two cells
/// share an edge depends on the two polygons and the layout's diagonal
/// only, and only pairs with a moved cell are compared. A weight edit moves
/// the cells of one branch, so this compares a few hundred cells' pairs
/// instead of every level's. When the diagonal changed (the outline moved),
/// every pair is compared. The same adjacency as comparing every pair
/// (tested).
fn levels_adjacency_after(
    dataset: &Dataset,
    layout: &Layout,
    before: &[LevelAdjacency],
    cells: &[&ConvexPolygon],
) -> Vec<LevelAdjacency> {
    use rayon::prelude::*;
    let diagonal = layout.diagonal();
    let same_scale = crate::geom::shared_edge::extent_diagonal(cells.iter().copied())
        .is_some_and(|d| d.to_bits() == diagonal.to_bits());
    if !same_scale || before.len() != dataset.max_depth() + 1 || cells.len() != layout.cells.len() {
        return levels_adjacency(dataset, layout);
    }
    let moved: Vec<bool> = layout
        .cells
        .par_iter()
        .zip(cells)
        .map(|(now, then)| now.polygon.points() != then.points())
        .collect();
    by_depth(dataset)
        .par_iter()
        .zip(before)
        .map(|(nodes, before)| {
            let mut pairs: Vec<(usize, usize)> = before
                .pairs()
                .iter()
                .filter(|&&(a, b)| !moved[a] && !moved[b])
                .copied()
                .collect();
            pairs.extend(crate::geom::adjacency::adjacent_pairs(
                |i| layout.cells.get(i).map(|c| &c.polygon),
                nodes,
                diagonal,
                |a, b| moved[a] || moved[b],
            ));
            LevelAdjacency::from_pairs(nodes.clone(), pairs)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    /// Three levels (4 groups of 5 subgroups of 8 leaves) with 3-d vectors;
    /// leaf `edited` weighs `factor` times its base weight.
    fn tree(edited: usize, factor: f64) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        let mut leaf = 0;
        for g in 0..4 {
            b.add(NodeSpec::new(format!("g{g}")).parent("root"));
            for s in 0..5 {
                b.add(NodeSpec::new(format!("g{g}s{s}")).parent(format!("g{g}")));
                for k in 0..8 {
                    let x = ((leaf * 7919) % 101) as f64 / 101.0;
                    let weight = (1.0 + ((leaf * 31) % 17) as f64)
                        * if leaf == edited { factor } else { 1.0 };
                    b.add(
                        NodeSpec::new(format!("g{g}s{s}l{k}"))
                            .parent(format!("g{g}s{s}"))
                            .weight(weight)
                            .features(vec![x, 1.0 - x, (g as f64) / 4.0]),
                    );
                    leaf += 1;
                }
            }
        }
        b.build().expect("valid")
    }

    /// A warm layout's adjacency, taken over for the cells that did not
    /// move and compared for the rest, is the adjacency of comparing every
    /// pair, edit after edit; and the edits leave cells unmoved, so the
    /// pairs taken over are not none.
    #[test]
    fn the_adjacency_after_a_warm_edit_is_that_of_comparing_every_pair() {
        // The neighbour method, and the plain treemap without a similarity
        // (`lay_out_plain`).
        for (method, similarity) in [
            (
                Method::Neighbor,
                Some(crate::neighborhood::SimilarityKind::Cosine),
            ),
            (Method::Plain, None),
        ] {
            warm_edits_keep_the_adjacency(Request {
                similarity,
                method: Some(method),
                ..Request::default()
            });
        }
    }

    fn warm_edits_keep_the_adjacency(request: Request) {
        let mut request = request;
        let mut last = compute(&tree(usize::MAX, 1.0), &request).expect("cold");
        assert_eq!(Some(last.method), request.method);
        for (edited, factor) in [(3, 1.4), (77, 0.6), (150, 2.0), (3, 1.0)] {
            request.previous = Some(last.previous());
            let next = compute(&tree(edited, factor), &request).expect("warm");
            assert!(matches!(next.start, Start::Warm { .. }), "{:?}", next.start);
            let unmoved = next
                .layout
                .cells
                .iter()
                .zip(&last.layout.cells)
                .filter(|(a, b)| a.polygon.points() == b.polygon.points())
                .count();
            assert!(
                unmoved > 0 && unmoved < next.layout.cells.len(),
                "{unmoved} cells did not move"
            );
            let every_pair = levels_adjacency(&next.dataset, &next.layout);
            assert_eq!(next.adjacency(), &every_pair[..], "edit of leaf {edited}");
            last = next;
        }
    }
}
