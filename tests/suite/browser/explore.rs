//! The page as an explorer (issue 24), in the same headless Chromium as the
//! rest of the browser test: a zoom places labels that the whole map had no
//! room for, the search box (reached with `/`) finds a leaf and zooms to it,
//! a first tap on a touch screen shows the tooltip and only a second one
//! zooms, the title and legend stay readable text on a phone, and the focus
//! ring differs from the partners' outline in light and dark mode.

use std::path::Path;

use serde_json::{json, Value};

use super::cdp::Browser;
use super::{file_url, hover_point, page_data, press, Page, PageModel, VIEWPORT};
use crate::support;

/// A generated map of 1,500 leaves in two levels: on the whole map most
/// leaves are too small for their label. Returns the page's URL and path.
pub(super) fn big_map(dir: &Path) -> (String, std::path::PathBuf) {
    let input = support::generate(dir, 1500, 2, 3);
    let html = dir.join("big.html");
    support::layout(&input, &[&html], &["--seed", "1"]);
    (file_url(&html), html)
}

/// Leaves of the page without a label on the whole map whose top-level
/// group can be zoomed into, in the page's order.
pub(super) fn unlabelled_leaves(html: &Path) -> Vec<String> {
    let data = page_data(&std::fs::read_to_string(html).expect("read page"));
    let model = PageModel::new(&data);
    let placed = placed_labels(&data);
    assert!(
        !placed.is_empty(),
        "some leaves have labels on the whole map"
    );
    model
        .leaves()
        .filter(|id| !placed.contains(&model.index(id)))
        .filter(|id| {
            model
                .top_group(id)
                .is_some_and(|g| model.node(g)["zoom"].is_array())
        })
        .map(str::to_owned)
        .collect()
}

/// The nodes the picture's labels name, by index (the page's data pairs
/// them).
fn placed_labels(data: &Value) -> Vec<usize> {
    data["labels"]["placed"]
        .as_array()
        .expect("the page pairs its labels with nodes")
        .iter()
        .filter_map(Value::as_u64)
        .map(|i| i as usize)
        .collect()
}

/// Whether a drawn label `text` names `label`: the whole of it, or a cut
/// that keeps at least four characters before its ellipsis.
pub(super) fn labelled_as(text: &str, label: &str) -> bool {
    let kept = text.trim_end_matches('\u{2026}');
    text == label || (kept.chars().count() >= 4 && label.starts_with(kept))
}

/// A point of leaf `id` (in layout units) where the cell itself is hit.
pub(super) fn point_of(browser: &mut Browser, id: &str) -> (f64, f64) {
    const POINT: &str = r##"(function (id) {
      var el = Array.prototype.find.call(document.querySelectorAll(".np-map svg path[data-id]"),
        function (e) { return e.getAttribute("data-id") === id; });
      if (!el) { return "no cell"; }
      var d = el.getAttribute("d").match(/-?[0-9.]+/g).map(Number);
      var m = el.getScreenCTM(), cx = 0, cy = 0, k = d.length / 2;
      for (var i = 0; i < d.length; i += 2) { cx += d[i] / k; cy += d[i + 1] / k; }
      var pts = [[cx, cy]];
      for (var i = 0; i < d.length; i += 2) { pts.push([(3 * cx + d[i]) / 4, (3 * cy + d[i + 1]) / 4]); }
      for (var j = 0; j < pts.length; j++) {
        var p = new DOMPoint(pts[j][0], pts[j][1]).matrixTransform(m);
        var x = Math.round(p.x), y = Math.round(p.y);
        if (x > 0 && y > 0 && x < innerWidth && y < innerHeight && document.elementFromPoint(x, y) === el) {
          return [x, y];
        }
      }
      return "no point of the cell is uncovered";
    })"##;
    let at = browser.eval(&format!("{POINT}({})", json!(id)));
    match (at[0].as_f64(), at[1].as_f64()) {
        (Some(x), Some(y)) => (x, y),
        _ => panic!("{id}: {at}"),
    }
}

