#!/usr/bin/env python3
"""Link status that tells the truth, and whom a 2016 robot side obeys (docs/safety.md).

    link_truth.py BIN_DIR CASE

Cases (each prints "PASS: ..." or "FAIL: ..."):
  never-up        no robot side, a robot side with another key, and one speaking the other
                  protocol: the bridge warns within 1 s that nothing obeyed, names the cause, and
                  exits non-zero (3)
  restart-2016    --protocol 2016: a bridge, then a restarted bridge (a new source port): the
                  emulator releases the first after its watchdog of silence and obeys the second,
                  saying whom it obeys; both bridges report the link up and exit 0
  peer-2016       --protocol 2016 with --peer: an intruder who speaks first is never obeyed (no
                  truth row with a motor enabled while only it speaks); the configured bridge is
  refused-options options that cannot apply are refused with the reason, never ignored
"""
import csv
import os
import re
import socket
import struct
import subprocess
import sys
import tempfile
import time

SETPOINT = struct.Struct(">4fB")


def start_emulator(bin_dir, args, work, name="truth.csv"):
    truth = os.path.join(work, name)
    p = subprocess.Popen(
        [os.path.join(bin_dir, "endohaptics-sbrio-emulator"), "--bind", "127.0.0.1", "--port", "0",
         "--truth-log", truth] + args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines = []
    while True:
        line = p.stdout.readline()
        if not line:
            raise RuntimeError("emulator ended before listening: " + "".join(lines))
        lines.append(line)
        m = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
        if m:
            return p, int(m.group(1)), truth, lines


def run_bridge(bin_dir, args, timeout=30):
    """Runs the bridge; returns (exit, stdout, [(seconds since start, line)])."""
    t0 = time.monotonic()
    p = subprocess.Popen([os.path.join(bin_dir, "endohaptics-bridge")] + args,
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    timed = []
    for line in p.stdout:
        timed.append((time.monotonic() - t0, line.rstrip("\n")))
    p.wait(timeout=timeout)
    return p.returncode, "\n".join(l for _, l in timed), timed


def finish(p, lines):
    out, _ = p.communicate(timeout=30)
    return "".join(lines) + out


def key(bin_dir, work, name):
    path = os.path.join(work, name)
    subprocess.run([os.path.join(bin_dir, "endohaptics-bridge"), "--generate-key", path],
                   check=True, stdout=subprocess.DEVNULL)
    return path


def never_up(bin_dir, work):
    k1, k2 = key(bin_dir, work, "a.key"), key(bin_dir, work, "b.key")
    checks = []
    # A port nobody answers on.
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    dead = s.getsockname()[1]
    s.close()
    cases = [("nobody", None, ["--sbrio", f"127.0.0.1:{dead}", "--key", k1], "no answer"),
             ("another key", ["--key", k2, "--duration", "4"], ["--key", k1], "no answer"),
             ("2016 robot, v2 bridge", ["--protocol", "2016", "--duration", "4"], ["--key", k1],
              "no answer"),
             ("v2 robot, 2016 bridge", ["--key", k1, "--duration", "4"], ["--protocol", "2016"],
              "no answer")]
    for name, emu_args, bridge_args, cause in cases:
        emu = None
        if emu_args is not None:
            emu, port, _, lines = start_emulator(bin_dir, emu_args + ["--quiet"], work)
            bridge_args = bridge_args + ["--sbrio", f"127.0.0.1:{port}"]
        code, out, timed = run_bridge(bin_dir, bridge_args + ["--duration", "2"])
        if emu is not None:
            finish(emu, lines)
        warned = [t for t, l in timed if "WARNING: no obeyed state" in l]
        verdict = re.search(r"bridge: link: never up \(([^)]*)\)", out)
        ok = (code == 3 and warned and warned[0] <= 1.5 and verdict and verdict.group(1) == cause)
        detail = (f"exit {code}, warned at {warned[0]:.2f} s" if warned
                  else f"exit {code}, no warning")
        checks.append((name, ok, detail, out))
    return checks


def restart_2016(bin_dir, work):
    emu, port, truth, lines = start_emulator(bin_dir, ["--protocol", "2016", "--duration", "5"],
                                             work)
    first = run_bridge(bin_dir, ["--protocol", "2016", "--sbrio", f"127.0.0.1:{port}",
                                 "--duration", "1.5"])
    time.sleep(0.3)  # longer than the emulator's 100 ms watchdog
    second = run_bridge(bin_dir, ["--protocol", "2016", "--sbrio", f"127.0.0.1:{port}",
                                  "--duration", "1.5"])
    text = finish(emu, lines)
    obeying = re.findall(r"obeying (127\.0\.0\.1:\d+) only", text)
    released = "fell silent" in text
    checks = [
        ("first bridge up", first[0] == 0 and "bridge: link: up" in first[1], first[1]),
        ("restarted bridge up", second[0] == 0 and "bridge: link: up" in second[1], second[1]),
        ("emulator says whom it obeys, twice", len(obeying) == 2 and obeying[0] != obeying[1]
         and released, text),
    ]
    return checks


def peer_2016(bin_dir, work):
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    bridge_port = s.getsockname()[1]
    s.close()
    emu, port, truth, lines = start_emulator(
        bin_dir, ["--protocol", "2016", "--duration", "4", "--peer", f"127.0.0.1:{bridge_port}"],
        work)
    intruder = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    intruder.bind(("127.0.0.1", 0))
    t_intruder = time.monotonic()
    for _ in range(500):  # 0.5 s of valid setpoints enabling every motor, before the bridge
        intruder.sendto(SETPOINT.pack(0.5, 0.5, 0.5, 0.5, 15), ("127.0.0.1", port))
        time.sleep(0.001)
    bridge = run_bridge(bin_dir, ["--protocol", "2016", "--sbrio", f"127.0.0.1:{port}",
                                  "--local", f"127.0.0.1:{bridge_port}", "--duration", "1.5"])
    for _ in range(200):  # and again while the bridge runs is covered by the kernel count below
        intruder.sendto(SETPOINT.pack(0.5, 0.5, 0.5, 0.5, 15), ("127.0.0.1", port))
    text = finish(emu, lines)
    rows = list(csv.DictReader(open(truth)))
    # Rows before the bridge started: the intruder alone.
    enabled_early = sum(1 for r in rows[:400] if int(r["active_mask"]) != 0)
    ignored = re.search(r"(\d+) datagrams from other senders ignored", text)
    checks = [
        ("intruder never obeyed", enabled_early == 0, f"{enabled_early} rows enabled"),
        ("intruder's datagrams counted", ignored is not None and int(ignored.group(1)) >= 500,
         text),
        ("configured bridge obeyed", bridge[0] == 0 and "bridge: link: up" in bridge[1], bridge[1]),
        ("emulator names its peer at start", f"only 127.0.0.1:{bridge_port} (--peer)" in text,
         text),
    ]
    return checks


def refused_options(bin_dir, work):
    k = key(bin_dir, work, "c.key")
    bridge = os.path.join(bin_dir, "endohaptics-bridge")
    emu = os.path.join(bin_dir, "endohaptics-sbrio-emulator")
    cases = [
        ([bridge, "--protocol", "2016", "--key", k], "--key applies to protocol v2"),
        ([bridge, "--protocol", "2016", "--max-answer-lag", "5"], "--max-answer-lag applies to"),
        ([bridge, "--key", k, "--passivity-round-trip", "50"],
         "--passivity-round-trip applies to --passivity tdpa"),
        ([bridge, "--key", k, "--rate", "21"], "use --rate 22 or more"),
        ([emu, "--protocol", "2016", "--key", k], "--key applies to protocol v2"),
        ([emu, "--key", k, "--peer", "127.0.0.1:5000"], "--peer applies to --protocol 2016"),
        ([emu, "--protocol", "2016", "--max-round-trip", "300"], "--max-round-trip applies to"),
        ([emu, "--protocol", "2016", "--peer", "127.0.0.1:0"], "port 1..65535"),
        ([emu, "--protocol", "2016", "--peer", "no-such-host:5000"], "not an IP address"),
    ]
    checks = []
    for argv, expected in cases:
        p = subprocess.run(argv + ["--duration", "0.2"], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=30)
        checks.append((" ".join(os.path.basename(a) for a in argv[:1]) + " " + " ".join(argv[1:]),
                       p.returncode != 0 and expected in p.stdout, p.stdout))
    return checks


def signals(bin_dir, work):
    """SIGINT and SIGTERM end the bridge and the emulator within 1 s wherever they wait."""
    import signal
    k = key(bin_dir, work, "d.key")
    fifo = os.path.join(work, "fifo.json")
    os.mkfifo(fifo)
    checks = []
    runs = [
        ("bridge, no robot", [os.path.join(bin_dir, "endohaptics-bridge"), "--sbrio",
                              "127.0.0.1:9", "--key", k]),
        ("emulator, idle", [os.path.join(bin_dir, "endohaptics-sbrio-emulator"), "--bind",
                            "127.0.0.1", "--port", "0", "--key", k]),
        ("bridge, a FIFO as its configuration", [os.path.join(bin_dir, "endohaptics-bridge"),
                                                 "--sbrio", "127.0.0.1:9", "--key", k,
                                                 "--config", fifo]),
        # Outputs: a FIFO nobody reads blocked open() beyond SIGTERM; now refused at once.
        ("bridge, a FIFO as its log", [os.path.join(bin_dir, "endohaptics-bridge"), "--sbrio",
                                       "127.0.0.1:9", "--key", k, "--log", fifo]),
        ("emulator, a FIFO as its truth log", [os.path.join(bin_dir, "endohaptics-sbrio-emulator"),
                                               "--bind", "127.0.0.1", "--port", "0", "--key", k,
                                               "--truth-log", fifo]),
    ]
    for name, argv in runs:
        for sig in (signal.SIGINT, signal.SIGTERM):
            p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            time.sleep(0.5)
            t0 = time.monotonic()
            if p.poll() is None:
                p.send_signal(sig)
            try:
                out, _ = p.communicate(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()
                out, _ = p.communicate()
            took = time.monotonic() - t0
            checks.append((f"{name}, {sig.name}: ended after {took:.2f} s (exit {p.returncode})",
                           took <= 1.0, out[-300:], out))
    return checks


CASES = {"signals": signals, "never-up": never_up, "restart-2016": restart_2016, "peer-2016": peer_2016,
         "refused-options": refused_options}


def main():
    bin_dir, case = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory() as work:
        checks = CASES[case](bin_dir, work)
    failed = [c for c in checks if not c[1]]
    for name, ok, detail, *rest in checks:
        print(f"{'ok  ' if ok else 'FAIL'} {name}: {detail if isinstance(detail, str) and len(detail) < 200 else ''}")
    if failed:
        for name, _, detail, *rest in failed:
            print(f"--- {name}\n{detail}\n{rest[0] if rest else ''}")
        print(f"FAIL: {case}: {len(failed)} of {len(checks)} checks failed")
        return 1
    print(f"PASS: {case}: {len(checks)} checks")
    return 0


if __name__ == "__main__":
    sys.exit(main())
