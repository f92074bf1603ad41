//! A minimal Chrome DevTools Protocol driver for the browser test: finds and
//! starts headless Chromium with a fresh profile, attaches to one tab over the
//! DevTools websocket, sends commands (mouse, keys, taps, typed text),
//! evaluates JavaScript, records every event and kills the browser when
//! dropped. Every wait (the start, each reply, each condition waited for)
//! is bounded on its own by the browser's patience, not by one deadline for
//! the whole session: on a loaded machine a long session of quick steps
//! must not fail for the sum of its steps (issue 30 item 14), while any one
//! step that never happens still fails in bounded time.

use std::fs::File;
use std::io::ErrorKind;
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use tungstenite::handshake::HandshakeError;
use tungstenite::{Message, WebSocket};

/// How often polls look again: short, so a wait costs little beyond the page's
/// own reaction time.
const POLL: Duration = Duration::from_millis(20);

/// Debian's Chromium (`/usr/bin/chromium`), else a `chromium` or
/// `chromium-browser` on `PATH`; `None` when there is none.
pub(crate) fn find_chromium() -> Option<PathBuf> {
    let debian = PathBuf::from("/usr/bin/chromium");
    if debian.is_file() {
        return Some(debian);
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| ["chromium", "chromium-browser"].map(|name| dir.join(name)))
        .find(|candidate| candidate.is_file())
}

/// A running headless Chromium with one attached tab.
pub(crate) struct Browser {
    child: Child,
    ws: WebSocket<TcpStream>,
    /// The tab's flat-mode session id; commands carry it to reach the tab.
    session: String,
    next_id: u64,
    /// Every event received so far, in order (the tab's and the browser's).
    events: Vec<Value>,
    /// How long any one wait may take.
    patience: Duration,
    log: PathBuf,
    profile: PathBuf,
}

impl Browser {
    /// Starts `binary` headless with a fresh profile under `dir`, connects to
    /// its DevTools endpoint and opens a blank tab. Each wait of this browser
    /// (its start included) fails after `patience`.
    pub(crate) fn launch(binary: &Path, dir: &Path, patience: Duration) -> Browser {
        let deadline = Instant::now() + patience;
        let profile = dir.join("profile");
        let _ = std::fs::remove_dir_all(&profile);
        std::fs::create_dir_all(&profile).expect("create profile dir");
        // Chromium reports its DevTools address on stderr; a file rather than a
        // pipe keeps it from ever blocking on a full pipe and keeps the log for
        // failure messages.
        let log = dir.join("chromium.log");
        let stderr = File::create(&log).expect("create chromium log");
        let child = Command::new(binary)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--lang=en-US",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(stderr)
            .spawn()
            .unwrap_or_else(|e| panic!("start {}: {e}", binary.display()));
        // The child is owned from here on, so a failure below still kills it.
        let mut starting = Starting {
            child: Some(child),
            log: log.clone(),
        };
        let url = starting.devtools_url(deadline);
        let ws = connect(&url, deadline);
        let mut browser = Browser {
            child: starting.child.take().expect("child"),
            ws,
            session: String::new(),
            next_id: 0,
            events: Vec::new(),
            patience,
            log,
            profile,
        };
        let target = browser.call("Target.createTarget", json!({"url": "about:blank"}));
        let target_id = target["targetId"].clone();
        let attached = browser.call(
            "Target.attachToTarget",
            json!({"targetId": target_id, "flatten": true}),
        );
        browser.session = attached["sessionId"]
            .as_str()
            .expect("attachToTarget gives a sessionId")
            .to_owned();
        browser
    }

