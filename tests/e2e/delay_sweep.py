#!/usr/bin/env python3
"""Protocol v2 under delay: does the robot obey, and does the bridge say so? (docs/safety.md)

    delay_sweep.py BIN_DIR [DELAY_MS ...] [--report]

For each one-way delay (default 10 50 100 150 400 1000 ms on the emulator's answers) runs
endohaptics-sbrio-emulator (--delay D, a truth log) and endohaptics-bridge (--max-answer-lag
set for the delay: the answer lags about D setpoints at 1 kHz) on 127.0.0.1 with a fresh key, and
prints one table row: whether the v2 session bound, how many truth rows have a motor enabled
(the robot obeyed), and what the bridge reported (exit status, link, its last words). Asserts
(unless --report) that the robot obeyed in most of the run after the first round trip and that
the bridge exited 0 saying the link was up; or, where the robot did not obey, that the bridge
exited non-zero naming why.
"""
import csv
import os
import re
import subprocess
import sys
import tempfile
import time


def run_case(bin_dir, delay_ms, work):
    key = os.path.join(work, "link.key")
    if not os.path.exists(key):
        subprocess.run([os.path.join(bin_dir, "endohaptics-bridge"), "--generate-key", key],
                       check=True, stdout=subprocess.DEVNULL)
    duration = 3.0 + 3 * delay_ms / 1000.0
    truth = os.path.join(work, f"truth{delay_ms}.csv")
    emu = subprocess.Popen(
        [os.path.join(bin_dir, "endohaptics-sbrio-emulator"), "--bind", "127.0.0.1", "--port", "0",
         "--key", key, "--delay", str(delay_ms), "--duration", str(duration + 1.5), "--quiet",
         "--truth-log", truth], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    port = None
    emu_lines = []
    while port is None:
        line = emu.stdout.readline()
        if not line:
            raise RuntimeError("emulator ended before listening: " + "".join(emu_lines))
        emu_lines.append(line)
        m = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
        if m:
            port = int(m.group(1))
    lag = int(delay_ms) + 50  # setpoints at 1 kHz, with margin
    bridge = subprocess.run(
        [os.path.join(bin_dir, "endohaptics-bridge"), "--sbrio", f"127.0.0.1:{port}", "--key", key,
         "--max-answer-lag", str(lag), "--duration", str(duration)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=duration + 30)
    out, _ = emu.communicate(timeout=30)
    emu_lines.append(out)
    emu_text = "".join(emu_lines)
    rows = list(csv.DictReader(open(truth)))
    obeyed = sum(1 for r in rows if int(r["active_mask"]) != 0)
    times = [float(r["time"]) for r in rows if int(r["active_mask"]) != 0]
    obeyed_span = times[-1] - times[0] if times else 0.0  # s from the first to the last obeyed row
    m = re.search(r"protocol v2 datagrams: accepted (\d+), handshakes (\d+)", emu_text)
    accepted, handshakes = (int(m.group(1)), int(m.group(2))) if m else (0, 0)
    link = re.search(r"bridge: link: (.*)", bridge.stdout)
    summary = re.search(r"complete=([0-9.]+)%", bridge.stdout)
    rtt = re.search(r"round trip .*?mean\s+([0-9.]+)", bridge.stdout)
    errors = [l for l in bridge.stdout.splitlines() if l.startswith(("error:", "bridge: WARNING"))]
    return {
        "delay": delay_ms, "bound": accepted > 0, "accepted": accepted, "handshakes": handshakes,
        "rows": len(rows), "obeyed": obeyed, "exit": bridge.returncode,
        "complete": summary.group(1) if summary else "?",
        "link": link.group(1) if link else "(no link line)",
        "said": errors[-1] if errors else "", "stdout": bridge.stdout, "emulator": emu_text,
        "duration": duration, "obeyed_span": obeyed_span,
    }


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    report = "--report" in sys.argv
    bin_dir = args[0]
    delays = [float(a) if "." in a else int(a) for a in args[1:]] or [10, 50, 100, 150, 400, 1000]
    failures = []
    print("| one-way delay (ms) | v2 session open | setpoints obeyed / handshakes | truth rows with a "
          "motor enabled | bridge exit | bridge's link line |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for d in delays:
            r = run_case(bin_dir, d, work)
            print(f"| {d} | {'yes' if r['bound'] else 'no'} | {r['accepted']} / {r['handshakes']} | "
                  f"{r['obeyed']} of {r['rows']} | {r['exit']} | {r['link']} {r['said']} |",
                  flush=True)
            # After the first round trip (2 x delay) the motors must be enabled for most of the
            # bridge's run: bound, obeyed, and the bridge saying so with exit 0.
            expected = (r["duration"] - 2 * d / 1000.0) * 0.8
            if report:
                continue
            if r["obeyed_span"] >= expected and r["exit"] == 0 and r["link"].startswith("up"):
                continue
            if r["obeyed"] == 0 and r["exit"] != 0 and r["link"] != "(no link line)":
                failures.append(f"delay {d} ms: the robot never obeyed (bridge said so: ok)")
                continue
            failures.append(f"delay {d} ms: obeyed for {r['obeyed_span']:.2f} s (expected >= "
                            f"{expected:.2f} s), "
                            f"bridge exit {r['exit']}, link '{r['link']}'\n{r['stdout'][-3000:]}\n"
                            f"{r['emulator'][-2000:]}")
    if failures and not report:
        print("FAIL:\n" + "\n".join(failures))
        return 1
    print("PASS" if not report else "(report only)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
