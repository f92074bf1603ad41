//! The interactive HTML page in a real browser: builds pages from the paper's
//! data, opens them in headless Chromium driven over the DevTools protocol, and
//! checks with real mouse events that hovering a leaf greys the non-neighbours,
//! outlines the constraint partners and shows the path-and-weight tooltip, that
//! leaving clears it, that the checkbox shows the unrealised links, and that
//! the page loads nothing from the network and logs no error.
//!
//! Without Chromium the test reports itself skipped, unless
//! `NPTREEMAP_REQUIRE_BROWSER=1` (set by CI) makes that a failure.

mod cdp;

use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::Path;
use std::time::Duration;

use serde_json::{json, Value};

use crate::support;
use cdp::Browser;

/// Cap on the whole browser session, startup included.
const BUDGET: Duration = Duration::from_secs(30);

/// Viewport size: the 1000-unit map plus the checkbox row fits without scrolling.
const VIEWPORT: (u32, u32) = (1100, 1100);

/// What the test expects of one page, taken from the layout JSON written in the
/// same run (path, weight, polygon, constraints) and the page's node data
/// (which cells are leaves, and their neighbours).
struct Page {
    url: String,
    /// Every leaf cell's id.
    leaves: BTreeSet<String>,
    /// The leaf the mouse hovers.
    target: String,
    /// Its labels from the root.
    path: Vec<String>,
    weight: f64,
    polygon: Vec<[f64; 2]>,
    neighbors: BTreeSet<String>,
    /// Constraint partners, each with whether the constraint is realised.
    partners: BTreeMap<String, bool>,
}

impl Page {
    /// Lays out `shared/paper-data/<name>.json` (see [`Page::build_from`]).
    fn build(dir: &Path, name: &str, extra: &[&str]) -> Page {
        let input = support::shared().join(format!("paper-data/{name}.json"));
        Page::build_from(dir, &input, name, extra, None)
    }

    /// Lays out `input` into `<name>.html` and `<name>.json` under `dir`, and
    /// hovers `target`, or else the first leaf (in file order) that has
    /// neighbours and partners, preferring one with an unrealised partner.
    fn build_from(
        dir: &Path,
        input: &Path,
        name: &str,
        extra: &[&str],
        target: Option<&str>,
    ) -> Page {
        let html = dir.join(format!("{name}.html"));
        let json = dir.join(format!("{name}.json"));
        support::layout(input, &[&html, &json], extra);
        let data = page_data(&std::fs::read_to_string(&html).expect("read page"));
        let layout: Value =
            serde_json::from_slice(&std::fs::read(&json).expect("read layout")).expect("JSON");

        let page_nodes: BTreeMap<&str, &Value> = data["nodes"]
            .as_array()
            .expect("page nodes")
            .iter()
            .map(|n| (n["id"].as_str().expect("id"), n))
            .collect();
        let leaves: BTreeSet<String> = page_nodes
            .iter()
            .filter(|(_, n)| n["leaf"] == true)
            .map(|(id, _)| (*id).to_owned())
            .collect();
        let nodes = layout["nodes"].as_array().expect("layout nodes");
        let by_id: BTreeMap<&str, &Value> = nodes
            .iter()
            .map(|n| (n["id"].as_str().expect("id"), n))
            .collect();
        let partners_of = |id: &str| -> BTreeMap<String, bool> {
            let mut partners = BTreeMap::new();
            for c in layout["constraints"].as_array().expect("constraints") {
                let (a, b) = (c["a"].as_str().expect("a"), c["b"].as_str().expect("b"));
                let realized = c["realized"].as_bool().expect("realized");
                if a == id {
                    partners.insert(b.to_owned(), realized);
                } else if b == id {
                    partners.insert(a.to_owned(), realized);
                }
            }
            partners
        };
        let neighbors_of = |id: &str| -> BTreeSet<String> {
            page_nodes[id]["neighbours"]
                .as_array()
                .expect("neighbours")
                .iter()
                .map(|v| v.as_str().expect("neighbour id").to_owned())
                .collect()
        };
        let candidates: Vec<&str> = nodes
            .iter()
            .map(|n| n["id"].as_str().expect("id"))
            .filter(|id| leaves.contains(*id) && by_id[id]["virtual"] != true)
            .filter(|id| !neighbors_of(id).is_empty() && !partners_of(id).is_empty())
            .collect();
        let target = match target {
            Some(id) => id.to_owned(),
            None => candidates
                .iter()
                .find(|id| partners_of(id).values().any(|r| !r))
                .or(candidates.first())
                .unwrap_or_else(|| panic!("{name}: no leaf with neighbours and partners"))
                .to_string(),
        };

        let mut path = Vec::new();
        let mut at = by_id[target.as_str()];
        loop {
            path.push(at["label"].as_str().expect("label").to_owned());
            match at["parent"].as_str() {
                Some(parent) => at = by_id[parent],
                None => break,
            }
        }
        path.reverse();
        let node = by_id[target.as_str()];
        Page {
            url: file_url(&html),
            path,
            weight: node["weight"].as_f64().expect("weight"),
            polygon: node["polygon"]
                .as_array()
                .expect("polygon")
                .iter()
                .map(|p| [p[0].as_f64().expect("x"), p[1].as_f64().expect("y")])
                .collect(),
            neighbors: neighbors_of(&target),
            partners: partners_of(&target),
            leaves,
            target,
        }
    }