    /// Sends `method` to the tab and returns its result, recording the events
    /// that arrive meanwhile. Panics on a protocol error or past the deadline.
    pub(crate) fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            message["sessionId"] = Value::from(self.session.clone());
        }
        self.ws
            .send(Message::text(message.to_string()))
            .unwrap_or_else(|e| panic!("send {method}: {e}"));
        let deadline = Instant::now() + self.patience;
        loop {
            let reply = self.receive(method, deadline);
            if reply["id"].as_u64() == Some(id) {
                if let Some(error) = reply.get("error") {
                    panic!("{method} failed: {error}");
                }
                return reply["result"].clone();
            }
            if reply.get("method").is_some() {
                self.events.push(reply);
            }
        }
    }

    /// Evaluates `expression` in the page and returns its value as JSON.
    pub(crate) fn eval(&mut self, expression: &str) -> Value {
        let result = self.call(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true}),
        );
        if let Some(details) = result.get("exceptionDetails") {
            panic!("evaluating {expression}\nthrew {details}");
        }
        result["result"]["value"].clone()
    }

    /// Evaluates `expression`, a promise, and returns the value it resolves
    /// to, once it has (bounded by the browser's patience).
    pub(crate) fn eval_await(&mut self, expression: &str) -> Value {
        let result = self.call(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true, "awaitPromise": true}),
        );
        if let Some(details) = result.get("exceptionDetails") {
            panic!("awaiting {expression}\nthrew {details}");
        }
        result["result"]["value"].clone()
    }

    /// Returns once the page has drawn two more frames after `ms`
    /// milliseconds: what it changed before the call is then on screen.
    /// Awaited in the page, so a loaded machine makes it longer, never
    /// short.
    pub(crate) fn settle(&mut self, ms: u32) {
        self.eval_await(&format!(
            "new Promise(function (r) {{ setTimeout(function () {{ \
             requestAnimationFrame(function () {{ requestAnimationFrame(function () {{ r(0); }}); }}); \
             }}, {ms}); }})"
        ));
    }

    /// Evaluates `expression` every few milliseconds until `check` accepts
    /// its value, and returns that value; past the browser's patience,
    /// panics naming `what` with the last complaint of `check`.
    pub(crate) fn wait_for(
        &mut self,
        what: &str,
        expression: &str,
        check: impl Fn(&Value) -> Result<(), String>,
    ) -> Value {
        let deadline = Instant::now() + self.patience;
        loop {
            let value = self.eval(expression);
            match check(&value) {
                Ok(()) => return value,
                Err(complaint) if Instant::now() >= deadline => {
                    panic!("timed out waiting for {what}: {complaint}")
                }
                Err(_) => std::thread::sleep(POLL),
            }
        }
    }

    /// Opens `url` in the tab and waits until its document has loaded.
    pub(crate) fn open(&mut self, url: &str) {
        self.call("Page.navigate", json!({ "url": url }));
        let expected = serde_json::to_string(url).expect("url as JSON");
        self.wait_for(
            &format!("{url} to load"),
            &format!("location.href === {expected} && document.readyState === 'complete'"),
            |v| match v {
                Value::Bool(true) => Ok(()),
                _ => Err(format!("not loaded yet ({v})")),
            },
        );
    }

    /// Moves the real mouse pointer to viewport point (`x`, `y`).
    pub(crate) fn mouse_move(&mut self, x: f64, y: f64) {
        self.call(
            "Input.dispatchMouseEvent",
            json!({"type": "mouseMoved", "x": x, "y": y, "button": "none"}),
        );
    }

    /// Clicks the left mouse button at viewport point (`x`, `y`).
    pub(crate) fn click(&mut self, x: f64, y: f64) {
        self.mouse_move(x, y);
        for kind in ["mousePressed", "mouseReleased"] {
            self.call(
                "Input.dispatchMouseEvent",
                json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": 1, "clickCount": 1}),
            );
        }
    }

    /// Taps the touch screen at viewport point (`x`, `y`): one finger down
    /// and up (the page must have touch emulation on to see a tap).
    pub(crate) fn tap(&mut self, x: f64, y: f64) {
        self.call(
            "Input.dispatchTouchEvent",
            json!({"type": "touchStart", "touchPoints": [{"x": x, "y": y}]}),
        );
        self.call(
            "Input.dispatchTouchEvent",
            json!({"type": "touchEnd", "touchPoints": []}),
        );
    }

    /// Types `text` into the focused element, as an input method would.
    pub(crate) fn insert_text(&mut self, text: &str) {
        self.call("Input.insertText", json!({ "text": text }));
    }

    /// The events received so far whose method is `method`.
    pub(crate) fn events(&self, method: &str) -> Vec<&Value> {
        self.events
            .iter()
            .filter(|e| e["method"] == method)
            .collect()
    }

    /// The next message from the browser; `during` names the command waited
    /// for in the panic message past `deadline`.
    fn receive(&mut self, during: &str, deadline: Instant) -> Value {
        loop {
            match self.ws.read() {
                Ok(Message::Text(text)) => {
                    return serde_json::from_str(text.as_str()).expect("DevTools sends JSON")
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(e) => panic!("DevTools connection failed during {during}: {e}"),
            }
            if Instant::now() >= deadline {
                panic!(
                    "timed out waiting for the reply to {during}\n{}",
                    log_tail(&self.log)
                );
            }
        }
    }
}

