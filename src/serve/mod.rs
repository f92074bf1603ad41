//! `nptreemap watch --serve`: the live preview (issue 25). An HTTP server
//! beside the daemon serves an index of the config's datasets, each
//! dataset's outputs (its HTML page with a live script added), and one
//! event stream that pushes every rebuild to the open pages, which morph to
//! the new layout. Owns the address (loopback and a fixed port by default,
//! the next free port when it is taken; host names only when they resolve
//! to loopback; never a broadcast or multicast address), routing, the
//! response headers and the runtime. Which requests are ours is `host.rs`'s,
//! the connections and their bounds `conn.rs`'s, the bodies and their
//! memory budget `body.rs`'s, what a path may name `paths.rs`'s, the stream
//! `events.rs`'s, the HTML `index.rs`'s, the browser side `live.js`.
//!
//! Why hyper on tokio (issue 30): the preview must stay answerable whatever
//! a client does, and tiny_http, used before, could not: it started a
//! thread per connection (2,000 idle sockets, 1,900 threads; a failed spawn
//! killed its accept loop for good) and buffered a request head whole (a
//! 300 MB header line, 319 MB of memory). hyper's HTTP/1 server bounds a
//! head in size and time, and on a one-thread tokio runtime every
//! connection is a task: an idle or stuck client costs a few KiB, not a
//! thread, and no client can hold a worker that others need. File reads
//! and the page's rewriting run on at most [`WORKERS`] blocking threads.
//! Cost (BENCHMARKS.md, "The preview server's crates"): the release binary
//! grows by 0.36 MB (2%), a clean release build by about 15 s on two cores
//! (of about 7 minutes); only HTTP/1, the server side and tokio's
//! current-thread scheduler are compiled. Under attack `/` is answered in
//! well under a millisecond (median), where tiny_http spent 1,900 threads,
//! 300 MB, or did not answer at all. The daemon only
//! ever hands events to bounded queues without waiting, so no client can
//! slow a rebuild.

/// The response bodies and their memory budget.
pub(crate) mod body;
/// Connections: the cap, the head limits, the write timeout.
pub(crate) mod conn;
/// The push channel (server-sent events).
pub(crate) mod events;
/// Which Host values are this server's (DNS rebinding).
pub(crate) mod host;
/// The index page, the served page's rewriting and the security policy.
pub(crate) mod index;
/// The pages served lately, for patches.
pub(crate) mod pages;
/// Which file a request path names.
pub(crate) mod paths;

use std::hash::{BuildHasher, Hasher};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, ToSocketAddrs};
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use hyper::header::{HeaderValue, ALLOW, HOST};
use hyper::{Method, Request, Response, StatusCode, Version};
use tokio::sync::Semaphore;

use crate::render::OutputKind;
use crate::daemon::status::Status;
use body::{Body, Hold};
use events::Hub;
use paths::Routes;

/// The port tried first when the address names none.
pub const DEFAULT_PORT: u16 = 7878;

/// Ports tried after [`DEFAULT_PORT`] when it is taken.
const PORT_TRIES: u16 = 32;

/// Threads reading files and rewriting pages (tokio's blocking pool).
const WORKERS: usize = 4;

/// Largest file served (a 20,000-leaf page is about 16 MB).
const MAX_FILE: u64 = 512 << 20;

/// How long a request waits for room in the body budget before it is
/// answered 503.
const BUDGET_WAIT: Duration = Duration::from_secs(5);

/// The browser side of the preview: `live.js` and the morph it imports from
/// the page's own steps (`render/page/history.js`), bundled at build time
/// into one function scope (`render/page/bundle.rs`, run by `build.rs`), so
/// that no name of its reaches the page's.
const LIVE_JS: &str = include_str!(concat!(env!("OUT_DIR"), "/live.js"));
/// Its style (the error overlay, the figures panel).
const LIVE_CSS: &str = include_str!("live.css");

/// Why the preview could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServeError {
    /// The address given is not `HOST`, `PORT` or `HOST:PORT`.
    #[error("--serve {0:?}: expected HOST, PORT or HOST:PORT (such as 127.0.0.1:7878)")]
    Address(String),
    /// The address given is one a server cannot or should not listen on.
    #[error("--serve {given:?}: {why}")]
    Refused {
        /// The address as given.
        given: String,
        /// What is wrong with it.
        why: String,
    },
    /// Nothing could be bound.
    #[error("cannot listen on {addr}: {message}")]
    Bind {
        /// The last address tried.
        addr: SocketAddr,
        /// Why.
        message: String,
    },
}

