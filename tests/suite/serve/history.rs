//! The page a `watch` session writes, opened from disk with no server
//! (issue 25 item 4): after two weight edits it carries the two earlier
//! layouts; ◀ morphs the picture to the previous layout (its cells exactly
//! the earlier page's: path data and fills), ◀ again to the first, ▶ back
//! to the latest; with `prefers-reduced-motion` stepping requests no
//! animation frame; no security-policy violation or script error. A
//! screenshot midway through a step back and one after it are left in the
//! test's folder (`history-*.png`) to look at.
//!
//! Without Chromium the test reports itself skipped, unless
//! `NPTREEMAP_REQUIRE_BROWSER=1` makes that a failure.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde_json::{json, Value};

use super::live::{chromium_or_skip, screenshot, wait_true, PROBE};
use super::{nodes_with, setup, weights, write_nodes, Served};
use crate::browser::cdp::Browser;

/// Cap on the browser session: a bound on a hang, not a speed target.
const BUDGET: Duration = Duration::from_secs(300);

/// Every cell of the picture: id to [path data, fill], the history layer's
/// cells included, cells faded out left out.
const SHOWN: &str = "(function () {
  var s = document.querySelector('.nptreemap .np-map > svg:not(.np-hover)'), o = {};
  s.querySelectorAll('path[data-id], path[data-past-id]').forEach(function (p) {
    if (p.style.opacity === '0') { return; }
    o[p.getAttribute('data-id') || p.getAttribute('data-past-id')] = [p.getAttribute('d'), p.getAttribute('fill')];
  });
  return o;
})()";

fn shown(browser: &mut Browser) -> BTreeMap<String, (String, String)> {
    serde_json::from_value(browser.eval(SHOWN)).expect("cells")
}

fn file_url(path: &Path) -> String {
    format!("file://{}", path.display())
}

/// Clicks ◀ or ▶ and waits for step `n` (counted from the page's start) to
/// have ended.
fn step(browser: &mut Browser, button: &str, n: u64) {
    browser.eval(&format!(
        "document.querySelector('.np-history-{button}').click()"
    ));
    wait_true(
        browser,
        &format!("step {n} to end"),
        &format!("window.npHistory.count >= {n} && window.npHistory.animating === 0"),
    );
}

/// Waits for the session's next status line that rewrote the page, then
/// copies the page aside as `page{n}.html`.
fn next_page(served: &mut Served, dir: &Path, n: usize) -> PathBuf {
    served.expect(&["grid", "wrote", "grid.html"]);
    let copy = dir.join(format!("page{n}.html"));
    std::fs::copy(dir.join("out/grid.html"), &copy).expect("copy the page");
    copy
}

#[test]
fn a_watch_page_on_disk_steps_through_its_last_layouts() {
    let Some(chromium) = chromium_or_skip("the page history's browser test") else {
        return;
    };
    let (dir, config) = setup("serve_history");
    let mut served = Served::start(&config, None);
    let pages = {
        let first = next_page(&mut served, &dir, 0);
        let mut w = weights();
        w[1] *= 5.0;
        write_nodes(&dir, &nodes_with(&w));
        let second = next_page(&mut served, &dir, 1);
        w[6] *= 4.0;
        write_nodes(&dir, &nodes_with(&w));
        let third = next_page(&mut served, &dir, 2);
        [first, second, third]
    };
    served.terminate();
    let text = std::fs::read_to_string(&pages[2]).expect("page");
    assert!(text.contains("layout 3 of 3 (latest)"), "three layouts");
    assert!(!text.contains("/_np/"), "the page on disk needs no server");

    let mut browser = Browser::launch(&chromium, &dir, BUDGET);
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": 900, "height": 900, "deviceScaleFactor": 1, "mobile": false}),
    );
    browser.call("Page.enable", json!({}));
    browser.call("Runtime.enable", json!({}));
    browser.call(
        "Page.addScriptToEvaluateOnNewDocument",
        json!({ "source": PROBE }),
    );

    // What each page draws, as written.
    let mut drawn = Vec::new();
    for page in &pages {
        browser.open(&file_url(page));
        wait_true(
            &mut browser,
            "the page to start",
            "!!window.performance.getEntriesByName('nptreemap-ready').length",
        );
        drawn.push(shown(&mut browser));
    }
    assert_ne!(drawn[1], drawn[2], "the second edit moved cells");
    assert_ne!(drawn[0], drawn[1], "the first edit moved cells");

    // The latest page steps back, back again, and ahead.
    browser.open(&file_url(&pages[2]));
    wait_true(&mut browser, "the steps", "!!window.npHistory");
    browser.eval("window.npHistory.slow = 8");
    browser.eval("document.querySelector('.np-history-back').click()");
    std::thread::sleep(Duration::from_millis(1200));
    screenshot(&mut browser, &dir.join("history-1-midway.png"));
    wait_true(
        &mut browser,
        "step 1 to end",
        "window.npHistory.count >= 1 && window.npHistory.animating === 0",
    );
    browser.eval("window.npHistory.slow = 1");
    screenshot(&mut browser, &dir.join("history-2-back.png"));
    assert_eq!(
        shown(&mut browser),
        drawn[1],
        "back: the previous layout's cells"
    );
    assert!(
        browser
            .eval("window.npHistory.frames")
            .as_u64()
            .unwrap_or(0)
            > 0,
        "it morphed"
    );
    let label = browser.eval("document.querySelector('.np-history-label').textContent");
    assert!(
        label.as_str().is_some_and(|t| t.contains("layout 2 of 3")),
        "{label}"
    );
    step(&mut browser, "back", 2);
    assert_eq!(
        shown(&mut browser),
        drawn[0],
        "back again: the first layout's cells"
    );
    assert_eq!(
        browser.eval("document.querySelector('.np-history-back').disabled"),
        Value::Bool(true)
    );
    step(&mut browser, "ahead", 3);
    step(&mut browser, "ahead", 4);
    assert_eq!(shown(&mut browser), drawn[2], "ahead: the latest again");
    assert_eq!(
        browser.eval("document.querySelector('.np-history-ahead').disabled"),
        Value::Bool(true)
    );
    screenshot(&mut browser, &dir.join("history-3-latest.png"));

    // With reduced motion: the same steps, no animation frame.
    browser.call(
        "Emulation.setEmulatedMedia",
        json!({"features": [{"name": "prefers-reduced-motion", "value": "reduce"}]}),
    );
    browser.open(&file_url(&pages[2]));
    wait_true(&mut browser, "the steps", "!!window.npHistory");
    wait_true(
        &mut browser,
        "the page to be ready",
        "!!window.performance.getEntriesByName('nptreemap-ready').length",
    );
    let raf = browser.eval("window.__raf").as_u64().unwrap_or(0);
    step(&mut browser, "back", 1);
    assert_eq!(
        shown(&mut browser),
        drawn[1],
        "reduced motion: back at once"
    );
    assert_eq!(browser.eval("window.npHistory.frames").as_u64(), Some(0));
    assert_eq!(
        browser.eval("window.__raf").as_u64(),
        Some(raf),
        "no animation frame"
    );

    let csp = browser.eval("JSON.stringify(window.__csp)");
    assert_eq!(csp, Value::String("[]".into()), "no policy violation");
    let errors = browser.events("Runtime.exceptionThrown");
    assert!(errors.is_empty(), "script errors: {errors:?}");
}
