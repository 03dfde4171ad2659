#!/usr/bin/env bash
# The streamed calibration's monitor survives a crash (issue 35): a calibration of rot19 read from
# standard input with a monitor is killed with SIGKILL at random times (an out-of-memory kill, a
# power loss: no handler runs). After each kill the monitor must hold every line the run had
# written, each a complete line of the uninterrupted run's monitor (so valid JSON), at most one
# cut last line after them that is the start of the next one, and plot-convergence must draw it.
#
# Usage: monitor_kill_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR [KILLS [SEED]]
# CI runs 3 kills; the longer run of docs/usage/streaming.md runs 20:
#   bash tests/monitor_kill_test.sh build/apps/sinscal . /tmp/kill 20
set -u
bin=$(cd "$(dirname "$1")" && pwd)/$(basename "$1"); src=$(cd "$2" && pwd); work=$3
kills=${4:-3}; RANDOM=${5:-35}
rm -rf "$work"; mkdir -p "$work"; work=$(cd "$work" && pwd)
fail=0; drawn=0; empty=0; cut=0
die() { echo "monitor_kill_test: $*" >&2; exit 1; }

"$bin" simulate --plan "$src/config/plans/rot19.ini" --sensor "$src/config/sensors/nav-fog.ini" \
  --out "$work/r19" --seed 2 > /dev/null || die "simulate rot19"
# The streamed calibration, the log on standard input (its arguments; run as its own process so
# that the kill reaches it, not a shell around it).
args=(calibrate --session "$work/r19/session.ini" --method kf --stream --monitor-interval 5)
start=$(date +%s%N)
"$bin" "${args[@]}" --monitor "$work/full.jsonl" --out "$work/r.json" < "$work/r19/imu.csv" \
  > /dev/null 2>&1 || die "the uninterrupted run failed"
run_ms=$(( ($(date +%s%N) - start) / 1000000 ))
total=$(wc -l < "$work/full.jsonl")
echo "uninterrupted run: $run_ms ms, $total monitor lines"

for k in $(seq 1 "$kills"); do
  m=$work/kill$k.jsonl
  at_ms=$(( 100 + RANDOM * RANDOM % (run_ms > 200 ? run_ms - 100 : 100) ))
  "$bin" "${args[@]}" --monitor "$m" --out "$work/kill$k.json" < "$work/r19/imu.csv" > /dev/null 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((at_ms / 1000)) $((at_ms % 1000)))"
  kill -KILL "$pid" 2> /dev/null
  wait "$pid" 2> /dev/null
  [ -e "$m" ] || { echo "kill $k at $at_ms ms: no monitor file"; fail=$((fail + 1)); continue; }
  lines=$(wc -l < "$m")  # complete lines
  # Every complete line is the uninterrupted run's line (the filter is deterministic).
  if ! cmp -s <(head -n "$lines" "$m") <(head -n "$lines" "$work/full.jsonl"); then
    echo "kill $k at $at_ms ms: a complete line differs from the uninterrupted run's"
    fail=$((fail + 1)); continue
  fi
  rest=$(tail -c +$(( $(head -n "$lines" "$m" | wc -c) + 1 )) "$m")
  if [ -n "$rest" ]; then
    cut=$((cut + 1))
    next=$(sed -n "$((lines + 1))p" "$work/full.jsonl")
    [ "${next#"$rest"}" != "$next" ] ||
      { echo "kill $k: the cut last line is not the start of the next"; fail=$((fail + 1)); continue; }
  fi
  if [ "$lines" -eq 0 ]; then
    empty=$((empty + 1)); echo "kill $k at $at_ms ms: killed before the first record"; continue
  fi
  if "$bin" plot-convergence --monitor "$m" --out "$work/kill$k.png" > /dev/null 2> "$work/kill$k.err" &&
    [ -s "$work/kill$k.png" ]; then
    drawn=$((drawn + 1))
    echo "kill $k at $at_ms ms: $lines of $total lines${rest:+ and a cut one}, drawn"
  else
    echo "kill $k at $at_ms ms: plot-convergence failed: $(head -n 2 "$work/kill$k.err")"
    fail=$((fail + 1))
  fi
done
echo "monitor kill test: $kills kills, $drawn drawn, $empty before the first record, $cut with a" \
  "cut last line, $fail failed"
[ "$fail" -eq 0 ]
