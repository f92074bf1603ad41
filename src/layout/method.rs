//! `Method`: which layout strategy runs, selectable everywhere a layout is made
//! (issue 3): the engine's classic treemap, the paper's two baselines, its
//! initialisation alone, and the full neighbourhood-preserving method.

/// A layout strategy. Named in configs (`layout.method`) and on the command
/// line (`--method`) by [`Method::name`].
#[derive(serde::Serialize, Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Method {
    /// The classic Voronoi treemap of the engine; similarity is ignored.
    Plain,
    /// Baseline of Yao et al.: a CVT per parent, children assigned to its cells
    /// by a seeded random permutation, then the classic optimisation.
    RandomCvt,
    /// Baseline of Nocaj and Brandes: 2-D projections moved and shrunk into the
    /// parent, then the classic optimisation.
    ProjScale,
    /// The paper's initialisation alone: CVT, Kuhn–Munkres matching of
    /// projections to CVT sites, greedy swaps; areas then settled with the sites
    /// held in place.
    MatchSwap,
    /// The full method: initialisation plus the joint per-level optimisation that
    /// pulls constrained cells together (paper Algorithms 1 and 2).
    Neighbor,
}

impl Method {
    /// Every method, baselines first.
    pub const ALL: [Method; 5] = [
        Method::Plain,
        Method::RandomCvt,
        Method::ProjScale,
        Method::MatchSwap,
        Method::Neighbor,
    ];

    /// The name used on the command line and in config files.
    pub fn name(self) -> &'static str {
        match self {
            Method::Plain => "plain",
            Method::RandomCvt => "random-cvt",
            Method::ProjScale => "proj-scale",
            Method::MatchSwap => "match-swap",
            Method::Neighbor => "neighbor",
        }
    }

    /// Parses a method name.
    pub fn parse(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Every name, for messages (`plain, random-cvt, ...`).
    pub fn names() -> String {
        Method::ALL.map(Method::name).join(", ")
    }

    /// True for the methods that use the similarity.
    pub fn uses_similarity(self) -> bool {
        self != Method::Plain
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for m in Method::ALL {
            assert_eq!(Method::parse(m.name()), Some(m));
        }
        assert_eq!(Method::parse("nope"), None);
        // The config and the command line spell them the same way.
        for m in Method::ALL {
            use serde::de::{value::Error, IntoDeserializer};
            let de = IntoDeserializer::<Error>::into_deserializer(m.name());
            assert_eq!(<Method as serde::Deserialize>::deserialize(de), Ok(m));
            #[cfg(feature = "cli")]
            let cli = <Method as clap::ValueEnum>::from_str(m.name(), false).expect("cli name");
            #[cfg(feature = "cli")]
            assert_eq!(cli, m);
        }
    }
}