    /// Points of the target cell in layout (= SVG user) units, best first: its
    /// centroid, then points between it and each corner. Cells are convex, so
    /// all lie inside; the page picks the first no overlay covers.
    fn hover_candidates(&self) -> Vec<[f64; 2]> {
        let n = self.polygon.len();
        let (mut area, mut cx, mut cy) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let ([x0, y0], [x1, y1]) = (self.polygon[i], self.polygon[(i + 1) % n]);
            let cross = x0 * y1 - x1 * y0;
            area += cross;
            cx += (x0 + x1) * cross;
            cy += (y0 + y1) * cross;
        }
        let center = [cx / (3.0 * area), cy / (3.0 * area)];
        let mut points = vec![center];
        for t in [0.5, 0.25, 0.75] {
            for [x, y] in &self.polygon {
                points.push([
                    center[0] + t * (x - center[0]),
                    center[1] + t * (y - center[1]),
                ]);
            }
        }
        points
    }
}

#[test]
fn html_page_reacts_to_a_real_mouse_in_headless_chromium() {
    let Some(chromium) = cdp::find_chromium() else {
        assert!(
            std::env::var("NPTREEMAP_REQUIRE_BROWSER").as_deref() != Ok("1"),
            "NPTREEMAP_REQUIRE_BROWSER=1 but no chromium at /usr/bin/chromium or on PATH"
        );
        // Straight to stderr: libtest captures eprintln! of passing tests, and
        // the skip should show in a plain `cargo test` run.
        let _ = writeln!(
            std::io::stderr(),
            "skipped: chromium not installed (the HTML page's browser test did not run)"
        );
        return;
    };
    let dir = support::temp_dir("browser");
    // Countries: large weights (thousands separators); every constraint realised.
    let countries = Page::build(&dir, "country_pop_50M_AUS", &[]);
    // Movies: unrealised constraints, so dashed partners and links to show.
    // Made with optimisation frames, for the slider.
    let movies = Page::build(&dir, "imdb_100_genre_sim_2child", &["--frames", "6"]);
    assert!(
        movies.partners.values().any(|r| !r),
        "movies target has an unrealised partner"
    );
    // Ids that are also names of every JavaScript object's properties
    // (issue 11, item 14): with plain objects as maps, `constructor` and its
    // kind counted as everyone's neighbours and never greyed out.
    let special_input =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/html/special-ids.json");
    let special: Vec<Page> = ["alpha", "constructor", "__proto__"]
        .iter()
        .map(|target| {
            let name = format!("special-{}", target.trim_matches('_'));
            Page::build_from(&dir, &special_input, &name, &[], Some(target))
        })
        .collect();
    let greyed: BTreeSet<&String> = special
        .iter()
        .flat_map(|p| {
            p.leaves
                .iter()
                .filter(|l| !p.neighbors.contains(*l) && **l != p.target)
        })
        .collect();
    for id in [
        "constructor",
        "toString",
        "__proto__",
        "hasOwnProperty",
        "valueOf",
    ] {
        assert!(
            greyed.contains(&id.to_string()),
            "{id} is to grey out on some hover: {greyed:?}"
        );
    }

    let mut browser = Browser::launch(&chromium, &dir, BUDGET);
    for domain in ["Page", "Runtime", "Log", "Network"] {
        browser.call(&format!("{domain}.enable"), json!({}));
    }
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": VIEWPORT.0, "height": VIEWPORT.1, "deviceScaleFactor": 1, "mobile": false}),
    );
    // The tooltip formats the weight with toLocaleString: pin the locale.
    browser.call("Emulation.setLocaleOverride", json!({"locale": "en-US"}));

    browser.open(&countries.url);
    hover_and_leave(&mut browser, &countries);
    tooltip_stays_in_view(&mut browser);
    browser.open(&movies.url);
    hover_and_leave(&mut browser, &movies);
    toggle_unrealized_links(&mut browser);
    step_through_frames(&mut browser);
    for page in &special {
        browser.open(&page.url);
        hover_and_leave(&mut browser, page);
    }

    // One more round trip, so every event sent before it has been read.
    browser.eval("0");
    let urls: Vec<&str> = browser
        .events("Network.requestWillBeSent")
        .iter()
        .map(|e| e["params"]["request"]["url"].as_str().expect("url"))
        .collect();
    for page in [&countries, &movies] {
        assert!(
            urls.contains(&page.url.as_str()),
            "requests are observed: {urls:?}"
        );
    }
    let remote: Vec<&&str> = urls
        .iter()
        .filter(|u| {
            !["file:", "data:", "about:"]
                .iter()
                .any(|s| u.starts_with(s))
        })
        .collect();
    assert!(
        remote.is_empty(),
        "the page made network requests: {remote:?}"
    );
    let mut errors = browser.events("Runtime.exceptionThrown");
    errors.extend(
        browser
            .events("Runtime.consoleAPICalled")
            .into_iter()
            .filter(|e| ["error", "assert"].contains(&e["params"]["type"].as_str().unwrap_or(""))),
    );
    errors.extend(
        browser
            .events("Log.entryAdded")
            .into_iter()
            .filter(|e| e["params"]["entry"]["level"] == "error"),
    );
    assert!(errors.is_empty(), "console errors: {errors:#?}");
}