/// What a zoom shows: the breadcrumb, the view, and the zoom labels.
const VIEW: &str = r##"(function () {
  var root = document.querySelector(".nptreemap");
  var labels = Array.prototype.map.call(root.querySelectorAll(".np-zoom-labels text[data-of]"), function (t) {
    return [t.getAttribute("data-of"), t.textContent, parseFloat(t.getAttribute("font-size"))];
  });
  var picture = root.querySelectorAll(".np-map > svg > .np-labels:not(.np-zoom-labels) text");
  var shown = Array.prototype.filter.call(picture, function (t) { return t.getBoundingClientRect().width > 0; });
  return { zoom: root.getAttribute("data-zoom"), zoomed: root.classList.contains("np-zoomed"),
           crumbs: root.querySelectorAll(".np-crumbs button").length,
           found: root.getAttribute("data-found"), labels: labels, pictureLabels: shown.length,
           marks: performance.getEntriesByName("nptreemap-zoomed").length };
})()"##;

/// Issue 24, item 1: a click into a group places labels for the zoomed
/// extent: the leaf clicked, which had no label on the whole map, gets one
/// (its text or a cut of it, at least four characters before the
/// ellipsis), and so do many others; the picture's own labels give way;
/// the breadcrumb's first entry restores the whole map.
pub(super) fn a_zoom_places_labels_that_were_absent(browser: &mut Browser, url: &str, html: &Path) {
    let data = page_data(&std::fs::read_to_string(html).expect("read page"));
    let model = PageModel::new(&data);
    let target = unlabelled_leaves(html)
        .into_iter()
        .next()
        .expect("an unlabelled leaf in a zoomable group");
    browser.open(url);
    let before = browser.eval(VIEW);
    assert_eq!(before["zoomed"], false, "{before}");
    assert_eq!(
        before["labels"].as_array().map(Vec::len),
        Some(0),
        "{before}"
    );
    let (x, y) = point_of(browser, &target);
    browser.click(x, y);
    let label = model.label(&target).to_owned();
    let after = browser.wait_for("the zoom's labels", VIEW, |v| {
        let mine = v["labels"]
            .as_array()
            .and_then(|ls| ls.iter().find(|l| l[0] == target.as_str()));
        match mine {
            Some(l) if v["zoomed"] == true => {
                let text = l[1].as_str().unwrap_or("");
                if labelled_as(text, &label) {
                    Ok(())
                } else {
                    Err(format!("{target} is labelled {text:?}, not {label:?}"))
                }
            }
            _ => Err(format!("no zoom label for {target} yet: {v}")),
        }
    });
    // Of the group's leaves, more are labelled now than on the whole map.
    let group = model.top_group(&target).expect("a group");
    let placed = placed_labels(&data);
    let members: Vec<&str> = model
        .leaves()
        .filter(|id| model.top_group(id) == Some(group))
        .collect();
    let on_map = members
        .iter()
        .filter(|id| placed.contains(&model.index(id)))
        .count();
    let zoomed = after["labels"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|l| l[0].as_str().is_some_and(|id| members.contains(&id)))
        .count();
    assert!(
        zoomed > on_map,
        "{group}: {zoomed} of {} leaves labelled after the zoom, {on_map} before",
        members.len()
    );
    assert_eq!(
        after["pictureLabels"], 0,
        "the picture's labels give way: {after}"
    );
    assert_eq!(after["crumbs"], 2, "{after}");
    const FIRST_CRUMB: &str = r##"(function () {
      var r = document.querySelector(".np-crumbs button").getBoundingClientRect();
      return [Math.round(r.left + r.width / 2), Math.round(r.top + r.height / 2)];
    })()"##;
    let at = browser.eval(FIRST_CRUMB);
    browser.click(at[0].as_f64().expect("x"), at[1].as_f64().expect("y"));
    browser.wait_for("the whole map again", VIEW, |v| {
        if v["zoomed"] == false
            && v["labels"].as_array().is_some_and(Vec::is_empty)
            && v["pictureLabels"] == before["pictureLabels"]
        {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    });
}

