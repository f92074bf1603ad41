//! The reader's own columns in the page (issue 24 items 4 and 5), in the
//! same headless Chromium as the rest of the browser test: a tooltip shows
//! the fields the config names (and the weight with its unit, no `root`); a
//! click on a cell shows its link, which is a real link only for `http(s):`
//! or relative URLs (a `javascript:` or `data:` value stays text, and
//! clicking it runs nothing); a map coloured by a numeric column has the
//! scale in its legend.

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::cdp::Browser;
use super::file_url;
use crate::support;

/// The nodes of the fields map: (id, group, weight, summary, url, score).
/// Two groups of six cells each; every cell is large enough to click.
const ROWS: [(&str, &str, u32, &str, &str, &str); 12] = [
    (
        "alpha",
        "one",
        40,
        "first <b>letter</b>",
        "https://example.org/alpha",
        "1",
    ),
    (
        "beta",
        "one",
        30,
        "second",
        "javascript:window.__pwned=1",
        "2",
    ),
    (
        "gamma",
        "one",
        30,
        "third",
        "data:text/html,<script>window.__pwned=2</script>",
        "3",
    ),
    ("delta", "one", 25, "fourth", "docs/delta.html", "4"),
    ("epsilon", "one", 25, "fifth", "", ""),
    ("zeta", "one", 20, "sixth", "http://example.org/zeta", "6"),
    ("eta", "two", 40, "seventh", "https://example.org/eta", "7"),
    (
        "theta",
        "two",
        30,
        "eighth",
        " javascript:window.__pwned=3",
        "8",
    ),
    ("iota", "two", 30, "ninth", "https://example.org/iota", "9"),
    (
        "kappa",
        "two",
        25,
        "tenth",
        "https://example.org/kappa",
        "10",
    ),
    (
        "lambda",
        "two",
        25,
        "eleventh",
        "https://example.org/lambda",
        "11",
    ),
    ("mu", "two", 20, "twelfth", "https://example.org/mu", "12"),
];

/// Writes the fields map's inputs and config (its `page:` section naming
/// `summary` and the `url` link, coloured by `score`) and builds it.
pub(super) fn fields_map(dir: &Path) -> PathBuf {
    let dir = dir.join("fields");
    std::fs::create_dir_all(&dir).expect("dir");
    let mut nodes = String::from("id,group,size,summary,url,score\n");
    for (id, group, size, summary, url, score) in ROWS {
        let quote = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
        nodes.push_str(&format!(
            "{id},{group},{size},{},{},{score}\n",
            quote(summary),
            quote(url)
        ));
    }
    std::fs::write(dir.join("nodes.csv"), nodes).expect("nodes");
    let mut pairs = String::from("a,b\n");
    for w in ROWS.windows(2) {
        pairs.push_str(&format!("{},{}\n", w[0].0, w[1].0));
    }
    std::fs::write(dir.join("pairs.csv"), pairs).expect("pairs");
    std::fs::write(
        dir.join("nptreemap.yaml"),
        "render:\n  labels: {unit: \" KiB\"}\n  color_by: score\n\
         datasets:\n  - name: fields\n    format: border-list\n\
         \x20   files: {nodes: nodes.csv, pairs: pairs.csv}\n\
         \x20   fields: {weight: size, groups: [group]}\n\
         \x20   page: {fields: [summary, score], link: url, link_target: new-tab}\n\
         \x20   outputs: [fields.html, fields.svg]\n",
    )
    .expect("config");
    support::build(&dir.join("nptreemap.yaml"));
    dir.join("fields.html")
}

/// The screen point of cell `id` that the cell itself is on top at.
fn point_of(browser: &mut Browser, id: &str) -> (f64, f64) {
    super::explore::point_of(browser, id)
}

/// Accepts a state whose `hidden` is false.
fn shown(v: &Value) -> Result<(), String> {
    if v["hidden"] == false {
        Ok(())
    } else {
        Err(v.to_string())
    }
}

const TIP: &str = r##"(function () {
  var tip = document.querySelector(".nptreemap .np-tooltip");
  return { hidden: tip.hidden, lines: Array.prototype.map.call(tip.children, function (d) { return d.textContent; }) };
})()"##;

