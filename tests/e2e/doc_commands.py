#!/usr/bin/env python3
"""Every shell block of the lab's documents runs, and their option tables match --help.

    doc_commands.py SOURCE_DIR BIN_DIR DOC.md...

The convention (docs/rig.md, "Checklist: from the bench to the rig"):
  - the ```sh blocks of each DOC run in order, each with `bash -e -o pipefail` in one temporary
    folder (with `build` pointing at BIN_DIR's build folder), a time limit each, and fail the
    test on a non-zero exit;
  - the block after `<!-- doc-test: settings -->` names the lab's shell variables; it is not run:
    this script sets exactly those variables (a variable it does not know fails the test) to
    127.0.0.1 addresses, free ports and temporary paths, with endohaptics-sbrio-emulator
    --protocol 2016 started here as the sbRIO and the native gateway standing in for the armhf one;
  - a block after `<!-- doc-test: background -->` runs until Ctrl-C: it is started in the
    background, the later blocks run, then its program gets SIGINT and the block must exit 0;
  - a block after `<!-- doc-test: skip REASON -->` is not run; the reason is printed;
  - ssh, scp, sudo, ip and ping are local stand-ins (ssh HOST CMD runs CMD here, scp copies locally
    -- a CSV whole lines only, as a closed log file --, ip and ping print their arguments), and
    `./run SUBCOMMAND` checks that ./run has the subcommand (this test runs inside that build);
  - the table after `<!-- doc-test: options PROGRAM -->` must name every option of PROGRAM --help
    and no other.
Prints "PASS: ..." or "FAIL: ...".
"""
import os
import re
import shutil
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import time

BLOCK_TIMEOUT_S = 180
MARKER = re.compile(r"^<!--\s*doc-test:\s*(\S+)\s*(.*?)\s*-->\s*$")


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def parse(path):
    """[(kind, argument, text, line)]: kind is sh (with the marker before it, if any) or options."""
    items = []
    lines = open(path).read().splitlines()
    marker = None
    i = 0
    while i < len(lines):
        line = lines[i]
        m = MARKER.match(line.strip())
        if m:
            marker = (m.group(1), m.group(2))
            i += 1
            continue
        if line.strip() == "```sh":
            start = i + 1
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                i += 1
            kind, arg = marker if marker else ("run", "")
            items.append((kind, arg, "\n".join(lines[start:i]), start))
            marker = None
        elif marker and marker[0] == "options" and line.startswith("|"):
            table = []
            while i < len(lines) and lines[i].startswith("|"):
                table.append(lines[i])
                i += 1
            items.append(("options", marker[1], "\n".join(table), i))
            marker = None
            continue
        elif line.strip() and marker and marker[0] != "options":
            pass  # prose between a marker and its block: the marker still applies
        i += 1
    return items


