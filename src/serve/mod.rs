//! `nptreemap watch --serve`: the live preview (issue 25). An HTTP server
//! beside the daemon serves an index of the config's datasets, each
//! dataset's outputs (its HTML page with a live script added), and one
//! event stream that pushes every rebuild to the open pages, which morph to
//! the new layout. Owns binding (loopback and a fixed port by default, the
//! next free port when it is taken), routing, the response headers and the
//! bounds on request handling. What a path may name is `paths.rs`'s, the
//! stream is `events.rs`'s, the HTML `index.rs`'s, the browser side
//! `live.js`.
//!
//! Why tiny_http: a maintained, small, synchronous server with no async
//! runtime; the preview answers a handful of local requests and keeps a few
//! streams open, which plain threads do well. Requests are answered by a
//! small fixed pool (a full queue is answered 503 at once), event streams by
//! a thread each up to a cap; the daemon only ever hands events to bounded
//! queues without waiting, so no client can slow a rebuild. (tiny_http
//! reads each connection on a thread of its own pool, which it does not
//! cap; loopback by default keeps that to this machine.)

/// The push channel (server-sent events).
pub(crate) mod events;
/// The index page, the served page's rewriting and the security policy.
pub(crate) mod index;
/// Which file a request path names.
pub(crate) mod paths;

use std::hash::{BuildHasher, Hasher};
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::Path;
use std::sync::mpsc::{sync_channel, Receiver, TrySendError};
use std::sync::{Arc, Mutex, PoisonError};

use tiny_http::{Header, Method, Request, Response, Server};

use crate::config::OutputKind;
use crate::daemon::status::Status;
use events::Hub;
use paths::Routes;

/// The port tried first when the address names none.
pub const DEFAULT_PORT: u16 = 7878;

/// Ports tried after [`DEFAULT_PORT`] when it is taken.
const PORT_TRIES: u16 = 32;

/// Threads answering ordinary requests.
const WORKERS: usize = 4;

/// Requests waiting for a worker before more are answered 503.
const QUEUED: usize = 64;

/// Largest file served (a 20,000-leaf page is about 16 MB).
const MAX_FILE: u64 = 512 << 20;

/// The browser side of the preview.
const LIVE_JS: &str = include_str!("live.js");
/// Its style (the error overlay, the figures panel, the history control).
const LIVE_CSS: &str = include_str!("live.css");

/// Why the preview could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServeError {
    /// The address given is not `HOST`, `PORT` or `HOST:PORT`.
    #[error("--serve {0:?}: expected HOST, PORT or HOST:PORT (such as 127.0.0.1:7878)")]
    Address(String),
    /// Nothing could be bound.
    #[error("cannot listen on {addr}: {message}")]
    Bind {
        /// The last address tried.
        addr: SocketAddr,
        /// Why.
        message: String,
    },
}

/// A running preview: where it listens and what to tell open pages.
pub struct Preview {
    addr: SocketAddr,
    hub: Hub,
}

impl Preview {
    /// The line that opens `watch --serve`'s output: the URL, and whether
    /// other machines can reach it.
    pub fn first_line(&self) -> String {
        let reach = if self.addr.ip().is_loopback() {
            "listening on loopback only: other machines cannot connect"
        } else {
            "listening beyond loopback: other machines can connect"
        };
        format!("serving http://{}/ ({reach})", self.addr)
    }

    /// Hands a daemon report to the open pages; never waits for them.
    pub fn publish(&self, status: &Status) {
        self.hub.publish(status);
    }
}

