//! The PNG's pixels, and the repaint of only the rows an edit touched
//! (issue 32, item 2: draw what moved).
//!
//! A picture is cut into bands of [`BAND`] rows for bookkeeping only. A
//! band's digest is the ordered list of the items that meet its rows
//! ([`Item::rows`]) and of the usvg documents; a repaint compares the digests
//! with the last picture's and paints again only the runs of bands that
//! differ. Pixels are always painted in the picture's own frame: a run is
//! painted by drawing every item that meets it, whole, onto a transparent
//! pixmap of the picture's size and copying the run's rows. A pixel's value
//! is a function of the items that cover it, in order, so the rows come out
//! as a single pass over the whole picture would paint them, by
//! construction; painting a run on a pixmap of its own height would cut
//! the paths at its edges and move the anti-aliasing there. A whole paint is
//! two such runs (the two halves, on two cores), or one pass straight onto
//! the picture when it is too large to keep a copy of.

use rayon::prelude::*;
use resvg::tiny_skia::{self, Transform};
use resvg::usvg;
use xxhash_rust::xxh3::Xxh3;

use super::paint::Item;

/// Rows per band. Small enough that a weight edit, which moves a few dozen
/// cells in one branch, repaints a small share of the picture; large enough
/// that the digests stay few.
pub(super) const BAND: u32 = 32;

/// Largest picture whose pixels a repaint keeps, and that a whole paint
/// paints in two halves with a pixmap per half (64 MB of RGBA each).
pub(super) const KEEP_PIXELS: u64 = 16 << 20;

/// A layer ready to paint.
pub(super) enum Drawn<'a> {
    /// A usvg document (and its text's digest), drawn whole in every run.
    Tree(Box<usvg::Tree>, u128),
    /// Items, drawn in the runs they meet.
    Items(&'a [Item]),
}

/// The last picture painted at one scale: its bands' digests and its
/// pixels (see the module docs).
pub struct Painted {
    scale: u64,
    bands: Vec<u128>,
    pixmap: tiny_skia::Pixmap,
    /// The digest of the SVG text it was painted from and its encoded
    /// bytes: the same text again is the same PNG, read, painted and
    /// encoded no more.
    pub(super) svg: u128,
    pub(super) bytes: Vec<u8>,
}

impl std::fmt::Debug for Painted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Painted")
            .field("scale", &f64::from_bits(self.scale))
            .field("size", &(self.pixmap.width(), self.pixmap.height()))
            .finish_non_exhaustive()
    }
}

impl Painted {
    /// The scale it was painted at.
    pub fn scale(&self) -> f64 {
        f64::from_bits(self.scale)
    }

    /// Its pixels.
    pub(super) fn pixmap(&self) -> &tiny_skia::Pixmap {
        &self.pixmap
    }

    /// Its bands' digests, top to bottom.
    pub fn bands(&self) -> &[u128] {
        &self.bands
    }

    /// The digest of the SVG text it was painted from.
    pub fn svg_digest(&self) -> u128 {
        self.svg
    }

    /// Its encoded PNG bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// A picture from its pixels and what was kept of it: `None` when the
    /// band count is not that of its height or it is too large to keep.
    pub(super) fn from_parts(
        pixmap: tiny_skia::Pixmap,
        scale: f64,
        svg: u128,
        bands: Vec<u128>,
        bytes: Vec<u8>,
    ) -> Option<Painted> {
        let (w, h) = (pixmap.width(), pixmap.height());
        (bands.len() == h.div_ceil(BAND) as usize && u64::from(w) * u64::from(h) <= KEEP_PIXELS)
            .then_some(Painted {
                scale: scale.to_bits(),
                bands,
                pixmap,
                svg,
                bytes,
            })
    }

    /// Itself when small enough for a repaint to keep ([`KEEP_PIXELS`]).
    pub(super) fn worth_keeping(self) -> Option<Painted> {
        let (w, h) = (self.pixmap.width(), self.pixmap.height());
        (u64::from(w) * u64::from(h) <= KEEP_PIXELS).then_some(self)
    }

    /// The counts of painting it again from the same text: every band kept.
    pub(super) fn unchanged(&self) -> BandCounts {
        BandCounts {
            painted: 0,
            kept: self.bands.len(),
            documents: 0,
        }
    }
}

/// How many bands the PNGs of a render painted and how many they took from
/// the last picture, and how many documents usvg parsed for them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BandCounts {
    /// Painted anew.
    pub painted: usize,
    /// Taken from the last picture.
    pub kept: usize,
    /// Documents usvg parsed: elements the items do not draw (none for a
    /// picture of the picture writer's).
    pub documents: usize,
}