def help_options(bin_dir, program):
    out = subprocess.run([os.path.join(bin_dir, program), "--help"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, timeout=30).stdout
    return set(re.findall(r"^\s+(?:-\w,)?(--[a-z0-9-]+)", out, re.M)) - {"--help"}


def table_options(table):
    names = set()
    for row in table.splitlines()[2:]:
        cells = row.replace("\\|", "/").split("|")  # an escaped | inside a cell
        first = cells[1] if len(cells) >= 3 else ""
        names |= set(re.findall(r"(--[a-z0-9-]+)", first))
    return names


STUBS = {
    "ssh": """#!/bin/bash
# ssh HOST CMD...: CMD runs here.
while [[ $1 == -* ]]; do shift; done
shift
exec bash -e -o pipefail -c "$*"
""",
    "scp": """#!/bin/bash
# scp [-p] SRC... DEST: local copies (HOST: dropped); a CSV whole lines only (a closed log).
args=()
for a in "$@"; do [[ $a == -* ]] || args+=("${a#*:}"); done
dest=${args[-1]}
unset 'args[-1]'
for src in "${args[@]}"; do
  if [[ $src == *.csv ]]; then
    target=$dest; [[ -d $dest ]] && target=$dest/$(basename "$src")
    python3 -c 'import sys; d=open(sys.argv[1],"rb").read(); open(sys.argv[2],"wb").write(d[:d.rfind(b"\\n")+1])' "$src" "$target"
  else
    cp -p "$src" "$dest"
  fi
done
""",
    "sudo": """#!/bin/bash
exec "$@"
""",
    "ip": """#!/bin/bash
echo "ip (stand-in): $*"
if [[ "$*" == *"route get"* ]]; then echo "${@: -1} dev eth1 src 169.254.4.10"; fi
""",
    "ping": """#!/bin/bash
echo "ping (stand-in): $*"
""",
}


def pids_in_group(pgid):
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            if int(fields[2]) == pgid:
                with open(f"/proc/{entry}/comm") as f:
                    pids.append((int(entry), f.read().strip()))
        except (OSError, IndexError, ValueError):
            pass
    return pids


def main():
    if len(sys.argv) < 4:
        fail("usage: doc_commands.py SOURCE_DIR BIN_DIR DOC.md...")
    source_dir, bin_dir = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    docs = sys.argv[3:]
    work = tempfile.mkdtemp(prefix="eh-doc-")
    os.symlink(os.path.dirname(bin_dir), os.path.join(work, "build"))
    stubs = os.path.join(work, ".stubs")
    os.mkdir(stubs)
    for name, text in STUBS.items():
        path = os.path.join(stubs, name)
        with open(path, "w") as f:
            f.write(text)
        os.chmod(path, 0o755)
    with open(os.path.join(work, "run"), "w") as f:
        f.write(f"""#!/bin/bash
# ./run SUBCOMMAND: checks that {source_dir}/run has it (this test runs inside that build).
grep -qE "^#   \\./run $1( |$)" "{source_dir}/run" || {{ echo "./run has no subcommand '$1'" >&2; exit 2; }}
echo "./run $1: a subcommand of ./run (not run here)"
""")
    os.chmod(os.path.join(work, "run"), 0o755)

    # The sbRIO: the emulator on the 2016 wire; its truth log is the sbRIO's log.
    sbrio_log = os.path.join(work, "sbrio-log.csv")
    emulator = subprocess.Popen(
        [os.path.join(bin_dir, "endohaptics-sbrio-emulator"), "--protocol", "2016", "--bind",
         "127.0.0.1", "--port", "0", "--truth-log", sbrio_log, "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    port = None
    for _ in range(50):
        line = emulator.stdout.readline()
        m = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
        if m:
            port = int(m.group(1))
            break
    if port is None:
        fail("the emulator (the sbRIO) did not start")
    gateway_port = free_port()
    variables = {
        "BIN": bin_dir, "ARMBIN": bin_dir, "GATEWAY_HOST": "root@gateway",
        "GW_DIR": os.path.join(work, "gateway"), "GATEWAY_LISTEN": f"127.0.0.1:{gateway_port}",
        "GATEWAY": f"127.0.0.1:{gateway_port}", "SBRIO": f"127.0.0.1:{port}",
        "SBRIO_IFACE": "eth1", "SBRIO_LOG": sbrio_log, "RIG": "doc-rig", "DEVICE": "sim",
        "RUN_S": "3"}
    env = dict(os.environ, PATH=stubs + os.pathsep + os.environ["PATH"], **variables)

    ran, skipped, background, tables = 0, [], [], 0
    try:
        for doc in docs:
            name = os.path.relpath(doc, source_dir)
            for kind, arg, text, line in parse(doc):
                where = f"{name}:{line}"
                if kind == "settings":
                    names = set(re.findall(r"^([A-Z_]+)=", text, re.M))
                    if names != set(variables):
                        fail(f"{where}: the settings block names {sorted(names)}; this test sets "
                             f"{sorted(variables)} (update tests/e2e/doc_commands.py with it)")
                    continue
                if kind == "options":
                    documented = table_options(text)
                    actual = help_options(bin_dir, arg)
                    if documented != actual:
                        fail(f"{where}: the {arg} options table lists "
                             f"{sorted(documented - actual)} that --help does not have and misses "
                             f"{sorted(actual - documented)}")
                    tables += 1
                    continue
                if kind == "skip":
                    skipped.append(f"{where} ({arg})")
                    continue
                if kind == "background":
                    p = subprocess.Popen(["bash", "-e", "-o", "pipefail", "-c", text], cwd=work,
                                         env=env, start_new_session=True,
                                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                         text=True)
                    time.sleep(1.5)
                    if p.poll() is not None:
                        fail(f"{where}: the background block ended at once ({p.returncode}):\n"
                             f"{p.stdout.read()}\n{text}")
                    background.append((where, p, text))
                    continue
                if kind != "run":
                    fail(f"{where}: unknown doc-test marker '{kind}'")
                t0 = time.monotonic()
                try:
                    r = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", text], cwd=work,
                                       env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                       text=True, timeout=BLOCK_TIMEOUT_S)
                except subprocess.TimeoutExpired:
                    fail(f"{where}: still running after {BLOCK_TIMEOUT_S} s:\n{text}")
                if r.returncode != 0:
                    fail(f"{where}: exit {r.returncode} after {time.monotonic() - t0:.1f} s:\n"
                         f"--- block\n{text}\n--- output\n{r.stdout[-4000:]}")
                print(f"ok {where} ({time.monotonic() - t0:.1f} s)")
                ran += 1
        for where, p, text in background:
            # SIGINT to the block's programs but the shell and tee: as Ctrl-C on the program.
            for pid, comm in pids_in_group(p.pid):
                if comm.startswith("endohaptics"):
                    os.kill(pid, signal.SIGINT)
            try:
                out, _ = p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                fail(f"{where}: did not end within 10 s of SIGINT")
            if p.returncode != 0:
                fail(f"{where}: exit {p.returncode} after SIGINT:\n{out[-4000:]}")
            print(f"ok {where} (background, ended by SIGINT): {out.strip().splitlines()[-1]}")
            ran += 1
    finally:
        for _, p, _ in background:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
        emulator.send_signal(signal.SIGINT)
        emulator.communicate(timeout=10)
    print(f"PASS: {ran} shell blocks of {', '.join(docs)} ran and exited 0, {tables} option "
          f"tables match --help; not run: {'; '.join(skipped) if skipped else 'none'}")
    shutil.rmtree(work, ignore_errors=True)  # kept after a failure, for its files


if __name__ == "__main__":
    main()
