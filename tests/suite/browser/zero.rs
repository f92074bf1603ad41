//! Items of weight 0 in the page (issue 34 item 2), in headless Chromium:
//! hidden ones have no cell, and the tooltip of a cell beside them (in the
//! same folder, or at the top level beside a hidden folder) names them.

use serde_json::Value;

use super::{chromium_or_skip, explore, file_url, session};
use crate::support;

const TIP: &str = r##"(function () {
  var tip = document.querySelector(".nptreemap .np-tooltip");
  return { hidden: tip.hidden, lines: Array.prototype.map.call(tip.children, function (d) { return d.textContent; }),
           cells: document.querySelectorAll(".np-map svg path[data-id]").length };
})()"##;

#[test]
fn the_tooltip_names_the_items_of_weight_zero_beside_a_cell() {
    let Some(chromium) = chromium_or_skip() else {
        return;
    };
    let dir = support::temp_dir("browser-zero");
    let input = dir.join("src.json");
    std::fs::write(&input, crate::zero_weights::tree(|_| true).to_string()).expect("input");
    let html = dir.join("src.html");
    support::layout(&input, &[&html], &[]);
    let mut browser = session(&chromium, &dir);
    browser.open(&file_url(&html));
    for (id, path, line) in [
        (
            "a/core.py",
            "a \u{203a} core.py",
            "a also holds 2 items of weight 0, not drawn: __init__.py, empty.py",
        ),
        (
            "setup.py",
            "setup.py",
            "src also holds 2 items of weight 0, not drawn: c",
        ),
    ] {
        let (x, y) = explore::point_of(&mut browser, id);
        browser.mouse_move(x, y);
        let tip = browser.wait_for(&format!("{id}'s tooltip"), TIP, |t| {
            if t["hidden"] == false && t["lines"][0] == path {
                Ok(())
            } else {
                Err(t.to_string())
            }
        });
        let lines: Vec<&str> = tip["lines"]
            .as_array()
            .expect("lines")
            .iter()
            .filter_map(Value::as_str)
            .collect();
        assert!(lines.contains(&line), "{id}: {tip}");
    }
    // No cell for a hidden file: the six files of weight and a and b.
    let cells = browser.eval(TIP)["cells"].as_u64().expect("cells");
    assert_eq!(cells, 8);
}
