#!/usr/bin/env bash
# The main job (./run demo; tests/e2e/teleop_e2e.sh identified): loopback teleoperation that
# identifies its own force models first, one per motor whose force the stylus renders.
#   1. identification experiment: sbRIO emulator (simulated EndoWrist; every joint closes on
#      tissue: the grasp also turns and lifts the wrist, so roll and pitch meet their contacts)
#      and bridge with the force feedback off, a scripted operator grasping at another depth and
#      pace than in the runs below, each grasp to another depth (operator.depth_variation); the
#      emulator logs what the sbRIO reports and the true force on an exact 1 ms grid;
#   2. endohaptics-identify, once per motor: a Hammerstein-Wiener model (that motor's reported
#      current and velocity -> its true force; pitch and the clamps: the current through a play
#      of the joint's static friction, the order chosen by the causal score; roll: order 2),
#      written into a model set
#      (model_sets/EW/<motor>.json) that the bridge loads by instrument name, with a free-motion
#      threshold chosen on the experiment alone (--free-threshold auto: the estimate reads 0 up
#      to what the model gave there while nothing touched). Order 2: the sbRIO's
#      current filter and velocity window are the fast dynamics between the reported signals and
#      the force (docs/identification_results.md, "The demo's clamp model");
#   3. teleoperation with the 2016 preset (appendix C), with the 2016 code's clamp estimator as
#      it ran (preset:clamp2016-as-run, half as long), with the identified models (and the
#      estimator's stiction memory, docs/models.md), with the
#      identified models over a 50 ms round trip (the emulator holds every answer 50 ms) with
#      TDPA, and with the identified models in free space (nothing to touch, half as long);
#   4. endohaptics-force-report: the runs against the emulator's truth (clamp 1), one plot:
#      "2016 as run: fit ...", "2016 preset: fit ...", "identified: fit ...", "identified, 50 ms
#      round trip, TDPA: fit ..."; then every rendered joint of the identified run and the stylus
#      force against the ideal one (the bridge's mapping of the true joint forces), with the
#      free-space run's stylus force: "identified, roll: ...", ..., "stylus: RMSE ...".
# Usage: demo.sh BIN_DIR OUT_DIR [SECONDS per teleoperation run, default 10; the identification
# experiment runs twice as long]
set -euo pipefail
bin=$1
out=$2
seconds=${3:-10}
experiment_seconds=$((2 * seconds))
duration=$seconds  # of the next run()
mkdir -p "$out"
rm -f "$out"/*.csv "$out"/*.png "$out"/*.json "$out"/*.out

emulator=""
trap '[[ -n $emulator ]] && kill "$emulator" 2>/dev/null || true' EXIT
# Protocol v2 (docs/protocol.md): one fresh key for this demo, shared by the emulator and the
# bridge, in a private temporary directory.
keydir=$(mktemp -d)
trap '[[ -n $emulator ]] && kill "$emulator" 2>/dev/null || true; rm -rf "$keydir"' EXIT
key="$keydir/link.key"
"$bin/endohaptics-bridge" --generate-key "$key" >/dev/null

# run NAME [bridge options...]: one emulator + bridge session; NAME.truth.csv, NAME.ticks.csv.
# $environment and $emulator_options (an array) go to the emulator.
environment=tissue
emulator_options=()
run() {
  local name=$1 port=""
  shift
  # Emptied here, before the emulator starts: a file left by an earlier demo in the same folder
  # would otherwise give the previous run's port to the first read below.
  : >"$out/$name.emulator.out"
  "$bin/endohaptics-sbrio-emulator" --bind 127.0.0.1 --port 0 --environment "$environment" \
    --key "$key" --truth-log "$out/$name.truth.csv" --quiet ${emulator_options[@]+"${emulator_options[@]}"} \
    >>"$out/$name.emulator.out" 2>&1 &
  emulator=$!
  for _ in $(seq 100); do
    port=$(sed -n 's/.*listening on 127.0.0.1:\([0-9]*\).*/\1/p' "$out/$name.emulator.out" 2>/dev/null || true)
    [[ -n $port ]] && break
    sleep 0.05
  done
  [[ -n $port ]] || { cat "$out/$name.emulator.out"; echo "the emulator did not start" >&2; exit 1; }
  "$bin/endohaptics-bridge" --sbrio "127.0.0.1:$port" --key "$key" --rate 1000 --duration "$duration" \
    --log "$out/$name.ticks.csv" "$@" >"$out/$name.bridge.out"
  kill -INT "$emulator"
  wait "$emulator" || true
  emulator=""
  grep -h "bridge: summary" "$out/$name.bridge.out"
  tail -n 1 "$out/$name.emulator.out"
}

# The operator of every teleoperation run: the grasp turns the wrist 0.8 rad of azimuth (roll)
# and lifts it 14 cm (pitch) as it closes, so that every joint meets its contact.
operator='"operator": { "theta_swing": 0.8, "z_swing": 0.14 }'

echo "== 1. identification experiment: ${experiment_seconds} s, force feedback off, deeper and faster grasps of varying depth"
cat >"$out/experiment.json" <<'JSON'
{ "mapping": { "force_scale": [0, 0, 0] },
  "operator": { "r_closed": 0.010, "open_time": 0.5, "close_time": 0.6, "hold_time": 1.0,
                "release_time": 0.6, "theta_swing": 0.9, "z_swing": 0.16,
                "depth_variation": 0.6 } }
