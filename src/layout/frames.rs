//! Snapshots of a similarity layout while it is optimised, for the HTML
//! page's slider that steps through the optimisation as the paper's prototype
//! does (method-reference §8.5: "a range slider steps through every saved
//! state"). Owns the [`Frame`] type and when frames are taken; may not change
//! the layout: recording is read-only, so a layout with frames is the same
//! layout as one without.

use crate::geom::ConvexPolygon;

/// The cells of one level at one moment of its optimisation.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Depth of the level being optimised (1 = the root's children).
    pub depth: usize,
    /// What the moment is: `matched and swapped`, `tick 40`, `final`.
    pub label: String,
    /// The level's cells then: node index and polygon (cells that were
    /// momentarily empty are left out).
    pub cells: Vec<(usize, ConvexPolygon)>,
}

/// Takes frames for one level: the start, every `every` ticks, the end.
#[derive(Clone, Debug)]
pub(crate) struct Recorder {
    depth: usize,
    every: usize,
    frames: Vec<Frame>,
}

impl Recorder {
    /// A recorder for the level at `depth` taking about `per_level` frames
    /// over `ticks` ticks; `None` when frames are off (`per_level` 0).
    pub(crate) fn new(depth: usize, per_level: usize, ticks: usize) -> Option<Self> {
        (per_level > 0).then(|| Self {
            depth,
            // Start and end are frames of their own; the ticks share the rest.
            every: ticks.div_ceil(per_level.saturating_sub(2).max(1)).max(1),
            frames: Vec::new(),
        })
    }

    /// Whether tick `tick` (0-based, counted after it ran) is one to record.
    pub(crate) fn wants(&self, tick: usize) -> bool {
        (tick + 1) % self.every == 0
    }

    /// Records the cells under `label`.
    pub(crate) fn take(&mut self, label: impl Into<String>, cells: Vec<(usize, ConvexPolygon)>) {
        self.frames.push(Frame {
            depth: self.depth,
            label: label.into(),
            cells,
        });
    }

    /// The frames taken, in order.
    pub(crate) fn into_frames(self) -> Vec<Frame> {
        self.frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_when_no_frames_are_asked_for() {
        assert!(Recorder::new(1, 0, 150).is_none());
    }

    #[test]
    fn ticks_share_the_frames_between_start_and_end() {
        let r = Recorder::new(2, 12, 150).expect("on");
        let recorded = (0..150).filter(|t| r.wants(*t)).count();
        // 10 frames for the ticks (150 / 10 = every 15th), plus start and end.
        assert_eq!(recorded, 10);
        let every_tick = Recorder::new(1, 500, 150).expect("on");
        assert_eq!((0..150).filter(|t| every_tick.wants(*t)).count(), 150);
    }
}
