//! The preview server against hostile clients (issue 30, items 1 to 5): a
//! Host naming another site (DNS rebinding) is refused; a request head that
//! never ends, in size or in time, is cut off without being buffered; a
//! flood of idle connections starts no thread per connection and leaves the
//! port answering; readers that never read hold only their own
//! connections, which the server drops once their writes stall; `--serve`
//! takes a host name that resolves to loopback and refuses broadcast and
//! multicast addresses. After every attack `/` is answered and the daemon
//! is alive.
//!
//! Deadlines here are bounds on a hang, several seconds wide for a loaded
//! two-core machine; the real latencies are printed and measured in
//! `benches/serve_attacks.py` (BENCHMARKS.md).

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

use super::{get, setup, Reply, Served};
use crate::support;

/// How long `/` may take under attack before the test fails: the issue asks
/// for a second; a loaded CI machine gets slack (the real figure is printed).
const ANSWERED: Duration = Duration::from_secs(8);

/// A field of `/proc/<pid>/status` (`VmHWM`, `Threads`, ...), as a number.
fn proc_status(pid: u32, field: &str) -> u64 {
    let text = std::fs::read_to_string(format!("/proc/{pid}/status")).expect("proc status");
    text.lines()
        .find_map(|l| l.strip_prefix(field)?.strip_prefix(':'))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| panic!("no {field} in /proc/{pid}/status"))
}

/// Open file descriptors of `pid`.
fn open_fds(pid: u32) -> usize {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|d| d.count())
        .unwrap_or(0)
}

/// Sends `head` (the whole request head, as written) and reads the answer,
/// within `bound`.
fn raw(addr: SocketAddr, head: &str, bound: Duration) -> Reply {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(bound)).expect("timeout");
    s.write_all(head.as_bytes()).expect("send");
    let mut raw = Vec::new();
    let _ = s.read_to_end(&mut raw);
    super::parse_reply(&raw)
}

/// `GET target` with `host` as the Host header (none when `None`).
fn get_as(addr: SocketAddr, target: &str, host: Option<&str>) -> Reply {
    let host = host.map_or(String::new(), |h| format!("Host: {h}\r\n"));
    raw(
        addr,
        &format!("GET {target} HTTP/1.1\r\n{host}Connection: close\r\n\r\n"),
        Duration::from_secs(30),
    )
}

/// Asserts that `/` is answered 200 within [`ANSWERED`] and the daemon is
/// alive; returns how long the answer took.
fn answers(served: &mut Served, after: &str) -> Duration {
    let started = Instant::now();
    let reply = raw(
        served.addr,
        &format!(
            "GET / HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n\r\n",
            served.addr
        ),
        ANSWERED,
    );
    let took = started.elapsed();
    assert_eq!(reply.status, 200, "/ after {after}: {}", reply.text());
    assert!(took < ANSWERED, "/ took {took:?} after {after}");
    assert!(
        served.child.try_wait().expect("try_wait").is_none(),
        "the daemon died after {after}"
    );
    let _ = writeln!(std::io::stderr(), "/ answered in {took:?} after {after}");
    took
}

#[test]
fn a_rebinding_host_is_refused() {
    let (_dir, config) = setup("serve_rebinding");
    let mut served = Served::start(&config, None);
    served.expect(&["grid", "wrote"]);
    let addr = served.addr;
    let port = addr.port();
    for target in ["/", "/out/grid.html", "/out/grid.svg", "/_np/events"] {
        for host in [
            format!("evil.example:{port}"),
            "evil.example".to_string(),
            format!("127.0.0.1.evil.example:{port}"),
            format!("localhost.evil.example:{port}"),
            format!("127.0.0.1:{}", port.wrapping_add(1)),
            "localhost".to_string(),
        ] {
            let reply = get_as(addr, target, Some(&host));
            assert!(
                matches!(reply.status, 421 | 403),
                "{target} with Host {host}: {} {}",
                reply.status,
                reply.text()
            );
            assert!(!reply.text().contains("<svg"), "{target} with Host {host}");
        }
        // HTTP/1.1 requires a Host; a request without one is refused too.
        let reply = get_as(addr, target, None);
        assert!(
            (400..500).contains(&reply.status),
            "{target} without Host: {}",
            reply.status
        );
    }
    // A request target in absolute form names its host itself.
    let reply = get_as(
        addr,
        &format!("http://evil.example:{port}/out/grid.html"),
        Some(&addr.to_string()),
    );
    assert!(matches!(reply.status, 421 | 403 | 404), "{}", reply.status);
    assert!(!reply.text().contains("<svg"));
    // The names of this machine's loopback, with the port, are answered.
    for host in [
        addr.to_string(),
        format!("localhost:{port}"),
        format!("LocalHost:{port}"),
        format!("[::1]:{port}"),
    ] {
        let reply = get_as(addr, "/out/grid.svg", Some(&host));
        assert_eq!(reply.status, 200, "Host {host}: {}", reply.text());
    }
    answers(&mut served, "rebinding Hosts");
}

