//! What a layout-JSON document carries beyond the dataset and the geometry:
//! the constraints with their `realized` flags and the producer's own quality
//! figures, taken from a finished computation. Owns that selection; the writer
//! (`super::write`) owns how it is spelled.

use serde::Serialize;

use crate::layout::Computed;
use crate::measure;

/// One neighbourhood constraint as written to the `constraints` array.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConstraintOut {
    /// Id of one node (same depth as `b`); the pair is undirected and listed once.
    pub a: String,
    /// Id of the other node.
    pub b: String,
    /// Value of the similarity function, in `[0, 1]`.
    pub similarity: f64,
    /// 1 (weak) to 3 (strong): the bin the constraint came from.
    pub strength: u8,
    /// True when the two cells share an edge in this layout.
    pub realized: bool,
}

/// What the layout JSON carries beyond the dataset and the geometry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JsonExtras {
    /// The `constraints` array, written in this order. Default: empty.
    pub constraints: Vec<ConstraintOut>,
    /// The producer's own figures, written as the `metrics` object in this order
    /// (keys should be unique); the field is left out when empty. Default: empty.
    pub metrics: Vec<(String, f64)>,
    /// Write coordinates in full precision instead of rounding them to six
    /// places: for the layout kept for warm starts (issue 6), which must
    /// reproduce the cells bit for bit so that a rebuild of unchanged data
    /// gives unchanged bytes. Default: false.
    pub exact: bool,
}

impl JsonExtras {
    /// The constraints and quality figures of a finished computation, with
    /// coordinates rounded (`exact: false`).
    pub fn of(computed: &Computed) -> JsonExtras {
        let ds = &computed.dataset;
        let q = measure::quality(ds, &computed.layout);
        JsonExtras {
            constraints: computed
                .constraints
                .iter()
                .zip(&computed.realized)
                .map(|(c, r)| ConstraintOut {
                    a: ds.node(c.a).id.clone(),
                    b: ds.node(c.b).id.clone(),
                    similarity: c.similarity,
                    strength: c.strength,
                    realized: *r,
                })
                .collect(),
            metrics: vec![
                (
                    "area_error_diagram_mean".to_string(),
                    q.area_error_diagram_mean,
                ),
                (
                    "area_error_diagram_max".to_string(),
                    q.area_error_diagram_max,
                ),
                ("aspect_ratio_mean".to_string(), q.aspect_ratio_mean),
            ],
            exact: false,
        }
    }
}