JSON
duration=$experiment_seconds
run experiment --config "$out/experiment.json"
duration=$seconds

echo "== 2. identify a model per motor: its reported current and velocity -> its true force"
# Generic CSVs: the force-model formats' near-integrating limit stated (csv has none by default;
# docs/identification_results.md).
# Pitch and the clamps: the current first passes a play of half width K_s, the joint's static
# friction in the current domain (docs/models/sim.md, "Parameters": 0.17, 0.21, 0.20 A): a joint
# pressed into an object sticks while the current stays within K_s of what the contact's force
# needs, so on unloading the current falls by up to 2 K_s while the force stays (docs/models.md,
# "Current play"). The play replaces the current's dead zone (0; the velocity's: auto), and the
# order is the causal score's choice on the experiment (auto, up to 4). Roll: as before, no play.
mkdir -p "$out/model_sets/EW"
motors=(roll pitch clamp1 clamp2)
plays=(0 0.17 0.21 0.20)
for slot in 0 1 2 3; do
  echo "-- ${motors[$slot]} (motor $slot)"
  if [[ ${plays[$slot]} == 0 ]]; then
    fit=(--order 2 --deadzone auto)
  else
    fit=(--order auto --max-order 4 --deadzone 0,auto --current-play "${plays[$slot]}")
  fi
  "$bin/endohaptics-identify" --format csv --log "$out/experiment.truth.csv" \
    --input "reported_current$slot" --input "reported_velocity$slot" --output "force$slot" \
    --ts 0.001 "${fit[@]}" --method best --max-time-constant 2 \
    --free-threshold auto --out "$out/model_sets/EW/${motors[$slot]}.json" | tail -n 2
done

echo "== 3. teleoperation with the 2016 preset (appendix C models)"
printf '{ %s }\n' "$operator" >"$out/preset.json"
run preset --config "$out/preset.json"
# The baseline the 2016 operators felt: the 2016 code's own clamp estimator (docs/models.md, "The
# 2016 code as it ran"), half as long as the other runs to keep the demo short.
half=$(( (seconds + 1) / 2 ))
echo "== 3. teleoperation with the 2016 code as it ran (baseline, $half s)"
printf '{ %s, "estimator": { "clamp_model": "preset:clamp2016-as-run" } }\n' "$operator" \
  >"$out/as_run.json"
duration=$half
run as_run --config "$out/as_run.json"
duration=$seconds
echo "== 3. teleoperation with the identified models (instrument EW)"
# The stiction memory (estimator.stick_*, per joint; docs/models/sim.md, "Parameters"): a joint
# pressed into an object stays put while its motor backs off through the static-friction band of
# the tendon's torque, 2 K_s k_tau / k_t (K_s 0.13, 0.17, 0.21, 0.20 A; k_tau 0.0171 N m/A x
# 76000/2048; k_t 5, 5, 8.5, 8.5 N m/rad): stick_travel; below the force the static friction
# holds against, K_s k_tau / lever (lever 0.18, 0.18, 0.32, 0.32 m): stick_force, also through
# the play (0.01745 rad): stick_play. So its force stays while its current relaxes. Roll only:
# pitch and the clamps hold that band in their models' current play (travel 0: off).
stick='"stick_travel": [0.0330, 0, 0, 0], '
stick+='"stick_play": [0.01745, 0.01745, 0.01745, 0.01745], '
stick+='"stick_force": [0.458, 0.599, 0.416, 0.397]'
printf '{ %s, "estimator": { "model_sets": "model_sets", "instrument": "EW", %s } }\n' \
  "$operator" "$stick" >"$out/identified.json"
run identified --config "$out/identified.json"
echo "== 3. the identified models over a 50 ms round trip (every answer held 50 ms), TDPA on"
emulator_options=(--delay 50)
run delayed --config "$out/identified.json" --passivity tdpa --passivity-round-trip 50 \
  --max-answer-lag 60
emulator_options=()
echo "== 3. the identified models in free space (nothing to touch, $half s)"
environment=free
duration=$half
run free --config "$out/identified.json"
environment=tissue
duration=$seconds

echo "== 4. force feedback against the emulator's truth (motor 2, clamp 1)"
"$bin/endohaptics-force-report" --joint 2 --plot-dir "$out" \
  --truth "$out/as_run.truth.csv" --log "$out/as_run.ticks.csv" --label "2016 as run" \
  --truth "$out/preset.truth.csv" --log "$out/preset.ticks.csv" --label "2016 preset" \
  --truth "$out/identified.truth.csv" --log "$out/identified.ticks.csv" --label identified \
  --truth "$out/delayed.truth.csv" --log "$out/delayed.ticks.csv" \
  --label "identified, 50 ms round trip, TDPA"
echo "== 4. every rendered joint of the identified run, and the stylus"
"$bin/endohaptics-force-report" --all-joints --config "$out/identified.json" \
  --truth "$out/identified.truth.csv" --log "$out/identified.ticks.csv" --label identified \
  --free-log "$out/free.ticks.csv"
