//! The three-zoom reach of issue 24 (item 1): on a map big enough that most
//! leaves have no label on the whole map, a reader reaches any leaf's label
//! in at most three zooms, each a click on the leaf's cell or Enter on it,
//! each zooming towards the leaf (to one of its groups, or to the leaf
//! itself).

use std::path::Path;

use serde_json::{json, Value};

use super::cdp::Browser;
use super::explore::{labelled_as, point_of, unlabelled_leaves};
use super::{file_url, page_data, press, PageModel};
use crate::support;

/// Leaves sampled, spread over the page's order (so over its groups).
const SAMPLE: usize = 8;
/// The zooms a reader may need.
const MOST: usize = 3;

/// A generated map of 3,000 leaves in three levels (fan-outs of about 15):
/// on the whole map nine leaves in ten have no label.
pub(super) fn deep_map(dir: &Path) -> std::path::PathBuf {
    let input = support::generate(dir, 3000, 3, 3);
    let html = dir.join("deep.html");
    support::layout(&input, &[&html], &["--seed", "1"]);
    html
}

/// Leaf `id`'s label as it shows: the view's zoom, the zoom marks so far,
/// the text of the leaf's zoom label when it is drawn inside the window
/// (null otherwise), and whether the picture's own label for it shows.
const SHOWN: &str = r##"(function (id) {
  var root = document.querySelector(".nptreemap");
  function visible(t) {
    var r = t.getBoundingClientRect();
    return r.width > 0 && r.height > 0 && r.right > 0 && r.bottom > 0 && r.left < innerWidth && r.top < innerHeight;
  }
  var zoomLabel = Array.prototype.find.call(root.querySelectorAll(".np-zoom-labels text[data-of]"),
    function (t) { return t.getAttribute("data-of") === id && visible(t); });
  var data = JSON.parse(root.querySelector(".np-data").textContent);
  var at = data.nodes.findIndex(function (n) { return n.id === id; });
  var placed = ((data.labels && data.labels.placed) || []).indexOf(at);
  var texts = root.querySelectorAll(".np-map > svg > .np-labels:not(.np-zoom-labels) text");
  var picture = placed >= 0 && texts[placed] && visible(texts[placed]) ? texts[placed].textContent : null;
  return { zoom: root.getAttribute("data-zoom"), zoomed: root.classList.contains("np-zoomed"),
           marks: performance.getEntriesByName("nptreemap-zoomed").length,
           label: zoomLabel ? zoomLabel.textContent : null, picture: picture };
})"##;

/// Issue 24, item 1: for a sample of leaves without a label on the whole
/// map, each shows its label (its name or a cut of it with at least four
/// characters) after at most three zooms on its cell, clicks for half of
/// them and Enter on the focused cell for the others; every zoom goes to one
/// of the leaf's groups or to the leaf itself.
pub(super) fn every_leaf_label_within_three_zooms(browser: &mut Browser, html: &Path) {
    let data = page_data(&std::fs::read_to_string(html).expect("read page"));
    let model = PageModel::new(&data);
    let leaves = model.leaves().count();
    let candidates = unlabelled_leaves(html);
    assert!(
        candidates.len() * 2 > leaves,
        "the map is big enough that most of its {leaves} leaves have no label on the whole map; {} do",
        leaves - candidates.len()
    );
    let step = candidates.len() / SAMPLE;
    let url = file_url(html);
    for (k, id) in candidates.iter().step_by(step).take(SAMPLE).enumerate() {
        let by_key = k % 2 == 1;
        let ancestors = model.ancestors(id);
        let name = model.label(id);
        browser.open("about:blank");
        browser.open(&url);
        let mut state = browser.eval(&format!("{SHOWN}({})", json!(id)));
        assert!(
            state["label"].is_null() && state["picture"].is_null() && state["zoomed"] == false,
            "{id} has no label on the whole map: {state}"
        );
        let mut zooms = 0;
        while state["label"].is_null() {
            assert!(
                zooms < MOST,
                "{id} ({name:?}, under {ancestors:?}): no label after {MOST} zooms by {}: {state}",
                if by_key { "Enter" } else { "click" }
            );
            let marks = state["marks"].as_u64().expect("marks");
            zoom_on(browser, id, by_key);
            zooms += 1;
            state = browser.wait_for(
                &format!("zoom {zooms} towards {id}"),
                &format!("{SHOWN}({})", json!(id)),
                |v| {
                    if v["marks"].as_u64().is_some_and(|m| m > marks) {
                        Ok(())
                    } else {
                        Err(format!("no new zoom yet: {v}"))
                    }
                },
            );
            let zoom = state["zoom"].as_str().unwrap_or("");
            assert!(
                zoom == id || ancestors.contains(&zoom),
                "zoom {zooms} on {id} went to {zoom:?}, not one of {ancestors:?} or the leaf"
            );
            // The pointer leaves the map, so the next check sees the
            // labels of the view, not a hover's copies.
            browser.mouse_move(1.0, 1.0);
        }
        let text = state["label"].as_str().unwrap_or("");
        assert!(
            labelled_as(text, name),
            "{id} is labelled {text:?} after {zooms} zooms, not {name:?}"
        );
    }
}

/// One zoom on leaf `id`: a click on its cell, or Enter with the cell focused.
fn zoom_on(browser: &mut Browser, id: &str, by_key: bool) {
    if by_key {
        let focused = browser.eval(&format!(
            r##"(function (id) {{
              var el = Array.prototype.find.call(document.querySelectorAll(".np-map svg path[data-id]"),
                function (e) {{ return e.getAttribute("data-id") === id; }});
              if (!el) {{ return false; }}
              el.focus();
              return document.activeElement === el;
            }})({})"##,
            json!(id)
        ));
        assert_eq!(focused, Value::Bool(true), "{id}'s cell takes the focus");
        press(browser, "Enter", "Enter", 13);
    } else {
        let (x, y) = point_of(browser, id);
        browser.click(x, y);
    }
}