const LINK: &str = r##"(function () {
  var line = document.querySelector(".nptreemap .np-link");
  var a = line.querySelector("a");
  return { hidden: line.hidden, text: line.textContent,
           anchors: line.querySelectorAll("a").length,
           href: a ? a.getAttribute("href") : null, target: a ? a.getAttribute("target") : null,
           rel: a ? a.getAttribute("rel") : null, pwned: window.__pwned === undefined ? null : window.__pwned,
           refused: line.querySelectorAll(".np-link-refused").length };
})()"##;

/// Issue 24 item 4: hovering `alpha` shows its configured fields (the
/// summary as text, markup and all) after its path and weight.
pub(super) fn tooltip_shows_the_configured_fields(browser: &mut Browser, html: &Path) {
    browser.open(&file_url(html));
    let (x, y) = point_of(browser, "alpha");
    browser.mouse_move(x, y);
    let tip = browser.wait_for("the tooltip", TIP, shown);
    let lines: Vec<&str> = tip["lines"]
        .as_array()
        .expect("lines")
        .iter()
        .filter_map(Value::as_str)
        .collect();
    assert_eq!(lines.first(), Some(&"one \u{203a} alpha"), "{tip}");
    assert!(lines.contains(&"weight 40 KiB"), "{tip}");
    assert!(lines.contains(&"summary: first <b>letter</b>"), "{tip}");
    assert!(lines.contains(&"score: 1"), "{tip}");
    // The link's column is not a tooltip field here, and `url` is not shown.
    assert!(!lines.iter().any(|l| l.starts_with("url")), "{tip}");
    // `epsilon` has no score: the line is left out, not shown empty.
    let (x, y) = point_of(browser, "epsilon");
    browser.mouse_move(x, y);
    let tip = browser.wait_for("epsilon's tooltip", TIP, |t| {
        if t["lines"][0].as_str() == Some("one \u{203a} epsilon") {
            Ok(())
        } else {
            Err(t.to_string())
        }
    });
    assert!(
        !tip["lines"]
            .as_array()
            .expect("lines")
            .iter()
            .any(|l| l.as_str().is_some_and(|l| l.starts_with("score"))),
        "{tip}"
    );
}

/// Issue 24 item 4: a click on a cell shows its link above the map; only an
/// `http(s):` or relative URL is a link (with `target=_blank` and
/// `rel=noopener`); `javascript:` and `data:` values, even with a leading
/// space, are shown as text, and clicking them runs nothing.
pub(super) fn a_link_opens_only_for_an_allowed_scheme(browser: &mut Browser, html: &Path) {
    for (id, href) in [
        ("alpha", Some("https://example.org/alpha")),
        ("delta", Some("docs/delta.html")),
        ("zeta", Some("http://example.org/zeta")),
        ("beta", None),
        ("gamma", None),
        ("theta", None),
    ] {
        browser.open(&file_url(html));
        let (x, y) = point_of(browser, id);
        browser.click(x, y);
        let link = browser.wait_for("the link line", LINK, shown);
        assert!(
            link["text"].as_str().is_some_and(|t| t.contains(id)),
            "{id}: {link}"
        );
        match href {
            Some(href) => {
                assert_eq!(link["anchors"], 1, "{id}: {link}");
                assert_eq!(link["href"], href, "{id}: {link}");
                assert_eq!(link["target"], "_blank", "{id}: {link}");
                assert_eq!(link["rel"], "noopener noreferrer", "{id}: {link}");
            }
            None => {
                assert_eq!(link["anchors"], 0, "{id}: no link: {link}");
                assert_eq!(link["refused"], 1, "{id}: shown as text: {link}");
                // Clicking the text follows nothing and runs nothing.
                let at = browser.eval(
                    r##"(function () { var r = document.querySelector(".nptreemap .np-link-refused").getBoundingClientRect();
                      return [r.left + r.width / 2, r.top + r.height / 2]; })()"##,
                );
                let (x, y) = (at[0].as_f64().expect("x"), at[1].as_f64().expect("y"));
                browser.click(x, y);
                let after = browser.eval(LINK);
                assert_eq!(after["pwned"], Value::Null, "{id}: {after}");
                assert!(
                    browser
                        .eval("location.href")
                        .as_str()
                        .is_some_and(|u| u.ends_with("fields.html")),
                    "{id}: the page stays"
                );
            }
        }
    }
}

