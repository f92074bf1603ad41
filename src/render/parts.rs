//! What one render keeps for the next (issue 32, "draw what moved"): the
//! PNG's last picture (`png_bands`), the layout JSON's node lines and the
//! SVG's cell elements (`crate::line_memo`), and each leaf's label, by
//! everything that decides it: its text and value line, its size range and
//! its cell as drawn (the SVG's two decimals). The picture, the page's
//! picture and the page's label list of one build share one placement per
//! leaf, and a render after an edit fits only the labels of the cells the
//! edit moved: the key is the drawn cell, and the label is fitted to the
//! drawn cell too (which is the cell the reader sees).
//!
//! The memo stores a 128-bit digest of each key (xxh3), not the key, and a
//! label boxed: some 40 bytes for a leaf without a label (most leaves of a
//! large map) instead of its text and its cell's corners, so two
//! generations of 600,000 leaves take tens of megabytes, not hundreds (a
//! collision, at 2⁻¹²⁸, is the same bet the state folder's fingerprints
//! make).
//!
//! Two generations: what the current render asked for, and what the one
//! before it did. [`Parts::next_render`] drops the older, so the memo holds
//! at most two renders' labels however long a `watch` runs. Thread-safe: the
//! outputs of one build render in parallel and share it.
//!
//! Hand-written rather than a caching crate: the generations are the
//! eviction rule a render needs (a cache sized by count would keep the
//! labels of a layout long gone, or drop those of a large one), and it is
//! one map of our own keys.

use std::collections::HashMap;
use std::sync::Mutex;

use rayon::prelude::*;

use super::labels::{place_leaf, Placed};
use crate::geom::{ConvexPolygon, Point};

/// Drawn coordinates per canvas unit: the SVG writes two decimals.
const DRAWN_PER_UNIT: f64 = 100.0;

/// Everything that decides a leaf's label.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct LabelKey {
    text: String,
    value: Option<String>,
    /// The cell's corners in hundredths of a canvas unit.
    cell: Vec<(i64, i64)>,
    /// The font size range's bits.
    sizes: (u64, u64),
}

/// A key's digest: what the memo stores.
type Digest = u128;

impl LabelKey {
    /// The key's digest (xxh3, 128 bits) over its fields, each with its
    /// length, so no two keys share their bytes.
    fn digest(&self) -> Digest {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        let mut field = |bytes: &[u8]| {
            h.update(&(bytes.len() as u64).to_le_bytes());
            h.update(bytes);
        };
        field(self.text.as_bytes());
        match &self.value {
            Some(v) => field(v.as_bytes()),
            None => field(&[0xff]),
        }
        let corners: Vec<u8> = self
            .cell
            .iter()
            .flat_map(|&(x, y)| x.to_le_bytes().into_iter().chain(y.to_le_bytes()))
            .collect();
        field(&corners);
        field(&self.sizes.0.to_le_bytes());
        field(&self.sizes.1.to_le_bytes());
        h.digest128()
    }

    /// The key of a leaf with `text` (and value line `value`) in `polygon`,
    /// fitted between `min` and `max`.
    pub(crate) fn new(
        text: String,
        value: Option<String>,
        polygon: &ConvexPolygon,
        min: f64,
        max: f64,
    ) -> LabelKey {
        // Coordinates are finite and within the canvas (`Layout::sanity_check`);
        // `as` saturates anything else, which still gives a key.
        let drawn = |v: f64| (v * DRAWN_PER_UNIT).round() as i64;
        LabelKey {
            text,
            value,
            cell: polygon
                .points()
                .iter()
                .map(|p| (drawn(p.x), drawn(p.y)))
                .collect(),
            sizes: (min.to_bits(), max.to_bits()),
        }
    }

    /// The label this key decides, for node `node`: fitted to the cell as
    /// drawn; none when that cell is degenerate at two decimals (too small
    /// for any label).
    fn place(&self, node: usize) -> Option<Placed> {
        let points = self
            .cell
            .iter()
            .map(|&(x, y)| Point::new(x as f64 / DRAWN_PER_UNIT, y as f64 / DRAWN_PER_UNIT))
            .collect();
        let cell = ConvexPolygon::from_convex(points)?;
        let (min, max) = (f64::from_bits(self.sizes.0), f64::from_bits(self.sizes.1));
        place_leaf(node, &self.text, self.value.as_deref(), &cell, min, max)
    }
}

