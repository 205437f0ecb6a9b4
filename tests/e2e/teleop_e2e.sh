#!/usr/bin/env bash
# End-to-end tests on UDP loopback: endohaptics-sbrio-emulator + endohaptics-bridge as separate
# processes, bounded in time. Usage: teleop_e2e.sh BIN_DIR steady|kill-restart|identified|delayed|
# instrument|stylus
set -euo pipefail
bin=$1
scenario=$2
work=$(mktemp -d)
emulator_pid=""
cleanup() {
  [[ -n $emulator_pid ]] && kill "$emulator_pid" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# Protocol v2: one fresh key (mode 0600) for both programs.
key="$work/link.key"
"$bin/endohaptics-bridge" --generate-key "$key" >/dev/null || fail "cannot generate a key"

# Starts the emulator on $1 (0: any port; further arguments are the emulator's) and sets
# emulator_pid and port. Each start writes its own file, created empty by this shell before the
# emulator runs: a reused name could still hold the previous emulator's "listening on" line
# when it is first read, and the bridge would then talk to a port nobody listens on.
emulator_starts=0
start_emulator() {
  emulator_starts=$((emulator_starts + 1))
  local out="$work/emulator.$emulator_starts.out"
  : >"$out"
  "$bin/endohaptics-sbrio-emulator" --bind 127.0.0.1 --port "$1" --key "$key" --quiet "${@:2}" \
    >>"$out" 2>&1 &
  emulator_pid=$!
  for _ in $(seq 100); do
    port=$(sed -n 's/.*listening on 127.0.0.1:\([0-9]*\).*/\1/p' "$out" 2>/dev/null || true)
    [[ -n $port ]] && return 0
    kill -0 "$emulator_pid" 2>/dev/null || fail "emulator died: $(cat "$out")"
    sleep 0.05
  done
  fail "emulator did not report its port"
}

summary_value() { sed -n "s/.*summary .*$1=\([0-9.]*\).*/\1/p" "$2"; }

case $scenario in
  steady)
    start_emulator 0
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 2 >"$work/bridge.out" 2>&1 ||
      fail "bridge exited with $?: $(cat "$work/bridge.out")"
    cat "$work/bridge.out"
    complete=$(summary_value complete "$work/bridge.out")
    decode=$(summary_value decode_errors "$work/bridge.out")
    ticks=$(summary_value ticks "$work/bridge.out")
    [[ -n $complete && -n $decode && -n $ticks ]] || fail "no summary line"
    awk -v c="$complete" 'BEGIN { exit !(c >= 95) }' || fail "only $complete % of ticks complete"
    [[ $decode == 0 ]] || fail "$decode decode errors"
    awk -v t="$ticks" 'BEGIN { exit !(t >= 1800) }' || fail "only $ticks ticks in 2 s at 1 kHz"
    echo "PASS: $ticks ticks, $complete % complete, 0 decode errors"
    ;;
  kill-restart)
    start_emulator 0
    first_port=$port
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 4 --log "$work/ticks.csv" \
      >"$work/bridge.out" 2>&1 &
    bridge_pid=$!
    sleep 1.3
    kill -9 "$emulator_pid"
    wait "$emulator_pid" 2>/dev/null || true
    emulator_pid=""
    sleep 1.0
    start_emulator "$first_port"
    wait "$bridge_pid" || fail "bridge exited with $?: $(cat "$work/bridge.out")"
    cat "$work/bridge.out"
    # Columns by header name (teleop::tick_log_columns), never by position. link: 0 waiting,
    # 1 up, 2 degraded, 3 lost, 4 recovering.
    awk -F, '
      NR == 1 {
        for (i = 1; i <= NF; i++) col[$i] = i
        n_need = split("time link force_scale stylus_fx stylus_fy stylus_fz", need, " ")
        for (k = 1; k <= n_need; k++) {
          if (!(need[k] in col)) { print "FAIL: the tick log has no column " need[k]; bad = 1; exit 1 }
        }
        T = col["time"]; L = col["link"]; S = col["force_scale"]
        FX = col["stylus_fx"]; FY = col["stylus_fy"]; FZ = col["stylus_fz"]
        next
      }
      { n++ }
      $L == 1 && !lost_at { last_up = $T; up_rows++ }
      $L == 2 && !lost_at { misses++ }
      $L == 1 { misses = 0 }
      $L == 3 && !lost_at { lost_at = $T; misses_at_loss = misses + 1 }
      $L == 3 { lost_rows++; if ($FX != 0 || $FY != 0 || $FZ != 0) forced++ }
      lost_at && $L == 4 && !rec_at { rec_at = $T; first_scale = $S }
      rec_at && $T > rec_at + 0.25 && $T < rec_at + 0.3 { mid_scale = $S }
      rec_at && $T > rec_at + 0.7 && $L == 1 { back_up = 1; final_scale = $S }
      END {
        if (bad) exit 1
        printf "rows %d, up before kill %d, lost at %.4f s after last up (%d misses), lost rows %d, " \
               "recovering at %.3f s, ramp %.3f -> %.3f -> %.3f\n", n, up_rows, lost_at - last_up,
               misses_at_loss, lost_rows, rec_at, first_scale, mid_scale, final_scale
        if (up_rows < 500) { print "FAIL: too few good ticks before the kill"; exit 1 }
        if (!lost_at) { print "FAIL: the bridge never entered its safe state"; exit 1 }
        if (misses_at_loss != 11) { print "FAIL: link lost after " misses_at_loss " misses, not 11"; exit 1 }
        if (lost_at - last_up > 0.05) { print "FAIL: safe state too late"; exit 1 }
        if (lost_rows < 700) { print "FAIL: the bridge did not keep running while the link was down"; exit 1 }
        if (forced) { print "FAIL: force rendered in the safe state"; exit 1 }
        if (!rec_at) { print "FAIL: no recovery after the restart"; exit 1 }
        if (!(first_scale < 0.05 && mid_scale > 0.3 && mid_scale < 0.8 && final_scale == 1)) {
          print "FAIL: the force did not ramp back in"; exit 1 }
        if (!back_up) { print "FAIL: the link did not come back up"; exit 1 }
      }' "$work/ticks.csv" || fail "kill/restart behaviour (see above)"
    grep -q "link_losses=1 recoveries=1" "$work/bridge.out" || fail "summary should count 1 loss, 1 recovery"
    echo "PASS: safe state on loss, kept running, recovered with a force ramp"
    ;;
  delayed)
    # Answers held 20 ms on the emulator's send path, below protocol v2: every state names the
    # setpoint it answered 20 ticks ago. The bridge refuses them as stale answers by default
    # (no link, never a stale state passed off as fresh) and accepts them with --max-answer-lag.
    start_emulator 0 --delay 20
    status=0
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 1.5 \
      >"$work/strict.out" 2>&1 || status=$?
    cat "$work/strict.out"
    # No state accepted: the run says why (the answers are late) and fails.
    [[ $status == 3 ]] || fail "bridge without --max-answer-lag exited with $status, expected 3"
    grep -q "bridge: link: never up (late answers)" "$work/strict.out" || fail "no verdict"
    received=$(summary_value received "$work/strict.out")
    [[ $received == 0 ]] || fail "$received delayed states accepted without --max-answer-lag"
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 2 \
      --max-answer-lag 40 >"$work/lag.out" 2>&1 || fail "bridge exited with $?: $(cat "$work/lag.out")"
    cat "$work/lag.out"
    complete=$(summary_value complete "$work/lag.out")
    [[ -n $complete ]] || fail "no summary line"
    awk -v c="$complete" 'BEGIN { exit !(c >= 90) }' || fail "only $complete % of ticks complete with --max-answer-lag 40"
    echo "PASS: 0 delayed states accepted by default, $complete % complete with --max-answer-lag 40"
    ;;
  identified)
    # The demo's pipeline (examples/demo.sh), 6 s per run: the models identified on the emulator
    # must render the forces they estimate. Regression bounds below what the demo reaches with the
    # current play (clamp 1 fit 96.7-97.1 %, correlation 1.000 over 5 runs of 10 s, 96.8 % and
    # 1.000 in a run of this test's 6 s; docs/models.md "Current play") for a loaded CI machine;
    # free motion as the demo reaches it (0.001-0.011 N RMS), within the 0.05 N goal.
    bash "$(dirname "${BASH_SOURCE[0]}")/../../examples/demo.sh" "$bin" "$work/demo" 6 \
      >"$work/demo.out" 2>&1 || fail "demo.sh exited with $?: $(cat "$work/demo.out")"
    cat "$work/demo.out"
    # The runs' summary lines, found by their start (the demo may end with more lines after them:
    # force-report --all-joints' joint and stylus lines).
    line=$(grep '^identified: fit ' "$work/demo.out" | head -n 1 || true)
    [[ -n $line ]] || fail "no line 'identified: fit ...'"
    fit=$(sed -n 's/^identified: fit \([-0-9.]*\)%.*/\1/p' <<<"$line")
    corr=$(sed -n 's/.*correlation \([-0-9.]*\),.*/\1/p' <<<"$line")
    [[ -n $fit && -n $corr ]] || fail "cannot read fit and correlation from: $line"
    awk -v f="$fit" -v c="$corr" 'BEGIN { exit !(f >= 90 && c >= 0.99) }' ||
      fail "identified model: fit $fit % (>= 90 needed), correlation $corr (>= 0.99 needed)"
    # The run over a 50 ms round trip with TDPA: the feedback still tracks the force.
    delayed=$(grep '^identified, 50 ms round trip, TDPA: fit ' "$work/demo.out" | head -n 1 || true)
    dcorr=$(sed -n 's/.*correlation \([-0-9.]*\),.*/\1/p' <<<"$delayed")
    [[ -n $dcorr ]] || fail "no line 'identified, 50 ms round trip, TDPA: fit ...'"
    awk -v c="$dcorr" 'BEGIN { exit !(c >= 0.9) }' ||
      fail "50 ms round trip, TDPA: correlation $dcorr (>= 0.9 needed)"
    # Every rendered joint identified and scored: roll, pitch, clamp 1, clamp 2. Over 5 demo runs
    # of 10 s with the current play on pitch and the clamps (docs/models.md "Current play"): pitch
    # fit 93.6-94.3 %, correlation 0.999; clamps 96.5-97.1 %, 1.000 (6 s: 92.7 %, 0.998; 96.8 %,
    # 1.000); roll: its correlation bound (0.9) as before, no fit bound. The bounds leave room for
    # a loaded machine.
    for joint in roll pitch clamp1 clamp2; do
      jline=$(grep "^identified, $joint: fit " "$work/demo.out" || true)
      jfit=$(sed -n 's/^identified, [a-z0-9]*: fit \([-0-9.]*\)%.*/\1/p' <<<"$jline")
      jcorr=$(sed -n 's/.*correlation \([-0-9.]*\),.*/\1/p' <<<"$jline")
      [[ -n $jcorr && -n $jfit ]] || fail "no line 'identified, $joint: fit ...'"
      bound=0.9 fit_bound=-1000
      [[ $joint == pitch ]] && bound=0.98 fit_bound=85
      [[ $joint == clamp1 || $joint == clamp2 ]] && bound=0.99 fit_bound=90
      awk -v c="$jcorr" -v b="$bound" -v f="$jfit" -v fb="$fit_bound" \
        'BEGIN { exit !(c >= b && f >= fb) }' ||
        fail "$joint: fit $jfit % (>= $fit_bound needed), correlation $jcorr (>= $bound needed): $jline"
    done
    preset=$(grep -n '^2016 preset: fit ' "$work/demo.out" | head -n 1 | cut -d: -f1)
    identified=$(grep -n '^identified: fit ' "$work/demo.out" | head -n 1 | cut -d: -f1)
    [[ -n $preset && $identified == $((preset + 1)) ]] ||
      fail "the line before 'identified: fit ...' is not the 2016 preset's"
    # When the demo scores every joint (force-report --all-joints), it ends with the stylus line.
    stylus=""
    if grep -q '^identified, clamp1: fit ' "$work/demo.out"; then
      stylus=$(tail -n 1 "$work/demo.out")
      [[ $stylus =~ ^stylus:\ RMSE\ [0-9.]+\ N\ against\ the\ ideal\ force,\ free\ motion\ RMS\ [0-9.]+\ N$ ]] ||
        fail "the demo scores every joint but does not end with the stylus line: $stylus"
      free=$(sed -n 's/.*free motion RMS \([0-9.]*\) N$/\1/p' <<<"$stylus")
      awk -v f="$free" 'BEGIN { exit !(f <= 0.05) }' ||
        fail "free motion: the stylus renders $free N RMS (<= 0.05 N needed)"
      stylus="; $stylus"
    fi
    echo "PASS: identified clamp model: fit $fit %, correlation $corr$stylus"
    ;;
  instrument)
    # One model set per instrument (files/model_set_file.hpp): --instrument picks the set from
    # the configuration's estimator.model_sets, the bridge logs the models it runs, and a set
    # that misses a motor whose force the stylus renders is refused before the loop starts.
    mkdir -p "$work/sets/EW2"
    cat >"$work/sets/EW1.json" <<'JSON'
{"format": "endohaptics model set", "format_version": 1, "instrument": "EW1",
 "models": {"clamp1": "preset:clamp2016-as-run", "clamp2": "preset:yaw2016",
            "roll": "preset:roll2016", "pitch": "preset:pitch2016"}}
