#!/usr/bin/env bash
# Mutation testing of the physics code: applies each mutation of tests/mutation/mutations.txt in
# turn (a sign flip, swapped indices, ... in the error dynamics, the coefficient coupling, the
# Jacobians, the measurements and the feedback), rebuilds the tests, runs every test except the
# golden file, and reports which test caught it. Every mutation must be caught.
#
# Usage: tests/mutation/run.sh [BUILD_DIR] [FIRST [LAST]]
#   BUILD_DIR  a build directory of its own (default build-mutation, Release); the source tree
#              is restored after every mutation, even on Ctrl-C
#   FIRST LAST run mutations FIRST..LAST of the list only (1-based; CI runs a few)
# Exit status: 0 when every mutation run was caught, 1 otherwise.
set -uo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build-mutation}
first=${2:-1}
last=${3:-100000}
list=tests/mutation/mutations.txt

cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null || exit 1
cmake --build "$build" -j2 --target sinscal_tests >/dev/null || exit 1
tests="$build/tests/sinscal_tests"

backup=""
target=""
restore() { if [ -n "$backup" ]; then cp "$backup" "$target" && rm -f "$backup"; backup=""; fi; }
trap 'restore; exit 130' INT TERM
trap restore EXIT

# One mutation: the text FROM (found exactly once) in FILE replaced by TO.
apply_mutation() {
  FROM="$2" TO="$3" perl -0777 -pi -e 'BEGIN { $f = $ENV{FROM}; $t = $ENV{TO} } s/\Q$f\E/$t/' "$1"
}

n=0
run=0
caught=0
survivors=()
printf '%-4s %-9s %-60s %s\n' "#" "result" "mutation" "caught by (first failure)"
while IFS= read -r line; do
  case "$line" in \#* | "") continue ;; esac
  n=$((n + 1))
  [ "$n" -lt "$first" ] || [ "$n" -gt "$last" ] && continue
  file=$(awk -F' [|][|][|] ' '{print $1}' <<<"$line")
  from=$(awk -F' [|][|][|] ' '{print $2}' <<<"$line")
  to=$(awk -F' [|][|][|] ' '{print $3}' <<<"$line")
  what=$(awk -F' [|][|][|] ' '{print $4}' <<<"$line")
  count=$(grep -cF -- "$from" "$file")
  if [ "$count" != 1 ]; then
    echo "mutation $n ($what): the text is found $count times in $file: update $list" >&2
    exit 1
  fi
  run=$((run + 1))
  target=$file
  backup=$(mktemp)
  cp "$file" "$backup"
  apply_mutation "$file" "$from" "$to"
  result=""
  if ! cmake --build "$build" -j2 --target sinscal_tests >/dev/null 2>&1; then
    result="INVALID (does not compile)"
  else
    # Fast tests first, stopping at the first failure; then the Monte Carlo ones. Hidden ([.])
    # measurements are left out: a filter of exclusions alone would run them.
    # Exit code 77: nothing failed, a test case was skipped for want of an optional program
    # (tests/skip.hpp): not a catch.
    out=$("$tests" "~[golden]~[monte_carlo]~[memory]~[.]" --abort -r compact 2>&1)
    status=$?
    [ $status -eq 77 ] && status=0
    if [ $status -eq 0 ]; then
      out=$("$tests" "[monte_carlo]" --abort -r compact 2>&1)
      status=$?
      [ $status -eq 77 ] && status=0
    fi
    if [ $status -ne 0 ]; then
      # The compact reporter's failure line ("FILE:LINE: failed: ..."), not a warning that
      # mentions an error; else the first line that says what stopped the run.
      result=$(grep -m1 -E "^[^ :]+:[0-9]+: (failed|FAILED)" <<<"$out" ||
        grep -m1 -E "failed|FAILED|error" <<<"$out")
      result=$(sed -E 's/^([^:]+:[0-9]+).*/\1/' <<<"$result")
      caught=$((caught + 1))
    fi
  fi
  restore
  if [ -z "$result" ]; then
    survivors+=("$n: $what")
    printf '%-4s %-9s %-60s %s\n' "$n" "SURVIVED" "$what" "-"
  else
    printf '%-4s %-9s %-60s %s\n' "$n" "caught" "$what" "$result"
  fi
done <"$list"
# Leave the build matching the restored sources.
cmake --build "$build" -j2 --target sinscal_tests >/dev/null 2>&1
echo "score: $caught of $run mutations caught"
[ ${#survivors[@]} -eq 0 ] || { printf 'survived: %s\n' "${survivors[@]}"; exit 1; }