impl ServeError {
    /// Whether the address given is at fault (the arguments' fault, exit
    /// code 2), rather than the machine.
    pub fn is_usage(&self) -> bool {
        matches!(self, ServeError::Address(_) | ServeError::Refused { .. })
    }
}

/// A running preview: where it listens and what to tell open pages.
pub struct Preview {
    addr: SocketAddr,
    hub: Hub,
    /// The URL path of the first page (`--open`'s): the first HTML output,
    /// else the index.
    first: String,
}

impl Preview {
    /// The line that opens `watch --serve`'s output: the URL, and whether
    /// other machines can reach it.
    pub fn first_line(&self) -> String {
        format!("serving http://{}/ ({})", self.addr, reach(self.addr.ip()))
    }

    /// The URL `--open` opens: the first dataset's page (the index when no
    /// output is a page), on a loopback address when the server listens on
    /// every address.
    pub fn first_page(&self) -> String {
        let mut addr = self.addr;
        if addr.ip().is_unspecified() {
            addr.set_ip(match addr.ip() {
                IpAddr::V4(_) => IpAddr::V4(Ipv4Addr::LOCALHOST),
                IpAddr::V6(_) => IpAddr::V6(std::net::Ipv6Addr::LOCALHOST),
            });
        }
        format!("http://{addr}{}", paths::encode(&self.first))
    }

    /// Hands a daemon report to the open pages; never waits for them.
    pub fn publish(&self, status: &Status) {
        self.hub.publish(status);
    }
}

/// Who can connect to a server listening on `ip`. Broadcast and multicast
/// addresses are refused before this ([`refuse`]), so what is not loopback
/// is the unspecified address or a unicast one: other machines can connect.
fn reach(ip: IpAddr) -> &'static str {
    if ip.to_canonical().is_loopback() {
        "listening on loopback only: other machines cannot connect"
    } else {
        "listening beyond loopback: other machines can connect"
    }
}

/// Why a server may not listen on `ip`, if it may not.
fn refuse(ip: IpAddr) -> Option<&'static str> {
    match ip.to_canonical() {
        IpAddr::V4(v4) if v4.is_broadcast() => Some(
            "a broadcast address cannot be listened on; give a loopback (127.0.0.1), \
             unspecified (0.0.0.0) or unicast address of this machine",
        ),
        ip if ip.is_multicast() => Some(
            "a multicast address cannot be listened on; give a loopback (127.0.0.1), \
             unspecified (0.0.0.0) or unicast address of this machine",
        ),
        _ => None,
    }
}

/// What `--serve` was given: an address to bind exactly, or a host whose
/// default port may move on to the next free one. A host name must resolve
/// to a loopback address, which is bound (the first IPv4 one if any).
fn parse_addr(text: &str) -> Result<(SocketAddr, bool), ServeError> {
    let text = text.trim();
    let loopback = IpAddr::V4(Ipv4Addr::LOCALHOST);
    let (addr, flexible) = if text.is_empty() {
        (SocketAddr::new(loopback, DEFAULT_PORT), true)
    } else if let Ok(port) = text.parse::<u16>() {
        (SocketAddr::new(loopback, port), false)
    } else if let Ok(addr) = text.parse::<SocketAddr>() {
        (addr, false)
    } else if let Ok(ip) = text
        .trim_start_matches('[')
        .trim_end_matches(']')
        .parse::<IpAddr>()
    {
        (SocketAddr::new(ip, DEFAULT_PORT), true)
    } else {
        by_name(text)?
    };
    if let Some(why) = refuse(addr.ip()) {
        return Err(ServeError::Refused {
            given: text.to_string(),
            why: why.to_string(),
        });
    }
    Ok((addr, flexible))
}

