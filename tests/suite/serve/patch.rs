//! The live preview's patch on a big map (issue 32): `watch --serve` on a
//! hierarchy of 20,000 leaves; one leaf's weight is edited; the page asks
//! for what changed and patches itself in place: no reload and no fetch of
//! the whole page, only the cells the patch names change in the document
//! (counted by a MutationObserver, against the cells whose outline or fill
//! differs between the two pages on disk), and afterwards every cell's
//! outline and fill are the new page's. A second edit makes the last group
//! the heaviest: the legend (by weight) comes whole in the patch, and its
//! entries answer. A patch the map refuses loads the whole page, and the
//! next edit patches again. A page opened after the edits gets the whole
//! current page. Without Chromium the test reports itself
//! skipped, unless `NPTREEMAP_REQUIRE_BROWSER=1`.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

use serde_json::{json, Value};

use super::live::chromium_or_skip;
use super::Served;
use crate::browser::cdp::Browser;
use crate::support;

/// Leaves of the map: the size the issue asks the patch to handle.
const LEAVES: usize = 20_000;
/// Top-level groups, and groups under each.
const GROUPS: usize = 20;
const SUBGROUPS: usize = 10;

const BUDGET: Duration = Duration::from_secs(600);

const CONFIG: &str = "layout: {method: plain}
render: {labels: {show: false}}
datasets:
  - name: big
    format: hierarchy-json
    files: {hierarchy: data/tree.json}
    outputs: [out/big.html]
";

/// The tree with the first leaf's weight `first` and the last one's
/// `last` (the others fixed, uneven).
fn tree(first: f64, last: f64) -> String {
    let mut groups = Vec::new();
    let per = LEAVES / (GROUPS * SUBGROUPS);
    for g in 0..GROUPS {
        let mut subs = Vec::new();
        for s in 0..SUBGROUPS {
            let leaves: Vec<Value> = (0..per)
                .map(|k| {
                    let i = (g * SUBGROUPS + s) * per + k;
                    let w = match i {
                        0 => first,
                        i if i == LEAVES - 1 => last,
                        i => 1.0 + (i * 37 % 101) as f64,
                    };
                    json!({"id": format!("n{i}"), "value": w})
                })
                .collect();
            subs.push(json!({"id": format!("g{g}s{s}"), "children": leaves}));
        }
        groups.push(json!({"id": format!("g{g}"), "children": subs}));
    }
    json!({"id": "root", "children": groups}).to_string()
}

fn write_tree(dir: &Path, first: f64, last: f64) {
    let tmp = dir.join("data/.tree.json.tmp");
    std::fs::write(&tmp, tree(first, last)).expect("write tree");
    std::fs::rename(&tmp, dir.join("data/tree.json")).expect("rename tree");
}

/// Writes the tree with `first` and `last`, waits for the daemon to write
/// the page and then for the page to reach `state` (a JS condition on
/// `npLive`, the live script's counters) with its animations ended; the
/// page's cells on disk then.
fn edit(
    served: &mut Served,
    browser: &mut Browser,
    dir: &Path,
    (first, last): (f64, f64),
    state: &str,
) -> BTreeMap<String, (String, String)> {
    write_tree(dir, first, last);
    served.expect(&["big: data", "wrote"]);
    super::live::wait_true(
        browser,
        state,
        &format!("{state} && npLive.animating === 0"),
    );
    cells_on_disk(&std::fs::read_to_string(dir.join("out/big.html")).expect("page"))
}

/// Every cell of a page's picture as written: id to (path data, fill).
fn cells_on_disk(page: &str) -> BTreeMap<String, (String, String)> {
    let attr = |line: &str, name: &str| -> String {
        let key = format!(" {name}=\"");
        let at = line.find(&key).expect("attribute") + key.len();
        line[at..at + line[at..].find('"').expect("quote")].to_owned()
    };
    let map = &page[page.find("class=\"np-map\"").expect("map")..];
    map.lines()
        .take_while(|l| !l.starts_with("</svg>"))
        .filter(|l| l.starts_with("<path data-id=\""))
        .map(|l| (attr(l, "data-id"), (attr(l, "d"), attr(l, "fill"))))
        .collect()
}

/// Every cell of the page shown: id to [path data, fill].
const CELLS: &str = "(function () {
  var s = document.querySelector('.nptreemap .np-map > svg:not(.np-hover)'), o = {};
  s.querySelectorAll('path[data-id]').forEach(function (p) { o[p.getAttribute('data-id')] = [p.getAttribute('d'), p.getAttribute('fill')]; });
  return o;
})()";

/// Records the ids of the cells whose outline or fill the document changes.
const WATCH_CELLS: &str = "window.__touched = new Set();
new MutationObserver(function (rs) {
  rs.forEach(function (r) { var id = r.target.getAttribute && r.target.getAttribute('data-id'); if (id !== null) { __touched.add(id); } });
}).observe(document.querySelector('.nptreemap .np-map > svg:not(.np-hover)'),
  { attributes: true, subtree: true, attributeFilter: ['d', 'fill'] });
true";