#[test]
fn a_request_head_that_never_ends_is_cut_off_without_being_kept() {
    let (_dir, config) = setup("serve_long_head");
    let mut served = Served::start(&config, None);
    served.expect(&["grid", "wrote"]);
    let pid = served.child.id();
    let before = proc_status(pid, "VmHWM");
    // 300 MB of one header line, in 1 MB writes, until the server closes.
    const TOTAL: usize = 300 << 20;
    let chunk = vec![b'a'; 1 << 20];
    let mut s = TcpStream::connect(served.addr).expect("connect");
    s.set_write_timeout(Some(Duration::from_secs(20)))
        .expect("timeout");
    write!(s, "GET / HTTP/1.1\r\nHost: {}\r\nX-Long: ", served.addr).expect("send");
    let mut sent = 0;
    let stopped = loop {
        if sent >= TOTAL {
            break None;
        }
        match s.write(&chunk) {
            Ok(n) => sent += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => break Some(e),
        }
    };
    let peak = proc_status(pid, "VmHWM");
    let _ = writeln!(
        std::io::stderr(),
        "sent {} MB before {stopped:?}; VmHWM {before} kB -> {peak} kB",
        sent >> 20
    );
    assert!(
        stopped.is_some(),
        "the server read all 300 MB of one header line"
    );
    // What the server kept of it: a bounded head, not the line.
    assert!(
        peak < before + 64 * 1024,
        "the daemon's peak memory grew from {before} kB to {peak} kB"
    );
    drop(s);
    answers(&mut served, "a 300 MB header line");

    // A head sent a byte at a time, never finished: dropped in bounded time.
    let mut slow = TcpStream::connect(served.addr).expect("connect");
    slow.set_write_timeout(Some(Duration::from_secs(5)))
        .expect("timeout");
    write!(slow, "GET / HTTP/1.1\r\nHost: {}\r\nX-Slow: ", served.addr).expect("send");
    let started = Instant::now();
    let cut = loop {
        assert!(
            started.elapsed() < Duration::from_secs(90),
            "a head trickling in for 90 s is still being read"
        );
        // One byte every 200 ms, until the server has closed the connection
        // (a write then fails, once the kernel has seen the close).
        std::thread::sleep(Duration::from_millis(200));
        if slow.write_all(b"a").is_err() {
            break started.elapsed();
        }
    };
    let _ = writeln!(std::io::stderr(), "a trickling head was cut after {cut:?}");
    answers(&mut served, "a trickling head");
}

/// Raises this process's open-file soft limit to what `want` sockets need,
/// and returns how many sockets that limit allows.
fn room_for_sockets(want: usize) -> usize {
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit/setrlimit with a valid resource and a pointer to a
    // local struct.
    unsafe {
        if libc::getrlimit(libc::RLIMIT_NOFILE, &mut lim) != 0 {
            return 0;
        }
        let need = (want + 256) as libc::rlim_t;
        if lim.rlim_cur < need {
            lim.rlim_cur = need.min(lim.rlim_max);
            libc::setrlimit(libc::RLIMIT_NOFILE, &lim);
            libc::getrlimit(libc::RLIMIT_NOFILE, &mut lim);
        }
    }
    (lim.rlim_cur as usize).saturating_sub(256).min(want)
}