/// What `--serve` was given: an address to bind exactly, or a host whose
/// default port may move on to the next free one.
fn parse_addr(text: &str) -> Result<(SocketAddr, bool), ServeError> {
    let text = text.trim();
    let loopback = IpAddr::V4(Ipv4Addr::LOCALHOST);
    if text.is_empty() {
        return Ok((SocketAddr::new(loopback, DEFAULT_PORT), true));
    }
    if let Ok(port) = text.parse::<u16>() {
        return Ok((SocketAddr::new(loopback, port), false));
    }
    if let Ok(addr) = text.parse::<SocketAddr>() {
        return Ok((addr, false));
    }
    let host = text.trim_start_matches('[').trim_end_matches(']');
    if let Ok(ip) = host.parse::<IpAddr>() {
        return Ok((SocketAddr::new(ip, DEFAULT_PORT), true));
    }
    if host == "localhost" {
        return Ok((SocketAddr::new(loopback, DEFAULT_PORT), true));
    }
    Err(ServeError::Address(text.to_string()))
}

fn bind(text: &str) -> Result<Server, ServeError> {
    let (first, flexible) = parse_addr(text)?;
    let tries = if flexible { PORT_TRIES } else { 1 };
    let mut last = String::new();
    for k in 0..tries {
        let addr = SocketAddr::new(first.ip(), first.port().saturating_add(k));
        match Server::http(addr) {
            Ok(server) => return Ok(server),
            Err(e) => last = e.to_string(),
        }
    }
    Err(ServeError::Bind {
        addr: first,
        message: last,
    })
}

/// Binds `addr` (`""` for the default) and starts serving the outputs of
/// the config at `config_path` on threads of its own, which end with the
/// process.
pub fn start(addr: &str, config_path: &Path) -> Result<Preview, ServeError> {
    let server = bind(addr)?;
    let local = server
        .server_addr()
        .to_ip()
        .ok_or_else(|| ServeError::Address(addr.to_string()))?;
    let hub = Hub::default();
    let shared = Arc::new(Shared {
        routes: Mutex::new(Routes::new(config_path)),
        hub: hub.clone(),
        title: config_path
            .file_name()
            .map_or_else(|| "nptreemap".to_string(), |n| n.to_string_lossy().into_owned()),
    });
    let (tx, rx) = sync_channel::<Request>(QUEUED);
    let rx = Arc::new(Mutex::new(rx));
    for _ in 0..WORKERS {
        let (rx, shared) = (rx.clone(), shared.clone());
        spawn("np-serve-worker", move || work(&rx, &shared));
    }
    spawn("np-serve", move || {
        for request in server.incoming_requests() {
            if !matches!(request.method(), Method::Get | Method::Head) {
                let allow = header("Allow", "GET, HEAD");
                let _ = request.respond(plain(405, "only GET and HEAD").with_header(allow));
                continue;
            }
            if paths::decode(request.url()).as_deref() == Some("/_np/events") {
                shared.hub.serve(request, &common_headers("none"));
                continue;
            }
            if let Err(TrySendError::Full(r) | TrySendError::Disconnected(r)) = tx.try_send(request)
            {
                let _ = r.respond(plain(503, "busy"));
            }
        }
    });
    Ok(Preview { addr: local, hub })
}

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) {
    if let Err(e) = std::thread::Builder::new().name(name.to_string()).spawn(f) {
        tracing::warn!(error = %e, "cannot start a thread of the preview server");
    }
}

/// What the request threads share.
struct Shared {
    routes: Mutex<Routes>,
    hub: Hub,
    title: String,
}

fn work(rx: &Mutex<Receiver<Request>>, shared: &Shared) {
    loop {
        let next = rx.lock().unwrap_or_else(PoisonError::into_inner).recv();
        let Ok(request) = next else { return };
        let response = answer(request.url(), shared);
        let _ = request.respond(response);
    }
}

type Answer = Response<std::io::Cursor<Vec<u8>>>;

