//! The fuzzing harness's long run (issue 11): the targets of
//! `tests/suite/fuzz/targets.rs` and `npy_adapter.rs` (`.npy` vectors and an
//! exec adapter's output, issue 21; shared with the suite's short slice), by
//! default 10 million cases per parser and 10,000 layouts, each case under a
//! time bound (a hang aborts with the input) and an allocation bound.
//!
//! ```text
//! cargo bench --bench fuzz                          # everything
//! cargo bench --bench fuzz -- csv --cases 1000000   # one target
//! cargo bench --bench fuzz -- --seed 7              # another stream
//! cargo bench --bench fuzz -- --jobs 1               # one thread
//! cargo bench --bench fuzz -- csv --seed 1000 --replay 4711   # print a hung case
//! ```
//!
//! Each target runs in `--jobs` shards (default: every core), shard j with
//! seed `seed·1000 + j`; a hang report names its shard's seed and the case.
//!
//! One line per target (cases, accepted, slowest case, largest allocation,
//! time); exit code 1 on the first failure, with the shrunk input.

#[path = "../tests/suite/fuzz/targets.rs"]
#[allow(dead_code)]
mod targets;

#[path = "../tests/suite/fuzz/npy_adapter.rs"]
mod npy_adapter;

use std::sync::Arc;
use std::time::Duration;

use targets::{Bounds, Run, Summary};

#[global_allocator]
static ALLOCATOR: targets::Counting = targets::Counting;

/// Parsers, release build: a case is a few hundred bytes.
const PARSER: Bounds = Bounds {
    time: Duration::from_secs(2),
    bytes: 64 << 20,
};

/// Layouts of at most 20 leaves.
const LAYOUT: Bounds = Bounds {
    time: Duration::from_secs(20),
    bytes: 256 << 20,
};

const TARGETS: [&str; 7] = ["csv", "json", "yaml", "state", "npy", "adapter", "layout"];

/// The command line.
struct Args {
    wanted: Vec<String>,
    cases: Option<u32>,
    seed: u64,
    jobs: u64,
    replay: Option<u64>,
}

fn args() -> Args {
    let mut a = Args {
        wanted: Vec::new(),
        cases: None,
        seed: 1,
        jobs: std::thread::available_parallelism().map_or(1, |n| n.get() as u64),
        replay: None,
    };
    let mut it = std::env::args().skip(1);
    let number = |v: Option<String>| v.and_then(|v| v.replace('_', "").parse::<u64>().ok());
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--cases" => a.cases = number(it.next()).map(|v| v.min(u64::from(u32::MAX)) as u32),
            "--seed" => a.seed = number(it.next()).unwrap_or(a.seed),
            "--jobs" => a.jobs = number(it.next()).unwrap_or(1).max(1),
            "--replay" => a.replay = number(it.next()),
            // Passed by `cargo bench`.
            "--bench" => {}
            t if TARGETS.contains(&t) => a.wanted.push(t.to_string()),
            other => {
                eprintln!(
                    "fuzz: unknown argument {other:?}; targets: {TARGETS:?}, --cases N, \
                     --seed S, --jobs J, --replay K"
                );
                std::process::exit(2);
            }
        }
    }
    if a.wanted.is_empty() {
        a.wanted = TARGETS.iter().map(|t| t.to_string()).collect();
    }
    a
}

/// Runs one target's shard.
fn shard(target: &str, run: Run) -> Summary {
    match target {
        "csv" => targets::drive("csv", targets::csv_cases(), targets::check_csv, run),
        "json" => targets::drive("json", targets::json_cases(), targets::check_json, run),
        "yaml" => targets::drive("yaml", targets::yaml_cases(), targets::check_yaml, run),
        "npy" => targets::drive("npy", npy_adapter::npy_cases(), npy_adapter::check_npy, run),
        "adapter" => targets::drive(
            "adapter",
            npy_adapter::adapter_cases(),
            npy_adapter::check_adapter,
            run,
        ),
        "state" => {
            let seeds = Arc::new(targets::state_seeds());
            targets::drive(
                "state",
                targets::state_cases(seeds),
                targets::check_state,
                run,
            )
        }
        _ => targets::drive(
            "layout",
            targets::layout_cases(),
            targets::check_layout,
            run,
        ),
    }
}

fn main() {
    let a = args();
    let mut failed = false;
    for target in &a.wanted {
        let layout = target == "layout";
        let cases = a.cases.unwrap_or(if layout { 10_000 } else { 10_000_000 });
        let bounds = if layout { LAYOUT } else { PARSER };
        if let Some(k) = a.replay {
            // A hang report names the shard's own seed: replay exactly that.
            let run = Run {
                cases,
                seed: a.seed,
                bounds,
                replay: Some(k),
            };
            failed |= report(&shard(target, run), 1);
            continue;
        }
        // Shards run side by side, each its own stream of cases: shard j of
        // seed s draws from seed s·1000 + j, so shards never repeat each
        // other and a run is reproducible from (seed, jobs).
        let jobs = a.jobs.min(u64::from(cases.max(1)));
        let per = cases / jobs as u32;
        let summary = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..jobs)
                .map(|j| {
                    let n = if j + 1 == jobs {
                        cases - per * (jobs as u32 - 1)
                    } else {
                        per
                    };
                    let run = Run {
                        cases: n,
                        seed: a.seed * 1000 + j,
                        bounds,
                        replay: None,
                    };
                    scope.spawn(move || shard(target, run))
                })
                .collect();
            let mut total: Option<Summary> = None;
            for h in handles {
                let s = h.join().expect("a shard's thread ends without panicking");
                match &mut total {
                    Some(t) => merge(t, s),
                    None => total = Some(s),
                }
            }
            total.unwrap_or_default()
        });
        failed |= report(&summary, jobs);
    }
    if failed {
        std::process::exit(1);
    }
}

/// Adds another shard's figures to `total`.
fn merge(total: &mut Summary, other: Summary) {
    total.cases += other.cases;
    total.accepted += other.accepted;
    total.failure = total.failure.take().or(other.failure);
    total.max_case_ms = total.max_case_ms.max(other.max_case_ms);
    total.max_case_bytes = total.max_case_bytes.max(other.max_case_bytes);
    total.seconds = total.seconds.max(other.seconds);
}

/// Prints one target's line; true when it failed.
fn report(s: &Summary, jobs: u64) -> bool {
    println!(
        "fuzz {:<6} {:>10} cases  {:>10} accepted  0 hangs  slowest {:>8.2} ms  largest {:>10} B  {:>8.1} s  {} jobs  {}",
        s.target,
        s.cases,
        s.accepted,
        s.max_case_ms,
        s.max_case_bytes,
        s.seconds,
        jobs,
        if s.failure.is_some() { "FAILED" } else { "0 panics" }
    );
    if let Some(failure) = &s.failure {
        println!("{failure}");
        return true;
    }
    false
}
