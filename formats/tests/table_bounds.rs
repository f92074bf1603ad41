//! CSV reading within bounds (issue 21, item 6): repeated header names are
//! found in about linear time (100,000 names took 16 s, 1,000,000 ran past
//! two minutes), a row far wider than the header is refused at its first
//! extra field without being kept (100 million commas took 3.5 GB), and a
//! flood of one kind of warning is summarised (a million repeated pairs gave
//! 378,713 warning lines). Allocation figures come from a counting allocator
//! with per-thread figures, so tests running side by side do not disturb them.

// InputError is the agreed plain struct; test helpers return it as the API does.
#![allow(clippy::result_large_err)]

use std::cell::Cell;
use std::sync::mpsc;
use std::time::Duration;

use nptreemap_formats::table::{read_rows, read_table};
use nptreemap_formats::{BorderList, EmbeddingMatrix, Format, FormatOptions, Inputs};

thread_local! {
    static CURRENT: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
}

/// Counts this thread's live bytes and their peak (forwarding to the system
/// allocator).
struct Counting;

// SAFETY: every call is forwarded to the system allocator unchanged; the
// counters are const-initialised thread-local cells without destructors.
unsafe impl std::alloc::GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let p = unsafe { std::alloc::System.alloc(layout) };
        if !p.is_null() {
            let _ = CURRENT.try_with(|c| {
                let now = c.get().saturating_add(layout.size());
                c.set(now);
                let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
            });
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) };
        let _ = CURRENT.try_with(|c| c.set(c.get().saturating_sub(layout.size())));
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// `f`'s result and the peak of this thread's allocations above their level
/// at the start.
fn peak_during<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let base = CURRENT.with(Cell::get);
    PEAK.with(|p| p.set(base));
    let r = f();
    (r, PEAK.with(Cell::get).saturating_sub(base))
}

/// Runs `f` on its own thread and waits for it at most `bound` (generous: a
/// bound on a hang, not a measure of speed).
fn within<R: Send + 'static>(bound: Duration, f: impl FnOnce() -> R + Send + 'static) -> R {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(f());
    });
    receive
        .recv_timeout(bound)
        .unwrap_or_else(|_| panic!("no result within {bound:?}"))
}

#[test]
fn repeated_header_names_are_found_in_about_linear_time() {
    // A million distinct names (7.9 MB), then two that repeat earlier ones
    // (names match ASCII case-insensitively). Comparing every name with every
    // earlier one ran past two minutes; linear work takes about a second.
    let mut header: Vec<String> = (0..1_000_000).map(|i| format!("c{i}")).collect();
    header.push("C17".to_owned());
    header.push("c999999".to_owned());
    let text = header.join(",") + "\n";
    let table = within(Duration::from_secs(120), move || {
        read_table(text.as_bytes(), None).expect("a header without rows")
    });
    let messages: Vec<String> = table.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        messages,
        [
            "line 1: column 1000001 repeats the name \"C17\" of column 18; only column 18 is read",
            "line 1: column 1000002 repeats the name \"c999999\" of column 1000000; only column \
             1000000 is read",
        ]
    );
}

#[test]
fn a_row_far_wider_than_the_header_is_refused_without_keeping_it() {
    // Two million commas on line 3: kept as fields they cost ~64 MB; the
    // reader stops keeping fields at the first one past the header's two.
    let mut text = b"id,weight\na,1\nb,1".to_vec();
    text.extend(std::iter::repeat_n(b',', 2_000_000));
    text.push(b'\n');
    let (result, peak) = peak_during(|| read_table(&text, None));
    let error = result.expect_err("too wide");
    assert_eq!(error.line(), Some(3));
    let message = error.to_string();
    assert!(
        message.contains("wrong number of fields: found 2000002, the header (line 1) has 2"),
        "{message}"
    );
    assert!(peak < 1 << 20, "peak {peak} bytes for a 2 MB row");
}

#[test]
fn a_vector_row_wider_than_max_dimensions_is_refused_without_keeping_it() {
    // Vectors have no header to compare with: their bound is the dimension
    // limit (plus the id).
    let nodes = b"id,weight\na,1\nb,1\n";
    let mut vectors = b"a,1,2\nb,1".to_vec();
    vectors.extend(std::iter::repeat_n(b',', 2_000_000));
    vectors.push(b'\n');
    let inputs = Inputs::new().with("nodes", nodes).with("vectors", &vectors);
    let options = FormatOptions::default();
    let (result, peak) = peak_during(|| EmbeddingMatrix.parse(&inputs, &options));
    let error = result.expect_err("too wide");
    assert_eq!(
        (error.role.as_str(), error.error.line()),
        ("vectors", Some(2))
    );
    let message = error.to_string();
    assert!(
        message.contains("more than 1024 values") && message.contains("`limits.max_dimensions`"),
        "{message}"
    );
    assert!(peak < 1 << 20, "peak {peak} bytes for a 2 MB row");
    // Rows without a header (`read_rows`) keep their own lengths.
    let rows = read_rows(b"a,1\nb,1,2,3\n", None).expect("ragged rows");
    assert_eq!(rows[1].fields.len(), 4);
}

#[test]
fn a_flood_of_one_warning_is_summarised() {
    // 100,000 repeats of a pair with another strength: the first few are
    // kept with their lines, the rest counted in one line.
    let nodes = b"id,weight\na,1\nb,1\nc,1\n";
    let mut pairs = String::from("a,b,strength\na,b,1\nc,c,1\n");
    for _ in 0..100_000 {
        pairs.push_str("b,a,2\n");
    }
    pairs.push_str("c,c,1\n");
    let inputs = Inputs::new()
        .with("nodes", nodes)
        .with("pairs", pairs.as_bytes());
    let dataset = BorderList
        .parse(&inputs, &FormatOptions::default())
        .expect("valid");
    let lines: Vec<String> = dataset
        .warnings()
        .iter()
        .map(|w| format!("{}: {w}", w.role))
        .collect();
    let repeat = |line: usize| {
        format!(
            "pairs: line {line}: the pair (b, a) repeats line 2 with another strength (1 there, \
             2 here); strengths only say whether two nodes are related"
        )
    };
    let itself = |line: usize| {
        format!("pairs: line {line}: the pair (c, c) joins a node to itself; it is ignored")
    };
    assert_eq!(
        lines,
        [
            itself(3),
            repeat(4),
            repeat(5),
            repeat(6),
            repeat(7),
            repeat(8),
            itself(100_004),
            "pairs: and 99995 more pairs repeated with another strength (the first 5 are listed)"
                .to_owned(),
        ]
    );
}
