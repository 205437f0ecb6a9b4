#!/usr/bin/python3
"""endohaptics-ros-bridge end to end on ROS 1 (docs/ros.md).

    ros_e2e.py BIN_DIR SOURCE_DIR CASE

Every case starts its own roscore on a free port with its own ROS_HOME and log folder, and stops
every process it started (by process group). Cases (each prints "PASS: ..." or "FAIL: ..."):
  topics      CRTK stylus stand-in (1 kHz, every 500th message NaN or in a wrong frame), emulator
              (protocol v2), bridge: `rostopic hz` on /EW/measured_js, a 3 s bag of every topic
              read back (the topic table: type, messages, rate; every tick the recorder kept of
              the stand-in's 1 kHz topic, at least 99 %, is there), the bag's tick log converted to
              the bridge's CSV and scored by endohaptics-force-report against the emulator's
              truth; the refused stylus messages counted; stylus message -> setpoint on the wire
  drop-in     the 2016 phantom_omni driver stand-in (TF base -> arm -> tip, /omni1_joint_states,
              rendering omni1_force_feedback) stops after 2 s: the bridge follows, renders, then
              holds the setpoint and releases the motors within the input timeout, never a jump
  three-hosts the console (stand-in + roscore) on 127.0.0.1, the bridge on 127.0.0.2, the
              emulator on 127.0.0.3: every connection goes to the address its node advertises
  alloc       the loop with the ROS stylus and publisher counts heap allocations on its own
              thread over 2000 ticks while ROS traffic flows both ways: 0
  p99         the loop's p99 period error with ROS publishing (a bag recording every topic)
              against endohaptics-bridge without ROS, same emulator, same rate (3 interleaved
              runs of 1.5 s each; ROS_E2E_P99_RUNS and ROS_E2E_P99_SECONDS for longer ones)
"""
import csv
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

BIN, SOURCE, CASE = sys.argv[1], sys.argv[2], sys.argv[3]
STARTED = []
# The loop as on the rig: SCHED_FIFO (root or CAP_SYS_NICE; without, the bridge says so and runs
# SCHED_OTHER), so what is measured is what ROS costs the loop, not the other builds on the machine.
# With two CPUs or more the loop gets the last one to itself, and the ROS bridge keeps ROS's threads
# and their network work off it (--cpu; endohaptics-bridge pins its loop the same way).
FIFO = ["--fifo-priority", "80"] + (["--cpu", str(max(os.sched_getaffinity(0)))]
                                    if len(os.sched_getaffinity(0)) > 1 else [])

LOOP_CPU = max(os.sched_getaffinity(0))
# ROS_E2E_P99_COUNTS=1: print the loop CPU's interrupt, IPI and softirq counts of each p99 run.
COUNTS = os.environ.get("ROS_E2E_P99_COUNTS") == "1"


def fail(message):
    print("FAIL: " + message)
    stop_all()
    sys.exit(1)


def free_port(kind=socket.SOCK_STREAM):
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start(args, env, log, **kw):
    """Starts a process in its own process group (stop_all ends the group)."""
    p = subprocess.Popen(args, env=env, stdout=open(log, "w"), stderr=subprocess.STDOUT,
                         start_new_session=True, **kw)
    STARTED.append(p)
    return p


def stop(p, timeout=5.0):
    if p.poll() is None:
        try:
            os.killpg(p.pid, signal.SIGINT)
            p.wait(timeout=timeout)
        except (ProcessLookupError, subprocess.TimeoutExpired):
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait()


def stop_all():
    for p in reversed(STARTED):
        stop(p)


def ros_env(work, master_ip, port, ip):
    env = dict(os.environ)
    env.update(ROS_HOME=os.path.join(work, "ros_home"), ROS_LOG_DIR=os.path.join(work, "ros_log"),
               ROS_MASTER_URI=f"http://{master_ip}:{port}", PYTHONUNBUFFERED="1")
    env.pop("ROS_HOSTNAME", None)
    env.pop("ROS_IP", None)
    # roscpp binds its TCPROS listener to 127.0.0.1 alone when ROS_IP starts with "127." and
    # still advertises ROS_IP: a node on 127.0.0.2 would be unreachable. ROS_HOSTNAME advertises
    # the address without that (docs/ros.md); on a real network ROS_IP is fine.
    env["ROS_IP" if ip == "127.0.0.1" else "ROS_HOSTNAME"] = ip
    # Debian's ROS tools are /usr/bin/python3 scripts; a virtualenv's python must not shadow it.
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    return env


