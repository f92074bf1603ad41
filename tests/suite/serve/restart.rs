//! An open page catches up after the daemon restarts (issue 30 item 10):
//! headless Chromium keeps a served page open while `watch --serve` stops,
//! the data is edited and built with the daemon down, and a new daemon
//! starts on the same address with nothing left to rebuild. The page's
//! stream reconnects by itself; told the current build's key, which is not
//! its own, the page fetches the current page and shows the new map, in
//! place (no reload).
//!
//! Without Chromium the test reports itself skipped, unless
//! `NPTREEMAP_REQUIRE_BROWSER=1` makes that a failure.

use std::time::Duration;

use serde_json::{json, Value};

use super::live::{chromium_or_skip, wait_true};
use super::{nodes_with, setup, weights, write_nodes, Served};
use crate::browser::cdp::Browser;
use crate::support;

/// Cap on the browser session: a bound on a hang, not a speed target.
const BUDGET: Duration = Duration::from_secs(240);

/// The path data of one cell of the shown picture.
fn cell(browser: &mut Browser, id: &str) -> Value {
    browser.eval(&format!(
        "(function () {{ var p = document.querySelector('.nptreemap .np-map > svg:not(.np-hover) path[data-id=\"{id}\"]');
           return p ? p.getAttribute('d') : null; }})()"
    ))
}

/// A loopback port in 20000..32000 that nothing listens on now, chosen from
/// the process id so that parallel runs start apart.
fn unused_port_below_ephemeral() -> u16 {
    let start = std::process::id() as usize * 7919;
    (0..200)
        .map(|k| 20_000 + ((start + k) % 12_000) as u16)
        .find(|&port| std::net::TcpListener::bind(("127.0.0.1", port)).is_ok())
        .expect("a free loopback port in 20000..32000")
}

#[test]
fn an_open_page_catches_up_after_the_daemon_restarts() {
    let Some(chromium) = chromium_or_skip("the restart's browser test") else {
        return;
    };
    let (dir, config) = setup("serve_restart");
    // A port below the kernel's ephemeral range (32768 and up on Linux): an
    // ephemeral port the first daemon was given could be handed to another
    // test's client socket while the daemon is down, and the restart could
    // not bind it again.
    let port = unused_port_below_ephemeral();
    let mut served = Served::start(&config, Some(&format!("127.0.0.1:{port}")));
    served.expect(&["grid", "wrote"]);
    let addr = served.addr;
    let mut browser = Browser::launch(&chromium, &dir, BUDGET);
    browser.call("Page.enable", json!({}));
    browser.open(&served.url("/out/grid.html"));
    wait_true(
        &mut browser,
        "the event stream to open",
        "document.querySelector('.np-live-status').textContent.indexOf('following grid') >= 0",
    );
    let origin = browser.eval("performance.timeOrigin");
    let before = cell(&mut browser, "n05");
    assert!(before.is_string(), "cell n05 is drawn");

    // The daemon stops; the page notices.
    served.terminate();
    drop(served);
    wait_true(
        &mut browser,
        "the page to see the stream go",
        "document.querySelector('.np-live-status').textContent.indexOf('reconnecting') >= 0",
    );
    // Meanwhile the data changes and a build writes the new map.
    let mut w = weights();
    w[5] *= 5.0;
    write_nodes(&dir, &nodes_with(&w));
    support::build(&config);
    // A new daemon on the same address: its first build finds nothing to do.
    let mut again = Served::start(&config, Some(&addr.to_string()));
    assert_eq!(again.addr, addr);
    again.expect(&["grid"]);

    wait_true(
        &mut browser,
        "the open page to update",
        "npLive.updates >= 1 && npLive.animating === 0",
    );
    let now = cell(&mut browser, "n05");
    assert_ne!(now, before, "the page shows the new map");
    assert_eq!(browser.eval("performance.timeOrigin"), origin, "no reload");
    let on_disk = std::fs::read_to_string(dir.join("out/grid.html")).expect("page");
    assert!(
        on_disk.contains(&format!("d=\"{}\"", now.as_str().unwrap_or("?"))),
        "the page shows the map on disk"
    );
    wait_true(
        &mut browser,
        "the stream to follow again",
        "document.querySelector('.np-live-status').textContent.indexOf('following grid') >= 0",
    );
}
