//! What a build's stages did: per stage, whether it ran or its result was
//! reused, how long it took and a word on why. Printed with `-v`; the tests
//! assert reuse through [`StageReport::ran`] and [`StageReport::reused`].

use std::fmt;

/// A stage of the graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Reading (and fingerprinting) the input files.
    Read,
    /// Parsing them into a dataset.
    Parse,
    /// Virtual nodes and aggregated vectors (paper §4).
    Prepare,
    /// The constraints (method-reference §3).
    Constraints,
    /// The layout.
    Layout,
    /// One output's bytes.
    Render,
    /// One output's file.
    Write,
}

impl Stage {
    /// The stage's name in `-v` lines.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Read => "read",
            Stage::Parse => "parse",
            Stage::Prepare => "prepare",
            Stage::Constraints => "constraints",
            Stage::Layout => "layout",
            Stage::Render => "render",
            Stage::Write => "write",
        }
    }
}

/// One stage's run.
#[derive(Clone, Debug, PartialEq)]
pub struct StageRun {
    /// The stage.
    pub stage: Stage,
    /// False when its result was reused (from memory, the state folder or
    /// the files already on disk).
    pub ran: bool,
    /// Its wall time in milliseconds.
    pub ms: f64,
    /// What it did or why it was reused, in a few words.
    pub note: String,
    /// The output it was for (render and write), as the config names it.
    pub output: Option<String>,
}

/// The stages of one dataset's build, in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StageReport {
    /// Every stage run or reused.
    pub runs: Vec<StageRun>,
}

impl StageReport {
    /// Records a stage (and logs it at info level: `-v`).
    pub fn record(
        &mut self,
        dataset: &str,
        stage: Stage,
        ran: bool,
        ms: f64,
        note: impl Into<String>,
    ) {
        self.push(dataset, stage, None, ran, ms, note.into());
    }

    /// Records a stage of one output (render, write), naming it.
    pub fn record_output(
        &mut self,
        dataset: &str,
        stage: Stage,
        output: String,
        ran: bool,
        ms: f64,
        note: impl Into<String>,
    ) {
        self.push(dataset, stage, Some(output), ran, ms, note.into());
    }

    fn push(
        &mut self,
        dataset: &str,
        stage: Stage,
        output: Option<String>,
        ran: bool,
        ms: f64,
        note: String,
    ) {
        let run = StageRun {
            stage,
            ran,
            ms,
            note,
            output,
        };
        tracing::info!("{dataset}: {run}");
        self.runs.push(run);
    }

    /// How many times `stage` ran.
    #[cfg(any(test, feature = "internals"))]
    pub fn ran(&self, stage: Stage) -> usize {
        self.runs
            .iter()
            .filter(|r| r.stage == stage && r.ran)
            .count()
    }

    /// How many times `stage`'s result was reused.
    #[cfg(any(test, feature = "internals"))]
    pub fn reused(&self, stage: Stage) -> usize {
        self.runs
            .iter()
            .filter(|r| r.stage == stage && !r.ran)
            .count()
    }
}

impl fmt::Display for StageRun {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let how = if self.ran { "ran" } else { "reused" };
        write!(f, "{}", self.stage.name())?;
        if let Some(output) = &self.output {
            write!(f, " {output}")?;
        }
        write!(f, " {how} in {:.1} ms", self.ms)?;
        if !self.note.is_empty() {
            write!(f, " ({})", self.note)?;
        }
        Ok(())
    }
}