/// Everything the hover changes, read from the DOM: which cells carry the
/// highlight classes, each cell's computed style, and the tooltip.
const HOVER_STATE: &str = r##"(function () {
  var map = document.getElementById("np-map");
  var tip = document.getElementById("np-tooltip");
  function ids(selector) {
    return Array.prototype.map.call(map.querySelectorAll(selector), function (el) {
      return el.getAttribute("data-id");
    });
  }
  var style = {};
  Array.prototype.forEach.call(map.querySelectorAll("path[data-id]"), function (el) {
    var s = getComputedStyle(el);
    style[el.getAttribute("data-id")] = {
      opacity: s.opacity, stroke: s.stroke, width: s.strokeWidth, dash: s.strokeDasharray
    };
  });
  var box = tip.getBoundingClientRect();
  return {
    dimmed: ids("path.np-dim"), partners: ids("path.np-partner"),
    dashed: ids("path.np-partner-unrealized"), style: style,
    tip: { hidden: tip.hidden, display: getComputedStyle(tip).display,
           text: tip.textContent, width: box.width, height: box.height,
           inside: box.left >= 0 && box.top >= 0 &&
                   box.right <= window.innerWidth && box.bottom <= window.innerHeight }
  };
})()"##;

/// Hovers a leaf at the map's right edge, where a tooltip to the right of the
/// pointer would run out of the window, and checks it is flipped into view.
fn tooltip_stays_in_view(browser: &mut Browser) {
    const EDGE: &str = r##"(function () {
      var r = document.querySelector("#np-map svg").getBoundingClientRect();
      return [Math.min(r.right, window.innerWidth) - 6, r.top + 0.3 * r.height];
    })()"##;
    let at = browser.eval(EDGE);
    let (x, y) = (at[0].as_f64().expect("x"), at[1].as_f64().expect("y"));
    browser.mouse_move(x, y);
    browser.wait_for(
        "a tooltip at the right edge inside the window",
        HOVER_STATE,
        |state| {
            let tip = &state["tip"];
            if tip["hidden"] == false && tip["width"].as_f64() > Some(0.0) && tip["inside"] == true
            {
                Ok(())
            } else {
                Err(format!("tooltip {tip}"))
            }
        },
    );
    browser.mouse_move(2.0, 2.0);
}