/// `NAME` or `NAME:PORT`, the name resolved to a loopback address.
fn by_name(text: &str) -> Result<(SocketAddr, bool), ServeError> {
    let (name, port, flexible) = match text.rsplit_once(':') {
        Some((name, port)) => match port.parse::<u16>() {
            Ok(port) => (name, port, false),
            Err(_) => return Err(ServeError::Address(text.to_string())),
        },
        None => (text, DEFAULT_PORT, true),
    };
    let plain = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '.';
    if name.is_empty() || !name.chars().all(plain) {
        return Err(ServeError::Address(text.to_string()));
    }
    let found: Vec<SocketAddr> = (name, port)
        .to_socket_addrs()
        .map(Iterator::collect)
        .unwrap_or_default();
    let lo = |a: &&SocketAddr| a.ip().to_canonical().is_loopback();
    let pick = found
        .iter()
        .filter(lo)
        .find(|a| a.is_ipv4())
        .or_else(|| found.iter().find(lo));
    match pick {
        Some(addr) => Ok((*addr, flexible)),
        None => Err(ServeError::Refused {
            given: text.to_string(),
            why: format!(
                "{name} does not resolve to a loopback address here (a host name must name this \
                 machine's loopback; to listen beyond it, give an IP address such as 0.0.0.0)"
            ),
        }),
    }
}

