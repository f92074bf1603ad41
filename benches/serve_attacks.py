#!/usr/bin/env python3
"""How fast the preview server answers `/` under each attack of issue 30.

Runs `nptreemap watch --serve` (the release binary by default) on a copy of
examples/countries in a temp folder, then, on loopback only:

  baseline      `/` alone
  rebinding     200 requests with `Host: evil.example:PORT`, then `/`
  long head     a 300 MB header line streamed until the server closes,
                `/` asked meanwhile from another connection
  idle flood    2,000 idle connections held open, `/` asked meanwhile
  slow readers  four connections asking for a 12 MB output, never reading

For each it prints the median and largest latency of 20 `/` requests, the
daemon's threads and peak memory (VmHWM). Every loop is bounded in count and
time, and everything is closed at the end.

    cargo build --release && python3 benches/serve_attacks.py [BINARY]
"""

import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target/release/nptreemap")


def status(pid, field):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return -1


def get_root(addr, timeout=30.0):
    """Seconds for one `GET /` answered 200 (raises on anything else)."""
    started = time.perf_counter()
    with socket.create_connection(addr, timeout=timeout) as s:
        s.settimeout(timeout)
        s.sendall(f"GET / HTTP/1.1\r\nHost: {addr[0]}:{addr[1]}\r\nConnection: close\r\n\r\n".encode())
        data = b""
        while True:
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    took = time.perf_counter() - started
    if not data.startswith(b"HTTP/1.1 200"):
        raise RuntimeError(f"/ answered {data[:40]!r}")
    return took


def sample(addr, n=20):
    """Median and largest latency of `n` requests; None at the first one
    not answered within 10 s."""
    times = []
    for _ in range(n):
        try:
            times.append(get_root(addr, timeout=10.0))
        except (OSError, RuntimeError):
            return None
    return statistics.median(times), max(times)


def report(name, pid, times):
    if times is None:
        answer = "/ not answered within 10 s             "
    else:
        med, top = times
        answer = f"/ median {med * 1000:8.2f} ms  max {top * 1000:8.2f} ms"
    print(f"{name:13} {answer}  threads {status(pid, 'Threads'):5}  "
          f"VmHWM {status(pid, 'VmHWM') / 1024:7.1f} MB", flush=True)


def main():
    work = tempfile.mkdtemp(prefix="np-serve-bench-")
    shutil.copytree(os.path.join(ROOT, "examples/countries"), os.path.join(work, "countries"))
    config = os.path.join(work, "countries/nptreemap.yaml")
    log = open(os.path.join(work, "watch.log"), "w")
    daemon = subprocess.Popen([BINARY, "watch", config, "--serve", "127.0.0.1:0"],
                              stdout=subprocess.PIPE, stderr=log, text=True)
    try:
        first = daemon.stdout.readline()
        url = next(w for w in first.split() if w.startswith("http://"))
        host, port = url[len("http://"):].rstrip("/").rsplit(":", 1)
        addr = (host, int(port))
        deadline = time.time() + 120
        while "wrote" not in daemon.stdout.readline():
            if time.time() > deadline:
                raise RuntimeError("no first build")
        pid = daemon.pid
        print(f"{BINARY}\n{first.strip()}")
        report("baseline", pid, sample(addr))

        for _ in range(200):
            with socket.create_connection(addr, timeout=10) as s:
                s.sendall(f"GET / HTTP/1.1\r\nHost: evil.example:{port}\r\nConnection: close\r\n\r\n".encode())
                s.recv(4096)
        report("rebinding", pid, sample(addr))

        # A 300 MB header line, and `/` asked while it streams.
        results = {}

        def long_head():
            sent = 0
            with socket.create_connection(addr, timeout=20) as s:
                s.sendall(f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nX-Long: ".encode())
                chunk = b"a" * (1 << 20)
                try:
                    while sent < 300 << 20:
                        s.sendall(chunk)
                        sent += len(chunk)
                except OSError as e:
                    results["stopped"] = repr(e)
            results["sent"] = sent

        t = threading.Thread(target=long_head)
        t.start()
        during = sample(addr)
        t.join(120)
        report("long head", pid, during)
        print(f"{'':13} sent {results.get('sent', 0) >> 20} MB before {results.get('stopped', 'the end')}")

        flood = []
        try:
            for _ in range(2000):
                flood.append(socket.create_connection(addr, timeout=10))
        except OSError as e:
            print(f"{'':13} flood stopped at {len(flood)}: {e}")
        report(f"idle x{len(flood)}", pid, sample(addr))
        for s in flood:
            s.close()

        big = os.path.join(work, "countries/out/countries.svg")
        with open(big + ".tmp", "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg"><!--' + "0123456789abcdef" * (12 << 16) + "--></svg>\n")
        os.replace(big + ".tmp", big)
        stuck = []
        for _ in range(4):
            s = socket.create_connection(addr, timeout=10)
            s.sendall(f"GET /countries/countries.svg HTTP/1.1\r\nHost: {host}:{port}\r\n\r\n".encode())
            stuck.append(s)
        report("slow readers", pid, sample(addr))
        for s in stuck:
            s.close()
        report("after", pid, sample(addr))
    finally:
        daemon.terminate()
        try:
            daemon.wait(10)
        except subprocess.TimeoutExpired:
            daemon.kill()
        log.close()
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
