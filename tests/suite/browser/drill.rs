//! The legend and the drill-down of issue 33, in the same headless Chromium
//! as the rest of the browser test, on a map of dotted module-like ids in
//! three levels with more top-level groups than the legend shows: "and N
//! more groups" opens the full list, which a typed filter narrows and whose
//! entries highlight and zoom to their group; a click goes one level down,
//! a shift-click and a double click to the deepest group, Backspace and the
//! Up button one level up; no hover veil is left on after a zoom; no zoomed
//! label is cut where its whole text fits in its cell; and at 390 x 844 the
//! map starts within 200 px of the top.

use std::path::Path;

use serde_json::{json, Value};

use super::cdp::Browser;
use super::{file_url, page_data, press, VIEWPORT};
use crate::support;

/// Top-level groups of the map: more than the legend's first twelve.
const GROUPS: usize = 20;

/// Writes a hierarchy of `GROUPS` packages, each with three subpackages of
/// four modules (ids `pkg07.sub2.mod3`), neighbours within a subpackage,
/// and one package holding a single module with a long name; lays it out
/// into `drill.html`. Returns the page's URL and path.
pub(super) fn drill_map(dir: &Path) -> (String, std::path::PathBuf) {
    let mut top = Vec::new();
    for g in 0..GROUPS {
        let pkg = format!("pkg{g:02}");
        let subs: Vec<Value> = (0..3)
            .map(|s| {
                let sub = format!("{pkg}.sub{s}");
                let leaves: Vec<Value> = (0..4)
                    .map(|m| {
                        let id = format!("{sub}.mod{m}");
                        let next = format!("{sub}.mod{}", (m + 1) % 4);
                        json!({"id": id, "name": id, "size": 10 + (g * 7 + s * 3 + m * 5) % 17,
                               "neighbors": [next]})
                    })
                    .collect();
                json!({"id": sub, "name": sub, "children": leaves})
            })
            .collect();
        top.push(json!({"id": pkg, "name": pkg, "children": subs}));
    }
    top.push(json!({"id": "postgres", "name": "postgres", "children": [
        {"id": "postgresql-common", "name": "postgresql-common", "size": 12}
    ]}));
    let input = dir.join("drill.json");
    let doc = json!({"name": "Modules", "useNeighborLeafs": true, "weightAttribute": "size", "children": top});
    std::fs::write(&input, doc.to_string()).expect("write hierarchy");
    let html = dir.join("drill.html");
    support::layout(&input, &[&html], &["--seed", "1"]);
    (file_url(&html), html)
}

/// The view and the hover layer.
const STATE: &str = r##"(function () {
  var root = document.querySelector(".nptreemap");
  var over = root.querySelector(".np-map > svg.np-hover");
  return { zoom: root.getAttribute("data-zoom"), zoomed: root.classList.contains("np-zoomed"),
           veil: over.classList.contains("np-on") && getComputedStyle(over).visibility === "visible",
           current: root.getAttribute("data-current"),
           marks: performance.getEntriesByName("nptreemap-zoomed").length };
})()"##;

/// The centre (window pixels) of the cell of `id`'s bounding box.
fn centre_of(browser: &mut Browser, id: &str) -> (f64, f64) {
    let at = browser.eval(&format!(
        "(function (id) {{
          var el = Array.prototype.find.call(document.querySelectorAll('.np-map svg path[data-id]'),
            function (e) {{ return e.getAttribute('data-id') === id; }});
          var r = el.getBoundingClientRect();
          return [r.left + r.width / 2, r.top + r.height / 2];
        }})({})",
        json!(id)
    ));
    (at[0].as_f64().expect("x"), at[1].as_f64().expect("y"))
}

