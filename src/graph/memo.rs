//! One stage's memo slot: the last result with the key it was made from,
//! reused while the key is unchanged, and the one place a stage's run or
//! reuse is recorded in the [`StageReport`].
//!
//! The stage graph is a fixed chain with one result per stage and dataset,
//! so a slot is a single `(key, value)` pair, not a map: a new key replaces
//! the old result (why the cache is our own, not salsa or comemo: see
//! [`crate::graph`]).

use std::time::Instant;

use super::report::{Stage, StageReport};

/// What a stage's producer made: computed now, or loaded from the state
/// folder (a reuse across processes, recorded as not run).
pub enum Made<V> {
    /// Computed, with a word on what it made (`"42 nodes"`).
    Ran(V, String),
    /// Taken from the state folder, with a word on where from.
    Loaded(V, String),
}

/// The context every stage records into: the dataset's name, whether reuse
/// is on (`NPTREEMAP_NO_CACHE` turns it off) and the report.
pub struct Cx<'a> {
    /// The dataset, for the `-v` lines.
    pub name: &'a str,
    /// Reuse anything at all.
    pub cache: bool,
    /// What the stages did.
    pub stages: &'a mut StageReport,
}

impl Cx<'_> {
    /// Records a stage of one output (render), named as `-v` shows it.
    pub fn record_output(
        &mut self,
        stage: Stage,
        output: String,
        ran: bool,
        since: Instant,
        note: impl Into<String>,
    ) {
        self.stages
            .record_output(self.name, stage, output, ran, ms_since(since), note);
    }

    /// Records an output's stage that ran and took `ms` milliseconds (timed
    /// apart from the others, as when they run at once).
    pub fn record_output_ms(&mut self, stage: Stage, output: String, ms: f64, note: impl Into<String>) {
        self.stages
            .record_output(self.name, stage, output, true, ms, note);
    }

    /// Records a stage that ran (`ran`) or was reused, timed from `since`.
    pub fn record(&mut self, stage: Stage, ran: bool, since: Instant, note: impl Into<String>) {
        self.stages
            .record(self.name, stage, ran, ms_since(since), note);
    }
}

/// Milliseconds since `t`: every stage's time in the report.
pub fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1000.0
}

/// The last result of one stage and the key it was made from.
pub struct Memo<K, V> {
    slot: Option<(K, V)>,
}

impl<K, V> Default for Memo<K, V> {
    fn default() -> Self {
        Memo { slot: None }
    }
}

impl<K: PartialEq, V: Clone> Memo<K, V> {
    /// The result for `key`: the slot's when it was made from the same key
    /// (and reuse is on), else what `make` makes, kept for next time. Either
    /// way the stage is recorded once: reused with `same` as its reason, or
    /// with `make`'s note.
    pub fn get_or<E>(
        &mut self,
        key: K,
        cx: &mut Cx<'_>,
        stage: Stage,
        same: &str,
        make: impl FnOnce() -> Result<Made<V>, E>,
    ) -> Result<V, E> {
        let t = Instant::now();
        if let Some(value) = self.get(&key, cx.cache) {
            cx.record(stage, false, t, same);
            return Ok(value);
        }
        let (value, ran, note) = match make()? {
            Made::Ran(value, note) => (value, true, note),
            Made::Loaded(value, note) => (value, false, note),
        };
        cx.record(stage, ran, t, note);
        self.slot = Some((key, value.clone()));
        Ok(value)
    }

    /// The slot's value when it was made from `key` and reuse is on.
    pub fn get(&self, key: &K, cache: bool) -> Option<V> {
        match &self.slot {
            Some((k, value)) if cache && k == key => Some(value.clone()),
            _ => None,
        }
    }

    /// The slot's key and value, whatever the key.
    pub fn last(&self) -> Option<&(K, V)> {
        self.slot.as_ref()
    }

    /// Puts a result in the slot.
    pub fn set(&mut self, key: K, value: V) {
        self.slot = Some((key, value));
    }

    /// Empties the slot, giving back what it held.
    pub fn take(&mut self) -> Option<(K, V)> {
        self.slot.take()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(memo: &mut Memo<u8, u32>, key: u8, cache: bool, made: u32) -> (u32, StageReport) {
        let mut stages = StageReport::default();
        let mut cx = Cx {
            name: "d",
            cache,
            stages: &mut stages,
        };
        let value = memo
            .get_or(key, &mut cx, Stage::Parse, "same", || {
                Ok::<_, ()>(Made::Ran(made, "made".into()))
            })
            .expect("made");
        (value, stages)
    }

    /// A slot reuses its value for the same key only, records each call
    /// once, and reuses nothing with the cache off.
    #[test]
    fn a_slot_reuses_for_the_same_key_only() {
        let mut memo = Memo::default();
        let (v, s) = run(&mut memo, 1, true, 10);
        assert_eq!((v, s.ran(Stage::Parse), s.reused(Stage::Parse)), (10, 1, 0));
        let (v, s) = run(&mut memo, 1, true, 20);
        assert_eq!((v, s.ran(Stage::Parse), s.reused(Stage::Parse)), (10, 0, 1));
        let (v, _) = run(&mut memo, 2, true, 30);
        assert_eq!(v, 30);
        let (v, s) = run(&mut memo, 2, false, 40);
        assert_eq!((v, s.ran(Stage::Parse)), (40, 1));
    }

    /// A value loaded from the state folder counts as reused, and an error
    /// leaves the slot as it was.
    #[test]
    fn loaded_is_reused_and_errors_keep_the_slot() {
        let mut memo: Memo<u8, u32> = Memo::default();
        let mut stages = StageReport::default();
        let mut cx = Cx {
            name: "d",
            cache: true,
            stages: &mut stages,
        };
        let v = memo
            .get_or(1, &mut cx, Stage::Constraints, "same", || {
                Ok::<_, ()>(Made::Loaded(5, "from the cache".into()))
            })
            .expect("loaded");
        assert_eq!(v, 5);
        let failed = memo.get_or(2, &mut cx, Stage::Constraints, "same", || Err::<Made<u32>, _>("bad"));
        assert_eq!(failed, Err("bad"));
        assert_eq!(memo.last(), Some(&(1, 5)));
        assert_eq!(stages.reused(Stage::Constraints), 1);
        assert_eq!(stages.ran(Stage::Constraints), 0);
    }
}
