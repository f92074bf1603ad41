//! The keys of the stage graph: what each stage's result depends on, as
//! fingerprints. Each key names exactly the inputs of its stage, so a stage
//! is reused precisely while those are unchanged; adding an input to a
//! stage means adding it here.

use nptreemap_formats::{Dataset, Features};

use crate::config::{DatasetConfig, OutputConfig, OutputKind};
use crate::fingerprint::{Fingerprint, Fingerprinter};
use crate::layout::ZeroWeights;
use crate::neighborhood::SimilarityKind;
use crate::pipeline::InputFile;
use crate::render::Style;

/// Read and parse: the input bytes by role and everything that decides how
/// they are read (format, field mapping, limits, an exec command). Not the
/// paths: a moved file with the same bytes gives the same dataset.
pub fn inputs(d: &DatasetConfig, files: &[InputFile]) -> Fingerprint {
    let mut f = Fingerprinter::new("inputs");
    f.str(&d.format).value(&d.fields).value(&d.command);
    for file in files {
        f.str(&file.role).bytes(&file.bytes);
    }
    f.finish()
}

/// What is drawn of the parsed inputs: the inputs' key and whether items of
/// weight 0 are hidden (`layout.zero_weights`), which decides the nodes
/// that are prepared. The key of the prepared dataset in a build.
pub fn drawn(inputs: Fingerprint, zero_weights: ZeroWeights) -> Fingerprint {
    Fingerprinter::new("drawn")
        .fingerprint(inputs)
        .str(zero_weights.name())
        .finish()
}

/// Prepare and constraints: what the constraints of a dataset depend on,
/// and nothing else: the measure, and per node (in order) its id, parent,
/// vector and relations. Weights, labels and colours are left out, so a
/// weight edit keeps the constraints (vectors of inner nodes are plain means
/// of their children's, never weighted: `neighborhood::prepare`).
pub fn similarity(dataset: &Dataset, kind: SimilarityKind) -> Fingerprint {
    Fingerprinter::new("similarity")
        .value(&kind)
        .fingerprint(similarity_of_nodes(dataset))
        .finish()
}

/// The per-node part of [`similarity`].
fn similarity_of_nodes(dataset: &Dataset) -> Fingerprint {
    let mut f = Fingerprinter::new("nodes");
    f.u64(dataset.len() as u64);
    for node in dataset.nodes() {
        f.str(&node.id)
            .u64(node.parent.map_or(u64::MAX, |p| p as u64));
        match &node.features {
            Some(Features::Dense(values)) => {
                f.u64(values.len() as u64);
                for &v in values.iter() {
                    f.f64(v);
                }
            }
            Some(Features::Sparse(sparse)) => {
                // Marked apart from a dense vector of the same length.
                f.u64(u64::MAX - 1).u64(sparse.len() as u64);
                f.u64(sparse.indices().len() as u64);
                for (k, v) in sparse.entries() {
                    f.u64(u64::from(k)).f64(v);
                }
            }
            None => {
                f.u64(u64::MAX);
            }
        }
        f.u64(node.relations.len() as u64);
        for &r in &node.relations {
            f.u64(r as u64);
        }
    }
    f.finish()
}

/// A dataset given in memory (`layout`, `eval`): all of it (what the
/// similarity key covers, and weights, labels, colours, virtual flags and
/// the similarity hint), for the memo of its prepared form.
pub fn dataset(dataset: &Dataset) -> Fingerprint {
    let mut f = Fingerprinter::new("dataset");
    f.value(&dataset.similarity_hint());
    for node in dataset.nodes() {
        f.str(&node.label)
            .f64(node.weight.unwrap_or(f64::NAN))
            .f64(node.value)
            .value(&node.color)
            .u64(u64::from(node.is_virtual));
    }
    f.fingerprint(similarity_of_nodes(dataset));
    f.finish()
}

/// Render: one output's bytes depend on the layout (the inputs and settings
/// it was made from and the stored layout's bytes, which hold every cell and
/// constraint), the style (except for layout JSON, which has none), and the
/// output's kind and scale.
pub fn render(
    inputs: Fingerprint,
    settings: Fingerprint,
    layout: Fingerprint,
    style: &Style,
    output: &OutputConfig,
) -> Fingerprint {
    let kind = output.kind.unwrap_or(OutputKind::Svg);
    let mut f = Fingerprinter::new("render");
    f.fingerprint(inputs)
        .fingerprint(settings)
        .fingerprint(layout)
        .value(&kind)
        .f64(output.scale);
    if kind != OutputKind::Json {
        f.value(style);
    }
    f.finish()
}

/// An HTML page's render key with its past layouts (their stored layouts'
/// fingerprints, oldest first): a different history is a different page.
pub fn history(render: Fingerprint, past: &[Fingerprint]) -> Fingerprint {
    let mut f = Fingerprinter::new("history");
    f.fingerprint(render);
    for state in past {
        f.fingerprint(*state);
    }
    f.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn data(weight: f64, features: Vec<f64>) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        b.add(NodeSpec::new("a").parent("r").weight(weight).features(features));
        b.add(NodeSpec::new("b").parent("r").weight(1.0).features(vec![1.0, 0.0]));
        b.build().expect("valid")
    }

    #[test]
    fn the_similarity_key_ignores_weights_only() {
        let k = |d: &Dataset| similarity(d, SimilarityKind::Cosine);
        let base = data(1.0, vec![0.0, 1.0]);
        assert_eq!(k(&base), k(&data(7.0, vec![0.0, 1.0])));
        assert_ne!(k(&base), k(&data(1.0, vec![1.0, 1.0])));
        assert_ne!(k(&base), similarity(&base, SimilarityKind::Jaccard));
    }
}
