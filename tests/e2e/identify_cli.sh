#!/usr/bin/env bash
# Command-line tests of endohaptics-identify and endohaptics-replay on a synthetic CSV from a
# known 2nd-order, 2-input system, their causal scoring and their error handling.
# Usage: identify_cli.sh BIN_DIR recover|errors|plot|joint   (each prints PASS: ... on success)
# joint: the joint force models (--method stall_hold, push_load_observer,
# bidirectional_load_observer) on synthetic clamp hits: chosen by the inner cross-validation, written as kind "stall_hold",
# replayed causally, --x0 oracle refused.
set -euo pipefail
bin=$1
scenario=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# x(k+1) = A x(k) + B u(k), y(k) = C x(k) + 0.2 u1(k): A = [1.5 -0.7; 1 0] (poles 0.75 +- 0.37i),
# B = [1 0.5; 0 -0.3], C = [0.5 0.3]; u1, u2 random levels held 1..8 samples (awk srand),
# 0.5 % output noise; rows at 0.01 s with a time column. $1: file, $2: rows, $3: seed.
make_csv() {
  awk -v rows="$2" -v seed="$3" 'BEGIN {
    srand(seed); x1 = 0; x2 = 0; u1 = 0; u2 = 0; h1 = 0; h2 = 0
    print "time,u1,u2,y"
    for (k = 0; k < rows; k++) {
      if (h1 == 0) { u1 = 2 * rand() - 1; h1 = 1 + int(8 * rand()) }
      if (h2 == 0) { u2 = 2 * rand() - 1; h2 = 1 + int(8 * rand()) }
      h1--; h2--
      y = 0.5 * x1 + 0.3 * x2 + 0.2 * u1 + 0.005 * (2 * rand() - 1)
      printf "%.4f,%.6f,%.6f,%.6f\n", k * 0.01, u1, u2, y
      n1 = 1.5 * x1 - 0.7 * x2 + u1 + 0.5 * u2
      n2 = x1 - 0.3 * u2
      x1 = n1; x2 = n2
    }
  }' >"$1"
}
mean_fit() { sed -n 's/^mean fit: \([-0-9.]*\)%$/\1/p' "$1" | tail -1; }
# An integrator: y(k) = 0.02 sum of u1 (awk seeded); identify must refuse it.
make_integrator_csv() {
  awk -v rows="$2" -v seed="$3" 'BEGIN {
    srand(seed); y = 0; u = 0; h = 0
    print "time,u1,y"
    for (k = 0; k < rows; k++) {
      if (h == 0) { u = 2 * rand() - 1; h = 1 + int(8 * rand()) }
      h--
      printf "%.4f,%.6f,%.6f\n", k * 0.01, u, y
      y += 0.02 * u
    }
  }' >"$1"
}
# Clamp hits at 10 ms (awk seeded): the jaw moves in (velocity 0.07 rad/s, current ramping to
# -depth A), stalls (current relaxing), moves out (+0.4 A of friction); the force is a stall-hold
# (dead zone 0.2 A, held at |v| <= 0.05 rad/s, 30 ms velocity filter, 0.3 s lag, gain -7.5 N/A)
# plus 1 % noise. $1: file, $2: hits, $3: seed.
make_hits_csv() {
  awk -v hits="$2" -v seed="$3" 'BEGIN {
    srand(seed); vf = 0; held = 0; lag = 0
    print "time,current,velocity,force"
    for (h = 0; h < hits; h++) {
      depth = 0.5 + 0.5 * rand()
      for (k = 0; k < 300; k++) {
        if (k < 100) { v = 0.07; i = -depth * k / 100 }
        else if (k < 200) { v = 0; i = -depth * exp(-(k - 100) / 20) }
        else { v = -0.07; i = 0.4 }
        vf += 0.25 * (v - vf)
        if (vf > 0.05 || vf < -0.05) held = (i < -0.2) ? i + 0.2 : 0
        lag += (0.01 / 0.31) * (held - lag)
        printf "%.4f,%.6f,%.6f,%.6f\n", (h * 300 + k) * 0.01, i, v, -7.5 * lag + 0.03 * (2 * rand() - 1)
      }
    }
  }' >"$1"
}
at_least() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a >= b) }'; }

# Runs "$@", expects a non-zero exit (not a crash) and $expected in stderr.
expect_error() {
  local expected=$1
  shift
  local rc=0
  "$@" >"$work/out" 2>"$work/err" || rc=$?
  [[ $rc -ne 0 ]] || fail "exit 0 for: $* (expected '$expected')"
  [[ $rc -lt 128 ]] || fail "crashed (exit $rc) for: $*: $(cat "$work/err")"
  grep -q -- "$expected" "$work/err" || fail "'$expected' not in stderr of $*: $(cat "$work/err")"
  if grep -q -E "terminate called|Aborted|Segmentation" "$work/err"; then
    fail "crash message for $*: $(cat "$work/err")"
  fi
  echo "ok ($rc): $(head -c 200 "$work/err")"
}

