//! The fuzzing harness's long run (issue 11): the targets of
//! `tests/suite/fuzz/targets.rs` (shared with the suite's short slice), by
//! default 10 million cases per parser and 10,000 layouts, each case under a
//! time bound (a hang aborts with the input) and an allocation bound.
//!
//! ```text
//! cargo bench --bench fuzz                          # everything
//! cargo bench --bench fuzz -- csv --cases 1000000   # one target
//! cargo bench --bench fuzz -- --seed 7              # another stream
//! ```
//!
//! One line per target (cases, accepted, slowest case, largest allocation,
//! time); exit code 1 on the first failure, with the shrunk input.

#[path = "../tests/suite/fuzz/targets.rs"]
#[allow(dead_code)]
mod targets;

use std::sync::Arc;
use std::time::Duration;

use targets::{Bounds, Summary};

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

const TARGETS: [&str; 5] = ["csv", "json", "yaml", "state", "layout"];

fn main() {
    let mut wanted = Vec::new();
    let mut cases: Option<u32> = None;
    let mut seed = 1u64;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--cases" => cases = args.next().and_then(|v| v.replace('_', "").parse().ok()),
            "--seed" => seed = args.next().and_then(|v| v.parse().ok()).unwrap_or(seed),
            // Passed by `cargo bench`.
            "--bench" => {}
            t if TARGETS.contains(&t) => wanted.push(t.to_string()),
            other => {
                eprintln!(
                    "fuzz: unknown argument {other:?}; targets: {TARGETS:?}, --cases N, --seed S"
                );
                std::process::exit(2);
            }
        }
    }
    if wanted.is_empty() {
        wanted = TARGETS.iter().map(|t| t.to_string()).collect();
    }
    let parser_cases = cases.unwrap_or(10_000_000);
    let layout_cases = cases.unwrap_or(10_000);
    let mut failed = false;
    for target in &wanted {
        let s = match target.as_str() {
            "csv" => targets::drive(
                "csv",
                targets::csv_cases(),
                targets::check_csv,
                parser_cases,
                seed,
                PARSER,
            ),
            "json" => targets::drive(
                "json",
                targets::json_cases(),
                targets::check_json,
                parser_cases,
                seed,
                PARSER,
            ),
            "yaml" => targets::drive(
                "yaml",
                targets::yaml_cases(),
                targets::check_yaml,
                parser_cases,
                seed,
                PARSER,
            ),
            "state" => {
                let seeds = Arc::new(targets::state_seeds());
                targets::drive(
                    "state",
                    targets::state_cases(seeds),
                    targets::check_state,
                    parser_cases,
                    seed,
                    PARSER,
                )
            }
            _ => targets::drive(
                "layout",
                targets::layout_cases(),
                targets::check_layout,
                layout_cases,
                seed,
                LAYOUT,
            ),
        };
        failed |= report(&s);
    }
    if failed {
        std::process::exit(1);
    }
}

/// Prints one target's line; true when it failed.
fn report(s: &Summary) -> bool {
    println!(
        "fuzz {:<6} {:>10} cases  {:>10} accepted  0 hangs  slowest {:>8.2} ms  largest {:>10} B  {:>8.1} s  {}",
        s.target,
        s.cases,
        s.accepted,
        s.max_case_ms,
        s.max_case_bytes,
        s.seconds,
        if s.failure.is_some() { "FAILED" } else { "0 panics" }
    );
    if let Some(failure) = &s.failure {
        println!("{failure}");
        return true;
    }
    false
}
