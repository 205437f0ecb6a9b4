#!/usr/bin/env python3
"""Checks the protocol v2 test vectors (docs/protocol.md) against an independent implementation:
Python's struct packing and hashlib.blake2b (key ids, handshake tags, session key derivation,
data packet tags under the session keys), and an RFC 4303 window.

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
    fields = {}
    vectors = []
    window = []
    handshake = []
    current = None
    for line in out:
        word, _, rest = line.partition(" ")
        if word in ("key", "key_id", "console_nonce", "robot_nonce"):
            fields[word] = bytes.fromhex(rest)
        elif word in ("hello", "welcome"):
            f = rest.split()
            current = {"name": word, "rig": f[1].encode()}
            current.update({f[i]: int(f[i + 1]) for i in range(2, len(f) - 1, 2)})
            handshake.append(current)
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
    key = fields.get("key")
    if key is None or len(key) != 32 or len(vectors) != 3 or len(handshake) != 2:
        fail("unexpected output of the vectors program:\n" + "\n".join(out))

    def tag(body, k):
        return hashlib.blake2b(body, key=k, digest_size=16).digest()

    # The key id: the key's keyed BLAKE2b-256 of the label, first 8 bytes.
    kid = hashlib.blake2b(b"endohaptics v2 key id", key=key, digest_size=32).digest()[:8]
    if kid != fields["key_id"]:
        fail(f"key id: library {fields['key_id'].hex()} != python {kid.hex()}")
    cn, rn = fields["console_nonce"], fields["robot_nonce"]
    hello, welcome = handshake
    rig = hello["rig"].ljust(16, b"\0")
    # HELLO: version, type 3, key id, rig, timestamp, console nonce, max round trip (us), 24 zero
    # bytes, tag under the long-term key: 110 bytes. WELCOME: type 4, key id, rig, both nonces,
    # the granted round trip, tag: 110 bytes.
    body = (struct.pack(">BB", 2, 3) + kid + rig + struct.pack(">Q", hello["timestamp"]) + cn +
            struct.pack(">I", hello["max_round_trip_us"]) + bytes(24))
    if body + tag(body, key) != hello["packet"] or len(hello["packet"]) != 110:
        fail(f"hello: library {hello['packet'].hex()} != python {(body + tag(body, key)).hex()}")
    body = (struct.pack(">BB", 2, 4) + kid + rig + cn + rn +
            struct.pack(">I", welcome["max_round_trip_us"]))
    if body + tag(body, key) != welcome["packet"] or len(welcome["packet"]) != 110:
        fail(f"welcome: library {welcome['packet'].hex()} != python "
             f"{(body + tag(body, key)).hex()}")
    # Session keys: BLAKE2b-256 keyed with the long-term key over label, direction, key id, rig,
    # console nonce, robot nonce. Session ids: each side's nonce's first 8 bytes.
    session_key = {d: hashlib.blake2b(b"endohaptics v2 session key" + bytes([d]) + kid + rig + cn +
                                      rn, key=key, digest_size=32).digest() for d in (1, 2)}
    pc_session, robot_session = struct.unpack(">Q", cn[:8])[0], struct.unpack(">Q", rn[:8])[0]

    # Every data packet from the fields, independently: version 2, type, four big-endian u64, the
    # 2016 payload, then BLAKE2b-128 keyed with its direction's session key.
    for v in vectors:
        body = struct.pack(">BBQQQQ", 2, v["type"], v["session"], v["sequence"], v["peer_session"],
                           v["ack"]) + v["payload"]
        t = tag(body, session_key[v["type"]])
        if body + t != v["packet"]:
            fail(f"vector {v['name']}: library packet {v['packet'].hex()} != python "
                 f"{(body + t).hex()}")
        expected_len = {1: 67, 2: 99}[v["type"]]
        if len(v["packet"]) != expected_len:
            fail(f"vector {v['name']}: {len(v['packet'])} bytes, expected {expected_len}")
        sender, receiver = ((pc_session, robot_session) if v["type"] == 1 else
                            (robot_session, pc_session))
        if (v["session"], v["peer_session"]) != (sender, receiver):
            fail(f"vector {v['name']}: session ids are not the nonces' first 8 bytes")
    # The 2016 payload of vector 3: 1.0, -0.75, 0.25, -0.25 as big-endian float32, mask 15.
    if vectors[0]["payload"] != struct.pack(">ffffB", 1.0, -0.75, 0.25, -0.25, 15):
        fail("vector 3's payload is not the 2016 setpoint packet of its values")
    vectors = handshake + vectors

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
    print(f"PASS: the key id, {len(vectors)} packets, their tags and the session keys agree with "
          "hashlib.blake2b, "
          f"{len(window)} window verdicts with RFC 4303, and docs/protocol.md shows every vector "
          "and the window trace")


if __name__ == "__main__":
    main()