identify="$bin/endohaptics-identify"
replay="$bin/endohaptics-replay"
make_csv "$work/sys.csv" 2000 7
csv=(--format csv --input u1 --input u2 --output y)

case $scenario in
  recover)
    "$identify" --log "$work/sys.csv" "${csv[@]}" --out "$work/model.json" | tee "$work/id.out"
    id_fit=$(mean_fit "$work/id.out")
    [[ -n $id_fit ]] || fail "identify printed no mean fit"
    at_least "$id_fit" 95 || fail "identify fit $id_fit % < 95 %"
    grep -q "order 2 (automatic)" "$work/id.out" || fail "automatic order is not 2"
    grep -q "Hankel singular values" "$work/id.out" || fail "no Hankel singular values printed"
    grep -q "rows kept" "$work/id.out" || fail "no reader report printed"
    [[ -s $work/model.json ]] || fail "no model written"
    grep -q '"files"' "$work/model.json" || fail "no provenance in the model"
    # Replay on fresh data from the same system (a longer file, other noise): defaults from the
    # model's signal names.
    make_csv "$work/val.csv" 3000 8
    "$replay" --model "$work/model.json" --format csv --log "$work/val.csv" | tee "$work/rp.out"
    rp_fit=$(mean_fit "$work/rp.out")
    [[ -n $rp_fit ]] || fail "replay printed no mean fit"
    at_least "$rp_fit" 95 || fail "replay fit $rp_fit % < 95 %"
    [[ $(tail -1 "$work/rp.out") == "mean fit: "*% ]] || fail "last line is not 'mean fit: X%'"
    [[ $(tail -2 "$work/rp.out" | head -1) == "mean RMSE: "* ]] || fail "line before last is not 'mean RMSE: X'"
    grep -q "^scoring (causal): x0 steady, warm-up 0.5 s" "$work/rp.out" || fail "replay does not state its causal scoring"
    grep -q "fit [0-9.]* %, correlation [0-9.]*, RMSE [0-9.e-]*, delay -\?[0-9]* ms$" "$work/rp.out" ||
      fail "no per-file fit, correlation, RMSE and delay"
    # The output-fitted score only when asked for, and labelled; the old name is refused.
    "$replay" --model "$work/model.json" --format csv --log "$work/val.csv" --x0 oracle >"$work/or.out"
    grep -q "^scoring: ORACLE, not a force-estimation result" "$work/or.out" || fail "oracle not labelled"
    # --method best tries all three weightings, scored causally.
    "$identify" --log "$work/sys.csv" "${csv[@]}" --method best --order 2 >"$work/best.out"
    for m in n4sid moesp cva; do grep -q "^$m: mean causal fit" "$work/best.out" || fail "no $m in best"; done
    at_least "$(mean_fit "$work/best.out")" 95 || fail "best fit < 95 %"
    grep -q "oracle x0, zero-phase data" "$work/id.out" || fail "identify does not show the oracle score beside"
    echo "PASS: identify fit $id_fit %, replay fit $rp_fit % (causal)"
    ;;
  errors)
    printf 'time,u1,u2,y\n0,1,2,3\n0.01,1,2,3\n0.02,2,1,3\n0.03,1,1,1\n0.04,2,2,2\n' >"$work/short.csv"
    { head -100 "$work/sys.csv"; echo "1.0,nan,0.1,0.2"; tail -n +102 "$work/sys.csv"; } \
      >"$work/nan.csv"
    echo '{"format": "endohaptics-model"' >"$work/broken.json"
    expect_error "does not exist" "$identify" --log "$work/missing.csv" "${csv[@]}"
    expect_error "no signal named 'u3'" "$identify" --log "$work/sys.csv" --format csv --input u3 --output y
    expect_error "no signal named 'force'" "$identify" --log "$work/sys.csv" --format csv --input u1 --output force
    expect_error "too few samples" "$identify" --log "$work/short.csv" "${csv[@]}"
    expect_error "non-finite" "$identify" --log "$work/nan.csv" "${csv[@]}"
    expect_error "unknown log format" "$identify" --log "$work/sys.csv" --format xls --input u1 --output y
    expect_error "--order: 'two' is not an integer" "$identify" --log "$work/sys.csv" "${csv[@]}" --order two
    expect_error "--deadzone" "$identify" --log "$work/sys.csv" "${csv[@]}" --deadzone 0.1,0.2,0.3
    "$identify" --log "$work/sys.csv" "${csv[@]}" --out "$work/model.json" >/dev/null
    expect_error "has 2 input(s) (u1, u2)" "$replay" --model "$work/model.json" --format csv --log "$work/sys.csv" --input u1 --output y
    expect_error "no signal named 'current'" "$replay" --model preset:yaw2016 --format csv --log "$work/sys.csv"
    expect_error "cannot be opened" "$replay" --model "$work/none.json" --format csv --log "$work/sys.csv"
    expect_error "model file" "$replay" --model "$work/broken.json" --format csv --log "$work/sys.csv"
    expect_error "unknown preset" "$replay" --model preset:roll --format csv --log "$work/sys.csv"
    expect_error "non-finite" "$replay" --model "$work/model.json" --format csv --log "$work/nan.csv"
    expect_error "too few samples" "$replay" --model "$work/model.json" --format csv --log "$work/short.csv"
    expect_error "renamed 'oracle'" "$replay" --model "$work/model.json" --format csv --log "$work/sys.csv" --x0 estimate
    expect_error "apply only to the output-fitted --x0 oracle score" "$replay" --model "$work/model.json" --format csv --log "$work/sys.csv" --offset median
    expect_error "--x0 must be steady or zero here" "$identify" --log "$work/sys.csv" "${csv[@]}" --x0 oracle
    make_integrator_csv "$work/int.csv" 1500 3
    expect_error "near-integrating" "$identify" --log "$work/int.csv" --format csv --input u1 --output y --order 1
    # --drop-non-finite turns the NaN row into a dropped, reported row.
    "$identify" --log "$work/nan.csv" "${csv[@]}" --drop-non-finite >"$work/drop.out"
    grep -q "non-finite 1" "$work/drop.out" || fail "dropped NaN row not reported"
    echo "PASS: every error case exits non-zero with its message"
    ;;
  plot)
    command -v gnuplot >/dev/null || { echo "PASS: skipped, no gnuplot"; exit 0; }
    "$identify" --log "$work/sys.csv" "${csv[@]}" --out "$work/model.json" >/dev/null
    "$replay" --model "$work/model.json" --format csv --log "$work/sys.csv" --plot "$work/fit.png" \
      >"$work/rp.out"
    [[ $(head -c 4 "$work/fit.png" | od -An -c | tr -d ' ') == '211PNG' ]] || fail "no PNG written"
    echo "PASS: plot written"
    ;;
  joint)
    make_hits_csv "$work/h1.csv" 6 11
    make_hits_csv "$work/h2.csv" 6 12
    make_hits_csv "$work/h3.csv" 8 13
    hits=(--format csv --input current --input velocity --output force --ts 0.01)
    "$identify" --log "$work/h1.csv" --log "$work/h2.csv" "${hits[@]}" \
      --method moesp,stall_hold --deadzone auto,none --out "$work/joint.json" | tee "$work/id.out"
    grep -q "^family choice (inner cross-validation, 2 folds)" "$work/id.out" ||
      fail "no inner cross-validation reported"
    grep -q "^family stall_hold: mean causal fit" "$work/id.out" || fail "stall_hold not scored"
    grep -q "^chosen: stall_hold" "$work/id.out" || fail "stall_hold not chosen"
    grep -q "loaded side negative" "$work/id.out" || fail "no fitted values reported"
    grep -q '"kind": "stall_hold"' "$work/joint.json" || fail "model file is not of kind stall_hold"
    "$replay" --model "$work/joint.json" --format csv --log "$work/h3.csv" | tee "$work/rp.out"
    grep -q "^scoring (causal): the model's state from its reset" "$work/rp.out" ||
      fail "replay does not state how a joint model is scored"
    [[ $(tail -1 "$work/rp.out") == "mean fit: "*% ]] || fail "last line is not 'mean fit: X%'"
    [[ $(tail -2 "$work/rp.out" | head -1) == "mean RMSE: "* ]] || fail "no mean RMSE line"
    at_least "$(mean_fit "$work/rp.out")" 95 || fail "replay fit < 95 %"
    expect_error "has no linear state to fit to the output" \
      "$replay" --model "$work/joint.json" --format csv --log "$work/h3.csv" --x0 oracle
    expect_error "push_load_observer and bidirectional_load_observer 2 or 3 (current, velocity" \
      "$identify" --log "$work/h1.csv" --format csv --input current --output force \
      --method push_load_observer
    echo "PASS: stall_hold chosen and replayed, fit $(mean_fit "$work/rp.out") % (causal)"
    ;;
  *)
    fail "unknown scenario $scenario"
    ;;
esac