/// Moves the mouse onto the page's target cell and checks the highlight and
/// tooltip, then off the map and checks that everything clears.
fn hover_and_leave(browser: &mut Browser, page: &Page) {
    let before = browser.eval(HOVER_STATE);
    check_cleared(&before, page).unwrap_or_else(|e| panic!("before hovering: {e}"));

    let (x, y) = hover_point(browser, page);
    browser.mouse_move(x, y);
    browser.wait_for(
        &format!("the hover highlight of {}", page.target),
        HOVER_STATE,
        |state| check_hovered(state, page),
    );

    // Top-left corner: inside the body's margin, outside the map.
    let outside = browser
        .eval("!document.getElementById('np-map').contains(document.elementFromPoint(2, 2))");
    assert_eq!(outside, true, "(2, 2) lies outside the map");
    browser.mouse_move(2.0, 2.0);
    browser.wait_for(
        &format!("the highlight of {} to clear", page.target),
        HOVER_STATE,
        |state| check_cleared(state, page),
    );
}

/// A viewport point (whole pixels) where the topmost element is the target
/// cell itself, not a tab, a region outline or anything else drawn over it.
fn hover_point(browser: &mut Browser, page: &Page) -> (f64, f64) {
    let script = format!(
        r##"(function (id, points) {{
  var cell = Array.prototype.find.call(
    document.querySelectorAll("#np-map path[data-id]"),
    function (el) {{ return el.getAttribute("data-id") === id; }});
  if (!cell) {{ return "no cell"; }}
  var m = cell.getScreenCTM();
  for (var i = 0; i < points.length; i++) {{
    var p = new DOMPoint(points[i][0], points[i][1]).matrixTransform(m);
    var x = Math.round(p.x), y = Math.round(p.y);
    if (x > 0 && y > 0 && x < innerWidth && y < innerHeight &&
        document.elementFromPoint(x, y) === cell) {{ return [x, y]; }}
  }}
  return "no point of the cell is uncovered";
}})({}, {})"##,
        json!(page.target),
        json!(page.hover_candidates())
    );
    let point = browser.eval(&script);
    match (point[0].as_f64(), point[1].as_f64()) {
        (Some(x), Some(y)) => (x, y),
        _ => panic!("{}: {point}", page.target),
    }
}

