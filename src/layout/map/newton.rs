//! The weight step of a `MapSimulation`: the Newton direction on the power
//! weights (the Jacobian of the areas is a graph Laplacian, solved by
//! conjugate gradients), and the weight-only settle with a line search.

use super::MapSimulation;
use crate::power::{power_diagram, PowerDiagram};

/// Newton steps are shortened so no bisector moves by more than this share of
/// its site distance: the linearisation is good for moderate moves, and a site
/// is never overtaken by a neighbour's bisector in one step.
const MAX_BISECTOR_SHIFT: f64 = 1.0;

/// Halvings tried by the line search of [`MapSimulation::settle_weights`].
const LINE_SEARCH_HALVINGS: usize = 12;

/// Conjugate-gradient stop: residual below this share of the right-hand side.
/// The step is re-linearised next tick anyway, so a rough solve is enough.
const CG_TOLERANCE: f64 = 1e-3;

/// Conjugate-gradient iteration cap (a 2-D Laplacian of n cells needs about √n).
const CG_MAX_ITER: usize = 200;

impl MapSimulation {
    /// Σ|A − A*| / A(clip) of the current diagram.
    pub(super) fn area_error(&self) -> f64 {
        area_error_of(&self.diagram, &self.targets, self.clip_area)
    }

    /// One step that moves only weights (sites stay put): the final settling
    /// of a layout whose site arrangement carries meaning, such as realised
    /// neighbourhoods. Returns the new area error.
    pub fn settle_weights(&mut self) -> f64 {
        // No `prevent_domination` here: with sites fixed, the weights that give
        // the target areas may leave a site outside its own cell, and forcing it
        // back in stalls the solve. Instead of the step cap, whose worst pair
        // can stall fixed sites, the full Newton step is tried and halved until
        // the area error drops (backtracking line search).
        self.iteration += 1;
        self.settle_step();
        self.error
    }

    /// [`Self::settle_weights`] without the tick count: true when a step
    /// lowered the area error.
    pub(super) fn settle_step(&mut self) -> bool {
        let Some((x, _)) = self.newton_direction() else {
            return false;
        };
        let base: Vec<f64> = self.sites.iter().map(|s| s.weight).collect();
        let mut alpha = 1.0;
        for _ in 0..LINE_SEARCH_HALVINGS {
            for ((site, w), dx) in self.sites.iter_mut().zip(&base).zip(&x) {
                site.weight = w + alpha * dx;
            }
            let diagram = power_diagram(&self.sites, &self.clip);
            let empty = diagram.cells.iter().any(|c| c.polygon.is_none());
            let error = area_error_of(&diagram, &self.targets, self.clip_area);
            if !empty && error < self.error {
                self.diagram = diagram;
                self.error = error;
                return true;
            }
            alpha *= 0.5;
        }
        // No step helped: keep the previous weights and diagram.
        for (site, w) in self.sites.iter_mut().zip(&base) {
            site.weight = *w;
        }
        false
    }

    /// Newton step on the power weights: solve `L Δw = A* − A` where `L` is the
    /// Laplacian with edge conductances `l_ij / (2 d_ij)`.
    pub(super) fn newton_weights(&mut self) {
        if let Some((x, alpha)) = self.newton_direction() {
            for (site, dx) in self.sites.iter_mut().zip(&x) {
                site.weight += alpha * dx;
            }
        }
    }