/// Issue 24 item 5: coloured by `score`, the legend shows the scale (its
/// field, lowest and highest values and a colour bar) and names the grey of
/// the cell without a value; the cells' colours differ by score.
pub(super) fn color_by_has_its_legend(browser: &mut Browser, html: &Path) {
    browser.open(&file_url(html));
    let legend = browser.eval(
        r##"(function () {
      var root = document.querySelector(".nptreemap");
      var scale = root.querySelector(".np-legend .np-legend-scale");
      var bar = scale && scale.querySelector(".np-scale-bar");
      var fills = {};
      Array.prototype.forEach.call(root.querySelectorAll(".np-map > svg path[data-id]"), function (p) {
        fills[p.getAttribute("data-id")] = p.getAttribute("fill");
      });
      return { text: scale ? Array.prototype.map.call(scale.querySelectorAll(".np-legend-text"), function (t) { return t.textContent; }) : null,
               bar: bar ? getComputedStyle(bar).backgroundImage : null,
               barWidth: bar ? bar.getBoundingClientRect().width : 0,
               items: Array.prototype.map.call(root.querySelectorAll(".np-legend > li"), function (li) { return li.textContent; }),
               alpha: fills.alpha, mu: fills.mu, epsilon: fills.epsilon };
    })()"##,
    );
    assert_eq!(
        legend["text"],
        serde_json::json!(["score: 1", "12"]),
        "{legend}"
    );
    assert!(
        legend["bar"]
            .as_str()
            .is_some_and(|b| b.starts_with("linear-gradient")),
        "{legend}"
    );
    assert!(
        legend["barWidth"].as_f64().unwrap_or(0.0) >= 40.0,
        "{legend}"
    );
    assert!(
        legend["items"]
            .as_array()
            .expect("items")
            .iter()
            .any(|i| i == "no score value"),
        "{legend}"
    );
    assert_ne!(legend["alpha"], legend["mu"], "{legend}");
    assert_eq!(legend["epsilon"], "#9e9e9e", "{legend}");
}

/// The search finding a group (issue 24 item 3): the group's own cells
/// stay bright on screen while everything else is dimmed (the found group
/// once sat under the veil with the rest of the map).
pub(super) fn a_found_group_keeps_its_cells_bright(browser: &mut Browser, html: &Path) {
    browser.open(&file_url(html));
    browser.eval("document.querySelector('.np-search-box').focus(); 0");
    browser.insert_text("one");
    browser.wait_for(
        "the matches",
        "document.querySelector('.np-matches [role=option]') !== null",
        |v| {
            if v == true {
                Ok(())
            } else {
                Err(v.to_string())
            }
        },
    );
    super::press(browser, "Enter", "Enter", 13);
    browser.wait_for(
        "the found group",
        "document.querySelector('.nptreemap').getAttribute('data-current')",
        |v| {
            if v == "group:one" {
                Ok(())
            } else {
                Err(v.to_string())
            }
        },
    );
    browser.settle(300);
    for (id, inside) in [("alpha", true), ("eta", false)] {
        let (x, y) = point_of(browser, id);
        let fill = browser.eval(&format!(
            "Array.prototype.find.call(document.querySelectorAll('.np-map > svg path[data-id]'), function (p) {{ return p.getAttribute('data-id') === {}; }}).getAttribute('fill')",
            serde_json::json!(id)
        ));
        let fill = fill.as_str().expect("fill").to_owned();
        let shot = browser.call(
            "Page.captureScreenshot",
            serde_json::json!({"format": "png", "clip": {"x": x, "y": y, "width": 1, "height": 1, "scale": 1}}),
        );
        let png = super::explore::base64(shot["data"].as_str().expect("screenshot data"));
        let pixmap = resvg::tiny_skia::Pixmap::decode_png(&png).expect("a PNG");
        let p = pixmap.pixel(0, 0).expect("one pixel").demultiply();
        let channel =
            |k: usize| f64::from(u8::from_str_radix(&fill[1 + 2 * k..3 + 2 * k], 16).unwrap_or(0));
        let got = [p.red(), p.green(), p.blue()].map(f64::from);
        let own = (0..3).all(|k| (got[k] - channel(k)).abs() <= 12.0);
        assert_eq!(
            own,
            inside,
            "{id} (fill {fill}) shows {got:?} at ({x}, {y}): {}",
            if inside {
                "bright inside the found group"
            } else {
                "dimmed outside it"
            }
        );
    }
}