/// The response to a GET (or HEAD: tiny_http leaves the body out) of `url`.
fn answer(url: &str, shared: &Shared) -> Answer {
    let nonce = nonce();
    let ok = |body: Vec<u8>, kind: &str| {
        let mut r = Response::from_data(body).with_header(header("Content-Type", kind));
        for (name, value) in headers(&nonce) {
            r.add_header(header(name, &value));
        }
        r
    };
    match paths::decode(url).as_deref() {
        Some("/_np/live.js") => return ok(LIVE_JS.into(), "text/javascript; charset=utf-8"),
        Some("/_np/live.css") => return ok(LIVE_CSS.into(), "text/css; charset=utf-8"),
        _ => {}
    }
    let (route, history) = {
        let mut routes = shared.routes.lock().unwrap_or_else(PoisonError::into_inner);
        routes.refresh();
        if paths::decode(url).as_deref() == Some("/") {
            return ok(index::index(&routes, &shared.title).into_bytes(), HTML);
        }
        (routes.find(url).cloned(), routes.history)
    };
    let Some(route) = route else {
        return plain(404, "not found");
    };
    let Some(bytes) = paths::inside(&route).and_then(|file| read(&file)) else {
        return plain(404, "not found");
    };
    match route.kind {
        OutputKind::Html => {
            let text = String::from_utf8_lossy(&bytes);
            let page = index::live_page(&text, &route.dataset, &nonce, history);
            ok(page.into_bytes(), HTML)
        }
        OutputKind::Svg => ok(bytes, "image/svg+xml"),
        OutputKind::Png => ok(bytes, "image/png"),
        OutputKind::Json => ok(bytes, "application/json"),
    }
}

const HTML: &str = "text/html; charset=utf-8";

fn read(file: &Path) -> Option<Vec<u8>> {
    use std::io::Read;
    let f = std::fs::File::open(file).ok()?;
    let mut bytes = Vec::new();
    f.take(MAX_FILE).read_to_end(&mut bytes).ok()?;
    Some(bytes)
}

/// Headers of every answer with a body of ours.
fn headers(nonce: &str) -> Vec<(&'static str, String)> {
    vec![
        ("Content-Security-Policy", index::csp(nonce)),
        ("X-Content-Type-Options", "nosniff".to_string()),
        ("Cache-Control", "no-store".to_string()),
        ("Referrer-Policy", "no-referrer".to_string()),
    ]
}

/// The same headers as raw lines (for the event stream, written by hand).
fn common_headers(nonce: &str) -> String {
    headers(nonce)
        .into_iter()
        .map(|(k, v)| format!("{k}: {v}\r\n"))
        .collect()
}

/// A short plain-text answer with `status`.
pub(crate) fn plain(status: u16, text: &str) -> Answer {
    let mut r = Response::from_data(text.as_bytes().to_vec())
        .with_status_code(status)
        .with_header(header("Content-Type", "text/plain; charset=utf-8"));
    for (name, value) in headers("none") {
        r.add_header(header(name, &value));
    }
    r
}

fn header(name: &str, value: &str) -> Header {
    // Only our own constant names and values without line breaks reach here.
    Header::from_bytes(name.as_bytes(), value.as_bytes())
        .unwrap_or_else(|()| Header::from_bytes(&b"X-Invalid"[..], &b"1"[..]).expect("constant"))
}

/// A fresh nonce per response: 128 bits from the standard library's
/// randomly keyed hasher (std seeds it from the operating system).
fn nonce() -> String {
    let state = std::collections::hash_map::RandomState::new();
    let mut out = String::new();
    for k in 0u64..2 {
        let mut h = state.build_hasher();
        h.write_u64(k);
        out.push_str(&format!("{:016x}", h.finish()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_default_to_loopback_and_a_movable_port() {
        let lo = IpAddr::V4(Ipv4Addr::LOCALHOST);
        assert_eq!(
            parse_addr("").expect("ok"),
            (SocketAddr::new(lo, DEFAULT_PORT), true)
        );
        assert_eq!(
            parse_addr("9000").expect("ok"),
            (SocketAddr::new(lo, 9000), false)
        );
        assert_eq!(
            parse_addr("0.0.0.0").expect("ok").0,
            SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), DEFAULT_PORT)
        );
        assert_eq!(
            parse_addr("[::1]:80").expect("ok").0,
            "[::1]:80".parse().expect("addr")
        );
        assert!(parse_addr("example.org:80").is_err());
    }

    #[test]
    fn nonces_differ() {
        assert_ne!(nonce(), nonce());
        assert_eq!(nonce().len(), 32);
    }
}