def start_roscore(work, ip="127.0.0.1"):
    port = free_port()
    env = ros_env(work, ip, port, ip)
    start(["roscore", "-p", str(port)], env, os.path.join(work, "roscore.log"))
    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        try:
            master.getPid("/ros_e2e")
            return port
        except OSError:
            time.sleep(0.1)
    fail("roscore did not answer within 20 s: " + open(os.path.join(work, "roscore.log")).read())


def start_emulator(work, env, ip="127.0.0.1", extra=()):
    port = free_port(socket.SOCK_DGRAM)
    key = os.path.join(work, "key")
    if not os.path.exists(key):
        subprocess.run([os.path.join(BIN, "endohaptics-bridge"), "--generate-key", key],
                       check=True, capture_output=True)
    truth = os.path.join(work, "truth.csv")
    start([os.path.join(BIN, "endohaptics-sbrio-emulator"), "--bind", ip, "--port", str(port),
           "--key", key, "--truth-log", truth, "--quiet", *extra], env,
          os.path.join(work, "emulator.log"))
    return port, key, truth


def run(args, env, timeout=60):
    r = subprocess.run(args, env=env, capture_output=True, text=True, timeout=timeout)
    return r.returncode, r.stdout + r.stderr


def wait_for(path, pattern, timeout=15.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if os.path.exists(path) and re.search(pattern, open(path).read()):
            return True
        time.sleep(0.05)
    return False


def bridge_args(port, key, ip="127.0.0.1", duration=6.0, extra=()):
    return [os.path.join(BIN, "endohaptics-ros-bridge"), "--sbrio", f"{ip}:{port}", "--key", key,
            "--duration", str(duration), *extra]


def number(pattern, text, what):
    m = re.search(pattern, text)
    if not m:
        fail(f"no {what} in:\n{text}")
    return float(m.group(1))


def bag_table(bag, env):
    """{topic: (type, messages, rate)} from `rosbag info --yaml`."""
    code, out = run(["rosbag", "info", "--yaml", bag], env)
    if code != 0:
        fail("rosbag info: " + out)
    duration = number(r"\nduration: ([0-9.]+)", out, "bag duration")
    table = {}
    for m in re.finditer(r"- topic: (\S+)\n\s+type: (\S+)\n\s+messages: (\d+)", out):
        n = int(m.group(3))
        table[m.group(1)] = (m.group(2), n, n / duration if duration > 0 else 0.0)
    return duration, table


def case_topics(work):
    port = start_roscore(work)
    env = ros_env(work, "127.0.0.1", port, "127.0.0.1")
    sbrio, key, truth = start_emulator(work, env, extra=["--duration", "10"])
    standin = start([os.path.join(BIN, "endohaptics-ros-touch-standin"), "--bad-every", "500",
                     "--duration", "8"], env, os.path.join(work, "standin.log"))
    bridge_log = os.path.join(work, "bridge.log")
    bridge = start(bridge_args(sbrio, key, duration=5.5,
                               extra=["--log", os.path.join(work, "tick.csv"), "--input-frame",
                                      "touch", *FIFO]), env, bridge_log)
    if not wait_for(bridge_log, r"bridge: sbRIO"):
        fail("the bridge did not start: " + open(bridge_log).read())
    time.sleep(1.0)
    bag = os.path.join(work, "session.bag")
    recorder = start(["rosbag", "record", "-a", "-O", bag, "--duration=3.5", "--tcpnodelay"], env,
                     os.path.join(work, "record.log"))
    hz = subprocess.Popen(["rostopic", "hz", "/EW/measured_js", "--tcpnodelay", "-w", "3000"],
                          env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          start_new_session=True)
    STARTED.append(hz)
    time.sleep(4.0)
    os.killpg(hz.pid, signal.SIGINT)
    hz_out = hz.communicate(timeout=10)[0]
    recorder.wait(timeout=20)
    bridge.wait(timeout=30)
    out = open(bridge_log).read()
    if bridge.returncode != 0:
        fail(f"bridge exit {bridge.returncode}:\n{out}")
    rates = [float(x) for x in re.findall(r"average rate: ([0-9.]+)", hz_out)]
    if not rates:
        fail("rostopic hz printed no rate:\n" + hz_out)
    hz_rate = rates[-1]
    duration, table = bag_table(bag, env)
    expected = {"/EW/measured_js": "sensor_msgs/JointState",
                "/EW/setpoint_js": "sensor_msgs/JointState",
                "/EW/measured_jf": "sensor_msgs/JointState",
                "/EW/operating_state": "std_msgs/String", "/EW/loop_stats": "std_msgs/String",
                "/EW/tick_log": "std_msgs/Float64MultiArray",
                "/touch/servo_cf": "geometry_msgs/WrenchStamped",
                "/touch/measured_cp": "geometry_msgs/PoseStamped"}
    print(f"bag: {duration:.2f} s, {sum(n for _, n, _ in table.values())} messages")
    print(f"{'topic':24s} {'type':30s} {'messages':>8s} {'rate (Hz)':>9s}")
    for topic in sorted(table):
        t, n, r = table[topic]
        print(f"{topic:24s} {t:30s} {n:8d} {r:9.1f}")
    for topic, t in expected.items():
        if topic not in table or table[topic][0] != t:
            fail(f"{topic} ({t}) not in the bag")
    print(f"rostopic hz /EW/measured_js: {hz_rate:.1f} Hz (window of up to 3000 messages)")
    converted = os.path.join(work, "from_bag.csv")
    code, conv = run([os.path.join(SOURCE, "examples/ros_bridge/bag_to_tick_log.py"), bag,
                      converted], env)
    print(conv.strip())
    if code != 0:
        fail("bag_to_tick_log: " + conv)
    with open(converted) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(work, "tick.csv")) as f:
        logged = {r["time"]: r for r in csv.DictReader(f)}
    # Every tick in the bag is a row of the bridge's own --log (same time, same numbers).
    mismatched = 0
    for r in rows:
        match = [v for t, v in logged.items() if abs(float(t) - float(r["time"])) < 1e-6]
        if not match or any(abs(float(match[0][c]) - float(r[c])) > 1e-5 * max(1, abs(float(r[c])))
                            for c in ("setpoint2", "position2", "current2", "motor_force2")):
            mismatched += 1
        if mismatched:
            break
    if mismatched:
        fail("a converted row differs from the bridge's own log")
    stop_all()
    # The bag's ticks and the bridge's own log, scored alike against the emulator's truth.
    code, report = run([os.path.join(BIN, "endohaptics-force-report"), "--truth", truth, "--log",
                        converted, "--label", "from the bag", "--log",
                        os.path.join(work, "tick.csv"), "--truth", truth, "--label",
                        "the bridge's --log"], env)
    print("\n".join(report.strip().splitlines()[-2:]))
    if code != 0:
        fail("endohaptics-force-report on the converted bag: " + report)
    refused = number(r"refused non-finite (\d+)", out, "refused count")
    wrong = number(r"wrong frame (\d+)", out, "wrong frame count")
    rt = re.search(r"stylus message -> setpoint on the wire: (\d+) samples, mean ([0-9.]+) ms, "
                   r"p99 ([0-9.]+) ms, max ([0-9.]+) ms", out)
    print("bridge: loop rate " + re.search(r"\nrate\s+([0-9.]+ Hz)", out).group(1))
    print(re.search(r"ros-bridge: input: .*", out).group(0))
    print(re.search(r"ros-bridge: published .*", out).group(0))
    problems = []
    if hz_rate < 990:
        problems.append(f"rostopic hz {hz_rate:.1f} Hz < 990")
    # `rosbag record` is a third party: a stall of it (its subscriptions queue 100 messages each)
    # drops every topic alike, the stand-in's 1 kHz stylus too (seen once: 3245 of each in a
    # 3.49 s bag while the rig page's test ran beside it). The bridge's ticks are judged against
    # what the same recorder kept of the stand-in's topic; the recorder itself may lose 10 %.
    standin_messages = table.get("/touch/measured_cp", ("", 0, 0.0))[1]
    if standin_messages < 0.99 * 1000 * duration:
        print(f"note: the recorder kept {standin_messages} of the stand-in's 1 kHz messages in a "
              f"{duration:.2f} s bag")
    if duration < 3.0 or len(rows) < 0.99 * min(1000 * duration, standin_messages):
        problems.append(f"{len(rows)} ticks in a {duration:.2f} s bag (the stand-in's topic: "
                        f"{standin_messages})")
    if standin_messages < 0.9 * 1000 * duration:
        problems.append(f"the recorder kept {standin_messages} of the stand-in's messages in a "
                        f"{duration:.2f} s bag (less than 90 %)")
    if refused < 1 or wrong < 1:
        problems.append("the NaN and wrong-frame stylus messages were not counted")
    if not rt or int(rt.group(1)) < 1000:
        problems.append("no stylus -> wire round trips")
    if problems:
        fail("; ".join(problems))
    print(f"PASS: topics at {hz_rate:.1f} Hz, a {duration:.1f} s bag of {len(table)} topics read "
          f"back ({len(rows)} ticks), refused stylus messages counted ({refused:.0f} non-finite, "
          f"{wrong:.0f} wrong frame), stylus -> wire mean {rt.group(2)} ms p99 {rt.group(3)} ms")