fn shown(browser: &mut Browser) -> BTreeMap<String, (String, String)> {
    let v: BTreeMap<String, Vec<String>> =
        serde_json::from_value(browser.eval(CELLS)).expect("cells");
    v.into_iter()
        .map(|(k, mut v)| {
            let fill = v.pop().expect("fill");
            (k, (v.pop().expect("d"), fill))
        })
        .collect()
}

#[test]
fn a_big_map_patches_only_the_changed_cells() {
    let Some(chromium) = chromium_or_skip("the live preview's patch test") else {
        return;
    };
    let dir = support::temp_dir("serve_patch");
    std::fs::create_dir_all(dir.join("data")).expect("data dir");
    write_tree(&dir, 50.0, 60.0);
    let config = dir.join("nptreemap.yaml");
    std::fs::write(&config, CONFIG).expect("config");
    let mut served = Served::start(&config, None);
    served.expect(&["big", "wrote"]);
    let page = dir.join("out/big.html");
    let before = cells_on_disk(&std::fs::read_to_string(&page).expect("page"));
    assert_eq!(
        before.values().filter(|c| c.1 != "none").count(),
        LEAVES,
        "every leaf is drawn"
    );

    let mut browser = Browser::launch(&chromium, &dir, BUDGET);
    browser.call("Page.enable", json!({}));
    browser.open(&served.url("/out/big.html"));
    super::live::wait_true(
        &mut browser,
        "the event stream to open",
        "document.querySelector('.np-live-status').textContent === 'live: following big'",
    );
    let origin = browser.eval("performance.timeOrigin");
    assert_eq!(browser.eval(WATCH_CELLS), json!(true));

    // One leaf's weight, +10%: a small change the layout settles locally.
    let after = edit(
        &mut served,
        &mut browser,
        &dir,
        (55.0, 60.0),
        "npLive.patches === 1",
    );
    let changed: Vec<&String> = after
        .iter()
        .filter(|(id, c)| before.get(*id) != Some(c))
        .map(|(id, _)| id)
        .collect();
    assert!(!changed.is_empty(), "the edit changed cells");
    assert!(
        changed.len() < LEAVES / 2,
        "a local edit: {} cells changed",
        changed.len()
    );
    assert_eq!(
        browser.eval("npLive.loads"),
        json!(0),
        "no whole page fetched"
    );
    assert_eq!(browser.eval("performance.timeOrigin"), origin, "no reload");
    assert_eq!(browser.eval("npLive.patched"), json!(changed.len()));
    let touched: Vec<String> =
        serde_json::from_value(browser.eval("Array.from(__touched).sort()")).expect("touched");
    let mut want: Vec<String> = changed.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(touched, want, "only the changed cells were touched");
    assert!(
        shown(&mut browser) == after,
        "the page shows the new page's cells"
    );
    // The map's own script read the new weight (its tooltip's source).
    let weight = browser.eval(
        "JSON.parse(document.querySelector('.nptreemap .np-data').textContent).nodes
           .filter(function (n) { return n.id === 'n0'; })[0].weight",
    );
    assert_eq!(weight, json!("55"));

    // An edit that makes the last group the heaviest: the legend, by
    // weight, lists it first; the page still patches (the legend whole).
    let first_entry =
        "document.querySelector('.nptreemap .np-legend li[data-id]').getAttribute('data-id')";
    let heavy = format!("g{}", GROUPS - 1);
    assert_ne!(browser.eval(first_entry), json!(heavy));
    let now = edit(
        &mut served,
        &mut browser,
        &dir,
        (55.0, 5_000.0),
        "npLive.patches === 2",
    );
    assert_eq!(
        browser.eval("npLive.loads"),
        json!(0),
        "no whole page fetched"
    );
    assert_eq!(
        browser.eval(first_entry),
        json!(heavy),
        "the legend reordered"
    );
    assert!(
        shown(&mut browser) == now,
        "the page shows the newest page's cells"
    );
    // The new legend answers as the old did: an entry lights its group.
    browser.eval(
        "document.querySelector('.nptreemap .np-legend li[data-id]').dispatchEvent(new FocusEvent('focusin', { bubbles: true }))",
    );
    super::live::wait_true(
        &mut browser,
        "the legend to light its group",
        "document.querySelectorAll('.nptreemap .np-hover .np-near').length > 0",
    );

    // A patch the map cannot take (forced here) loads the whole page, and
    // the edit after it patches again, from the page loaded.
    browser
        .eval("document.querySelector('.nptreemap').npPatch.check = function () { return null; }");
    edit(
        &mut served,
        &mut browser,
        &dir,
        (60.0, 5_000.0),
        "npLive.loads === 1 && npLive.updates === 3",
    );
    let now = edit(
        &mut served,
        &mut browser,
        &dir,
        (66.0, 5_000.0),
        "npLive.patches === 3 && npLive.updates === 4",
    );
    assert_eq!(browser.eval("npLive.loads"), json!(1));
    assert!(
        shown(&mut browser) == now,
        "the page shows the newest page's cells"
    );

    // A page opened now gets the whole current page (another URL of it,
    // so that the navigation is not mistaken for the page already open).
    browser.open(&served.url("/out/big.html?opened=later"));
    assert!(shown(&mut browser) == now, "a new page is the current one");
    drop(browser);
    served.terminate();
}