/// The hover state is the page's documented behaviour for `page.target`.
fn check_hovered(state: &Value, page: &Page) -> Result<(), String> {
    let dimmed = id_set(&state["dimmed"]);
    // Every leaf but the hovered one and its neighbours (issue 11, item 14:
    // the hovered cell used to grey itself out).
    let mut expected: BTreeSet<String> = page.leaves.difference(&page.neighbors).cloned().collect();
    expected.remove(&page.target);
    if dimmed != expected {
        return Err(format!("dimmed {dimmed:?}, expected {expected:?}"));
    }
    for leaf in &page.leaves {
        let opacity = state["style"][leaf]["opacity"].as_str().unwrap_or("");
        let want = if expected.contains(leaf) { "0.25" } else { "1" };
        if opacity != want {
            return Err(format!("{leaf} has opacity {opacity}, expected {want}"));
        }
    }
    let outlined = id_set(&state["partners"]);
    let partners: BTreeSet<String> = page.partners.keys().cloned().collect();
    if outlined != partners {
        return Err(format!("outlined {outlined:?}, expected {partners:?}"));
    }
    let dashed = id_set(&state["dashed"]);
    let unrealized: BTreeSet<String> = page
        .partners
        .iter()
        .filter(|(_, realized)| !**realized)
        .map(|(id, _)| id.clone())
        .collect();
    if dashed != unrealized {
        return Err(format!("dashed {dashed:?}, expected {unrealized:?}"));
    }
    for (partner, realized) in &page.partners {
        let style = &state["style"][partner];
        let dash = style["dash"].as_str().unwrap_or("");
        if style["stroke"] != "rgb(0, 0, 0)"
            || style["width"] != "4px"
            || (dash == "none") != *realized
        {
            return Err(format!("{partner} (realised: {realized}) is drawn {style}"));
        }
    }
    let tip = &state["tip"];
    let text = tip["text"].as_str().unwrap_or("");
    let visible = tip["hidden"] == false
        && tip["display"] != "none"
        && tip["width"].as_f64() > Some(0.0)
        && tip["height"].as_f64() > Some(0.0)
        // Within the window, wherever the pointer is.
        && tip["inside"] == true;
    let weight = format!("weight {}", en_us(page.weight));
    if !visible || !in_order(text, &page.path) || !text.contains(&weight) {
        return Err(format!(
            "tooltip {tip}, expected visible with {:?} in order and {weight:?}",
            page.path
        ));
    }
    Ok(())
}

/// Nothing highlighted, every leaf fully opaque, tooltip hidden.
fn check_cleared(state: &Value, page: &Page) -> Result<(), String> {
    for class in ["dimmed", "partners", "dashed"] {
        if !id_set(&state[class]).is_empty() {
            return Err(format!("{class} still set: {}", state[class]));
        }
    }
    for leaf in &page.leaves {
        let opacity = state["style"][leaf]["opacity"].as_str().unwrap_or("");
        if opacity != "1" {
            return Err(format!("{leaf} has opacity {opacity}"));
        }
    }
    let tip = &state["tip"];
    if tip["hidden"] != true || tip["display"] != "none" {
        return Err(format!("tooltip still shown: {tip}"));
    }
    Ok(())
}

/// The checkbox, its effect, and how many unrealised-link shapes are drawn.
const LINKS_STATE: &str = r##"(function () {
  var box = document.getElementById("np-unrealized");
  var shapes = [];
  Array.prototype.forEach.call(document.querySelectorAll("#np-map .np-unrealized"), function (g) {
    Array.prototype.push.apply(shapes, g.children);
  });
  var visible = shapes.filter(function (s) {
    var r = s.getBoundingClientRect();
    return s.checkVisibility() && (r.width > 0 || r.height > 0);
  });
  var r = box.getBoundingClientRect();
  var x = Math.round(r.left + r.width / 2), y = Math.round(r.top + r.height / 2);
  return {
    checked: box.checked, shapes: shapes.length, visible: visible.length,
    click: document.elementFromPoint(x, y) === box ? [x, y] : null
  };
})()"##;

/// Clicks "Show unrealized links" on the open page (which must draw some): off
/// by default with every link hidden, on shows every one, off hides them again.
fn toggle_unrealized_links(browser: &mut Browser) {
    let before = browser.eval(LINKS_STATE);
    let shapes = before["shapes"].as_u64().expect("shape count");
    assert!(shapes > 0, "the page draws unrealised links: {before}");
    assert_eq!(before["checked"], false, "{before}");
    assert_eq!(before["visible"], 0, "hidden by default: {before}");
    let (x, y) = match (before["click"][0].as_f64(), before["click"][1].as_f64()) {
        (Some(x), Some(y)) => (x, y),
        _ => panic!("the checkbox's centre is covered: {before}"),
    };
    for (checked, visible) in [(true, shapes), (false, 0)] {
        browser.click(x, y);
        browser.wait_for(
            &format!(
                "the checkbox to turn {}",
                if checked { "on" } else { "off" }
            ),
            LINKS_STATE,
            |state| {
                if state["checked"] == checked && state["visible"] == visible {
                    Ok(())
                } else {
                    Err(format!(
                        "{state}, expected {visible} of {shapes} links visible"
                    ))
                }
            },
        );
    }
}