/// Waits until the view shows `zoom` (its node id) with its zoom finished
/// (a new `nptreemap-zoomed` mark after `marks`), and returns the state.
fn wait_zoom(browser: &mut Browser, zoom: &str, marks: u64) -> Value {
    browser.wait_for(&format!("the zoom to {zoom}"), STATE, |v| {
        if v["zoom"] == zoom && v["marks"].as_u64().unwrap_or(0) > marks {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    })
}

fn marks(browser: &mut Browser) -> u64 {
    browser.eval(STATE)["marks"].as_u64().unwrap_or(0)
}

/// After every zoom: no hover veil, no hovered cell (the pointer did not
/// move), and no zoom label cut where its whole text fits in its cell.
fn settled_view(browser: &mut Browser, what: &str) {
    browser.settle(150);
    let s = browser.eval(STATE);
    assert_eq!(s["veil"], false, "{what}: the hover veil is cleared: {s}");
    assert_eq!(s["current"], Value::Null, "{what}: nothing hovered: {s}");
    labels_not_cut_with_room(browser, what);
}

/// Every zoom label cut with an ellipsis belongs to a cell in which the
/// whole text, at the smallest size the page draws, does not fit on one
/// line around the cell's centre: checked with the corners of the text's
/// box against the cell's outline on screen (not with the page's own
/// fitting).
fn labels_not_cut_with_room(browser: &mut Browser, what: &str) {
    const CUT: &str = r##"(function () {
      var root = document.querySelector(".nptreemap");
      var data = JSON.parse(root.querySelector(".np-data").textContent);
      var byId = new Map(data.nodes.map(function (n) { return [n.id, n]; }));
      var min = Math.max(data.labels.min, 6);
      var ctx = document.createElement("canvas").getContext("2d");
      ctx.font = min + "px " + data.labels.font;
      var wrong = [], cut = 0, all = 0;
      root.querySelectorAll(".np-zoom-labels text[data-of]").forEach(function (t) {
        all++;
        if (!/\u2026$/.test(t.textContent)) { return; }
        cut++;
        var id = t.getAttribute("data-of"), n = byId.get(id);
        var cell = Array.prototype.find.call(root.querySelectorAll(".np-map svg path[data-id]"),
          function (e) { return e.getAttribute("data-id") === id; });
        var m = cell.getScreenCTM();
        var d = cell.getAttribute("d").match(/-?[0-9.]+/g).map(Number), p = [];
        for (var k = 0; k + 1 < d.length; k += 2) { var q = new DOMPoint(d[k], d[k + 1]).matrixTransform(m); p.push([q.x, q.y]); }
        var a = 0, cx = 0, cy = 0;
        for (var k = 0; k < p.length; k++) {
          var u = p[k], v = p[(k + 1) % p.length], c = u[0] * v[1] - v[0] * u[1];
          a += c; cx += (u[0] + v[0]) * c; cy += (u[1] + v[1]) * c;
        }
        cx /= 3 * a; cy /= 3 * a;
        // Roomier than the page asks (0.15 em on each side, 1.35 em high).
        var w = ctx.measureText(n.label || n.id).width / 2 + 0.2 * min, h = 0.7 * min;
        function inside(x, y) {
          var sign = 0;
          for (var k = 0; k < p.length; k++) {
            var u = p[k], v = p[(k + 1) % p.length];
            var s = (v[0] - u[0]) * (y - u[1]) - (v[1] - u[1]) * (x - u[0]);
            if (Math.abs(s) < 1e-9) { continue; }
            if (sign === 0) { sign = s > 0 ? 1 : -1; } else if ((s > 0 ? 1 : -1) !== sign) { return false; }
          }
          return true;
        }
        if (inside(cx - w, cy - h) && inside(cx + w, cy - h) && inside(cx - w, cy + h) && inside(cx + w, cy + h)) {
          wrong.push(id + ": " + t.textContent);
        }
      });
      return { wrong: wrong, cut: cut, all: all };
    })()"##;
    let r = browser.eval(CUT);
    assert_eq!(
        r["wrong"],
        json!([]),
        "{what}: labels cut although the whole text fits: {r}"
    );
    assert!(
        r["all"].as_u64().unwrap_or(0) > 0,
        "{what}: the zoom placed labels: {r}"
    );
}

