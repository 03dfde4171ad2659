#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, SINSCAL_FUZZ=ON) in their own build directory and runs each
# for SECONDS_PER_TARGET seconds (default 60) on a copy of its seed corpus. Prints the executions
# per target; exits non-zero on any finding (crash, sanitizer report, leak, timeout, out of
# memory), whose reproducer is left in the findings directory it names.
#
#   tests/fuzz/run.sh [SECONDS_PER_TARGET] [TARGET...]
#
# Environment: SINSCAL_FUZZ_BUILD (build directory, default build-fuzz), CXX (default clang++),
# SINSCAL_FUZZ_JOBS (build jobs, default 2), SINSCAL_FUZZ_PARALLEL (targets fuzzed at once,
# default 1), SINSCAL_FUZZ_OUT (findings and working corpora,
# default $SINSCAL_FUZZ_BUILD/fuzz-out), SINSCAL_FUZZ_KEEP_GOING=1 (go on after a finding, in
# libFuzzer's fork mode, to collect every finding of the time given; still exits 1 if any).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
seconds="${1:-60}"
shift || true
case "$seconds" in '' | *[!0-9]*) echo "run.sh: SECONDS_PER_TARGET must be a whole number, got '$seconds'" >&2; exit 2 ;; esac

all_targets=(fuzz_quantities fuzz_ini fuzz_plan fuzz_sensor fuzz_session fuzz_log_native
  fuzz_log_custom fuzz_log_novatel fuzz_result_json fuzz_monitor fuzz_chamber fuzz_table
  fuzz_targets fuzz_log_columns fuzz_export)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all_targets[@]}")

build="${SINSCAL_FUZZ_BUILD:-$root/build-fuzz}"
out="${SINSCAL_FUZZ_OUT:-$build/fuzz-out}"
cxx="${CXX:-clang++}"
if ! command -v "$cxx" >/dev/null 2>&1; then
  echo "run.sh: $cxx not found (Debian: apt-get install clang-14 libclang-rt-14-dev)" >&2
  exit 2
fi

echo "== building ${targets[*]} in $build"
# A build directory already configured with SINSCAL_FUZZ=ON (CI's sanitizer build, which also
# holds the sanitized tests) is used as it is configured.
if ! grep -q '^SINSCAL_FUZZ:BOOL=ON$' "$build/CMakeCache.txt" 2>/dev/null; then
  cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DSINSCAL_FUZZ=ON -DSINSCAL_TESTS=OFF -DSINSCAL_WERROR=OFF >/dev/null
fi
cmake --build "$build" -j"${SINSCAL_FUZZ_JOBS:-2}" --target "${targets[@]}" >/dev/null

# One target: fuzz it, write its line of the table to $out/$t.result.
fuzz_target() {
  local t="$1"
  local corpus="$out/corpus/$t"  # grows while fuzzing; the seeds stay untouched
  local findings="$out/findings/$t"
  rm -rf "$findings"
  mkdir -p "$corpus" "$findings"
  local log="$out/$t.log"
  local status=0
  local keep_going=()
  [ "${SINSCAL_FUZZ_KEEP_GOING:-0}" = 1 ] &&
    keep_going=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  # The session target reads files the input names; keep standard input out of its reach.
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=0" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    "$build/tests/fuzz/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len=8192 -print_final_stats=1 -artifact_prefix="$findings/" ${keep_going[@]+"${keep_going[@]}"} \
    "$corpus" "$here/corpus/$t" </dev/null >"$log" 2>&1 || status=$?
  local runs rate
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)"
  if [ -z "$runs" ]; then  # fork mode: the last status line, "#N: cov: ... exec/s: R ..."
    runs="$(sed -n 's/^#\([0-9]*\): cov:.*/\1/p' "$log" | tail -1)"
    rate="$(sed -n 's/^#[0-9]*: cov:.* exec\/s:\{0,1\} \([0-9]*\).*/\1/p' "$log" | tail -1)"
  fi
  local result=ok
  if [ "$status" -ne 0 ] || ls "$findings" | grep -q .; then
    result="FINDING (exit $status): $(ls "$findings" | head -3 | tr '\n' ' ') log: $log"
  fi
  printf '%-18s %12s %10s  %s\n' "$t" "${runs:-?}" "${rate:-?}" "$result" >"$out/$t.result"
}

# SINSCAL_FUZZ_PARALLEL targets at a time (default 1; CI runs 2, one per core).
parallel="${SINSCAL_FUZZ_PARALLEL:-1}"
case "$parallel" in '' | *[!0-9]* | 0) echo "run.sh: SINSCAL_FUZZ_PARALLEL must be a positive whole number, got '$parallel'" >&2; exit 2 ;; esac
running=0
for t in "${targets[@]}"; do
  rm -f "$out/$t.result"
  if [ "$running" -ge "$parallel" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  fuzz_target "$t" &
  running=$((running + 1))
done
wait || true

failed=()
printf '%-18s %12s %10s  %s\n' target executions exec/s result
for t in "${targets[@]}"; do
  if [ -f "$out/$t.result" ]; then
    cat "$out/$t.result"
    grep -q ' FINDING ' "$out/$t.result" && failed+=("$t")
  else
    printf '%-18s %12s %10s  %s\n' "$t" "?" "?" "FINDING: the run did not finish (log: $out/$t.log)"
    failed+=("$t")
  fi
done

if [ ${#failed[@]} -gt 0 ]; then
  echo "== findings in: ${failed[*]} (reproduce: $build/tests/fuzz/TARGET FILE)" >&2
  for t in "${failed[@]}"; do grep -a -m3 -E "^(FINDING|SUMMARY)|runtime error" "$out/$t.log" >&2 || true; done
  exit 1
fi
echo "== no findings"