impl Drop for Browser {
    /// Kills the browser (its helper processes exit with it) and removes the
    /// profile, so neither a pass nor a failure leaves Chromium running.
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}

/// The browser between spawning and connecting: kills it if startup fails.
struct Starting {
    child: Option<Child>,
    log: PathBuf,
}

impl Starting {
    /// The `ws://` address Chromium prints on stderr once DevTools listens.
    fn devtools_url(&mut self, deadline: Instant) -> String {
        const MARK: &str = "DevTools listening on ";
        loop {
            let text = std::fs::read_to_string(&self.log).unwrap_or_default();
            if let Some(line) = text.lines().find_map(|l| l.strip_prefix(MARK)) {
                return line.trim().to_owned();
            }
            let child = self.child.as_mut().expect("child");
            if let Ok(Some(status)) = child.try_wait() {
                panic!("chromium exited with {status} before DevTools listened\n{text}");
            }
            if Instant::now() >= deadline {
                panic!(
                    "chromium did not report its DevTools address in time\n{}",
                    log_tail(&self.log)
                );
            }
            std::thread::sleep(POLL);
        }
    }
}

impl Drop for Starting {
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// Opens the websocket at `url` (`ws://127.0.0.1:PORT/devtools/browser/...`).
fn connect(url: &str, deadline: Instant) -> WebSocket<TcpStream> {
    let authority = url
        .strip_prefix("ws://")
        .and_then(|rest| rest.split('/').next())
        .unwrap_or_else(|| panic!("unexpected DevTools address {url}"));
    let address = authority
        .parse()
        .unwrap_or_else(|e| panic!("DevTools address {authority}: {e}"));
    let stream = TcpStream::connect_timeout(&address, Duration::from_secs(5))
        .unwrap_or_else(|e| panic!("connect to {url}: {e}"));
    // Reads time out quickly so every loop can check the deadline.
    stream
        .set_read_timeout(Some(Duration::from_millis(100)))
        .expect("set read timeout");
    let mut attempt = tungstenite::client::client(url, stream);
    loop {
        match attempt {
            Ok((ws, _)) => return ws,
            Err(HandshakeError::Interrupted(mid)) if Instant::now() < deadline => {
                attempt = mid.handshake();
            }
            Err(HandshakeError::Interrupted(_)) => panic!("websocket handshake timed out"),
            Err(HandshakeError::Failure(e)) => panic!("websocket handshake with {url}: {e}"),
        }
    }
}

/// The last lines of Chromium's log, for failure messages.
fn log_tail(log: &Path) -> String {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.len().saturating_sub(20);
    format!(
        "chromium log ({}):\n{}",
        log.display(),
        lines[start..].join("\n")
    )
}