/// Issue 24, item 3: `/` jumps to the search box; typing a leaf's name
/// lists it first among the matches; Enter zooms to it, labels it and
/// highlights it (ring, tooltip).
pub(super) fn search_finds_and_zooms(browser: &mut Browser, url: &str, html: &Path) {
    let target = unlabelled_leaves(html)
        .into_iter()
        .last()
        .expect("an unlabelled leaf in a zoomable group");
    browser.open(url);
    for kind in ["keyDown", "keyUp"] {
        browser.call(
            "Input.dispatchKeyEvent",
            json!({"type": kind, "key": "/", "code": "Slash", "windowsVirtualKeyCode": 191}),
        );
    }
    let focused = browser.eval("document.activeElement && document.activeElement.className");
    assert_eq!(focused, "np-search-box", "`/` focuses the search box");
    browser.insert_text(&target);
    const MATCHES: &str = r##"(function () {
      var list = document.querySelector(".np-matches");
      return { hidden: list.hidden,
               options: Array.prototype.map.call(list.querySelectorAll("[role=option]"), function (li) {
                 return li.getAttribute("data-id");
               }),
               expanded: document.querySelector(".np-search-box").getAttribute("aria-expanded") };
    })()"##;
    let listed = browser.wait_for("the matches", MATCHES, |m| {
        if m["hidden"] == false && m["options"][0] == target.as_str() {
            Ok(())
        } else {
            Err(format!("{m}"))
        }
    });
    assert_eq!(listed["expanded"], "true", "{listed}");
    assert!(
        listed["options"].as_array().map_or(0, Vec::len) <= 12,
        "a bounded list: {listed}"
    );
    press(browser, "Enter", "Enter", 13);
    const FOUND: &str = r##"(function (id) {
      var over = document.querySelector(".np-map svg.np-hover");
      var ring = Array.prototype.some.call(over.querySelectorAll(".np-ring-outer"), function (r) {
        return r.getAttribute("data-of") === id;
      });
      var tip = document.querySelector(".np-tooltip");
      return { ring: ring, tip: !tip.hidden && tip.textContent.indexOf(id) >= 0,
               list: document.querySelector(".np-matches").hidden };
    })"##;
    let found = format!("{FOUND}({})", json!(target));
    browser.wait_for("the search's zoom", VIEW, |v| {
        let labelled = v["labels"]
            .as_array()
            .is_some_and(|ls| ls.iter().any(|l| l[0] == target.as_str()));
        if v["found"] == target.as_str() && v["zoomed"] == true && labelled {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    });
    browser.wait_for("the found leaf's highlight", &found, |f| {
        if f["ring"] == true && f["tip"] == true && f["list"] == true {
            Ok(())
        } else {
            Err(format!("{f}"))
        }
    });
}

/// Issue 24, item 7: on a touch screen the first tap on a cell shows its
/// tooltip and highlight without zooming (the mouse events a browser sends
/// after a tap once made it zoom), and a second tap on it zooms.
pub(super) fn a_first_tap_shows_the_tooltip(browser: &mut Browser, page: &Page) {
    browser.call(
        "Emulation.setTouchEmulationEnabled",
        json!({"enabled": true, "maxTouchPoints": 1}),
    );
    browser.open(&page.url);
    let (x, y) = hover_point(browser, page);
    browser.tap(x, y);
    // Give a zoom, if the tap caused one, time to show.
    browser.settle(400);
    let crumbs = browser.eval("document.querySelectorAll('.np-crumbs button').length");
    assert_eq!(crumbs, 1, "the first tap does not zoom");
    browser.wait_for(
        &format!("the tap's hover state of {}", page.target),
        super::HOVER_STATE,
        |state| super::check_hovered(state, page),
    );
    browser.tap(x, y);
    browser.wait_for("the second tap's zoom", VIEW, |v| {
        if v["zoomed"] == true && v["crumbs"].as_u64() >= Some(2) {
            Ok(())
        } else {
            Err(format!("{v}"))
        }
    });
    browser.call(
        "Emulation.setTouchEmulationEnabled",
        json!({"enabled": false}),
    );
}

/// Issue 24, item 6: on a 390 px wide phone the title and the legend are
/// HTML text of at least 12 px, inside the screen's width (the legend
/// unfolded by its button: issue 33 folds it on a phone).
pub(super) fn legend_is_readable_on_a_phone(browser: &mut Browser, url: &str) {
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": 390, "height": 844, "deviceScaleFactor": 1, "mobile": true}),
    );
    browser.open(url);
    browser.eval("document.querySelector('.np-legend-toggle').click()");
    const TEXT: &str = r##"(function () {
      var out = [];
      document.querySelectorAll(".np-title, .np-legend-text, .np-legend-more summary").forEach(function (el) {
        var r = el.getBoundingClientRect();
        if (r.width === 0) { return; }
        out.push({ text: el.textContent, size: parseFloat(getComputedStyle(el).fontSize),
                   left: r.left, right: r.right, svg: !!el.closest("svg") });
      });
      return { items: out, width: document.documentElement.clientWidth,
               scroll: document.documentElement.scrollWidth };
    })()"##;
    let text = browser.eval(TEXT);
    let items = text["items"].as_array().expect("items");
    assert!(
        items.len() >= 3,
        "a title and legend entries are shown: {text}"
    );
    for item in items {
        assert!(item["size"].as_f64() >= Some(12.0), "{item}");
        assert_eq!(item["svg"], false, "HTML, not SVG text: {item}");
        assert!(
            item["left"].as_f64() >= Some(0.0)
                && item["right"].as_f64() <= text["width"].as_f64().map(|w| w + 0.5),
            "{item} within {}",
            text["width"]
        );
    }
    assert!(text["scroll"].as_f64() <= text["width"].as_f64(), "{text}");
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        json!({"width": VIEWPORT.0, "height": VIEWPORT.1, "deviceScaleFactor": 1, "mobile": false}),
    );
}