JSON
    cat >"$work/sets/EW2/model_set.json" <<'JSON'
{"format": "endohaptics model set", "format_version": 1, "instrument": "EW2",
 "models": {"clamp1": "preset:yaw2016", "clamp2": "preset:yaw2016"}}
JSON
    echo '{"estimator": {"model_sets": "sets"}}' >"$work/bridge.json"
    start_emulator 0
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 1 \
      --config "$work/bridge.json" --instrument EW1 >"$work/ew1.out" 2>&1 ||
      fail "bridge --instrument EW1 exited with $?: $(cat "$work/ew1.out")"
    cat "$work/ew1.out"
    want="bridge: force models: instrument EW1 (model set $work/sets/EW1.json): clamp1"
    want+=" preset:clamp2016-as-run, clamp2 preset:yaw2016, roll preset:roll2016, pitch"
    want+=" preset:pitch2016"
    grep -qxF "$want" "$work/ew1.out" || fail "no line: $want"
    ticks=$(summary_value ticks "$work/ew1.out")
    [[ -n $ticks ]] || fail "no summary line"
    # EW2 has no roll and pitch models, and the default mapping renders their force: refused.
    status=0
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 1 \
      --config "$work/bridge.json" --instrument EW2 >"$work/ew2.out" 2>&1 || status=$?
    cat "$work/ew2.out"
    [[ $status != 0 ]] || fail "bridge ran EW2's set, which misses roll and pitch"
    grep -q "instrument 'EW2': no model for roll, pitch" "$work/ew2.out" || fail "roll, pitch not named"
    # An instrument without a set: refused, naming it.
    status=0
    "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 1 \
      --config "$work/bridge.json" --instrument EW3 >"$work/ew3.out" 2>&1 || status=$?
    [[ $status != 0 ]] || fail "bridge ran without EW3's set"
    grep -q "instrument 'EW3': no model set" "$work/ew3.out" || fail "EW3 not named: $(cat "$work/ew3.out")"
    echo "PASS: --instrument EW1 runs and logs its set ($ticks ticks); EW2 (no roll, pitch) and EW3 (no set) refused"
    ;;
  stylus)
    # endohaptics-force-report --all-joints (workflow/force_report.hpp): a run in tissue and one
    # in free space, each 3 s with the 2016 models and the bridge's --config, scored at every
    # motor and at the stylus. The report's replay of the bridge's mapping on its own estimate
    # must match the rendered force (the report maps as the bridge did; without the bridge's
    # --config it does not); the lines end the output.
    echo '{ "mapping": { "force_scale": [0.5, 1, 1] } }' >"$work/bridge.json"
    for environment in tissue free; do
      start_emulator 0 --environment "$environment" --truth-log "$work/$environment.truth.csv"
      "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --duration 3 \
        --config "$work/bridge.json" --log "$work/$environment.ticks.csv" \
        >"$work/$environment.out" 2>&1 || fail "bridge exited with $?: $(cat "$work/$environment.out")"
      kill -INT "$emulator_pid"
      wait "$emulator_pid" || true
      emulator_pid=""
    done
    "$bin/endohaptics-force-report" --all-joints --config "$work/bridge.json" \
      --truth "$work/tissue.truth.csv" --log "$work/tissue.ticks.csv" --label tissue \
      --free-log "$work/free.ticks.csv" >"$work/report.out" 2>&1 ||
      fail "force-report exited with $?: $(cat "$work/report.out")"
    cat "$work/report.out"
    number='-?([0-9.]+|inf|nan)'
    tail -n 5 "$work/report.out" | head -n 4 >"$work/last.out"
    expected=("tissue, roll: fit" "tissue, pitch: fit" "tissue, clamp1: fit" "tissue, clamp2: fit")
    for k in 0 1 2 3; do
      row=$(sed -n "$((k + 1))p" "$work/last.out")
      [[ $row == "${expected[$k]}"* ]] || fail "line $((k + 1)) of the last 5 is not '${expected[$k]} ...': $row"
      grep -Eq "fit $number%, correlation $number, RMSE [0-9.]+ N, delay [0-9]+ ms, peak [0-9.]+ N \(true [0-9.]+ N\)$" <<<"$row" ||
        fail "not a joint line: $row"
    done
    last=$(tail -n 1 "$work/report.out")
    [[ $last =~ ^stylus:\ RMSE\ ([0-9.]+)\ N\ against\ the\ ideal\ force,\ free\ motion\ RMS\ ([0-9.]+)\ N$ ]] ||
      fail "the last line is not the stylus line: $last"
    rmse=${BASH_REMATCH[1]}
    free=${BASH_REMATCH[2]}
    replay=$(sed -n 's/.*the mapping replayed on the estimate: RMSE \([0-9.]*\) N.*/\1/p' "$work/report.out")
    [[ -n $replay ]] || fail "no replay figure"
    awk -v r="$replay" 'BEGIN { exit !(r < 0.01) }' ||
      fail "the report's mapping differs from the bridge's: RMSE $replay N replayed on the estimate"
    "$bin/endohaptics-force-report" --all-joints --truth "$work/tissue.truth.csv" \
      --log "$work/tissue.ticks.csv" >"$work/default.out" 2>&1 ||
      fail "force-report without --config exited with $?: $(cat "$work/default.out")"
    other=$(sed -n 's/.*the mapping replayed on the estimate: RMSE \([0-9.]*\) N.*/\1/p' "$work/default.out")
    awk -v r="$other" 'BEGIN { exit !(r > 0.05) }' ||
      fail "the default mapping (clamp scale 1) replayed the bridge's (0.5) to $other N"
    grep -q "over [0-9]* ticks of $work/free.ticks.csv (free space)" "$work/report.out" ||
      fail "the free-motion figure is not over the free log"
    echo "PASS: every motor and the stylus scored: stylus RMSE $rmse N against the ideal force, free motion RMS $free N, the mapping replayed on the estimate to $replay N (default mapping: $other N)"
    ;;
  *) fail "unknown scenario $scenario" ;;
esac