/// What the renders of one dataset keep for the next (see the module
/// docs): labels, line memos and the PNG's last picture at each scale.
#[derive(Debug, Default)]
pub struct Parts {
    labels: Mutex<Generations>,
    /// The layout JSON's memo (the output's and the stored layout's): node
    /// lines, precision checks, extras.
    documents: crate::layout_json::DocumentMemo,
    /// The SVG's cell elements (the picture's and the page's picture's).
    cells: crate::line_memo::LineMemo,
    /// Renders started ([`Parts::next_render`]).
    renders: std::sync::atomic::AtomicUsize,
    #[cfg(feature = "png")]
    pictures: Mutex<Pictures>,
}

/// The PNGs' last pictures: those the last render painted (`last`), those
/// this render painted (`current`), and this render's band counts. A
/// render takes a picture of its scale from either; [`Parts::next_render`]
/// drops what the render before last painted, so at most two renders'
/// pictures are held (one per PNG output in practice).
#[cfg(feature = "png")]
#[derive(Debug, Default)]
struct Pictures {
    current: Vec<super::png::Painted>,
    last: Vec<super::png::Painted>,
    counts: super::png::BandCounts,
}

#[derive(Debug, Default)]
struct Generations {
    current: HashMap<Digest, Option<Box<Placed>>>,
    previous: HashMap<Digest, Option<Box<Placed>>>,
    /// Labels found and fitted since the last [`Parts::next_render`].
    reused: usize,
    fitted: usize,
}

/// How many labels a render found in the memo and how many it fitted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LabelCounts {
    /// Found (from this render's other outputs or the render before).
    pub reused: usize,
    /// Fitted anew.
    pub fitted: usize,
}

impl Parts {
    /// An empty memo.
    pub fn new() -> Parts {
        Parts::default()
    }

    /// Starts the next render: what the render before last asked for, and
    /// not the last, is dropped. Returns the last render's counts.
    pub fn next_render(&self) -> LabelCounts {
        let mut g = self.lock();
        let counts = LabelCounts {
            reused: g.reused,
            fitted: g.fitted,
        };
        // Sized for the last render's labels, which move over one by one.
        let capacity = g.current.len();
        g.previous = std::mem::replace(&mut g.current, HashMap::with_capacity(capacity));
        g.reused = 0;
        g.fitted = 0;
        self.documents.next_build();
        self.cells.next_build();
        let renders = self
            .renders
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if renders >= 1 {
            self.documents.keep_lines();
        }
        #[cfg(feature = "png")]
        {
            let mut p = self.pictures();
            p.last = std::mem::take(&mut p.current);
            p.counts = super::png::BandCounts::default();
        }
        counts
    }

    /// [`super::png()`] of the `picture` at `scale` (its cells from their
    /// shapes), repainting over the last
    /// picture of that scale (this render's or the last one's) only the
    /// bands that changed; the bytes are those of a whole paint.
    #[cfg(feature = "png")]
    pub fn png(&self, picture: &super::Picture, scale: f64) -> Result<Vec<u8>, super::PngError> {
        let last = {
            let mut p = self.pictures();
            let Pictures { current, last, .. } = &mut *p;
            let take = |v: &mut Vec<super::png::Painted>| {
                let k = v.iter().position(|x| x.scale() == scale)?;
                Some(v.swap_remove(k))
            };
            take(current).or_else(|| take(last))
        };
        let (bytes, keep, counts) =
            super::png::png_with(&picture.text, picture.cells.as_ref(), scale, last)?;
        let mut p = self.pictures();
        p.counts += counts;
        p.current.extend(keep);
        Ok(bytes)
    }

    /// The layout JSON's memo: its node lines of this render and the last
    /// from the second render on (the first render of a process, every
    /// one-shot build, has none to find, and keeping its lines would cost
    /// it a third of the documents' time for nothing), its precision checks
    /// and this render's extras always.
    pub fn documents(&self) -> &crate::layout_json::DocumentMemo {
        &self.documents
    }