/// Moves the optimisation slider to its first frame, then back to the end:
/// the frame layer holds exactly that frame's cells (every one of them a
/// node of the page) with its caption, and the end shows the finished map.
fn step_through_frames(browser: &mut Browser) {
    const SET: &str = r##"(function (k) {
      var slider = document.getElementById("np-frame");
      var data = JSON.parse(document.getElementById("nptreemap-data").textContent);
      if (!slider) { return { slider: false }; }
      slider.value = String(k < 0 ? slider.max : k);
      slider.dispatchEvent(new Event("input"));
      var layer = document.getElementById("np-frame-layer");
      var known = {};
      data.nodes.forEach(function (n) { known[n.id] = true; });
      var drawn = Array.prototype.map.call(layer.querySelectorAll("path"), function (p) {
        return p.getAttribute("data-frame-id");
      });
      return {
        slider: true, max: parseInt(slider.max, 10), frames: data.frames.length,
        expected: k < 0 ? 0 : data.frames[k].cells.length,
        drawn: drawn.length, unknown: drawn.filter(function (id) { return !known[id]; }).length,
        caption: document.getElementById("np-frame-label").textContent
      };
    })"##;
    let first = browser.eval(&format!("{SET}(0)"));
    assert_eq!(
        first["slider"], true,
        "a page made with frames has a slider"
    );
    assert_eq!(first["max"], first["frames"], "{first}");
    assert!(first["frames"].as_u64().unwrap_or(0) >= 2, "{first}");
    assert!(first["drawn"].as_u64().unwrap_or(0) > 0, "{first}");
    assert_eq!(first["drawn"], first["expected"], "{first}");
    assert_eq!(first["unknown"], 0, "{first}");
    let caption = first["caption"].as_str().unwrap_or("");
    assert!(caption.contains("level 1"), "{first}");
    let last = browser.eval(&format!("{SET}(-1)"));
    assert_eq!(last["drawn"], 0, "{last}");
    assert_eq!(last["caption"], "final layout", "{last}");
}

/// The JSON node data embedded in a page.
fn page_data(page: &str) -> Value {
    let open = "<script type=\"application/json\" id=\"nptreemap-data\">";
    let start = page.find(open).expect("data block") + open.len();
    let len = page[start..].find("</script>").expect("end of data block");
    serde_json::from_str(&page[start..start + len]).expect("data block is JSON")
}

/// A `file://` URL for an absolute path, percent-encoding all but the
/// characters that need none.
fn file_url(path: &Path) -> String {
    let mut url = String::from("file://");
    for b in path.to_str().expect("UTF-8 path").bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            url.push(char::from(b));
        } else {
            url.push_str(&format!("%{b:02X}"));
        }
    }
    url
}

/// A whole number as en-US `toLocaleString` writes it: "1,411,778,724".
fn en_us(weight: f64) -> String {
    assert!(
        weight.fract() == 0.0 && weight.abs() < 1e15,
        "the test formats whole weights only, not {weight}"
    );
    let digits = format!("{}", weight.abs() as u64);
    let mut out = String::new();
    for (i, d) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(d);
    }
    if weight < 0.0 {
        out.insert(0, '-');
    }
    out
}

/// Whether every one of `parts` occurs in `text`, in order, without overlap.
fn in_order(text: &str, parts: &[String]) -> bool {
    let mut rest = text;
    for part in parts {
        match rest.find(part.as_str()) {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    true
}

/// A JSON array of strings as a set.
fn id_set(value: &Value) -> BTreeSet<String> {
    value
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn en_us_groups_thousands() {
    assert_eq!(en_us(0.0), "0");
    assert_eq!(en_us(175.0), "175");
    assert_eq!(en_us(1000.0), "1,000");
    assert_eq!(en_us(1_411_778_724.0), "1,411,778,724");
}
