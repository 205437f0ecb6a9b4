#!/usr/bin/env python3
"""endohaptics-sbrio-gateway between the bridge (protocol v2) and the emulator (--protocol 2016).

    gateway_e2e.py BIN_DIR GATEWAY [RUNNER...]

BIN_DIR holds the x86 bridge and emulator; GATEWAY is the gateway to test (the native one, or the
armhf one with RUNNER qemu-arm-static). The bridge talks to the gateway through a relay in this
script that records the bridge's datagrams. Checks, each against the emulator's truth log and the
programs' counters:
  obeys     while the bridge runs, the truth log shows motors enabled and active; the gateway
            relayed setpoints and returned states
  forged    forged v2 setpoints sent to the gateway during the session are refused (counted as
            forged) and never relayed
  replayed  recorded setpoints and the recorded HELLO, sent again during the session and after it,
            are refused (counted) and never relayed; plain 2016 setpoints sent to the gateway too
  silence   the bridge is killed (SIGKILL: no orderly disable), the gateway sends disabled setpoints: every truth row later
            than the bridge's last setpoint + the gateway's watchdog + a margin has enable mask 0
            (the emulator's own watchdog is 5 s: it never trips)
Prints "PASS: ..." with the counts, or "FAIL: ...".
GATEWAY_EXTRA_ARGS (environment, split at spaces) is appended to the gateway's command line, e.g.
"--spin-us 50 --listen-spin-us 50" to run the same checks with the gateway's receives spinning.
"""
import csv
import os
import re
import select
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

SETPOINT_V2 = 67
HELLO = 110
WATCHDOG_MS = 100
# Between the bridge's last setpoint and the first disabled truth row: the gateway's watchdog,
# one period, and room for a slow host (qemu) and the truth log's row period.
MARGIN_S = 0.15


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def wait_line(p, pattern, what, lines):
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        line = p.stdout.readline()
        if not line:
            break
        lines.append(line)
        m = re.search(pattern, line)
        if m:
            return m
    fail(f"{what} did not start: {''.join(lines)}")


class Relay(threading.Thread):
    """Bridge <-> gateway: forwards both ways and records what the bridge sent (monotonic time)."""

    def __init__(self, gateway_port):
        super().__init__(daemon=True)
        self.front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.front.bind(("127.0.0.1", 0))
        self.back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.back.bind(("127.0.0.1", 0))
        self.back.connect(("127.0.0.1", gateway_port))
        self.port = self.front.getsockname()[1]
        self.bridge = None
        self.recorded = []  # (time, datagram) from the bridge
        self.stop = False

    def run(self):
        while not self.stop:
            ready, _, _ = select.select([self.front, self.back], [], [], 0.05)
            for s in ready:
                try:
                    if s is self.front:
                        data, self.bridge = self.front.recvfrom(4096)
                        self.recorded.append((time.monotonic(), data))
                        self.back.send(data)
                    else:
                        data = self.back.recv(4096)
                        if self.bridge:
                            self.front.sendto(data, self.bridge)
                except OSError:
                    pass


def forged_setpoint(i):
    body = struct.pack(">BBQQQQ", 2, 1, 0x4242 + i, 1000 + i, 0, 0) + struct.pack(
        ">ffffB", 0.5, -0.5, 0.5, -0.5, 15)
    return body + os.urandom(16)


def counters(text, prefix):
    for line in text.splitlines():
        if prefix in line:
            return line
    fail(f"no '{prefix}' in:\n{text}")


def number(line, label):
    m = re.search(r"(\d+) " + re.escape(label), line) or re.search(re.escape(label) + r" (\d+)",
                                                                      line)
    if not m:
        fail(f"no '{label}' in: {line}")
    return int(m.group(1))