    /// The SVG's cell elements of this render and the last, from the second
    /// render on (as the node lines of [`Parts::documents`]).
    pub fn cell_lines(&self) -> Option<&crate::line_memo::LineMemo> {
        (self.renders.load(std::sync::atomic::Ordering::Relaxed) > 1).then_some(&self.cells)
    }

    /// How many cell elements the pictures of this render wrote and found.
    pub fn cell_counts(&self) -> crate::line_memo::LineCounts {
        self.cells.counts()
    }

    /// How many node lines the layout JSON of this render wrote and found.
    pub fn line_counts(&self) -> crate::line_memo::LineCounts {
        self.documents.lines.counts()
    }

    /// Whether a picture at `scale` is there to repaint over (this
    /// render's or the last one's).
    #[cfg(feature = "png")]
    pub fn has_png(&self, scale: f64) -> bool {
        let p = self.pictures();
        p.current.iter().chain(&p.last).any(|x| x.scale() == scale)
    }

    /// Takes a picture read back from an earlier process
    /// ([`super::png::read_back`]) as the last render's.
    #[cfg(feature = "png")]
    pub fn seed_png(&self, painted: super::png::Painted) {
        self.pictures().last.push(painted);
    }

    /// What this render's PNG at `scale` was painted from, when its bytes
    /// are `bytes`: its bands' digests and its SVG text's digest (for the
    /// state folder, so that a later process repaints over it).
    #[cfg(feature = "png")]
    pub fn painted(&self, scale: f64, bytes: &[u8]) -> Option<(Vec<u128>, u128)> {
        let p = self.pictures();
        let x = p
            .current
            .iter()
            .find(|x| x.scale() == scale && x.bytes() == bytes)?;
        Some((x.bands().to_vec(), x.svg_digest()))
    }

    /// The band counts of the PNGs of the render under way.
    #[cfg(feature = "png")]
    pub fn band_counts(&self) -> super::png::BandCounts {
        self.pictures().counts
    }

    #[cfg(feature = "png")]
    fn pictures(&self) -> std::sync::MutexGuard<'_, Pictures> {
        // A panic while the lock was held leaves whole entries only.
        self.pictures.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The counts of the render under way.
    pub fn counts(&self) -> LabelCounts {
        let g = self.lock();
        LabelCounts {
            reused: g.reused,
            fitted: g.fitted,
        }
    }

    /// Whether the memo holds no label (a process's first render).
    pub fn no_labels(&self) -> bool {
        let g = self.lock();
        g.current.is_empty() && g.previous.is_empty()
    }

    /// Takes labels kept by an earlier process (by digest, as
    /// [`Parts::kept_labels`] gave them) as the last render's, when the memo
    /// holds none.
    pub fn seed_labels(&self, labels: Vec<(u128, Option<Placed>)>) {
        let mut g = self.lock();
        if g.current.is_empty() && g.previous.is_empty() {
            g.previous = labels
                .into_iter()
                .map(|(d, p)| (d, p.map(Box::new)))
                .collect();
        }
    }

    /// The labels of the render under way by digest, in digest order (for
    /// the state folder), when it fitted any (else the kept ones hold).
    pub fn kept_labels(&self) -> Option<Vec<(u128, Option<Placed>)>> {
        let g = self.lock();
        if g.fitted == 0 {
            return None;
        }
        let mut all: Vec<(u128, Option<Placed>)> = g
            .current
            .iter()
            .map(|(d, p)| (*d, p.as_deref().cloned()))
            .collect();
        all.sort_unstable_by_key(|(d, _)| *d);
        Some(all)
    }

