//! The rounds a `MapSimulation` makes once its Lloyd ticks stall: every site
//! to its cell's centroid, then the weights solved for the areas at those
//! sites (a capacity-constrained Lloyd iteration), so cells keep their shape
//! where weight-only steps would freeze the sites in slivers.

use super::MapSimulation;
use crate::power::power_diagram;

/// Weight-only Newton steps (each with its line search) a round may take to
/// bring the areas to the target before the next move. From a pivoted move
/// the error starts near 0.5–1.5 on skewed diagrams and falls to the 1:1000
/// target in 4–10 steps (issue 34: 1,826 half-empty children); a round that
/// runs out moves again and goes on from where it stopped.
const ROUND_NEWTON_STEPS: usize = 10;

/// Halvings of the weight spread tried by [`MapSimulation::open_cells`]; the
/// last try is the plain Voronoi diagram, where distinct sites all own a cell.
const OPEN_HALVINGS: usize = 10;

impl MapSimulation {
    /// One round: the pivoted move, every cell opened, Newton weight steps
    /// with a line search until the area error meets the target. Counts as a
    /// tick.
    pub(super) fn transport_round(&mut self) {
        self.pivot_to_centroids();
        self.open_cells();
        self.error = self.area_error();
        let goal = self.area_target();
        for _ in 0..ROUND_NEWTON_STEPS {
            if self.error <= goal || !self.settle_step() {
                break;
            }
        }
        self.iteration += 1;
        self.progress.rounds += 1;
    }

    /// Moves every site with a cell to its centroid `c` and lowers its weight
    /// by `|c − x|²`, which leaves the site's power at `c` as it was: to first
    /// order the cell stays where it is, so the weights solved before remain a
    /// good start (moving the sites alone shifted every bisector of a tiny cell
    /// beside a huge one past its site and emptied it). Returns nothing; a site
    /// without a cell stays put.
    fn pivot_to_centroids(&mut self) {
        for (site, cell) in self.sites.iter_mut().zip(&self.diagram.cells) {
            if cell.polygon.is_some() {
                let shift = cell.centroid - site.position;
                site.position = cell.centroid;
                site.weight -= shift.length_squared();
            }
        }
    }

    /// Computes the diagram of the moved sites with their weights' spread
    /// around the mean halved until no cell is empty: the Newton solve needs
    /// every cell open (Kitagawa, Mérigot and Thibert 2019), and equal
    /// weights open every cell of distinct sites. What stays empty (coincident
    /// sites) goes to the ordinary repair.
    fn open_cells(&mut self) {
        let pivot: Vec<f64> = self.sites.iter().map(|s| s.weight).collect();
        let mean = pivot.iter().sum::<f64>() / pivot.len().max(1) as f64;
        let mut share = 1.0;
        for halving in 0..=OPEN_HALVINGS {
            if halving == OPEN_HALVINGS {
                share = 0.0;
            }
            for (site, w) in self.sites.iter_mut().zip(&pivot) {
                site.weight = mean + share * (w - mean);
            }
            self.diagram = power_diagram(&self.sites, &self.clip);
            if self.diagram.cells.iter().all(|c| c.polygon.is_some()) {
                return;
            }
            share *= 0.5;
        }
        self.repair();
    }
}
