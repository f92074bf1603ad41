//! One level being laid out: its diagrams ([`Diagram`]) and a snapshot of
//! their current geometry ([`Snapshot`]): sites, centroids and which cells
//! share an edge across the whole level, which the attraction moves, the swaps
//! and the score all read.
//!
//! The snapshot's adjacency is built without comparing every cell's polygon:
//! inside one diagram, the power diagram already lists each cell's neighbours
//! and their common edge; only cells on their parent's boundary can touch a
//! cousin, so only those go through [`level_adjacency`]. Same graph as the
//! checker's up to round-off at the 1e-6 threshold ([`MIN_SHARED`]).

use super::links::{LevelLinks, Score};
use super::NeighborParams;
use crate::geom::shared_edge::{MIN_SHARED, PERPENDICULAR_TOL};
use crate::geom::{level_adjacency, ConvexPolygon, LevelAdjacency, Point};
use crate::layout::map::MapSimulation;

/// One parent's diagram on the level being laid out.
#[derive(Clone)]
pub(super) enum Diagram {
    /// A parent with one child: the child takes the parent's cell.
    Single {
        child: usize,
        polygon: ConvexPolygon,
    },
    /// A parent with several children.
    Sim {
        children: Vec<usize>,
        sim: Box<MapSimulation>,
    },
}

impl Diagram {
    /// How many children the diagram lays out.
    pub(super) fn len(&self) -> usize {
        match self {
            Diagram::Single { .. } => 1,
            Diagram::Sim { children, .. } => children.len(),
        }
    }

    /// The parent's cell.
    pub(super) fn clip(&self) -> &ConvexPolygon {
        match self {
            Diagram::Single { polygon, .. } => polygon,
            Diagram::Sim { sim, .. } => sim.clip(),
        }
    }

    /// The cell of the `slot`-th child, if it has one.
    pub(super) fn cell(&self, slot: usize) -> Option<&ConvexPolygon> {
        match self {
            Diagram::Single { polygon, .. } => Some(polygon),
            Diagram::Sim { sim, .. } => sim.state().diagram.cells[slot].polygon.as_ref(),
        }
    }

    /// The diagram's area error (0 for an only child).
    pub(super) fn area_error(&self) -> f64 {
        match self {
            Diagram::Single { .. } => 0.0,
            Diagram::Sim { sim, .. } => sim.state().convergence_ratio,
        }
    }
}

/// Current geometry of the level: per level-local index the site, centroid,
/// the diagram it belongs to and its index there; the level's adjacency and
/// the score it gives.
pub(super) struct Snapshot {
    pub(super) site: Vec<Point>,
    pub(super) centroid: Vec<Point>,
    pub(super) diagram: Vec<usize>,
    pub(super) slot: Vec<usize>,
    pub(super) adjacency: LevelAdjacency,
    pub(super) score: Score,
    /// Largest area error of the level's diagrams.
    pub(super) area_error: f64,
}

/// What every step of one level's layout reads: its constraints, the length
/// scale adjacency is judged at, the settings.
pub(super) struct LevelCtx<'a> {
    pub(super) links: &'a LevelLinks,
    /// The layout's length scale (the root's bounding-box diagonal), which the
    /// adjacency threshold is relative to.
    pub(super) scale: f64,
    pub(super) np: &'a NeighborParams,
}

impl LevelCtx<'_> {
    /// The snapshot of `diagrams`.
    pub(super) fn snapshot(&self, diagrams: &[Diagram]) -> Snapshot {
        snapshot(diagrams, self.links, self.scale, self.np)
    }
}