/// Issue 24, item 7: the focused cell's ring is at least 2 px wide on both
/// of its two colours, the two contrast at least 3:1 (so it shows on any
/// fill), and neither is the partners' outline colour, in light and dark
/// mode.
pub(super) fn focus_ring_differs_from_partners(browser: &mut Browser, page: &Page) {
    const RING: &str = r##"(function () {
      var over = document.querySelector(".np-map svg.np-hover");
      var outer = over.querySelector(".np-ring-outer"), inner = over.querySelector(".np-ring-inner");
      var partner = over.querySelector(".np-partner");
      function style(el) {
        if (!el) { return null; }
        var s = getComputedStyle(el);
        return { stroke: s.stroke, width: parseFloat(s.strokeWidth), effect: s.vectorEffect };
      }
      return { outer: style(outer), inner: style(inner), partner: style(partner),
               focused: document.activeElement && document.activeElement.getAttribute("data-id") };
    })()"##;
    for scheme in ["light", "dark"] {
        browser.call(
            "Emulation.setEmulatedMedia",
            json!({"features": [{"name": "prefers-color-scheme", "value": scheme}]}),
        );
        browser.open(&page.url);
        let focus = format!(
            r##"(function (id) {{
              var el = Array.prototype.find.call(document.querySelectorAll(".np-map svg path[data-id]"),
                function (e) {{ return e.getAttribute("data-id") === id; }});
              el.focus({{ focusVisible: true }});
              return document.activeElement === el;
            }})({})"##,
            json!(page.target)
        );
        assert_eq!(
            browser.eval(&focus),
            true,
            "{} takes the focus",
            page.target
        );
        let ring = browser.wait_for(&format!("the focus ring ({scheme})"), RING, |r| {
            if r["outer"].is_object() && r["inner"].is_object() && r["partner"].is_object() {
                Ok(())
            } else {
                Err(format!("{r}"))
            }
        });
        let rgb = |v: &Value| -> [f64; 3] {
            let n: Vec<f64> = v
                .as_str()
                .unwrap_or("")
                .split(|c: char| !c.is_ascii_digit() && c != '.')
                .filter_map(|x| x.parse().ok())
                .collect();
            [n[0], n[1], n[2]]
        };
        let (outer, inner, partner) = (
            rgb(&ring["outer"]["stroke"]),
            rgb(&ring["inner"]["stroke"]),
            rgb(&ring["partner"]["stroke"]),
        );
        assert!(
            outer != partner && inner != partner,
            "{scheme}: the ring is not the partners' colour: {ring}"
        );
        let contrast = luminance(outer).max(luminance(inner)) + 0.05;
        let contrast = contrast / (luminance(outer).min(luminance(inner)) + 0.05);
        assert!(
            contrast >= 3.0,
            "{scheme}: ring contrast {contrast:.2}: {ring}"
        );
        // Both bands at least 2 px: the outer band shows (outer - inner) / 2
        // on each side of the inner line.
        let (wo, wi) = (
            ring["outer"]["width"].as_f64().unwrap_or(0.0),
            ring["inner"]["width"].as_f64().unwrap_or(0.0),
        );
        assert!(wi >= 2.0 && (wo - wi) / 2.0 >= 2.0, "{scheme}: {ring}");
        assert_eq!(ring["outer"]["effect"], "non-scaling-stroke", "{ring}");
    }
    browser.call(
        "Emulation.setEmulatedMedia",
        json!({"features": [{"name": "prefers-color-scheme", "value": "light"}]}),
    );
}