    /// The labels of `(node, key)` pairs, in their order (`None` for a leaf
    /// whose label does not fit): from the memo where it has them, the rest
    /// fitted in parallel and kept.
    pub(crate) fn labels(&self, keys: Vec<(usize, LabelKey)>) -> Vec<Option<Placed>> {
        let digests: Vec<Digest> = keys.par_iter().map(|(_, key)| key.digest()).collect();
        let mut found: Vec<Option<Option<Placed>>> = {
            let mut g = self.lock();
            keys.iter()
                .zip(&digests)
                .map(|((node, _), d)| g.take(*d).map(|p| p.map(|p| Placed { node: *node, ..*p })))
                .collect()
        };
        let missing: Vec<usize> = (0..keys.len()).filter(|&k| found[k].is_none()).collect();
        let fitted: Vec<Option<Placed>> = missing
            .par_iter()
            .map(|&k| keys[k].1.place(keys[k].0))
            .collect();
        let mut g = self.lock();
        g.fitted += missing.len();
        g.reused += keys.len() - missing.len();
        for (&k, placed) in missing.iter().zip(fitted) {
            g.current.insert(digests[k], placed.clone().map(Box::new));
            found[k] = Some(placed);
        }
        found.into_iter().map(Option::flatten).collect()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Generations> {
        // A panic while the lock was held leaves whole entries only.
        self.labels.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Generations {
    /// The entry of `key` from either generation, kept in the current one.
    fn take(&mut self, key: Digest) -> Option<Option<Box<Placed>>> {
        if let Some(p) = self.current.get(&key) {
            return Some(p.clone());
        }
        let p = self.previous.remove(&key)?;
        self.current.insert(key, p.clone());
        Some(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::Layout;
    use crate::render::labels::LabelStyle;
    use crate::render::svg::leaf_labels;
    use crate::render::test_support::sample;

    #[test]
    fn a_label_from_the_memo_is_the_label_fitted_to_the_drawn_cell() {
        let (dataset, layout) = sample();
        let style = LabelStyle::default();
        let parts = Parts::new();
        let first = leaf_labels(&dataset, &layout, &style, &parts);
        assert!(!first.is_empty(), "the sample has labels");
        let fitted = parts.counts().fitted;
        assert_eq!(parts.counts().reused, 0);
        // The same drawing again: every label found, none fitted, same labels.
        let again = leaf_labels(&dataset, &layout, &style, &parts);
        assert_eq!(again, first);
        assert_eq!(
            parts.counts(),
            LabelCounts {
                reused: fitted,
                fitted
            }
        );
        // A fresh memo fits the same labels: the memo changes no byte.
        assert_eq!(leaf_labels(&dataset, &layout, &style, &Parts::new()), first);
    }

    #[test]
    fn a_cell_moved_at_two_decimals_is_fitted_again_and_one_moved_less_is_not() {
        let (dataset, mut layout) = sample();
        let style = LabelStyle::default();
        let parts = Parts::new();
        leaf_labels(&dataset, &layout, &style, &parts);
        parts.next_render();
        let leaf = dataset.find("A1").expect("A1");
        let shift = |layout: &mut Layout, d: f64| {
            let moved: Vec<Point> = layout.cells[leaf]
                .polygon
                .points()
                .iter()
                .map(|p| Point::new(p.x + d, p.y))
                .collect();
            layout.cells[leaf].polygon = ConvexPolygon::new(moved).expect("convex");
        };
        shift(&mut layout, 0.001);
        leaf_labels(&dataset, &layout, &style, &parts);
        let counts = parts.next_render();
        assert_eq!(
            counts.fitted, 0,
            "a thousandth does not move the drawn cell"
        );
        shift(&mut layout, 0.5);
        leaf_labels(&dataset, &layout, &style, &parts);
        let counts = parts.next_render();
        assert_eq!(counts.fitted, 1, "only the moved cell's label is fitted");
        assert!(counts.reused >= 1);
    }

    /// The layout JSON's node lines are kept from a process's second render
    /// on: a one-shot build (one render) would only pay for them.
    #[test]
    fn node_lines_are_kept_from_the_second_render() {
        let parts = Parts::new();
        parts.next_render();
        assert!(parts.documents().lines().is_none());
        parts.next_render();
        assert!(parts.documents().lines().is_some());
    }

    #[test]
    fn the_memo_keeps_two_renders_at_most() {
        let (dataset, layout) = sample();
        let parts = Parts::new();
        let sizes = [9.0, 10.0, 11.0];
        for &min in &sizes {
            let style = LabelStyle {
                min_size: min,
                ..LabelStyle::default()
            };
            leaf_labels(&dataset, &layout, &style, &parts);
            parts.next_render();
        }
        let g = parts.lock();
        let leaves = (0..dataset.len()).filter(|&i| dataset.is_leaf(i)).count();
        assert!(g.current.is_empty() && g.previous.len() <= leaves);
    }
}
