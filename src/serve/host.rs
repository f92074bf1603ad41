//! Which requests are for this server: the defence against DNS rebinding.
//! A web page on another site that gets its own name to resolve to this
//! machine can make the browser send requests here, but the browser still
//! names that site in `Host` (or in an absolute request target). Owns the
//! rule: a request is answered only when it names, with the server's port,
//! `localhost`, a loopback address (`127.0.0.1`, `[::1]`, ...) or the very
//! address the connection reached (so `0.0.0.0` still answers
//! `http://192.0.2.7:PORT/`). An IP address cannot be rebound: a page that
//! reaches us by one is served by us.

use std::net::{IpAddr, Ipv6Addr};

/// Whether `host` (a `Host` value or a target's authority) names this
/// server, which listens on `port` and was reached at `local`.
pub(crate) fn allowed(host: &str, local: IpAddr, port: u16) -> bool {
    let Some((name, named_port)) = split(host) else {
        return false;
    };
    if named_port != port {
        return false;
    }
    if name.eq_ignore_ascii_case("localhost") {
        return true;
    }
    let ip = match name.strip_prefix('[').and_then(|n| n.strip_suffix(']')) {
        Some(v6) => v6.parse::<Ipv6Addr>().ok().map(IpAddr::V6),
        // Only the dotted form: `2130706433` or `0x7f.1` are not addresses
        // a browser shows, and not worth a second parser.
        None => name.parse::<std::net::Ipv4Addr>().ok().map(IpAddr::V4),
    };
    ip.is_some_and(|ip| ip.to_canonical().is_loopback() || ip.to_canonical() == local.to_canonical())
}

/// A host and its port (80 when none is given, as for any `http:` URL);
/// `None` when the value is not `name`, `name:port`, `[v6]` or `[v6]:port`.
fn split(host: &str) -> Option<(&str, u16)> {
    let (name, port) = match host.rfind(':') {
        // A colon inside brackets belongs to an IPv6 address.
        Some(at) if !host[at..].contains(']') => (&host[..at], Some(&host[at + 1..])),
        _ => (host, None),
    };
    if name.is_empty() || name.contains(['/', '@', ' ', '\t']) {
        return None;
    }
    let port = match port {
        None => 80,
        Some(p) if !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()) => p.parse().ok()?,
        Some(_) => return None,
    };
    Some((name, port))
}

#[cfg(test)]
mod tests {
    use super::*;

    const LO: IpAddr = IpAddr::V4(std::net::Ipv4Addr::LOCALHOST);

    #[test]
    fn loopback_names_with_the_port_are_ours() {
        for host in [
            "localhost:7878",
            "LOCALHOST:7878",
            "127.0.0.1:7878",
            "127.0.0.2:7878",
            "[::1]:7878",
            "[::ffff:127.0.0.1]:7878",
        ] {
            assert!(allowed(host, LO, 7878), "{host}");
        }
    }

    #[test]
    fn other_names_ports_and_spellings_are_not() {
        for host in [
            "evil.example:7878",
            "evil.example",
            "localhost.evil.example:7878",
            "127.0.0.1.evil.example:7878",
            "localhost:7879",
            "localhost",
            "localhost:",
            "localhost:+7878",
            "localhost:7878:7878",
            "localhost.:7878",
            "::1:7878",
            "[::1:7878",
            "user@localhost:7878",
            "2130706433:7878",
            "0x7f.1:7878",
            "192.0.2.7:7878",
            "",
        ] {
            assert!(!allowed(host, LO, 7878), "{host}");
        }
    }

    #[test]
    fn the_address_a_connection_reached_is_ours_and_port_80_may_go_unsaid() {
        let lan: IpAddr = "192.0.2.7".parse().expect("ip");
        assert!(allowed("192.0.2.7:8000", lan, 8000));
        assert!(!allowed("192.0.2.8:8000", lan, 8000));
        assert!(allowed("localhost", LO, 80));
        assert!(allowed("[::1]", LO, 80));
    }
}
