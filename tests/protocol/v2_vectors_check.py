#!/usr/bin/env python3
"""Checks the protocol v2 test vectors (docs/protocol.md) against an independent implementation:
Python's struct packing and hashlib.blake2b(key=..., digest_size=16), and an RFC 4303 window.

    v2_vectors_check.py VECTORS_PROGRAM DOCS_PROTOCOL_MD

Prints "PASS: ..." when every packet, tag and window verdict agrees and docs/protocol.md shows
every packet's hex; "FAIL: ..." otherwise.
"""
import hashlib
import re
import struct
import subprocess
import sys


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def main():
    program, docs = sys.argv[1], sys.argv[2]
    out = subprocess.run([program], capture_output=True, text=True, check=True).stdout.splitlines()
    key = None
    vectors = []
    window = []
    current = None
    for line in out:
        word, _, rest = line.partition(" ")
        if word == "key":
            key = bytes.fromhex(rest)
        elif word == "vector":
            current = {"name": rest}
            vectors.append(current)
        elif word == "type":
            f = rest.split()
            current["type"] = int(f[0])
            current["session"] = int(f[2], 16)
            current["sequence"] = int(f[4])
            current["peer_session"] = int(f[6], 16)
            current["ack"] = int(f[8])
        elif word in ("payload", "packet"):
            current[word] = bytes.fromhex(rest)
        elif word == "window":
            seq, verdict = rest.split(" ", 1)
            window.append((int(seq), verdict))
    if key is None or len(key) != 32 or len(vectors) != 4:
        fail("unexpected output of the vectors program:\n" + "\n".join(out))

    # Every packet from the fields, independently: version 2, type, four big-endian u64, the
    # 2016 payload, then BLAKE2b-128 keyed with the 32-byte key over everything before the tag.
    for v in vectors:
        body = struct.pack(">BBQQQQ", 2, v["type"], v["session"], v["sequence"], v["peer_session"],
                           v["ack"]) + v["payload"]
        tag = hashlib.blake2b(body, key=key, digest_size=16).digest()
        if body + tag != v["packet"]:
            fail(f"vector {v['name']}: library packet {v['packet'].hex()} != python "
                 f"{(body + tag).hex()}")
        expected_len = {1: 67, 2: 99}[v["type"]]
        if len(v["packet"]) != expected_len:
            fail(f"vector {v['name']}: {len(v['packet'])} bytes, expected {expected_len}")
    # The 2016 payload of vector 1: 1.0, -0.75, 0.25, -0.25 as big-endian float32, mask 0.
    if vectors[0]["payload"] != struct.pack(">ffffB", 1.0, -0.75, 0.25, -0.25, 0):
        fail("vector 1's payload is not the 2016 setpoint packet of its values")

    # RFC 4303 3.4.3 window of 64, as a set of accepted numbers.
    seen, top = set(), 0
    for seq, verdict in window:
        if seq == 0 or (seq <= top and top - seq >= 64):
            expected = "older than the replay window"
        elif seq in seen:
            expected = "duplicate or replay"
        else:
            expected = "ok"
            seen.add(seq)
            top = max(top, seq)
        if verdict != expected:
            fail(f"window: sequence {seq}: library says '{verdict}', RFC 4303 says '{expected}'")

    # docs/protocol.md shows the same bytes (hex may be split over lines and spaced).
    text = re.sub(r"[\s`|]", "", open(docs).read()).lower()
    for v in vectors:
        if v["packet"].hex() not in text:
            fail(f"docs/protocol.md does not show vector {v['name']}: {v['packet'].hex()}")
    if key.hex() not in text:
        fail("docs/protocol.md does not show the test key")
    words = {"ok": "ok", "duplicate or replay": "replayed", "older than the replay window": "too old"}
    trace = ", ".join(f"{seq} {words[verdict]}" for seq, verdict in window)
    if " ".join(trace.split()) not in " ".join(open(docs).read().split()):
        fail(f"docs/protocol.md does not show the window trace: {trace}")
    print(f"PASS: {len(vectors)} packets and tags agree with hashlib.blake2b, "
          f"{len(window)} window verdicts with RFC 4303, and docs/protocol.md shows every vector "
          "and the window trace")


if __name__ == "__main__":
    main()