def case_drop_in(work):
    port = start_roscore(work)
    env = ros_env(work, "127.0.0.1", port, "127.0.0.1")
    sbrio, key, _ = start_emulator(work, env, extra=["--duration", "10"])
    standin_log = os.path.join(work, "standin.log")
    standin = start([os.path.join(BIN, "endohaptics-ros-touch-standin"), "--mode", "phantom-omni",
                     "--stop-after", "2.0", "--duration", "6"], env, standin_log)
    if not wait_for(standin_log, r"standin: phantom-omni"):
        fail("the stand-in did not start: " + open(standin_log).read())
    tick = os.path.join(work, "tick.csv")
    # 4 s: the stylus moves for 2 s from the bridge's subscription (late on a loaded machine),
    # then the release is watched.
    code, out = run(bridge_args(sbrio, key, duration=4.0,
                                extra=["--input", "phantom-omni", "--input-timeout", "100",
                                       "--log", tick]), env)
    standin.wait(timeout=20)
    standin_out = open(standin_log).read()
    print(out.strip())
    print(standin_out.strip())
    if code != 0:
        fail(f"bridge exit {code}")
    md5 = re.search(r"phantom_omni/OmniFeedback md5 ([0-9a-f]{32})", out).group(1)
    # The md5 genmsg gives the definition (the .msg we ship: phantom_omni's, field for field).
    sys.path.insert(0, "/usr/lib/python3/dist-packages")
    import genmsg.msg_loader
    import genmsg.gentools
    ctx = genmsg.msg_loader.MsgContext.create_default()
    search = {"geometry_msgs": ["/usr/share/geometry_msgs/msg"],
              "std_msgs": ["/usr/share/std_msgs/msg"],
              "phantom_omni": [os.path.join(SOURCE, "examples/ros_bridge/msg/phantom_omni")]}
    spec = genmsg.msg_loader.load_msg_by_type(ctx, "phantom_omni/OmniFeedback", search)
    genmsg.msg_loader.load_depends(ctx, spec, search)
    expected_md5 = genmsg.gentools.compute_md5(ctx, spec)
    with open(tick) as f:
        rows = list(csv.DictReader(f))
    # Rendered while the stylus moved; after it stopped: released within the input timeout
    # (+ a tick), the setpoint held, every step within the rate limit (1 rad/s default: 1 mrad).
    received = int(re.search(r"received (\d+) force commands", standin_out).group(1))
    up = [r for r in rows if int(r["status"]) == 0]
    released = [r for r in rows if int(r["status"]) == 4]  # device_error: the operator is lost
    problems = []
    if md5 != expected_md5:
        problems.append(f"md5 {md5} != {expected_md5}")
    if received < 1000:
        problems.append(f"the stand-in got {received} force commands")
    if len(up) < 1000:
        problems.append(f"only {len(up)} ticks ok while the stylus moved")
    if not released or any(int(r["enable_mask"]) != 0 for r in released):
        problems.append("no release after the stylus stopped")
    # Every step within the rate limit (SafetyConfig::max_setpoint_rate, 4 rad/s) over the time
    # between the two ticks (1 ms, more when a loaded machine delayed a tick), while the motors
    # follow. After a lost link (status 2) or with the motors released (enable mask 0: a lost
    # link or a lost operator) the limiter restarts from the measured position, so the logged
    # setpoint may jump to where the tool is; that row is checked for it instead: within one step
    # of the tool (of its position in either row: the state the limiter started from).
    max_step = worst = 0.0
    for a, b in zip(rows, rows[1:]):
        dt = max(float(b["time"]) - float(a["time"]), 1e-3)
        if int(a["status"]) == 2 or int(a["enable_mask"]) == 0:
            if int(b["enable_mask"]) != 0:
                for j in range(4):
                    tool = float(b[f"position{j}"])
                    away = abs(float(b[f"setpoint{j}"]) - tool)
                    if away > 4.0 * dt + abs(tool - float(a[f"position{j}"])) + 1e-6:
                        problems.append(f"motor {j} re-enabled {away:.4f} rad from the tool "
                                        f"at t = {b['time']}")
            continue
        for j in range(4):
            step = abs(float(b[f"setpoint{j}"]) - float(a[f"setpoint{j}"]))
            max_step = max(max_step, step)
            worst = max(worst, step / (4.0 * dt + 1e-6))
    if worst > 1.0 + 1e-6:
        problems.append(f"a setpoint step beyond 4 rad/s (largest step {max_step} rad)")
    # The setpoint held through each loss: while the operator is lost the loop follows no input.
    # One change is allowed, to where the tool is, on the tick after the link recovered (link state
    # 3 lost -> 4 recovering) during the loss: the recovery restarts the rate limiter from that
    # tick's measured position (the motors are released, so it moves nothing). The loss itself is
    # counted below: the stand-in stops once, so one loss, one status-4 stretch in the tick log.
    episodes = 0
    for i, b in enumerate(rows):
        if int(b["status"]) != 4:
            continue
        a = rows[i - 1] if i > 0 else None
        if a is None or int(a["status"]) != 4:
            episodes += 1
            continue
        if all(a[f"setpoint{j}"] == b[f"setpoint{j}"] for j in range(4)):
            continue
        restarted = (i >= 2 and int(a["link"]) == 4 and int(rows[i - 2]["link"]) == 3 and
                     all(abs(float(b[f"setpoint{j}"]) - float(a[f"position{j}"])) <= 1e-6
                         for j in range(4)))
        if not restarted:
            problems.append(f"the setpoint moved while the operator was lost (t = {b['time']})")
            break
    lost = re.search(r"lost (\d+) times", out)
    if not lost or int(lost.group(1)) != 1:
        problems.append(f"the input loss was counted {lost.group(1) if lost else 'no'} times, "
                        f"not once (the stand-in stops once; {episodes} losses in the tick log)")
    if problems:
        fail("; ".join(problems))
    print(f"PASS: phantom_omni drop-in: {len(up)} ticks followed TF base -> tip, {received} "
          f"OmniFeedback (md5 {md5}) rendered; stylus silent: setpoint held, motors released "
          f"({len(released)} ticks), largest setpoint step {max_step * 1e3:.3f} mrad")


