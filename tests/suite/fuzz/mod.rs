//! The fuzzing harness's short, deterministic slice (issue 11): every parser
//! (CSV tables through each table format, hierarchy JSON, the YAML config,
//! layout JSON state files, `.npy` vectors and an exec adapter's output, issue
//! 21) and the layout on random small datasets, a few
//! thousand cases each from fixed seeds, with no panic, no case over its time
//! bound and no case allocating past its bound. The long run (≥ 10 million
//! cases per parser) is `cargo bench --bench fuzz`; BENCHMARKS.md has its
//! figures.

mod npy_adapter;
mod targets;

use std::sync::Arc;
use std::time::Duration;

use targets::{Bounds, Run, Summary};

/// Counts allocations per thread, for the allocation bound (it forwards to
/// the system allocator, so the rest of the suite is unaffected).
#[global_allocator]
static ALLOCATOR: targets::Counting = targets::Counting;

/// Parsers: a case is a few hundred bytes and takes milliseconds, so a
/// minute is a hang even on a machine at load 8 (the watchdog aborts the
/// whole suite binary, so a tight bound loses every other test's result),
/// and 64 MiB a runaway allocation.
const PARSER: Bounds = Bounds {
    time: Duration::from_secs(60),
    bytes: 64 << 20,
};

/// The layout of at most 20 leaves (the same generous bound for a hang).
const LAYOUT: Bounds = Bounds {
    time: Duration::from_secs(120),
    bytes: 256 << 20,
};

/// Fails with the summary when the run found anything, and checks it ran
/// the cases asked for and exercised both paths (accepted and refused).
fn assert_clean(s: &Summary, cases: u64) {
    let line = format!(
        "fuzz {}: {} cases, {} accepted, slowest {:.1} ms, largest {} bytes, {:.1} s",
        s.target, s.cases, s.accepted, s.max_case_ms, s.max_case_bytes, s.seconds
    );
    eprintln!("{line}");
    if let Some(failure) = &s.failure {
        panic!("{line}\n{failure}");
    }
    assert!(s.cases >= cases, "{line}: fewer cases than asked for");
    assert!(s.max_case_bytes <= PARSER.bytes.max(LAYOUT.bytes), "{line}");
}

#[test]
fn csv_tables_never_panic() {
    let s = targets::drive(
        "csv",
        targets::csv_cases(),
        targets::check_csv,
        Run {
            cases: 3_000,
            seed: 11,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_clean(&s, 3_000);
    assert!(s.accepted > 0 && s.accepted < s.cases, "both paths: {s:?}");
}

#[test]
fn hierarchy_json_never_panics() {
    let s = targets::drive(
        "json",
        targets::json_cases(),
        targets::check_json,
        Run {
            cases: 3_000,
            seed: 12,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_clean(&s, 3_000);
    assert!(s.accepted > 0 && s.accepted < s.cases, "both paths: {s:?}");
}

#[test]
fn npy_vectors_never_panic() {
    let s = targets::drive(
        "npy",
        npy_adapter::npy_cases(),
        npy_adapter::check_npy,
        Run {
            cases: 3_000,
            seed: 16,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_clean(&s, 3_000);
    assert!(s.accepted > 0 && s.accepted < s.cases, "both paths: {s:?}");
}

#[test]
fn adapter_output_never_panics() {
    let s = targets::drive(
        "adapter",
        npy_adapter::adapter_cases(),
        npy_adapter::check_adapter,
        Run {
            cases: 3_000,
            seed: 17,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_clean(&s, 3_000);
    assert!(s.accepted > 0 && s.accepted < s.cases, "both paths: {s:?}");
}

#[test]
fn yaml_config_never_panics() {
    let s = targets::drive(
        "yaml",
        targets::yaml_cases(),
        targets::check_yaml,
        Run {
            cases: 3_000,
            seed: 13,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_clean(&s, 3_000);
    assert!(s.accepted > 0 && s.accepted < s.cases, "both paths: {s:?}");
}

#[test]
fn state_files_never_panic() {
    let seeds = Arc::new(targets::state_seeds());
    assert!(!seeds.is_empty(), "no state documents to mutate");
    let s = targets::drive(
        "state",
        targets::state_cases(seeds),
        targets::check_state,
        Run {
            cases: 3_000,
            seed: 14,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_clean(&s, 3_000);
    assert!(s.accepted > 0 && s.accepted < s.cases, "both paths: {s:?}");
}

#[test]
fn small_layouts_never_panic() {
    let s = targets::drive(
        "layout",
        targets::layout_cases(),
        targets::check_layout,
        Run {
            cases: 60,
            seed: 15,
            bounds: LAYOUT,
            replay: None,
        },
    );
    assert_clean(&s, 60);
    assert!(s.accepted > 0, "no layout succeeded: {s:?}");
}

/// The allocation counter counts: a 1 MiB vector shows as at least 1 MiB.
#[test]
fn the_allocation_bound_is_measured() {
    let (v, peak) = targets::peak_during(|| vec![1u8; 1 << 20]);
    assert_eq!(v.len(), 1 << 20);
    assert!(peak >= 1 << 20, "peak {peak}");
}

/// A replay checks exactly the case it names, after generating the ones
/// before it (so the case is the one a hang report numbered).
#[test]
fn a_replay_checks_only_the_named_case() {
    let checked = std::sync::Mutex::new(Vec::new());
    let s = targets::drive(
        "replay",
        0u32..1_000_000,
        |v| {
            checked.lock().unwrap().push(*v);
            Ok(true)
        },
        Run {
            cases: 50,
            seed: 3,
            bounds: PARSER,
            replay: Some(7),
        },
    );
    assert!(s.failure.is_none(), "{s:?}");
    let checked = checked.into_inner().unwrap();
    assert_eq!(checked.len(), 1, "checked {checked:?}");
    // The same value is the seventh of a plain run of the same seed.
    let all = std::sync::Mutex::new(Vec::new());
    targets::drive(
        "replay",
        0u32..1_000_000,
        |v| {
            all.lock().unwrap().push(*v);
            Ok(true)
        },
        Run {
            cases: 7,
            seed: 3,
            bounds: PARSER,
            replay: None,
        },
    );
    assert_eq!(all.into_inner().unwrap()[6], checked[0]);
}
