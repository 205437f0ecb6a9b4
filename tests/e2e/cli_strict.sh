#!/usr/bin/env bash
# Strict command lines (docs/safety.md): every program's numbers parse whole and inside their stated range or
# the program exits non-zero naming the option; a run whose result is not finite, or whose output
# could not be written (/dev/full), exits non-zero with a message. Each case failed before.
# Usage: cli_strict.sh BIN_DIR numbers|results|outputs|keys|inputs   (prints PASS: ... on success)
# keys: protocol v2 key files and --protocol 2016 (docs/protocol.md).
# inputs: every file a program reads is a regular file within a stated size (docs/safety.md).
set -euo pipefail
bin=$1
scenario=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# Runs "$@", expects a non-zero exit (not a crash) and $expected in stderr.
expect_error() {
  local expected=$1
  shift
  local rc=0
  timeout 20 "$@" >"$work/out" 2>"$work/err" || rc=$?
  [[ $rc -ne 0 ]] || fail "exit 0 for: $* (expected '$expected')"
  [[ $rc -ne 124 ]] || fail "timed out: $*"
  [[ $rc -lt 128 ]] || fail "crashed (exit $rc) for: $*: $(cat "$work/err")"
  grep -q -F -- "$expected" "$work/err" || fail "'$expected' not in stderr of $*: $(cat "$work/err")"
  echo "ok ($rc): $* -> $(head -1 "$work/err" | head -c 160)"
}

# The e2e system of identify_cli.sh: 2 inputs, 1 output, 2nd order, rows at 0.01 s; $4 scales
# every value (inputs and output).
make_csv() {
  awk -v rows="$2" -v seed="$3" -v scale="$4" 'BEGIN {
    srand(seed); x1 = 0; x2 = 0; u1 = 0; u2 = 0; h1 = 0; h2 = 0
    print "time,u1,u2,y"
    for (k = 0; k < rows; k++) {
      if (h1 == 0) { u1 = 2 * rand() - 1; h1 = 1 + int(8 * rand()) }
      if (h2 == 0) { u2 = 2 * rand() - 1; h2 = 1 + int(8 * rand()) }
      h1--; h2--
      y = 0.5 * x1 + 0.3 * x2 + 0.2 * u1 + 0.005 * (2 * rand() - 1)
      printf "%.4f,%.6e,%.6e,%.6e\n", k * 0.01, u1 * scale, u2 * scale, y * scale
      n1 = 1.5 * x1 - 0.7 * x2 + u1 + 0.5 * u2
      n2 = x1 - 0.3 * u2
      x1 = n1; x2 = n2
    }
  }' >"$1"
}
mean_fit() { sed -n 's/^mean fit: \([-0-9.]*\)%$/\1/p' "$1" | tail -1; }

identify="$bin/endohaptics-identify"
replay="$bin/endohaptics-replay"
bridge="$bin/endohaptics-bridge"
emulator="$bin/endohaptics-sbrio-emulator"
force_report="$bin/endohaptics-force-report"
csv=(--format csv --input u1 --input u2 --output y)