def case_three_hosts(work):
    port = start_roscore(work, "127.0.0.1")
    console = ros_env(work, "127.0.0.1", port, "127.0.0.1")
    robot_side = ros_env(work, "127.0.0.1", port, "127.0.0.2")
    sbrio, key, _ = start_emulator(work, console, ip="127.0.0.3", extra=["--duration", "10"])
    standin_log = os.path.join(work, "standin.log")
    standin = start([os.path.join(BIN, "endohaptics-ros-touch-standin"), "--duration", "4"],
                    console, standin_log)
    bridge_log = os.path.join(work, "bridge.log")
    bridge = start(bridge_args(sbrio, key, ip="127.0.0.3", duration=2.5,
                               extra=["--local", f"127.0.0.2:{free_port(socket.SOCK_DGRAM)}"]),
                   robot_side, bridge_log)
    if not wait_for(bridge_log, r"bridge: sbRIO"):
        fail("the bridge did not start: " + open(bridge_log).read())
    time.sleep(1.0)
    _, info_js = run(["rostopic", "info", "/EW/measured_js"], console)
    _, info_cp = run(["rostopic", "info", "/touch/measured_cp"], robot_side)
    bridge.wait(timeout=30)
    standin.wait(timeout=30)
    out = open(bridge_log).read()
    standin_out = open(standin_log).read()
    print(info_js.strip())
    print(info_cp.strip())
    print(re.search(r"ros-bridge: ROS master.*", out).group(0))
    print(re.search(r"bridge: link: .*", out).group(0))
    print(standin_out.strip())
    problems = []
    if bridge.returncode != 0:
        problems.append(f"bridge exit {bridge.returncode}")
    if not re.search(r"Publishers:\s*\n\s*\* /endohaptics_bridge \(http://127\.0\.0\.2:", info_js):
        problems.append("/EW/measured_js not published from 127.0.0.2")
    if not re.search(r"Publishers:\s*\n\s*\* /touch_standin \(http://127\.0\.0\.1:", info_cp):
        problems.append("/touch/measured_cp not published from 127.0.0.1")
    if not re.search(r"Subscribers:\s*\n\s*\* /touch_standin \(http://127\.0\.0\.1:", info_js) and \
            "/touch_standin" not in info_js:
        pass  # the stand-in subscribes to servo_cf, not measured_js
    if "this node /endohaptics_bridge (127.0.0.2)" not in out:
        problems.append("the bridge did not advertise 127.0.0.2")
    if "link: up" not in out:
        problems.append("the link to 127.0.0.3 never came up")
    received = int(re.search(r"received (\d+) force commands", standin_out).group(1))
    if received < 1000:
        problems.append(f"the console got {received} force commands")
    if problems:
        fail("; ".join(problems))
    print(f"PASS: console + roscore on 127.0.0.1, bridge on 127.0.0.2, emulator on 127.0.0.3: "
          f"link up, {received} force commands back at the console")