fn bind(text: &str) -> Result<std::net::TcpListener, ServeError> {
    let (first, flexible) = parse_addr(text)?;
    let tries = if flexible { PORT_TRIES } else { 1 };
    let mut last = String::new();
    for k in 0..tries {
        let addr = SocketAddr::new(first.ip(), first.port().saturating_add(k));
        match std::net::TcpListener::bind(addr).and_then(|l| l.set_nonblocking(true).map(|()| l)) {
            Ok(listener) => return Ok(listener),
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
    let listener = bind(addr)?;
    let local = listener.local_addr().map_err(|e| ServeError::Bind {
        addr: SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0),
        message: e.to_string(),
    })?;
    let failed = |e: std::io::Error| ServeError::Bind {
        addr: local,
        message: e.to_string(),
    };
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .enable_time()
        .max_blocking_threads(WORKERS)
        .thread_name("np-serve-worker")
        .build()
        .map_err(failed)?;
    let hub = Hub::new(&nonce()[..16]);
    let routes = Routes::new(config_path);
    let first = routes.first_page();
    let shared = Arc::new(Shared {
        routes: Mutex::new(routes),
        hub: hub.clone(),
        title: config_path
            .file_name()
            .map_or_else(|| "nptreemap".to_string(), |n| n.to_string_lossy().into_owned()),
        port: local.port(),
        budget: Arc::new(Semaphore::new(body::BUDGET_KIB as usize)),
        pages: Mutex::new(pages::Pages::default()),
    });
    std::thread::Builder::new()
        .name("np-serve".to_string())
        .spawn(move || runtime.block_on(conn::accept(listener, shared)))
        .map_err(failed)?;
    Ok(Preview {
        addr: local,
        hub,
        first,
    })
}

/// What the connections share.
pub(crate) struct Shared {
    routes: Mutex<Routes>,
    hub: Hub,
    title: String,
    /// The port listened on (what `Host` must name).
    port: u16,
    /// Room for bodies in memory, in KiB ([`body::BUDGET_KIB`]).
    budget: Arc<Semaphore>,
    /// The pages served lately, which patches start from.
    pages: Mutex<pages::Pages>,
}

type Answer = Response<Body>;

/// The answer to one request that reached `local`.
pub(crate) async fn handle<B>(request: Request<B>, shared: &Arc<Shared>, local: SocketAddr) -> Answer {
    if let Some(refused) = check_host(&request, shared.port, local.ip()) {
        return refused;
    }
    if !matches!(*request.method(), Method::GET | Method::HEAD) {
        let mut r = plain(405, "only GET and HEAD");
        r.headers_mut()
            .insert(ALLOW, HeaderValue::from_static("GET, HEAD"));
        return r;
    }
    let target = request
        .uri()
        .path_and_query()
        .map_or("/", |p| p.as_str())
        .to_string();
    if paths::decode(&target).as_deref() == Some("/_np/events") {
        return match shared.hub.subscribe() {
            Some(stream) => {
                let mut r = Response::new(Body::Events(Box::new(stream), Hold::default()));
                for (name, value) in headers("none") {
                    insert(&mut r, name, &value);
                }
                insert(&mut r, "Content-Type", "text/event-stream");
                r
            }
            None => plain(503, "too many open pages"),
        };
    }
    let found = {
        let shared = shared.clone();
        tokio::task::spawn_blocking(move || route(&target, &shared)).await
    };
    match found {
        Ok(Routed::Ready(answer)) => answer,
        Ok(Routed::File(file)) => load(file, shared).await,
        Err(_) => plain(500, "internal error"),
    }
}

/// Refuses a request that does not name this server (see `host.rs`): 421,
/// or 400 when HTTP/1.1's required `Host` is missing or repeated.
fn check_host<B>(request: &Request<B>, port: u16, local: IpAddr) -> Option<Answer> {
    let hosts: Vec<&HeaderValue> = request.headers().get_all(HOST).iter().collect();
    if hosts.len() > 1 || (hosts.is_empty() && request.version() >= Version::HTTP_11) {
        return Some(plain(400, "one Host header is required"));
    }
    let named = hosts
        .iter()
        .map(|h| h.to_str().unwrap_or(""))
        .chain(request.uri().authority().map(|a| a.as_str()));
    for host in named {
        if !host::allowed(host, local, port) {
            let text = format!(
                "this server answers requests for localhost:{port} or 127.0.0.1:{port} only"
            );
            return Some(plain(421, &text));
        }
    }
    None
}

/// A file to read for a request, with what its answer needs.
struct FileAnswer {
    file: crate::workspace::Opened,
    len: u64,
    kind: OutputKind,
    dataset: String,
    key: String,
    /// For a page: the key of the page the asker has, when it asks for
    /// the changes since (`?since=KEY`) instead of the whole page.
    since: Option<String>,
}

enum Routed {
    Ready(Answer),
    File(FileAnswer),
}

/// What `target` names: an answer at once (the index, the live script and
/// style, 404), or an output file, opened.
fn route(target: &str, shared: &Shared) -> Routed {
    let decoded = paths::decode(target);
    match decoded.as_deref() {
        Some("/_np/live.js") => {
            return Routed::Ready(ok(LIVE_JS, "text/javascript; charset=utf-8", "none"));
        }
        Some("/_np/live.css") => {
            return Routed::Ready(ok(LIVE_CSS, "text/css; charset=utf-8", "none"))
        }
        _ => {}
    }
    let route = {
        let mut routes = shared.routes.lock().unwrap_or_else(PoisonError::into_inner);
        routes.refresh();
        if decoded.as_deref() == Some("/") {
            let page = index::index(&routes, &shared.title);
            return Routed::Ready(ok(page, OutputKind::Html.content_type(), "none"));
        }
        match routes.find(target) {
            Some(route) => Ok(route.clone()),
            None => Err(routes.moved(target).map(str::to_string)),
        }
    };
    let route = match route {
        Ok(route) => route,
        Err(Some(now)) => return Routed::Ready(moved(&now)),
        Err(None) => return Routed::Ready(plain(404, "not found")),
    };
    // The key before the file: a page's key is never newer than its bytes.
    let key = shared.hub.key(&route.dataset);
    match paths::inside(&route).and_then(|file| open(&file)) {
        Some((file, len)) => Routed::File(FileAnswer {
            file,
            len,
            since: pages::since(target)
                .filter(|_| route.kind == OutputKind::Html)
                .map(str::to_string),
            kind: route.kind,
            dataset: route.dataset,
            key,
        }),
        None => Routed::Ready(plain(404, "not found")),
    }
}

/// Reads an output within the body budget and answers with it: a page
/// with the live script, and noted for later patches; or, asked `since` a
/// page it noted, the patch from that page to this one (204 when only
/// the whole page will do).
async fn load(file: FileAnswer, shared: &Arc<Shared>) -> Answer {
    let share = body::share(file.len);
    let waited = tokio::time::timeout(
        BUDGET_WAIT,
        shared.budget.clone().acquire_many_owned(share),
    )
    .await;
    let Ok(Ok(permit)) = waited else {
        return plain(503, "busy: too many large answers under way");
    };
    let shared = shared.clone();
    let read = tokio::task::spawn_blocking(move || {
        let nonce = nonce();
        let bytes = read(file.file)?;
        Some(match file.kind {
            OutputKind::Html => {
                let text: Arc<str> = String::from_utf8_lossy(&bytes).into();
                let before = {
                    let mut pages = shared.pages.lock().unwrap_or_else(PoisonError::into_inner);
                    let before = file.since.as_deref().and_then(|k| pages.get(&file.dataset, k));
                    pages.remember(&file.dataset, &file.key, &text);
                    before
                };
                match (&file.since, before) {
                    (Some(_), Some(before)) => {
                        match crate::render::page_patch(&before, &text, &file.key) {
                            Some(patch) => ok(patch, "application/json", "none"),
                            None => plain(204, ""),
                        }
                    }
                    (Some(_), None) => plain(204, ""),
                    (None, _) => {
                        let page = index::live_page(&text, &file.dataset, &nonce, &file.key);
                        ok(page, OutputKind::Html.content_type(), &nonce)
                    }
                }
            }
            kind => ok(bytes, kind.content_type(), &nonce),
        })
    })
    .await;
    match read {
        Ok(Some(mut answer)) => {
            if let Body::Bytes { hold, .. } = answer.body_mut() {
                hold.budget = Some(permit);
            }
            answer
        }
        _ => plain(404, "not found"),
    }
}


fn open(file: &Path) -> Option<(crate::workspace::Opened, u64)> {
    crate::workspace::open_capped(file, MAX_FILE)
}

fn read(file: crate::workspace::Opened) -> Option<Vec<u8>> {
    crate::workspace::read_opened(file, MAX_FILE)
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

fn insert(r: &mut Answer, name: &'static str, value: &str) {
    // Only our own constant names, and values without line breaks.
    if let Ok(v) = HeaderValue::from_str(value) {
        r.headers_mut().insert(name, v);
    }
}

/// A 200 answer of `body` as `kind`, its scripts allowed by `nonce`.
fn ok(body: impl Into<bytes::Bytes>, kind: &str, nonce: &str) -> Answer {
    let mut r = Response::new(Body::bytes(body));
    insert(&mut r, "Content-Type", kind);
    for (name, value) in headers(nonce) {
        insert(&mut r, name, &value);
    }
    r
}

/// A short plain-text answer with `status`.
pub(crate) fn plain(status: u16, text: &str) -> Answer {
    let mut r = ok(text.to_string(), "text/plain; charset=utf-8", "none");
    *r.status_mut() = StatusCode::from_u16(status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
    r
}

/// A permanent redirect (308: the method and body are kept) to `path`, an
/// output's URL path now that it is served where it lies.
fn moved(path: &str) -> Answer {
    let mut r = plain(308, &format!("moved to {path}"));
    insert(&mut r, "Location", &paths::encode(path));
    r
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
        assert!(parse_addr("a b:80").is_err());
    }

    #[test]
    fn loopback_names_resolve_and_broadcast_and_multicast_are_refused() {
        let (addr, flexible) = parse_addr("localhost:8123").expect("localhost");
        assert!(addr.ip().is_loopback() && addr.port() == 8123 && !flexible);
        assert!(parse_addr("localhost").expect("localhost").1, "no port: movable");
        for bad in [
            "255.255.255.255",
            "255.255.255.255:80",
            "224.0.0.1",
            "239.255.255.250:1900",
            "[ff02::1]:80",
            "ff05::2",
            "[::ffff:224.0.0.1]:80",
        ] {
            let e = parse_addr(bad).expect_err(bad);
            assert!(e.is_usage(), "{bad}: {e}");
            let text = e.to_string();
            assert!(text.contains(bad) && text.contains("cannot be listened on"), "{text}");
        }
    }

    #[test]
    fn only_loopback_says_other_machines_cannot_connect() {
        for ip in ["127.0.0.1", "127.0.0.2", "::1", "::ffff:127.0.0.1"] {
            let ip: IpAddr = ip.parse().expect("ip");
            assert!(reach(ip).contains("cannot connect"), "{ip}");
        }
        for ip in ["0.0.0.0", "::", "192.0.2.7", "2001:db8::1", "169.254.1.1"] {
            let ip: IpAddr = ip.parse().expect("ip");
            assert!(reach(ip).contains("can connect"), "{ip}");
            assert_eq!(refuse(ip), None, "{ip}");
        }
    }

    #[test]
    fn nonces_differ() {
        assert_ne!(nonce(), nonce());
        assert_eq!(nonce().len(), 32);
    }
}