impl std::ops::AddAssign for BandCounts {
    fn add_assign(&mut self, other: BandCounts) {
        self.painted += other.painted;
        self.kept += other.kept;
        self.documents += other.documents;
    }
}

/// The pixels of `layers` (`user` maps the items' user units to the
/// picture's, `scale` the picture's to pixels) in a `w` × `h` pixmap,
/// painting only the bands that differ from `last` when it has the same
/// scale and size. Returns the picture (its SVG digest and bytes left to
/// the caller, who encodes it) and the counts; `None` when a pixmap cannot
/// be made.
pub(super) fn paint(
    layers: &[Drawn<'_>],
    (w, h): (u32, u32),
    scale: f64,
    user: Transform,
    last: Option<Painted>,
) -> Option<(Painted, BandCounts)> {
    let count = h.div_ceil(BAND) as usize;
    let s = scale as f32;
    let ts = Transform::from_scale(s, s).pre_concat(user);
    let (reach, bands) = bands_of(layers, count, ts, (w, h, scale));
    let frame = Frame {
        layers,
        reach: &reach,
        scale: Transform::from_scale(s, s),
        items: ts,
        size: (w, h),
    };
    let small = u64::from(w) * u64::from(h) <= KEEP_PIXELS;
    let last = last
        .filter(|p| p.scale == scale.to_bits() && (p.pixmap.width(), p.pixmap.height()) == (w, h));
    let dirty: Vec<usize> = match &last {
        Some(p) => (0..count).filter(|&b| p.bands[b] != bands[b]).collect(),
        None => (0..count).collect(),
    };
    let pixmap = match last {
        // A few bands: in two groups at once (the upper and the lower
        // half of them), each painted in one pass on a pixmap of the
        // picture's size, an item meeting several of its bands drawn once.
        Some(p) if 2 * dirty.len() <= count => {
            let mut pixmap = p.pixmap;
            let groups: Vec<&[usize]> = match dirty.len() {
                0 => Vec::new(),
                1 => vec![&dirty[..]],
                n => vec![&dirty[..n / 2], &dirty[n / 2..]],
            };
            let painted: Vec<Option<tiny_skia::Pixmap>> = groups
                .par_iter()
                .map(|group| {
                    let mut scratch = tiny_skia::Pixmap::new(w, h)?;
                    frame.run(&mut scratch, group);
                    Some(scratch)
                })
                .collect();
            for (group, scratch) in groups.iter().zip(painted) {
                let scratch = scratch?;
                for run in runs(group) {
                    copy_rows(&scratch, &mut pixmap, rows_of(run, h));
                }
            }
            pixmap
        }
        _ if small && count >= 2 => {
            let halves = [0..count / 2, count / 2..count];
            let painted: Vec<Option<tiny_skia::Pixmap>> = halves
                .par_iter()
                .map(|half| {
                    let mut pixmap = tiny_skia::Pixmap::new(w, h)?;
                    frame.run(&mut pixmap, &half.clone().collect::<Vec<_>>());
                    Some(pixmap)
                })
                .collect();
            let mut painted = painted.into_iter();
            let mut pixmap = painted.next()??;
            copy_rows(
                &painted.next()??,
                &mut pixmap,
                rows_of(halves[1].clone(), h),
            );
            pixmap
        }
        _ => {
            let mut pixmap = tiny_skia::Pixmap::new(w, h)?;
            frame.run(&mut pixmap, &(0..count).collect::<Vec<_>>());
            pixmap
        }
    };
    let counts = BandCounts {
        painted: dirty.len(),
        kept: count - dirty.len(),
        documents: layers
            .iter()
            .filter(|l| matches!(l, Drawn::Tree(..)))
            .count(),
    };
    let painted = Painted {
        scale: scale.to_bits(),
        bands,
        pixmap,
        svg: 0,
        bytes: Vec::new(),
    };
    Some((painted, counts))
}

/// What a run is painted with: the layers, each item's first and last band
/// (`None`: it meets no row), and the transforms of the documents and of
/// the items.
struct Frame<'a> {
    layers: &'a [Drawn<'a>],
    reach: &'a [Vec<Option<(usize, usize)>>],
    scale: Transform,
    items: Transform,
    size: (u32, u32),
}