/// Issue 33, item 3: "and N more groups" opens the list of every group;
/// typing narrows it to the groups whose name holds the text; an entry
/// highlights its group while hovered and zooms to it on a click.
pub(super) fn legend_lists_filters_and_zooms(browser: &mut Browser, url: &str, html: &Path) {
    let data = page_data(&std::fs::read_to_string(html).expect("read page"));
    let tops: Vec<String> = data["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .filter(|n| n["parent"] == 0)
        .map(|n| n["id"].as_str().expect("id").to_owned())
        .collect();
    assert_eq!(tops.len(), GROUPS + 1, "the map's top-level groups");
    browser.open(url);
    let summary = browser.eval("document.querySelector('.np-legend-more summary').textContent");
    assert!(
        summary.as_str().is_some_and(|s| s.contains("more groups")),
        "{summary}"
    );
    browser.eval("document.querySelector('.np-legend-more summary').click()");
    const LIST: &str = "(function () {
      var list = document.querySelector('.np-legend-list');
      var box = list.getBoundingClientRect();
      return { open: document.querySelector('.np-legend-more details').open,
        focused: document.activeElement === document.querySelector('.np-legend-filter'),
        scrolls: getComputedStyle(list).overflowY, height: box.height, window: innerHeight,
        shown: Array.prototype.filter.call(list.children, function (li) { return !li.hidden; })
          .map(function (li) { return li.getAttribute('data-id'); }) };
    })()";
    let opened = browser.wait_for("the full list", LIST, |v| {
        if v["open"] == true && v["focused"] == true {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    });
    let mut shown: Vec<String> = serde_json::from_value(opened["shown"].clone()).expect("ids");
    shown.sort();
    let mut want = tops.clone();
    want.sort();
    assert_eq!(shown, want, "the full list holds every group");
    assert_eq!(opened["scrolls"], "auto", "{opened}");
    assert!(
        opened["height"].as_f64() < opened["window"].as_f64(),
        "{opened}"
    );
    browser.insert_text("G07");
    let filtered = browser.wait_for("the filter", LIST, |v| {
        if v["shown"] == json!(["pkg07"]) {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    });
    assert_eq!(filtered["open"], true);
    // Hover the entry: its group is highlighted on the map.
    let at = browser.eval(
        "(function () { var li = document.querySelector('.np-legend-list li[data-id=\"pkg07\"]');
           var r = li.getBoundingClientRect(); return [r.left + 8, r.top + r.height / 2]; })()",
    );
    let (x, y) = (at[0].as_f64().expect("x"), at[1].as_f64().expect("y"));
    browser.mouse_move(x, y);
    browser.wait_for("the group's highlight", STATE, |v| {
        if v["current"] == "pkg07" && v["veil"] == true {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    });
    let before = marks(browser);
    browser.click(x, y);
    wait_zoom(browser, "pkg07", before);
    assert_eq!(
        browser.eval("document.querySelector('.np-legend-more details').open"),
        false,
        "the list closes on the zoom"
    );
    settled_view(browser, "the legend's zoom");
}

/// Issue 33, item 4: a click one level down, Backspace up; a shift-click
/// and a double click straight to the deepest group; the Up button one
/// level up; after each zoom the veil is off and the labels fit.
pub(super) fn drill_down_and_up(browser: &mut Browser, url: &str) {
    let leaf = "pkg03.sub1.mod2";
    browser.open(url);
    let (x, y) = centre_of(browser, leaf);
    let m = marks(browser);
    browser.click(x, y);
    wait_zoom(browser, "pkg03", m);
    settled_view(browser, "a click");
    let (x, y) = centre_of(browser, leaf);
    let m = marks(browser);
    browser.click(x, y);
    wait_zoom(browser, "pkg03.sub1", m);
    settled_view(browser, "a second click");
    let m = marks(browser);
    press(browser, "Backspace", "Backspace", 8);
    wait_zoom(browser, "pkg03", m);
    settled_view(browser, "Backspace");
    let up = browser.eval("!document.querySelector('.nptreemap .np-up').hidden");
    assert_eq!(up, true, "an Up button while zoomed");
    let m = marks(browser);
    browser.eval("document.querySelector('.nptreemap .np-up').click()");
    let root_id = browser
        .eval("document.querySelector('.np-crumbs button[data-id]').getAttribute('data-id')");
    let root_id = root_id.as_str().expect("root id").to_owned();
    wait_zoom(browser, &root_id, m);
    assert_eq!(
        browser.eval("document.querySelector('.nptreemap .np-up').hidden"),
        true,
        "no Up button on the whole map"
    );
    // Shift-click: from the whole map straight to the leaf's subpackage.
    let (x, y) = centre_of(browser, leaf);
    let m = marks(browser);
    browser.call(
        "Input.dispatchMouseEvent",
        json!({"type": "mouseMoved", "x": x, "y": y, "modifiers": 8}),
    );
    for kind in ["mousePressed", "mouseReleased"] {
        browser.call(
            "Input.dispatchMouseEvent",
            json!({"type": kind, "x": x, "y": y, "button": "left", "clickCount": 1, "modifiers": 8}),
        );
    }
    wait_zoom(browser, "pkg03.sub1", m);
    settled_view(browser, "a shift-click");
    // A double click from the whole map: the deepest group too.
    let m = marks(browser);
    press(browser, "Escape", "Escape", 27);
    wait_zoom(browser, "pkg03", m);
    let m = marks(browser);
    press(browser, "Escape", "Escape", 27);
    wait_zoom(browser, &root_id, m);
    let (x, y) = centre_of(browser, leaf);
    let m = marks(browser);
    browser.mouse_move(x, y);
    for count in [1, 2] {
        for kind in ["mousePressed", "mouseReleased"] {
            browser.call(
                "Input.dispatchMouseEvent",
                json!({"type": kind, "x": x, "y": y, "button": "left", "clickCount": count}),
            );
        }
    }
    wait_zoom(browser, "pkg03.sub1", m);
    settled_view(browser, "a double click");
    // The group of one module: its label whole once zoomed.
    let m = marks(browser);
    press(browser, "Backspace", "Backspace", 8);
    wait_zoom(browser, "pkg03", m);
    let m = marks(browser);
    press(browser, "Backspace", "Backspace", 8);
    wait_zoom(browser, &root_id, m);
    let (x, y) = centre_of(browser, "postgresql-common");
    let m = marks(browser);
    browser.click(x, y);
    wait_zoom(browser, "postgres", m);
    settled_view(browser, "the group of one module");
    let text = browser.eval(
        "(function () { var t = document.querySelector('.np-zoom-labels text[data-of=\"postgresql-common\"]');
           return t ? t.textContent : null; })()",
    );
    assert_eq!(text, json!("postgresql-common"), "the whole label");
}

