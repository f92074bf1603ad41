//! The live page's memory stays bounded however many edits it follows
//! (issue 30 item 12): with `history: 8` and a 400-leaf map, after 24 edits
//! the page holds one map (no detached copy of an earlier one kept alive),
//! and its JavaScript heap has not grown with the edits: each history
//! layout is kept once, in the current page's own data, not once per page
//! fetched. Counted through the DevTools protocol after a garbage
//! collection: `Runtime.queryObjects` for the maps, `Runtime.getHeapUsage`
//! for the heap.
//!
//! Without Chromium the test reports itself skipped, unless
//! `NPTREEMAP_REQUIRE_BROWSER=1` makes that a failure.

use std::io::Write;
use std::time::Duration;

use serde_json::{json, Value};

use super::live::{chromium_or_skip, wait_true};
use super::{nodes_with, setup, write_nodes, Served};
use crate::browser::cdp::Browser;

/// Cap on the browser session: a bound on a hang, not a speed target.
const BUDGET: Duration = Duration::from_secs(420);

/// Leaves of the map: enough that a page weighs several hundred KB.
const LEAVES: usize = 400;

/// Edits followed: three times the history's length.
const EDITS: usize = 24;

/// Map containers (`div.nptreemap`) alive in the page, attached or not,
/// after a garbage collection.
fn maps_alive(browser: &mut Browser) -> u64 {
    browser.call("HeapProfiler.collectGarbage", json!({}));
    let proto = browser.call(
        "Runtime.evaluate",
        json!({"expression": "HTMLDivElement.prototype"}),
    );
    let proto = proto["result"]["objectId"].clone();
    let all = browser.call("Runtime.queryObjects", json!({"prototypeObjectId": proto}));
    let counted = browser.call(
        "Runtime.callFunctionOn",
        json!({
            "objectId": all["objects"]["objectId"],
            "functionDeclaration": "function () { return this.filter(function (d) { return d.classList.contains('nptreemap'); }).length; }",
            "returnByValue": true
        }),
    );
    counted["result"]["value"].as_u64().expect("a count")
}

/// The JavaScript heap in use after a garbage collection, bytes.
fn heap_used(browser: &mut Browser) -> u64 {
    browser.call("HeapProfiler.collectGarbage", json!({}));
    let usage = browser.call("Runtime.getHeapUsage", json!({}));
    usage["usedSize"].as_f64().expect("usedSize") as u64
}

fn weights(k: usize) -> Vec<f64> {
    (0..LEAVES)
        .map(|i| 10.0 + ((i * 7 + k * 13) % 17) as f64 + if i == k % LEAVES { 40.0 } else { 0.0 })
        .collect()
}

/// Waits until the page has made its `n`th live update.
fn wait_updates(browser: &mut Browser, n: usize) {
    browser.wait_for(
        &format!("live update {n}"),
        "+(document.documentElement.getAttribute('data-np-live-updates') || 0)",
        |v: &Value| match v.as_u64() {
            Some(k) if k >= n as u64 => Ok(()),
            _ => Err(format!("{v} updates")),
        },
    );
}

#[test]
fn a_live_page_keeps_one_map_and_each_layout_once_however_many_edits() {
    let Some(chromium) = chromium_or_skip("the live page's memory test") else {
        return;
    };
    let (dir, config) = setup("serve_memory");
    write_nodes(&dir, &nodes_with(&weights(0)));
    let mut served = Served::start(&config, None);
    served.expect(&["grid", "wrote"]);
    let mut browser = Browser::launch(&chromium, &dir, BUDGET);
    browser.call("Page.enable", json!({}));
    browser.call("HeapProfiler.enable", json!({}));
    // Updates swap at once: the test is about what stays, not the morph.
    browser.call(
        "Emulation.setEmulatedMedia",
        json!({"features": [{"name": "prefers-reduced-motion", "value": "reduce"}]}),
    );
    browser.open(&served.url("/out/grid.html"));
    wait_true(
        &mut browser,
        "the event stream to open",
        "document.querySelector('.np-live-status').textContent.indexOf('following grid') >= 0",
    );
    let mut heap_after = Vec::new();
    for k in 1..=EDITS {
        write_nodes(&dir, &nodes_with(&weights(k)));
        wait_updates(&mut browser, k);
        if k == 9 || k == EDITS {
            heap_after.push((k, heap_used(&mut browser)));
        }
    }
    let page = std::fs::metadata(dir.join("out/grid.html"))
        .expect("page")
        .len();
    let maps = maps_alive(&mut browser);
    let _ = writeln!(
        std::io::stderr(),
        "page {page} bytes; heap after edits {heap_after:?}; maps alive {maps}"
    );
    assert_eq!(maps, 1, "maps kept alive after {EDITS} edits");
    let (first, last) = (heap_after[0].1, heap_after[1].1);
    assert!(
        last < first + page,
        "the heap grew from {first} to {last} bytes between edits 9 and {EDITS} (a page is {page} bytes)"
    );
    assert!(
        last < 12 * page + (16 << 20),
        "the heap holds {last} bytes after {EDITS} edits (a page is {page} bytes)"
    );
}