case $scenario in
  numbers)
    make_csv "$work/sys.csv" 600 7 1
    log=(--log "$work/sys.csv" "${csv[@]}")
    # The bridge and the emulator fail while parsing: no sbRIO, no socket needed.
    expect_error "--rate: '100abc' is not a number" "$bridge" --rate 100abc --duration 1
    expect_error "--rate: '0x10' is not a number" "$bridge" --rate 0x10 --duration 1
    expect_error "--rate: 'inf'" "$bridge" --rate inf --duration 1
    expect_error "--duration: 'nan' is not a finite number" "$bridge" --duration nan
    expect_error "--duration: '1e999' is out of range" "$bridge" --duration 1e999
    expect_error "--fifo-priority: '0x10' is not an integer" "$bridge" --fifo-priority 0x10
    expect_error "--cpu: '010' has a leading zero" "$bridge" --cpu 010
    expect_error "--busy-wait-us: 'nan'" "$bridge" --busy-wait-us nan
    expect_error "--sbrio port: '0x50' is not an integer" "$bridge" --sbrio 127.0.0.1:0x50 --duration 0.1
    expect_error "--port: '0x10' is not an integer" "$emulator" --port 0x10 --duration 0.1
    expect_error "--port: '70000' is out of range: expected an integer in [0, 65535]" "$emulator" --port 70000 --duration 0.1
    expect_error "--duration: 'nan'" "$emulator" --duration nan
    expect_error "--truth-period-ms: 'inf'" "$emulator" --truth-period-ms inf
    expect_error "--motors: '0x4'" "$emulator" --motors 0x4
    expect_error "--count: '5x'" "$bin/endohaptics-codec-loopback" --count 5x
    # The gateway's envelope: a jitter allowance that is no number or above 100 ms is refused.
    gateway="$bin/endohaptics-sbrio-gateway"
    expect_error "--jitter-ms: 'nan'" "$gateway" --jitter-ms nan
    expect_error "--jitter-ms: '200' is outside [0, 100]" "$gateway" --jitter-ms 200
    expect_error "--ticks: '0x10'" "$bin/endohaptics-custom-transport" --ticks 0x10
    expect_error "--joint: '0x2'" "$bin/endohaptics-force-report" --truth "$work/sys.csv" --log "$work/sys.csv" --joint 0x2
    expect_error "--skip: 'nan'" "$bin/endohaptics-force-report" --truth "$work/sys.csv" --log "$work/sys.csv" --skip nan
    expect_error "--ts: '-1' is outside" "$identify" "${log[@]}" --ts -1
    expect_error "--ts: 'nan'" "$identify" "${log[@]}" --ts nan
    expect_error "--min-segment: '-1' is outside [2, 10000000]" "$identify" "${log[@]}" --min-segment -1
    expect_error "--max-order: '0x3' is not an integer" "$identify" "${log[@]}" --max-order 0x3
    expect_error "--order: '2abc' is not an integer" "$identify" "${log[@]}" --order 2abc
    expect_error "--lowpass: 'nan'" "$identify" "${log[@]}" --lowpass nan
    expect_error "--filter-order: '33' is outside [1, 32]" "$identify" "${log[@]}" --filter-order 33
    expect_error "--min-segment: '0x10'" "$replay" --model preset:yaw2016 --log "$work/sys.csv" --min-segment 0x10
    expect_error "--ts: '-1' is outside" "$replay" --model preset:yaw2016 --log "$work/sys.csv" --ts -1
    # Sizes that would need unbounded memory: refused with the limit, before allocating.
    expect_error "more than the limit of 10000000 per log" "$identify" "${log[@]}" --ts 1e-7
    expect_error "signal 'u1' is named twice (as input and as output)" "$identify" --log "$work/sys.csv" --format csv --input u1 --output u1
    echo "PASS: every bad number or size exits non-zero naming the option"
    ;;
  results)
    make_csv "$work/sys.csv" 2000 7 1
    make_csv "$work/big.csv" 2000 7 1e150
    make_csv "$work/huge.csv" 2000 7 1e155
    "$identify" --log "$work/sys.csv" "${csv[@]}" --out "$work/model.json" >"$work/id.out"
    fit=$(mean_fit "$work/id.out")
    # The same data in other units: the same fit (identify scales each column internally).
    "$identify" --log "$work/big.csv" "${csv[@]}" >"$work/big.out"
    big_fit=$(mean_fit "$work/big.out")
    [[ -n $fit && $big_fit == "$fit" ]] || fail "fit on data x 1e150 is '$big_fit' %, unscaled '$fit' %"
    grep -q "^scaling: each column divided by its RMS" "$work/big.out" || fail "scaling not reported"
    "$replay" --model "$work/model.json" --format csv --log "$work/huge.csv" >"$work/rp.out" ||
      fail "replay on data x 1e155 failed: $(cat "$work/rp.out")"
    grep -q "correlation 1.0000" "$work/rp.out" || fail "correlation on data x 1e155: $(cat "$work/rp.out")"
    [[ $(mean_fit "$work/rp.out") == "$fit" ]] || fail "replay fit on data x 1e155 differs: $(cat "$work/rp.out")"
    # An unstable model replayed from x0 = 0 diverges: no "fit -inf %" with exit 0.
    # (A replaced by one with an eigenvalue > 1; "states" by 2^32 + 2, which an int wraps to 2.)
    awk '/^  "A": \[$/ { print "  \"A\": [[1.5, -0.7], [1.0, 0.9]],"; skip = 1; next }
         skip && /^  \],$/ { skip = 0; next }
         !skip { print }' "$work/model.json" >"$work/unstable.json"
    sed 's/^  "states": 2,$/  "states": 4294967298,/' "$work/model.json" >"$work/states.json"
    grep -q 4294967298 "$work/states.json" || fail "could not edit states"
    expect_error "the simulated output is not finite" "$replay" --model "$work/unstable.json" --format csv --log "$work/sys.csv" --x0 zero
    expect_error "field \"states\" is 4294967298, outside [1, 100]" "$replay" --model "$work/states.json" --format csv --log "$work/sys.csv"
    echo "PASS: identify on x 1e150 fits $big_fit % (unscaled $fit %), non-finite results fail"
    ;;
  outputs)
    [[ -w /dev/full ]] || { echo "PASS: skipped, no /dev/full"; exit 0; }
    make_csv "$work/sys.csv" 2000 7 1
    expect_error "save_model: writing /dev/full failed" "$identify" --log "$work/sys.csv" "${csv[@]}" --out /dev/full
    to_full=(bash -c '"$@" >/dev/full' to_full)  # runs the rest with stdout on a full disk
    expect_error "writing standard output failed" "${to_full[@]}" "$identify" --log "$work/sys.csv" "${csv[@]}"
    "$identify" --log "$work/sys.csv" "${csv[@]}" --out "$work/model.json" >/dev/null
    expect_error "writing standard output failed" "${to_full[@]}" "$replay" --model "$work/model.json" --format csv --log "$work/sys.csv"
    # The bridge runs without an sbRIO (the link stays down, every tick is logged); a short run
    # writes less than stdio's buffer, a longer one fails in the writer thread: both fail.
    expect_error "writing the log '/dev/full' failed" "$bridge" --sbrio 127.0.0.1:9 --duration 0.01 --log /dev/full --protocol 2016
    expect_error "'/dev/full'" "$bridge" --sbrio 127.0.0.1:9 --duration 0.3 --log /dev/full --protocol 2016
    expect_error "writing the truth log '/dev/full' failed" "$emulator" --bind 127.0.0.1 --port 0 --duration 0.2 --quiet --truth-log /dev/full --protocol 2016
    echo "PASS: every unwritable output exits non-zero naming it"
    ;;
  keys)
    # Protocol v2 key files: written 0600 from the random source, never overwritten,
    # never printed; refused when group or others may read them, or of the wrong length.
    for prog in "$bridge" "$emulator"; do
      name=$(basename "$prog")
      "$prog" --generate-key "$work/$name.key" >"$work/out" 2>&1 || fail "$name --generate-key: $(cat "$work/out")"
      [[ $(stat -c %a "$work/$name.key") == 600 ]] || fail "$name: key mode $(stat -c %a "$work/$name.key")"
      [[ $(stat -c %s "$work/$name.key") == 32 ]] || fail "$name: key of $(stat -c %s "$work/$name.key") bytes"
      hex=$(od -An -tx1 "$work/$name.key" | tr -d ' \n')
      ! grep -q -i -F "${hex:0:16}" "$work/out" || fail "$name printed its key"
      expect_error "exists already; refusing to overwrite a key" "$prog" --generate-key "$work/$name.key"
      cp -p "$work/$name.key" "$work/$name.open.key"
      chmod 640 "$work/$name.open.key"
      expect_error "lets group or others read or write the key; run: chmod 600" "$prog" --key "$work/$name.open.key" --duration 0.1
      head -c 31 "$work/$name.key" >"$work/$name.short.key"
      chmod 600 "$work/$name.short.key"
      expect_error "must hold exactly 32 bytes, holds 31" "$prog" --key "$work/$name.short.key" --duration 0.1
      expect_error "protocol v2 needs --key FILE" "$prog" --duration 0.1
    done
    [[ $(cmp -s "$work/endohaptics-bridge.key" "$work/endohaptics-sbrio-emulator.key"; echo $?) == 1 ]] ||
      fail "two generated keys are equal"
    # --protocol 2016 runs, and says that it is unauthenticated.
    "$emulator" --bind 127.0.0.1 --port 0 --duration 0.1 --quiet --protocol 2016 >"$work/out" 2>&1 ||
      fail "emulator --protocol 2016: $(cat "$work/out")"
    grep -q "WARNING: --protocol 2016: unauthenticated" "$work/out" || fail "no warning: $(cat "$work/out")"
    # (No robot side at 127.0.0.1:9: the run says so and exits 3, link never up.)
    status=0
    "$bridge" --sbrio 127.0.0.1:9 --duration 0.05 --protocol 2016 >"$work/out" 2>&1 || status=$?
    [[ $status == 3 ]] || fail "bridge --protocol 2016 without a robot: exit $status: $(cat "$work/out")"
    grep -q "bridge: link: never up (no answer)" "$work/out" || fail "no verdict: $(cat "$work/out")"
    grep -q "WARNING: --protocol 2016: unauthenticated" "$work/out" || fail "no warning: $(cat "$work/out")"
    echo "PASS: key files: generated 0600, never overwritten or printed; group-readable, short and missing keys refused; 2016 warns"
    ;;
  inputs)
    # A FIFO, a device or a directory given as any input file is refused at
    # once, naming the file (before: a FIFO blocked every program for ever, SIGTERM did not end the
    # bridge; /dev/zero as a log ended in std::bad_alloc naming no file), and so is a file above
    # its reader's limit (sparse files: nothing is read).
    make_csv "$work/sys.csv" 600 7 1
    "$identify" --log "$work/sys.csv" "${csv[@]}" --out "$work/model.json" >/dev/null
    printf 'time,force2\n0,1\n0.01,2\n' >"$work/truth.csv"
    mkfifo "$work/pipe"
    inputs=("$work/pipe" "FIFO (named pipe)" /dev/zero "character device" "$work" "directory")
    for ((i = 0; i < ${#inputs[@]}; i += 2)); do
      f=${inputs[i]}
      what="' is a ${inputs[i + 1]}, not a regular file"
      expect_error "read_csv: log file '$f$what" "$identify" --log "$f" "${csv[@]}"
      expect_error "read_endowrist_2016: log file '$f$what" "$identify" --log "$f"
      expect_error "read_umn_mis_2018: log file '$f$what" "$identify" --log "$f" --format umn-mis-2018
      expect_error "read_csv: log file '$f$what" "$replay" --model "$work/model.json" --format csv --log "$f"
      expect_error "model file '$f$what" "$replay" --model "$f" --format csv --log "$work/sys.csv"
      expect_error "key file '$f$what" "$bridge" --key "$f" --duration 0.1
      expect_error "key file '$f$what" "$emulator" --key "$f" --duration 0.1
      [[ -d $f ]] && continue  # CLI11 refuses a directory for --config, --truth and --log itself
      expect_error "configuration file '$f$what" "$bridge" --config "$f" --protocol 2016 --duration 0.1
      expect_error "read_csv: log file '$f$what" "$force_report" --truth "$f" --log "$work/sys.csv"
      expect_error "tick log '$f$what" "$force_report" --truth "$work/truth.csv" --log "$f"
    done
    truncate -s 1048577 "$work/big.json"
    expect_error "configuration file '$work/big.json' holds 1048577 bytes, more than the limit of 1048576 bytes" "$bridge" --config "$work/big.json" --protocol 2016 --duration 0.1
    truncate -s 67108865 "$work/big.json"
    expect_error "model file '$work/big.json' holds 67108865 bytes, more than the limit of 67108864 bytes" "$replay" --model "$work/big.json" --format csv --log "$work/sys.csv"
    truncate -s 1073741825 "$work/big.csv"
    expect_error "read_csv: log file '$work/big.csv' holds 1073741825 bytes, more than the limit of 1073741824 bytes (raise LogReadOptions::max_bytes to read it)" "$identify" --log "$work/big.csv" "${csv[@]}"
    expect_error "tick log '$work/big.csv' holds 1073741825 bytes, more than the limit of 1073741824 bytes (raise TickLogOptions::max_bytes to read it)" "$force_report" --truth "$work/truth.csv" --log "$work/big.csv"
    echo "PASS: FIFOs, devices, directories and files above their limit refused at once, named"
    ;;
  *)
    fail "unknown scenario $scenario"
    ;;
esac