/// Issue 33, item 5: at 390 x 844 the title and legend fold, so that the
/// map starts within 200 px of the top; the legend's button unfolds it.
pub(super) fn map_near_the_top_on_a_phone(browser: &mut Browser, url: &str) {
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": 390, "height": 844, "deviceScaleFactor": 2, "mobile": true}),
    );
    browser.open(url);
    const TOP: &str =
        "(function () { var r = document.querySelector('.np-map svg').getBoundingClientRect();
      var l = document.querySelector('.nptreemap > .np-legend').getBoundingClientRect();
      return { top: r.top, width: r.width, legend: l.height }; })()";
    let folded = browser.eval(TOP);
    let top = folded["top"].as_f64().expect("top");
    assert!(top <= 200.0, "the map starts at {top} px: {folded}");
    assert!(folded["width"].as_f64() > Some(300.0), "{folded}");
    browser.eval("document.querySelector('.np-legend-toggle').click()");
    let unfolded = browser.eval(TOP);
    assert!(
        unfolded["legend"].as_f64() > Some(0.0) && unfolded["top"].as_f64() > Some(top),
        "the legend unfolds above the map: {unfolded}"
    );
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": VIEWPORT.0, "height": VIEWPORT.1, "deviceScaleFactor": 1, "mobile": false}),
    );
}

/// Labels of path-like ids show their last segment (`render.labels.text`,
/// issue 33 item 1), so the search matches ids as well: typing a module's
/// whole dotted id lists it first (it found nothing beyond the segment
/// before).
pub(super) fn search_finds_a_whole_dotted_id(browser: &mut Browser, url: &str) {
    let target = "pkg03.sub1.mod2";
    browser.open(url);
    let label = browser.eval(&format!(
        "window.__np_label = (function () {{ var t = document.querySelector('.np-map text[data-of=\"{target}\"]'); return t ? t.textContent : ''; }})()"
    ));
    assert!(
        !label.as_str().unwrap_or("").contains("pkg03"),
        "the label shows the segment, not the whole id: {label}"
    );
    browser.eval("document.querySelector('.np-search-box').focus(); 0");
    browser.insert_text(target);
    const FIRST: &str = r##"(function () {
      var list = document.querySelector(".np-matches");
      var first = list.querySelector("[role=option]");
      return { hidden: list.hidden, first: first ? first.getAttribute("data-id") : null };
    })()"##;
    browser.wait_for("the dotted id's match", FIRST, |m| {
        if m["hidden"] == false && m["first"] == target {
            Ok(())
        } else {
            Err(format!("{m}"))
        }
    });
}