impl Frame<'_> {
    /// Paints onto `pixmap` (the picture's size) the rows of `bands`
    /// (ascending): they are cleared, then every document and every item
    /// meeting any of them is drawn whole, once, in paint order.
    fn run(&self, pixmap: &mut tiny_skia::Pixmap, bands: &[usize]) {
        debug_assert_eq!((pixmap.width(), pixmap.height()), self.size);
        let stride = self.size.0 as usize * 4;
        for run in runs(bands) {
            let rows = rows_of(run, self.size.1);
            pixmap.data_mut()[rows.start * stride..rows.end * stride].fill(0);
        }
        // How many of `bands` lie below each band: an item meets one of
        // them when the count grows across its reach.
        let count = self.size.1.div_ceil(BAND) as usize;
        let mut below = vec![0usize; count + 1];
        for &b in bands {
            below[b + 1] += 1;
        }
        for b in 0..count {
            below[b + 1] += below[b];
        }
        for (drawn, reach) in self.layers.iter().zip(self.reach) {
            match drawn {
                Drawn::Tree(tree, _) => resvg::render(tree, self.scale, &mut pixmap.as_mut()),
                Drawn::Items(items) => {
                    for (item, r) in items.iter().zip(reach) {
                        if r.is_some_and(|(first, last)| below[last + 1] > below[first]) {
                            item.draw(&mut pixmap.as_mut(), self.items);
                        }
                    }
                }
            }
        }
    }
}

/// The pixel rows of the bands `run` in a picture of `h` rows.
fn rows_of(run: std::ops::Range<usize>, h: u32) -> std::ops::Range<usize> {
    let band = BAND as usize;
    run.start * band..(run.end * band).min(h as usize)
}

/// Copies `rows` of `from` into `to` (two pixmaps of one size).
fn copy_rows(from: &tiny_skia::Pixmap, to: &mut tiny_skia::Pixmap, rows: std::ops::Range<usize>) {
    let stride = from.width() as usize * 4;
    let (a, b) = (rows.start * stride, rows.end * stride);
    to.data_mut()[a..b].copy_from_slice(&from.data()[a..b]);
}

/// The maximal runs of consecutive bands in `dirty` (ascending).
fn runs(dirty: &[usize]) -> Vec<std::ops::Range<usize>> {
    let mut out: Vec<std::ops::Range<usize>> = Vec::new();
    for &b in dirty {
        match out.last_mut() {
            Some(r) if r.end == b => r.end = b + 1,
            _ => out.push(b..b + 1),
        }
    }
    out
}

/// Per layer, each item's first and last band (`None` when it meets no
/// row); per band, its digest (the picture's size and scale, each usvg
/// document's digest, the digests of the items that meet it, in order).
#[allow(clippy::type_complexity)]
fn bands_of(
    layers: &[Drawn<'_>],
    count: usize,
    ts: Transform,
    (w, h, scale): (u32, u32, f64),
) -> (Vec<Vec<Option<(usize, usize)>>>, Vec<u128>) {
    let mut hashers: Vec<Xxh3> = (0..count)
        .map(|_| {
            let mut hash = Xxh3::new();
            hash.update(&w.to_le_bytes());
            hash.update(&h.to_le_bytes());
            hash.update(&scale.to_bits().to_le_bytes());
            hash
        })
        .collect();
    let mut reach = Vec::with_capacity(layers.len());
    for drawn in layers {
        match drawn {
            Drawn::Tree(_, digest) => {
                for hash in &mut hashers {
                    hash.update(b"T");
                    hash.update(&digest.to_le_bytes());
                }
                reach.push(Vec::new());
            }
            Drawn::Items(items) => {
                let found: Vec<Option<(usize, usize, u128)>> = items
                    .par_iter()
                    .map(|item| {
                        let (top, end) = item.rows(ts)?;
                        if end <= 0 || top >= i64::from(h) {
                            return None;
                        }
                        let band = i64::from(BAND);
                        let first = (top.max(0) / band) as usize;
                        let last = ((end.min(i64::from(h)) - 1) / band) as usize;
                        let mut d = Xxh3::new();
                        item.digest(&mut d);
                        Some((first, last.min(count - 1), d.digest128()))
                    })
                    .collect();
                for hash in &mut hashers {
                    hash.update(b"I");
                }
                for &(first, last, digest) in found.iter().flatten() {
                    for hash in &mut hashers[first..=last] {
                        hash.update(&digest.to_le_bytes());
                    }
                }
                reach.push(found.iter().map(|f| f.map(|(a, b, _)| (a, b))).collect());
            }
        }
    }
    (reach, hashers.iter().map(Xxh3::digest128).collect())
}