/// Issue 24, item 7, on the screen itself: while a leaf is hovered, the
/// pixels of a tab between two dimmed cells are as pale as the dimmed cells
/// (three quarters of the white background over the tab's colour), not the
/// tab's own bright colour floating over a greyed map.
pub(super) fn hover_dims_the_tabs_on_screen(browser: &mut Browser, page: &Page) {
    browser.open(&page.url);
    let (x, y) = hover_point(browser, page);
    browser.mouse_move(x, y);
    // The tabs whose two cells are both dimmed: each one's fill colour and
    // a screen point inside it.
    const TABS: &str = r##"(function (kept) {
      var keep = new Set(kept), out = [];
      Array.prototype.forEach.call(document.querySelectorAll(".np-map svg g.np-tab"), function (t) {
        if (keep.has(t.getAttribute("data-a")) || keep.has(t.getAttribute("data-b")) || out.length >= 6) { return; }
        var poly = t.querySelector("polygon");
        var pts = poly.getAttribute("points").trim().split(/\s+/).map(function (p) { return p.split(",").map(Number); });
        var cx = 0, cy = 0;
        pts.forEach(function (p) { cx += p[0] / pts.length; cy += p[1] / pts.length; });
        var q = new DOMPoint(cx, cy).matrixTransform(poly.getScreenCTM());
        var x = Math.round(q.x), y = Math.round(q.y);
        if (x < 1 || y < 1 || x >= innerWidth - 1 || y >= innerHeight - 1) { return; }
        // Only where the tab itself is the picture's topmost shape.
        var hit = document.elementsFromPoint(x, y).filter(function (e) { return !e.closest(".np-hover"); })[0];
        if (hit !== poly) { return; }
        out.push({ fill: poly.getAttribute("fill"), x: x, y: y });
      });
      return out;
    })"##;
    let mut kept: Vec<&str> = page.neighbors.iter().map(String::as_str).collect();
    kept.push(page.target.as_str());
    // Wait for the hover to show, and for the frames after it (any fading
    // included) to be drawn, before reading the screen.
    browser.wait_for(
        "the hover's tooltip",
        "!document.querySelector('.np-tooltip').hidden",
        |v| {
            if v == true {
                Ok(())
            } else {
                Err(format!("{v}"))
            }
        },
    );
    browser.settle(300);
    let tabs = browser.eval(&format!("{TABS}({})", json!(kept)));
    let tabs = tabs.as_array().expect("tabs");
    assert!(
        !tabs.is_empty(),
        "the map has tabs away from the hovered cell"
    );
    for tab in tabs {
        let (x, y) = (tab["x"].as_f64().expect("x"), tab["y"].as_f64().expect("y"));
        let shot = browser.call(
            "Page.captureScreenshot",
            json!({"format": "png", "clip": {"x": x, "y": y, "width": 1, "height": 1, "scale": 1}}),
        );
        let png = base64(shot["data"].as_str().expect("screenshot data"));
        let pixmap = resvg::tiny_skia::Pixmap::decode_png(&png).expect("a PNG");
        let p = pixmap.pixel(0, 0).expect("one pixel").demultiply();
        let fill = tab["fill"].as_str().unwrap_or("#000000");
        let channel = |k: usize| u8::from_str_radix(&fill[1 + 2 * k..3 + 2 * k], 16).unwrap_or(0);
        let dimmed = |k: usize| 0.25 * f64::from(channel(k)) + 0.75 * 255.0;
        for (k, got) in [p.red(), p.green(), p.blue()].into_iter().enumerate() {
            assert!(
                (f64::from(got) - dimmed(k)).abs() <= 12.0,
                "the tab at ({x}, {y}) filled {fill} shows channel {k} = {got}, dimmed it would be {:.0}: {tab}",
                dimmed(k)
            );
        }
    }
    browser.mouse_move(2.0, 2.0);
}

/// The bytes of standard base64 text (a screenshot from the browser).
pub(super) fn base64(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for v in text.bytes().filter_map(value) {
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    out
}

/// WCAG relative luminance of an sRGB colour given in 0–255.
fn luminance(rgb: [f64; 3]) -> f64 {
    let lin = |c: f64| {
        let c = c / 255.0;
        if c <= 0.039_28 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    0.2126 * lin(rgb[0]) + 0.7152 * lin(rgb[1]) + 0.0722 * lin(rgb[2])
}