def main():
    if len(sys.argv) < 3:
        fail("usage: gateway_e2e.py BIN_DIR GATEWAY [RUNNER...]")
    bin_dir, gateway_exe, runner = sys.argv[1], sys.argv[2], sys.argv[3:]
    # The relay is a thread of this script: with Python's default 5 ms switch interval, the
    # attacking thread could hold it back for 5 ms at a time, a latency variation that is the
    # harness's, not the rig's (the gateway tolerates --jitter-ms, 10 ms, of it).
    sys.setswitchinterval(0.0005)
    if not os.access(gateway_exe, os.X_OK):
        fail(f"no gateway at {gateway_exe} (the armhf one: ./run cross)")
    work = tempfile.mkdtemp(prefix="eh-gateway-")
    key = os.path.join(work, "rig.key")
    subprocess.run([os.path.join(bin_dir, "endohaptics-bridge"), "--generate-key", key],
                   check=True, stdout=subprocess.DEVNULL)
    truth = os.path.join(work, "truth.csv")
    emulator = subprocess.Popen(
        [os.path.join(bin_dir, "endohaptics-sbrio-emulator"), "--protocol", "2016", "--bind",
         "127.0.0.1", "--port", "0", "--watchdog-ms", "5000", "--truth-log", truth, "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    emu_lines = []
    emu_port = int(wait_line(emulator, r"listening on 127\.0\.0\.1:(\d+)", "emulator",
                             emu_lines).group(1))
    gw_port = free_port()
    gateway = subprocess.Popen(
        runner + [gateway_exe, "--listen", f"127.0.0.1:{gw_port}", "--sbrio",
                  f"127.0.0.1:{emu_port}", "--key", key, "--watchdog-ms", str(WATCHDOG_MS)]
        + os.environ.get("GATEWAY_EXTRA_ARGS", "").split(),
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    gw_lines = []
    wait_line(gateway, r"protocol v2 on 127\.0\.0\.1:", "gateway", gw_lines)
    relay = Relay(gw_port)
    relay.start()
    attacker = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    attacker.bind(("127.0.0.1", 0))
    injected = {"forged": 0, "replayed": 0, "2016": 0}

    def attack_live():
        time.sleep(1.5)  # the session is up
        recorded = [d for _, d in relay.recorded if len(d) == SETPOINT_V2]
        for i in range(100):
            attacker.sendto(forged_setpoint(i), ("127.0.0.1", gw_port))
            injected["forged"] += 1
            attacker.sendto(recorded[i % len(recorded)], ("127.0.0.1", gw_port))
            injected["replayed"] += 1
            time.sleep(0.002)

    live = threading.Thread(target=attack_live)
    live.start()
    # The bridge is killed (SIGKILL) while the motors follow it: no orderly disable, its last
    # setpoint has the motors enabled; only the gateway's watchdog can disable them.
    bridge = subprocess.Popen(
        [os.path.join(bin_dir, "endohaptics-bridge"), "--sbrio", f"127.0.0.1:{relay.port}",
         "--key", key, "--stats"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    time.sleep(3.5)
    bridge.kill()
    bridge_out = bridge.communicate(timeout=30)[0]
    live.join()
    setpoints = [(t, d) for t, d in relay.recorded if len(d) == SETPOINT_V2]
    if not setpoints:
        fail("the bridge sent no setpoint:\n" + bridge_out)
    last_setpoint = setpoints[-1][0]
    # After the bridge: the recording again (setpoints, the HELLO) and plain 2016 setpoints.
    hellos = [d for _, d in relay.recorded if len(d) == HELLO]
    for i in range(300):
        attacker.sendto(setpoints[i * len(setpoints) // 300][1], ("127.0.0.1", gw_port))
        injected["replayed"] += 1
        if i % 30 == 0 and hellos:
            attacker.sendto(hellos[0], ("127.0.0.1", gw_port))
            injected["replayed"] += 1
        attacker.sendto(struct.pack(">ffffB", 0.5, -0.5, 0.5, -0.5, 15), ("127.0.0.1", gw_port))
        injected["2016"] += 1
        time.sleep(0.002)
    time.sleep(0.5)
    end_of_attacks = time.monotonic()
    time.sleep(0.3)
    relay.stop = True
    gateway.send_signal(signal.SIGTERM)
    t_signal = time.monotonic()
    gw_out, _ = gateway.communicate(timeout=30)
    gw_stop_s = time.monotonic() - t_signal
    gw_text = "".join(gw_lines) + gw_out
    emulator.send_signal(signal.SIGTERM)
    emu_text = "".join(emu_lines) + emulator.communicate(timeout=30)[0]

    # The programs' own accounts.
    if gateway.returncode != 0:
        fail(f"the gateway exited {gateway.returncode}:\n{gw_text}")
    if gw_stop_s > 1.0:
        fail(f"the gateway took {gw_stop_s:.2f} s to end after SIGTERM (limit 1 s)")
    relay_line = counters(gw_text, "setpoints relayed")
    v2_line = counters(gw_text, "protocol v2 datagrams")
    relayed = number(relay_line, "setpoints relayed")
    returned = number(relay_line, "states returned")
    disabled = number(relay_line, "disabled setpoints sent on silence")
    refused = number(v2_line, "rejected")
    forged = number(v2_line, "forged")
    wrong_size = number(v2_line, "wrong size")
    if relayed == 0 or returned == 0:
        fail(f"nothing relayed: {relay_line}")
    # The gateway's own envelope (joint range, rate) never touches a bridge within the same limits.
    final_line = [line for line in gw_text.splitlines() if "done after" in line][-1:]
    moved = number(final_line[0] if final_line else gw_text,
                   "relayed setpoints moved into the envelope")
    if moved != 0:
        fail(f"the gateway moved {moved} of the bridge's setpoints into its envelope: {final_line}")
    if relayed > len(setpoints):
        fail(f"the gateway relayed {relayed} setpoints, the bridge sent {len(setpoints)}")
    if forged < injected["forged"]:
        fail(f"{injected['forged']} forged setpoints sent, {forged} counted forged: {v2_line}")
    if wrong_size < injected["2016"]:
        fail(f"{injected['2016']} plain 2016 setpoints sent, {wrong_size} counted: {v2_line}")
    attacks = sum(injected.values())
    if refused < attacks:
        fail(f"{attacks} attack datagrams sent, {refused} refused: {v2_line}")
    if disabled == 0:
        fail(f"no disabled setpoint sent on silence: {relay_line}")
    obeyed_line = counters(emu_text, "setpoint packets obeyed")
    if number(obeyed_line, "watchdog trips") != 0:
        fail("the emulator's own watchdog tripped (the gateway should have disabled first): " +
             obeyed_line)

    # The truth log: enabled while the bridge ran, disabled within the watchdog after it stopped,
    # through every replay after.
    with open(truth) as f:
        rows = [(float(r["time"]), int(r["enable_mask"]), int(r["active_mask"]))
                for r in csv.DictReader(f)]
    enabled_rows = [t for t, mask, active in rows if mask != 0 and active != 0]
    if len(enabled_rows) < 1000:
        fail(f"the truth log shows motors enabled and active in {len(enabled_rows)} rows only")
    if not any(mask != 0 for t, mask, _ in rows if last_setpoint - 0.05 < t <= last_setpoint):
        fail("the motors were not enabled when the bridge was killed: nothing for the watchdog")
    deadline = last_setpoint + WATCHDOG_MS / 1000 + MARGIN_S
    late = [t for t, mask, _ in rows if mask != 0 and t > deadline]
    if late:
        fail(f"{len(late)} truth rows with motors enabled later than {WATCHDOG_MS} ms + "
             f"{MARGIN_S * 1000:.0f} ms after the bridge's last setpoint (first "
             f"{late[0] - last_setpoint:.3f} s after it)")
    after = [t for t, _, _ in rows if deadline < t < end_of_attacks]
    if len(after) < 100:
        fail(f"only {len(after)} truth rows after the bridge stopped")
    disabled_at = min((t for t, mask, _ in rows if t > last_setpoint and mask == 0), default=None)
    print(f"PASS: gateway {' '.join(runner + [os.path.basename(gateway_exe)])}: obeyed "
          f"({len(enabled_rows)} truth rows enabled and active); relayed {relayed} "
          f"setpoints, returned {returned} states; refused {refused} of {attacks} attack "
          f"datagrams (forged {injected['forged']} -> {forged} counted forged, replayed "
          f"{injected['replayed']}, plain 2016 {injected['2016']} -> {wrong_size} wrong size), "
          f"none relayed; silence: motors disabled "
          f"{(disabled_at - last_setpoint) * 1000:.0f} ms after the bridge's last setpoint "
          f"(watchdog {WATCHDOG_MS} ms), {disabled} disabled setpoints sent; SIGTERM -> exit in "
          f"{gw_stop_s:.2f} s")
    print(relay_line.strip())
    print(v2_line.strip())
    for line in gw_text.splitlines():
        if "spins:" in line:
            print(line.strip())  # GATEWAY_EXTRA_ARGS with a spin: how often it saved a wait
    shutil.rmtree(work, ignore_errors=True)  # kept after a failure, for its logs


if __name__ == "__main__":
    main()
