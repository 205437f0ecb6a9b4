#!/usr/bin/env bash
# File names and labels never reach gnuplot as code (docs/safety.md). endohaptics-replay
# --plot and endohaptics-force-report --plot-dir are run on files named like the one that once did:
# `run';system "touch INJECTED";print '.csv`, with labels and signal names that break quoted
# strings and lines; no INJECTED file may appear, the PNGs must be written (exit 0). A plot that
# was asked for and cannot be drawn (no gnuplot on PATH, a gnuplot that fails) exits non-zero
# with the reason; without a plot option nothing is plotted and gnuplot is not needed.
# Usage: plot_injection.sh BIN_DIR replay|force-report   (prints PASS: ... on success)
set -euo pipefail
bin=$(cd "$1" && pwd)
scenario=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# The programs run in $work/a/b (where the old scripts ran gnuplot) and gnuplot now runs in a
# private folder under TMPDIR=$work/tmp: the issue's payload, and one that reaches $work from
# either place (so that a regression leaves nothing outside $work).
hostile="';system \"touch INJECTED\";print '"
hostile_up="';system \"cd ..;cd ..;touch INJECTED\";print '"
mkdir -p "$work/a/b" "$work/tmp"
cd "$work/a/b"
export TMPDIR=$work/tmp
# Labels: a quote of each kind, a line break, the data-block terminator, a backquote, a macro.
label_a="a${hostile}"
label_b=$'b"; system "touch '"$work"$'/INJECTED"\nEOD\nsystem "touch '"$work"$'/INJECTED" `touch '"$work"$'/INJECTED` @x \\'

no_injection() {
  local found
  found=$(find "$work" -name INJECTED)
  [[ -z $found ]] || fail "$1: injected command ran: $found"
  [[ -z $(ls -A "$work/tmp") ]] || fail "$1: gnuplot's private folder left behind: $(ls -A "$work/tmp")"
}
is_png() { [[ -s $1 && $(head -c 4 "$1" | od -An -c | tr -d ' ') == '211PNG' ]]; }
# No gnuplot (PATH without it), and a gnuplot that fails.
mkdir "$work/empty-path" "$work/fake-path"
printf '#!/bin/sh\necho "\\"plot.gp\\" line 1: fake failure" >&2\nexit 1\n' >"$work/fake-path/gnuplot"
chmod +x "$work/fake-path/gnuplot"
# Runs "$@", expects a non-zero exit (not a crash) and $expected in stderr.
expect_error() {
  local expected=$1
  shift
  local rc=0
  "$@" >"$work/out" 2>"$work/err" || rc=$?
  [[ $rc -ne 0 ]] || fail "exit 0 for: $* (expected '$expected')"
  [[ $rc -lt 128 ]] || fail "crashed (exit $rc) for: $*: $(cat "$work/err")"
  grep -q -F -- "$expected" "$work/err" || fail "'$expected' not in stderr of $*: $(cat "$work/err")"
  echo "ok ($rc): $(head -1 "$work/err" | head -c 200)"
}
have_gnuplot=1
command -v gnuplot >/dev/null || have_gnuplot=0