def case_alloc(work):
    port = start_roscore(work)
    env = ros_env(work, "127.0.0.1", port, "127.0.0.1")
    # Long enough for a loaded machine (the test stops it): the alloc check waits for its stylus.
    start([os.path.join(BIN, "endohaptics-ros-touch-standin"), "--duration", "40"], env,
          os.path.join(work, "standin.log"))
    hz = start(["rostopic", "hz", "/EW/measured_js", "--tcpnodelay"], env,
               os.path.join(work, "hz.log"))
    code, out = run([os.path.join(BIN, "endohaptics-ros-alloc-test")], env, timeout=45)
    print(out.strip())
    if code != 0 or "PASS" not in out:
        fail(f"endohaptics-ros-alloc-test exit {code}")
    print("PASS: " + out.strip().splitlines()[-1].replace("PASS: ", ""))


def p99_error(text):
    return number(r"period err\s+mean\s+[0-9.]+ us\s+p99\s+([0-9.]+) us", text, "p99 period error")


def p99_compute(text):
    return number(r"compute\s+mean\s+[0-9.]+ us\s+p99\s+([0-9.]+) us", text, "p99 compute time")


def cpu_counts(cpu):
    """Per-CPU interrupt/IPI and softirq counts of one CPU (from /proc/interrupts, /proc/softirqs)."""
    counts = {}
    for path in ("/proc/interrupts", "/proc/softirqs"):
        lines = open(path).read().splitlines()
        ncpu = len(lines[0].split())
        for line in lines[1:]:
            parts = line.split()
            if len(parts) > cpu + 1 and parts[cpu + 1].isdigit() and len(parts) >= ncpu + 1:
                counts[parts[0].rstrip(":")] = int(parts[cpu + 1])
    return counts