    /// The Newton step on the weights and the capped step length (see
    /// `MAX_BISECTOR_SHIFT` and the flicker damping); `None` when there is
    /// nothing to solve.
    pub(super) fn newton_direction(&self) -> Option<(Vec<f64>, f64)> {
        let n = self.sites.len();
        if n < 2 {
            return None;
        }
        // Conductances in compressed rows.
        let mut start = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        let mut vals = Vec::new();
        let mut diag = vec![0.0; n];
        for (i, cell) in self.diagram.cells.iter().enumerate() {
            start.push(cols.len());
            for nb in &cell.neighbors {
                let d = self.sites[i]
                    .position
                    .distance(self.sites[nb.site].position);
                let l = nb.edge[0].distance(nb.edge[1]);
                if d > 0.0 && l > 0.0 {
                    let c = l / (2.0 * d);
                    cols.push(nb.site);
                    vals.push(c);
                    diag[i] += c;
                }
            }
        }
        start.push(cols.len());
        let active: Vec<bool> = diag.iter().map(|d| *d > 0.0).collect();
        let mut b: Vec<f64> = (0..n)
            .map(|i| {
                if active[i] {
                    self.targets[i] - self.diagram.cells[i].area
                } else {
                    0.0
                }
            })
            .collect();
        // The Laplacian is singular (adding a constant to every weight changes
        // nothing); a consistent right-hand side sums to zero.
        let count = active.iter().filter(|a| **a).count();
        if count < 2 {
            return None;
        }
        let mean = b.iter().sum::<f64>() / count as f64;
        for (bi, a) in b.iter_mut().zip(&active) {
            if *a {
                *bi -= mean;
            }
        }
        let apply = |x: &[f64], out: &mut [f64]| {
            for i in 0..n {
                let mut s = diag[i] * x[i];
                for k in start[i]..start[i + 1] {
                    s -= vals[k] * x[cols[k]];
                }
                out[i] = s;
            }
        };
        let x = conjugate_gradient(&b, &diag, apply);
        // Shorten the step so no bisector moves too far (see MAX_BISECTOR_SHIFT).
        let mut alpha: f64 = self.damping;
        for i in 0..n {
            for &j in &cols[start[i]..start[i + 1]] {
                let dw = (x[i] - x[j]).abs();
                if dw > 0.0 {
                    let d2 = self.sites[i]
                        .position
                        .distance_squared(self.sites[j].position);
                    alpha = alpha.min(2.0 * MAX_BISECTOR_SHIFT * d2 / dw);
                }
            }
        }
        Some((x, alpha))
    }
}

/// Σ|A − A*| / A(clip) of a diagram.
fn area_error_of(diagram: &PowerDiagram, targets: &[f64], clip_area: f64) -> f64 {
    let sum: f64 = diagram
        .cells
        .iter()
        .zip(targets)
        .map(|(c, t)| (c.area - t).abs())
        .sum();
    sum / clip_area
}

/// Jacobi-preconditioned conjugate gradients for `L x = b` with `L` symmetric
/// positive semi-definite and `b` in its range. Rows with a zero diagonal are
/// left at 0.
fn conjugate_gradient(b: &[f64], diag: &[f64], apply: impl Fn(&[f64], &mut [f64])) -> Vec<f64> {
    let n = b.len();
    let inv: Vec<f64> = diag
        .iter()
        .map(|d| if *d > 0.0 { 1.0 / d } else { 0.0 })
        .collect();
    let dot = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(x, y)| x * y).sum::<f64>();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let b_norm = dot(b, b).sqrt();
    if b_norm == 0.0 {
        return x;
    }
    let mut z: Vec<f64> = r.iter().zip(&inv).map(|(r, m)| r * m).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for _ in 0..CG_MAX_ITER {
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let a = rz / pap;
        for i in 0..n {
            x[i] += a * p[i];
            r[i] -= a * ap[i];
        }
        if dot(&r, &r).sqrt() <= CG_TOLERANCE * b_norm {
            break;
        }
        for i in 0..n {
            z[i] = r[i] * inv[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conjugate_gradient_solves_a_path_laplacian() {
        // Path 0 - 1 - 2 with unit conductances; b sums to zero.
        let diag = [1.0, 2.0, 1.0];
        let apply = |x: &[f64], out: &mut [f64]| {
            out[0] = x[0] - x[1];
            out[1] = 2.0 * x[1] - x[0] - x[2];
            out[2] = x[2] - x[1];
        };
        let b = [1.0, 0.0, -1.0];
        let x = conjugate_gradient(&b, &diag, apply);
        let mut lx = [0.0; 3];
        apply(&x, &mut lx);
        for (l, b) in lx.iter().zip(b) {
            assert!((l - b).abs() < 1e-9, "{lx:?}");
        }
    }
}