case $scenario in
  replay)
    # The e2e system of identify_cli.sh, its output column named to end a quoted string.
    awk 'BEGIN {
      srand(7); x1 = 0; x2 = 0; u1 = 0; u2 = 0; h1 = 0; h2 = 0
      print "time,u1,u2,y'"'"'x"
      for (k = 0; k < 2000; k++) {
        if (h1 == 0) { u1 = 2 * rand() - 1; h1 = 1 + int(8 * rand()) }
        if (h2 == 0) { u2 = 2 * rand() - 1; h2 = 1 + int(8 * rand()) }
        h1--; h2--
        y = 0.5 * x1 + 0.3 * x2 + 0.2 * u1 + 0.005 * (2 * rand() - 1)
        printf "%.4f,%.6f,%.6f,%.6f\n", k * 0.01, u1, u2, y
        n1 = 1.5 * x1 - 0.7 * x2 + u1 + 0.5 * u2
        n2 = x1 - 0.3 * u2
        x1 = n1; x2 = n2
      }
    }' >"run${hostile}.csv"
    cp "run${hostile}.csv" run  # the old script's plot 'run' found a file
    csv=(--format csv --input u1 --input u2 --output "y'x")
    "$bin/endohaptics-identify" --log "run${hostile}.csv" "${csv[@]}" --order 2 --out model.json \
      >/dev/null || fail "identify failed"
    mkdir "out${hostile_up}"
    png="out${hostile_up}/fit${hostile}.png"
    replay=("$bin/endohaptics-replay" --model model.json --format csv --log "run${hostile}.csv")
    if [[ $have_gnuplot == 1 ]]; then
      "${replay[@]}" --plot "$png" >out 2>err || fail "replay --plot exited non-zero: $(cat err)"
      is_png "$png" || fail "no PNG written to $png"
      grep -q -F "plot written to $png" out || fail "replay did not say where the plot is"
      [[ ! -e "$png.dat" ]] || fail "a data file beside the plot"
      no_injection "replay --plot"
    fi
    expect_error "gnuplot is not installed or not on PATH (Debian: apt-get install gnuplot-nox)" \
      env PATH="$work/empty-path" "${replay[@]}" --plot "$work/missing.png"
    expect_error "gnuplot failed (exit status 1): line 1: fake failure" \
      env PATH="$work/fake-path:$PATH" "${replay[@]}" --plot "$work/failing.png"
    [[ ! -e $work/missing.png && ! -e $work/failing.png ]] || fail "a plot file after a failed plot"
    env PATH="$work/empty-path" "${replay[@]}" >out 2>err || fail "replay without --plot needs gnuplot: $(cat err)"
    no_injection "replay"
    echo "PASS: replay --plot with hostile names: $([[ $have_gnuplot == 1 ]] && echo "PNG written, " || echo "gnuplot absent, ")nothing injected; no or failing gnuplot exits non-zero"
    ;;
  force-report)
    # A truth log (time, force0..3) and a bridge tick log (teleop::tick_log_columns) of 3 s at
    # 1 kHz: the estimate is 0.9 x the truth, 10 ms late.
    awk 'BEGIN { print "time,force0,force1,force2,force3"
      for (k = 0; k < 3000; k++) { t = 100 + k * 0.001; printf "%.6f,0,0,%.6f,0\n", t, sin(6.28 * t) } }' \
      >"truth${hostile}.csv"
    awk 'BEGIN {
      h = "time,status,link,state_fault,enable_mask,active_mask,round_trip,force_scale"
      split("setpoint position velocity current motor_force", group, " ")
      for (g = 1; g <= 5; g++) for (m = 0; m < 4; m++) h = h "," group[g] m
      print h ",passivity_energy,passivity_damping,passivity_force_gain,passivity_drift,stylus_fx,stylus_fy,stylus_fz"
      for (k = 0; k < 3000; k++) {
        t = 100 + k * 0.001; f = 0.9 * sin(6.28 * (t - 0.01))
        printf "%.6f,0,0,0,15,15,0.001,1", t
        for (i = 0; i < 20; i++) printf ",%s", (i == 18 ? sprintf("%.6f", f) : "0")
        printf ",0,0,1,0,%.6f,0,0\n", f
      }
    }' >"run${hostile}.csv"
    cp "truth${hostile}.csv" truth  # the old script's plot 'truth' and 'run' found files
    cp "run${hostile}.csv" run
    report=("$bin/endohaptics-force-report" --truth "truth${hostile}.csv" --log "run${hostile}.csv"
      --label "$label_a" --truth "truth${hostile}.csv" --log "run${hostile}.csv" --label "$label_b")
    plots="plots${hostile_up}"
    if [[ $have_gnuplot == 1 ]]; then
      "${report[@]}" --plot-dir "$plots" >out 2>err || fail "force-report --plot-dir exited non-zero: $(cat err)"
      is_png "$plots/forces.png" || fail "no forces.png"
      is_png "$plots/period.png" || fail "no period.png"
      grep -q -F "plots: $plots/forces.png and $plots/period.png" out || fail "no 'plots:' line: $(cat out)"
      no_injection "force-report --plot-dir"
    fi
    expect_error "gnuplot is not installed or not on PATH (Debian: apt-get install gnuplot-nox)" \
      env PATH="$work/empty-path" "${report[@]}" --plot-dir "$work/missing"
    expect_error "gnuplot failed (exit status 1): line 1: fake failure" \
      env PATH="$work/fake-path:$PATH" "${report[@]}" --plot-dir "$work/failing"
    [[ ! -e $work/missing/forces.png && ! -e $work/failing/forces.png ]] || fail "a plot file after a failed plot"
    # No --plot-dir: nothing plotted, gnuplot not needed, the summary lines last.
    env PATH="$work/empty-path" "${report[@]}" >out 2>err || fail "force-report without --plot-dir: $(cat err)"
    ! grep -q "plots:" out || fail "plotted without --plot-dir"
    [[ $(tail -1 out) == *", peak "*" N (true "*" N)" ]] || fail "last line is not a summary: $(tail -1 out)"
    no_injection "force-report"
    echo "PASS: force-report --plot-dir with hostile names and labels: $([[ $have_gnuplot == 1 ]] && echo "PNGs written, " || echo "gnuplot absent, ")nothing injected; no or failing gnuplot exits non-zero"
    ;;
  *)
    fail "unknown scenario $scenario"
    ;;
esac
