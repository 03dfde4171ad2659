#!/usr/bin/env bash
# calibrate --method kf --base estimated|known (issue 20.3): the table base's attitude estimated
# (three states, the default) or known (the plan's, not estimated), said in the result and on the
# terminal; a value other than these is a usage error.
# Usage: kf_base_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR
set -u
bin=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
. "$src/tests/cli/check.sh"

# The README's session: rot19, nav-fog-extended, the table's base where the plan says.
"$bin" simulate --plan "$src/config/plans/rot19.ini" --sensor "$src/config/sensors/nav-fog-extended.ini" \
  --out "$work/r19" > /dev/null
"$bin" calibrate --method kf --session "$work/r19/session.ini" --out "$work/est.json" > "$work/est.txt"
check "--base estimated (default) exits 0" test $? -eq 0
"$bin" calibrate --method kf --base known --session "$work/r19/session.ini" --out "$work/known.json" \
  > "$work/known.txt"
check "--base known exits 0" test $? -eq 0
states() { sed -nE 's/.*: ([0-9]+) states,.*/\1/p' "$1"; }
check "--base known removes the three base states" test "$(states "$work/known.txt")" -eq $(($(states "$work/est.txt") - 3))
check "... the result says known" json "$work/known.json" \
  "r['method']['base'] == 'known' and r['installation']['base'] == {'estimated': False, 'known': True}"
check "... the default says estimated" json "$work/est.json" \
  "r['method']['base'] == 'estimated' and r['installation']['base']['estimated']"
check "... the terminal says known" contains "$work/known.txt" "Table base: known (--base known)"
check "... and still calibrates right (every estimate within 3 sigma of the truth)" \
  grep -qE "Against the injected truth: every one of the [0-9]+ estimates within [0-2]\.[0-9]+ sigma" "$work/known.txt"
# The control: a base 0.3 deg off level while --base known says it is the plan's fails (the
# estimates beyond 3 sigma, or the alarm), where --base estimated calibrates.
"$bin" simulate --plan "$src/config/plans/rot19.ini" --sensor "$src/config/sensors/nav-fog-extended.ini" \
  --out "$work/tilt" --base-level-error 0.3,0 > /dev/null
"$bin" calibrate --method kf --base known --session "$work/tilt/session.ini" --out "$work/tilt-known.json" \
  > "$work/tilt-known.txt" 2>&1
check "a tilted base taken as known does not calibrate right" \
  grep -qE "beyond 3 sigma|filter diverging" "$work/tilt-known.txt"
check "... the alignment's base is not taken (its mounting, zero, not significant)" \
  json "$work/tilt-known.json" "not r['installation']['alignment']['applied']"
"$bin" calibrate --method kf --session "$work/tilt/session.ini" --out "$work/tilt-est.json" > "$work/tilt-est.txt"
check "... estimated, it does" grep -qE "within [0-2]\.[0-9]+ sigma \(the errors" "$work/tilt-est.txt"
check "... starting from the alignment's base" json "$work/tilt-est.json" "r['installation']['alignment']['applied']"
# Bad values: usage errors (exit 1) naming the option.
"$bin" calibrate --method kf --base surveyed --session "$work/r19/session.ini" --out "$work/x.json" 2> "$work/bad.err"
check "--base surveyed exits 1" test $? -eq 1
check "... naming the values" contains "$work/bad.err" "--base must be estimated or known"
"$bin" calibrate --method closed-form --base known --session "$work/r19/session.ini" --out "$work/x.json" 2> "$work/cf.err"
check "--base with the closed form exits 1" test $? -eq 1
check "... kf only" contains "$work/cf.err" "--base acts in --method kf only"
check "no result written on a usage error" test ! -e "$work/x.json"

finish
