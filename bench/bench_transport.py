"""Robot transport benchmark: commands/s through a real broker and end-to-end command latency.

For N = 12, 50, 200 robots at 30 Hz: a `swarmdeck robots` fleet runs as its
own process on a private mosquitto; this process streams commands through the
console path (CommandStreamer.submit + tick → MqttTransport → broker). Each
tick's ω encodes the tick number, the fleet writes one trace line per command
it receives (monotonic clock, shared by both processes on Linux), and the
latency is fleet receive time (the moment the firmware model applies the
command) minus the time the streamer was handed the tick's safe commands.

Baseline in the same process: a bare paho publisher and a bare paho subscriber\n(another process) exchanging the same JSON through the same broker.

    python bench/bench_transport.py [--seconds 5] [--rate 30] [--robots 12 50 200]
"""
from __future__ import annotations

import argparse
import os
import platform
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.streamer import CommandStreamer
from swarmdeck.devices.net.transport_mqtt import MqttTransport

W_STEP = 1e-4  # ω of tick k is (k + 1)·W_STEP rad/s (robots turn in place, v = 0)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_broker(workdir: Path, nodelay: bool) -> tuple[subprocess.Popen, str]:
    port = free_port()
    conf = workdir / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\nmax_queued_messages 100000\n"
                    + ("set_tcp_nodelay true\n" if nodelay else ""))
    exe = shutil.which("mosquitto") or "/usr/sbin/mosquitto"
    proc = subprocess.Popen([exe, "-c", str(conf)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
            return proc, f"mqtt://127.0.0.1:{port}"
        except OSError:
            time.sleep(0.02)
    raise RuntimeError("mosquitto did not start")


def proc_cpu_seconds(pid: int) -> float:
    """utime + stime of a process (all threads), s."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run_one(url: str, n: int, seconds: float, rate: float, workdir: Path) -> dict:
    trace = workdir / f"trace_{n}.txt"
    fleet = subprocess.Popen(
        [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())", "robots",
         "--broker", url, "--robots", str(n), "--bounds", "-5", "5", "-3", "3", "--trace", str(trace), "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )
    transport = MqttTransport(parse_broker_url(url), ids=np.arange(n)).start()
    streamer = CommandStreamer(transport, transport)
    ids = np.arange(n)
    try:
        deadline = time.monotonic() + 30
        while len(transport.latest_poses().ids) < n:
            if time.monotonic() > deadline:
                raise RuntimeError(f"fleet of {n} did not publish poses: {fleet.stderr.read() if fleet.poll() else ''}")
            time.sleep(0.05)
        ticks = int(seconds * rate)
        t_handed = np.empty(ticks)
        send_cost = np.empty(ticks)
        zeroed = 0
        fleet_cpu0, cpu0, wall0 = proc_cpu_seconds(fleet.pid), time.process_time(), time.monotonic()
        pacer = RealTimePacer(1.0 / rate)
        for k in range(ticks):
            t0 = time.monotonic()
            streamer.submit(ids, np.zeros(n), np.full(n, (k + 1) * W_STEP), stamp=t0)
            tick = streamer.tick()
            t_handed[k] = t0
            send_cost[k] = time.monotonic() - t0
            zeroed += int(tick.zeroed.sum())
            pacer.wait()
        time.sleep(0.5)  # let the last commands arrive
        fleet_cpu = proc_cpu_seconds(fleet.pid) - fleet_cpu0
        console_cpu = time.process_time() - cpu0
        wall = time.monotonic() - wall0
        sent = transport.status().counters.get("commands_sent", 0)
    finally:  # fleet first, so the trace holds only the streamed commands (not the final stop)
        fleet.terminate()
        fleet.wait(timeout=20)
        streamer.stop()
        transport.close()
    rows = np.loadtxt(trace, ndmin=2) if trace.stat().st_size else np.empty((0, 4))
    k = np.rint(rows[:, 3] / W_STEP).astype(int) - 1
    ok = (k >= 0) & (k < ticks)
    lat = rows[ok, 0] - t_handed[k[ok]]
    span = ticks / rate
    return {
        "n": n,
        "offered": n * rate,
        "sent_per_s": sent / span,
        "received_per_s": len(rows) / span,
        "lost": int(sent - len(rows)),
        "fleet_cpu": fleet_cpu / wall,
        "console_cpu": console_cpu / wall,
        "zeroed": zeroed,
        "lat_median_ms": float(np.median(lat) * 1e3) if len(lat) else float("nan"),
        "lat_p99_ms": float(np.percentile(lat, 99) * 1e3) if len(lat) else float("nan"),
        "send_ms": float(np.median(send_cost) * 1e3),
        "overruns": pacer.overruns,
    }


RAW_SUBSCRIBER = """
import sys, time, threading
import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion
port, n, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
out = open(path, "w", buffering=1 << 16)
ready = threading.Event()
def on_connect(c, u, f, r, p):
    c.subscribe([(f"matlab_api/{i}", 0) for i in range(n)])
def on_subscribe(c, u, mid, r, p):
    ready.set(); print("ready", flush=True)
def on_message(c, u, m):
    out.write(f"{time.monotonic()!r} {m.topic[11:]} {m.payload.decode()}\\n")
c = mqtt.Client(CallbackAPIVersion.VERSION2)
c.on_connect, c.on_subscribe, c.on_message = on_connect, on_subscribe, on_message
c.connect("127.0.0.1", port); c.loop_start()
sys.stdin.read()  # until the parent closes stdin
c.loop_stop(); out.close()
"""


def run_raw(url: str, n: int, seconds: float, rate: float, workdir: Path) -> dict:
    """Baseline: bare paho publisher (this process) → bare paho subscriber (another process), same payloads."""
    import json

    import paho.mqtt.client as mqtt
    from paho.mqtt.enums import CallbackAPIVersion

    port = int(url.rsplit(":", 1)[1])
    path = workdir / f"raw_{n}.txt"
    sub = subprocess.Popen([sys.executable, "-c", RAW_SUBSCRIBER, str(port), str(n), str(path)],
                           stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert sub.stdout is not None and sub.stdout.readline().strip() == "ready"
    pub = mqtt.Client(CallbackAPIVersion.VERSION2)
    pub.connect("127.0.0.1", port)
    pub.loop_start()
    time.sleep(0.2)
    ticks = int(seconds * rate)
    t_handed = np.empty(ticks)
    pacer = RealTimePacer(1.0 / rate)
    for k in range(ticks):
        t_handed[k] = time.monotonic()
        w = (k + 1) * W_STEP
        for i in range(n):
            pub.publish(f"matlab_api/{i}", json.dumps({"v": 0.0, "w": w}))
        pacer.wait()
    time.sleep(0.5)
    pub.loop_stop()
    pub.disconnect()
    sub.communicate("", timeout=20)
    lines = [l.split(" ", 2) for l in path.read_text().splitlines()]
    t = np.array([float(a) for a, _, _ in lines])
    k = np.array([int(round(json.loads(p)["w"] / W_STEP)) - 1 for _, _, p in lines])
    lat = t - t_handed[k]
    return {"n": n, "received_per_s": len(lat) / (ticks / rate), "lat_median_ms": float(np.median(lat) * 1e3),
            "lat_p99_ms": float(np.percentile(lat, 99) * 1e3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--rate", type=float, default=30.0)
    ap.add_argument("--robots", type=int, nargs="+", default=[12, 50, 200])
    args = ap.parse_args()
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    print(f"machine: {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}; load average at start "
          f"{os.getloadavg()[0]:.1f}; {args.seconds:g} s per N at {args.rate:g} Hz\n")
    for nodelay in (False, True):
        with tempfile.TemporaryDirectory() as tmp:
            broker, url = start_broker(Path(tmp), nodelay)
            try:
                results = [run_one(url, n, args.seconds, args.rate, Path(tmp)) for n in args.robots]
                raws = [run_raw(url, n, args.seconds, args.rate, Path(tmp)) for n in args.robots]
            finally:
                broker.terminate()
                broker.wait()
        print(f"mosquitto {'with set_tcp_nodelay true' if nodelay else 'defaults (Nagle on)'}:\n")
        print("| N | offered cmd/s | sent cmd/s | received cmd/s | lost | zeroed by watchdog | latency median (ms) "
              "| latency p99 (ms) | bare paho median / p99 (ms) | median vs bare paho | console send+watchdog per tick (ms) "
              "| CPU console / fleet (cores) |")
        print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for r, b in zip(results, raws):
            print(f"| {r['n']} | {r['offered']:.0f} | {r['sent_per_s']:.0f} | {r['received_per_s']:.0f} | {r['lost']} | "
                  f"{r['zeroed']} | {r['lat_median_ms']:.2f} | {r['lat_p99_ms']:.2f} | "
                  f"{b['lat_median_ms']:.2f} / {b['lat_p99_ms']:.2f} | {r['lat_median_ms'] / b['lat_median_ms']:.1f}x | "
                  f"{r['send_ms']:.2f} | {r['console_cpu']:.2f} / {r['fleet_cpu']:.2f} |")
        print()
    print(f"load average at end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