fn snapshot(diagrams: &[Diagram], links: &LevelLinks, scale: f64, np: &NeighborParams) -> Snapshot {
    let m = links.nodes.len();
    let mut site = vec![Point::ZERO; m];
    let mut centroid = vec![Point::ZERO; m];
    let mut diagram = vec![0; m];
    let mut slot = vec![0; m];
    let mut present = Vec::with_capacity(m);
    let mut pairs = Vec::new();
    let mut boundary = Vec::new();
    let mut elongation = 0.0;
    let mut area_error: f64 = 0.0;
    let threshold = MIN_SHARED * scale;
    let on_edge = 10.0 * PERPENDICULAR_TOL * scale;
    for (d, dg) in diagrams.iter().enumerate() {
        area_error = area_error.max(dg.area_error());
        match dg {
            Diagram::Single { child, polygon } => {
                let k = links.local[*child];
                site[k] = polygon.centroid();
                centroid[k] = site[k];
                diagram[k] = d;
                present.push(k);
                boundary.push(k);
                elongation += aspect(polygon) - 1.0;
            }
            Diagram::Sim { children, sim } => {
                let state = sim.state();
                let clip = sim.clip();
                for (j, c) in children.iter().enumerate() {
                    let k = links.local[*c];
                    let cell = &state.diagram.cells[j];
                    site[k] = state.sites[j].position;
                    centroid[k] = cell.centroid;
                    diagram[k] = d;
                    slot[k] = j;
                    let Some(polygon) = &cell.polygon else {
                        continue;
                    };
                    present.push(k);
                    elongation += aspect(polygon) - 1.0;
                    for nb in &cell.neighbors {
                        if nb.site > j && nb.edge[0].distance(nb.edge[1]) >= threshold {
                            let o = links.local[children[nb.site]];
                            pairs.push((k.min(o), k.max(o)));
                        }
                    }
                    if diagrams.len() > 1
                        && polygon
                            .points()
                            .iter()
                            .any(|v| clip.boundary_distance(*v) <= on_edge)
                    {
                        boundary.push(k);
                    }
                }
            }
        }
    }
    if diagrams.len() > 1 {
        let cell = |k: usize| diagrams[diagram[k]].cell(slot[k]);
        let cross = level_adjacency(cell, &boundary, scale);
        pairs.extend(
            cross
                .pairs()
                .iter()
                .copied()
                .filter(|&(a, b)| diagram[a] != diagram[b]),
        );
    }
    let adjacency = LevelAdjacency::from_pairs(present, pairs);
    let score = Score {
        realized: links.realized(&adjacency),
        elongation,
        shape_weight: np.shape_weight,
    };
    Snapshot {
        site,
        centroid,
        diagram,
        slot,
        adjacency,
        score,
        area_error,
    }
}

/// Bounding-box aspect ratio of a cell (long side over short, the checker's
/// `aspect_ratio_mean` term); 1 for a degenerate box.
pub(super) fn aspect(polygon: &ConvexPolygon) -> f64 {
    let (lo, hi) = polygon.bbox();
    let (w, h) = (hi.x - lo.x, hi.y - lo.y);
    if w > 0.0 && h > 0.0 {
        w.max(h) / w.min(h)
    } else {
        1.0
    }
}

/// The level's current cells, for a [`Frame`](crate::layout::Frame).
pub(super) fn frame_cells(diagrams: &[Diagram]) -> Vec<(usize, ConvexPolygon)> {
    let mut cells = Vec::new();
    for d in diagrams {
        match d {
            Diagram::Single { child, polygon } => cells.push((*child, polygon.clone())),
            Diagram::Sim { children, sim } => {
                let state = sim.state();
                for (c, cell) in children.iter().zip(&state.diagram.cells) {
                    if let Some(p) = &cell.polygon {
                        cells.push((*c, p.clone()));
                    }
                }
            }
        }
    }
    cells
}

/// Settles a diagram's areas with its sites held in place, to `target` or
/// for `np.settle_iterations` weight steps at most.
pub(super) fn settle_to(d: &mut Diagram, np: &NeighborParams, target: f64) {
    if let Diagram::Sim { sim, .. } = d {
        for _ in 0..np.settle_iterations {
            let before = sim.state().convergence_ratio;
            if before <= target {
                break;
            }
            let after = sim.settle_weights();
            // A step that found no better weights keeps them, and the next
            // would search from the same weights to the same end.
            if after <= target || after >= before {
                break;
            }
        }
    }
}

/// [`settle_to`] the run's own area target.
pub(super) fn settle(d: &mut Diagram, np: &NeighborParams) {
    if let Diagram::Sim { sim, .. } = d {
        let target = sim.area_target();
        settle_to(d, np, target);
    }
}