#[test]
fn an_idle_connection_flood_starts_no_threads_and_leaves_the_port_answering() {
    const FLOOD: usize = 2000;
    let n = room_for_sockets(FLOOD);
    if n < FLOOD {
        let _ = writeln!(
            std::io::stderr(),
            "the open-file hard limit allows only {n} sockets: flooding with {n}, not {FLOOD}"
        );
    }
    let (_dir, config) = setup("serve_flood");
    let mut served = Served::start(&config, None);
    served.expect(&["grid", "wrote"]);
    let pid = served.child.id();
    let threads_before = proc_status(pid, "Threads");
    let mut flood = Vec::with_capacity(n);
    for k in 0..n {
        match TcpStream::connect(served.addr) {
            Ok(s) => flood.push(s),
            // Refused, or timed out in a full backlog: the server is
            // shedding; what counts is that it still answers.
            Err(e) => {
                let _ = writeln!(std::io::stderr(), "connection {k} of the flood: {e}");
            }
        }
    }
    let took = answers(&mut served, &format!("{} idle connections", flood.len()));
    let threads = proc_status(pid, "Threads");
    let _ = writeln!(
        std::io::stderr(),
        "flood of {}: threads {threads_before} -> {threads}, / in {took:?}",
        flood.len()
    );
    assert!(
        threads < threads_before + 16,
        "{} idle connections took the daemon from {threads_before} to {threads} threads",
        flood.len()
    );
    drop(flood);
    answers(&mut served, "the flood ended");
}

/// A connection that asks for `target` and never reads the answer.
fn stuck_reader(addr: SocketAddr, target: &str) -> TcpStream {
    let mut s = TcpStream::connect(addr).expect("connect");
    write!(s, "GET {target} HTTP/1.1\r\nHost: {addr}\r\n\r\n").expect("send");
    s
}

#[test]
fn readers_that_never_read_hold_only_their_own_connections() {
    let (dir, config) = setup("serve_slow_readers");
    let mut served = Served::start(&config, None);
    served.expect(&["grid", "wrote"]);
    // A large output: 12 MB, more than loopback's socket buffers hold.
    let big = dir.join("out/.grid.svg.big");
    write_big_svg(&big, 12 << 20);
    std::fs::rename(&big, dir.join("out/grid.svg")).expect("rename");
    let pid = served.child.id();
    let fds = open_fds(pid);
    let stuck: Vec<TcpStream> = (0..4)
        .map(|_| stuck_reader(served.addr, "/out/grid.svg"))
        .collect();
    // Every stuck request has its connection (and its answer under way).
    let started = Instant::now();
    while open_fds(pid) < fds + 4 {
        assert!(
            started.elapsed() < ANSWERED,
            "the stuck requests never arrived"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    answers(&mut served, "four stuck readers of a 12 MB output");
    let reply = get(served.addr, "/out/grid.html");
    assert_eq!(reply.status, 200);
    // The server gives up on them once their writes stall: their sockets
    // close (waited for as the daemon's open descriptors falling back).
    let started = Instant::now();
    while open_fds(pid) > fds {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "the stuck readers' connections are still open after 120 s ({} fds, {fds} before)",
            open_fds(pid)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let _ = writeln!(
        std::io::stderr(),
        "stuck readers dropped after {:?}",
        started.elapsed()
    );
    drop(stuck);
    answers(&mut served, "the stuck readers were dropped");
}

/// A valid SVG of about `bytes` bytes (one long comment).
fn write_big_svg(path: &Path, bytes: usize) {
    let mut text = String::with_capacity(bytes + 200);
    text.push_str("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 10 10\"><!--");
    while text.len() < bytes {
        text.push_str("0123456789abcdef");
    }
    text.push_str("--></svg>\n");
    std::fs::write(path, text).expect("write a big svg");
}

/// A port nobody listens on now (bound and let go).
fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    l.local_addr().expect("addr").port()
}

#[test]
fn serve_takes_loopback_names_and_refuses_broadcast_and_multicast() {
    let (_dir, config) = setup("serve_addresses");
    let port = free_port();
    let mut served = Served::start(&config, Some(&format!("localhost:{port}")));
    assert!(served.addr.ip().is_loopback(), "{}", served.first);
    assert_eq!(served.addr.port(), port, "{}", served.first);
    assert!(
        served.first.contains("other machines cannot connect"),
        "{}",
        served.first
    );
    served.expect(&["grid", "wrote"]);
    answers(&mut served, "--serve localhost:PORT");
    drop(served);
    for (addr, word) in [
        ("255.255.255.255", "broadcast"),
        ("255.255.255.255:8123", "broadcast"),
        ("224.0.0.1:8123", "multicast"),
        ("239.1.2.3", "multicast"),
        ("[ff02::1]:8123", "multicast"),
    ] {
        let out = support::output_within(
            support::bin()
                .arg("watch")
                .arg(&config)
                .args(["--serve", addr]),
            60,
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(2),
            "--serve {addr}: {stdout}{stderr}"
        );
        assert!(
            stderr.contains(addr) && stderr.contains(word),
            "--serve {addr}: {stderr}"
        );
        assert!(!stdout.contains("serving"), "--serve {addr}: {stdout}");
    }
}