def counts_diff(before, after):
    return {k: after[k] - before.get(k, 0) for k in after if after[k] - before.get(k, 0)}


def case_p99(work):
    port = start_roscore(work)
    env = ros_env(work, "127.0.0.1", port, "127.0.0.1")
    sbrio, key, _ = start_emulator(work, env)
    start([os.path.join(BIN, "endohaptics-ros-touch-standin")], env,
          os.path.join(work, "standin.log"))
    record = start(["rosbag", "record", "-a", "-O", os.path.join(work, "p99.bag")], env,
                   os.path.join(work, "record.log"))
    results = {"without ROS": [], "with ROS": []}
    compute = {"without ROS": [], "with ROS": []}  # the tick's own time, p99
    # Longer measurements: ROS_E2E_P99_RUNS (default 3), ROS_E2E_P99_SECONDS (default 2.5).
    runs = int(os.environ.get("ROS_E2E_P99_RUNS", "3"))
    seconds = os.environ.get("ROS_E2E_P99_SECONDS", "1.5")
    for _ in range(runs):  # interleaved, so both see the same machine load; the median of each
        before = cpu_counts(LOOP_CPU) if COUNTS else {}
        code, plain = run([os.path.join(BIN, "endohaptics-bridge"), "--sbrio",
                           f"127.0.0.1:{sbrio}", "--key", key, "--duration", seconds, *FIFO],
                          env)
        if COUNTS:
            print("loop CPU counts without ROS:", counts_diff(before, cpu_counts(LOOP_CPU)))
        if code != 0:
            fail("endohaptics-bridge: " + plain)
        results["without ROS"].append(p99_error(plain))
        compute["without ROS"].append(p99_compute(plain))
        before = cpu_counts(LOOP_CPU) if COUNTS else {}
        code, ros = run(bridge_args(sbrio, key, duration=float(seconds), extra=FIFO), env)
        if COUNTS:
            print("loop CPU counts with ROS:   ", counts_diff(before, cpu_counts(LOOP_CPU)))
        if code != 0:
            fail("endohaptics-ros-bridge: " + ros)
        results["with ROS"].append(p99_error(ros))
        compute["with ROS"].append(p99_compute(ros))
    stop(record)
    without = sorted(results["without ROS"])[runs // 2]
    with_ros = sorted(results["with ROS"])[runs // 2]
    ratio = with_ros / without if without > 0 else float("inf")
    print(f"p99 period error (us) without ROS: {results['without ROS']}; with ROS publishing, a "
          f"stylus at 1 kHz and a bag recording every topic: {results['with ROS']}")
    print(f"medians {with_ros:.1f} / {without:.1f} us: ratio {ratio:.2f} (goal <= 1.1)")
    print(f"p99 compute time of the tick (us) without ROS: {compute['without ROS']}; with ROS: "
          f"{compute['with ROS']}")
    # The test holds a looser bound than the goal: other builds share these 2 cores, and the
    # runs' own spread is larger than the goal's margin (docs/ros.md has measured figures).
    if ratio > 3.0:
        fail(f"p99 period error ratio {ratio:.2f} > 3.0")
    print(f"PASS: p99 period error {with_ros:.1f} us with ROS vs {without:.1f} us without "
          f"(medians of {runs} runs of {seconds} s), ratio {ratio:.2f}")


CASES = {"topics": case_topics, "drop-in": case_drop_in, "three-hosts": case_three_hosts,
         "alloc": case_alloc, "p99": case_p99}

if __name__ == "__main__":
    if CASE not in CASES:
        sys.exit(f"unknown case {CASE}; one of {', '.join(CASES)}")
    with tempfile.TemporaryDirectory(prefix="ros_e2e_") as work:
        try:
            CASES[CASE](work)
        except Exception as e:  # say why, whatever broke (a timeout, a missing line)
            import traceback
            traceback.print_exc()
            logs = [f for f in os.listdir(work) if f.endswith(".log")]
            for f in sorted(logs):
                print(f"--- {f} (last lines)\n" +
                      "".join(open(os.path.join(work, f), errors="replace").readlines()[-15:]))
            print(f"FAIL: {CASE}: {type(e).__name__}: {e}")
            sys.exit(1)
        finally:
            stop_all()
