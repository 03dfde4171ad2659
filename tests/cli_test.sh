#!/usr/bin/env bash
# End-to-end checks of the sinscal command line: exit codes, files, error messages.
# Usage: cli_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR
set -u
bin=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
pass=0; fail=0
check() {  # check NAME CONDITION...
  local name=$1; shift
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAILED: $name"; fi
}
contains() { grep -q -- "$2" "$1"; }

"$bin" --help > "$work/help.txt"; check "help exits 0" test $? -eq 0
"$bin" simulate --help > "$work/simhelp.txt"; check "simulate --help exits 0" test $? -eq 0
check "simulate --help lists --plan" contains "$work/simhelp.txt" "--plan"
"$bin" frobnicate 2> "$work/err.txt"; check "unknown command exits 1" test $? -eq 1

"$bin" simulate --plan "$src/config/plans/seed8.ini" --sensor "$src/config/sensors/nav-fog.ini" \
  --out "$work/s8" --seed 3 > "$work/sim.txt"
check "simulate exits 0" test $? -eq 0
for f in imu.csv session.ini plan.ini sensor.ini truth.json; do
  check "simulate writes $f" test -s "$work/s8/$f"
done
check "truth.json has the contract schema" contains "$work/s8/truth.json" '"gyro.bias.x"'
"$bin" navigate --session "$work/s8/session.ini" --out "$work/s8/nav.csv" > "$work/nav.txt"
check "navigate exits 0" test $? -eq 0
check "navigate prints 8 dwells" test "$(grep -cE '^ +[1-8] ' "$work/nav.txt")" -eq 8
check "nav.csv has 8 x 181 rows + header" test "$(wc -l < "$work/s8/nav.csv")" -eq $((8 * 181 + 1))

# A log cut short: plan mismatch, non-zero exit, finished dwells still written.
mkdir -p "$work/short"; cp "$work/s8/"{session.ini,plan.ini,sensor.ini,truth.json} "$work/short/"
head -n 50000 "$work/s8/imu.csv" > "$work/short/imu.csv"
"$bin" navigate --session "$work/short/session.ini" --out "$work/short/nav.csv" > "$work/short.txt" 2> "$work/short.err"
check "short log exits 2" test $? -eq 2
check "short log names the mismatch" contains "$work/short.err" "plan does not match the data"
check "short log keeps finished dwells" test "$(grep -cE '^ +[1-2] ' "$work/short.txt")" -eq 2

# A corrupt sample: file and line in the message.
mkdir -p "$work/bad"; cp "$work/s8/"{session.ini,plan.ini,sensor.ini,truth.json} "$work/bad/"
sed '1000s/^\([^,]*\),[^,]*/\1,oops/' "$work/s8/imu.csv" > "$work/bad/imu.csv"
"$bin" navigate --session "$work/bad/session.ini" --out "$work/bad/nav.csv" > /dev/null 2> "$work/bad.err"
check "corrupt log exits 2" test $? -eq 2
check "corrupt log names file and line" contains "$work/bad.err" "imu.csv:1000: field 2 'oops' is not a number"

# A sensor profile with a wrong unit.
printf '[gyro]\nbias = 0.1 0.3 ug\n' > "$work/badsensor.ini"
"$bin" simulate --plan "$src/config/plans/seed8.ini" --sensor "$work/badsensor.ini" --out "$work/x" 2> "$work/unit.err"
check "wrong unit exits 2" test $? -eq 2
check "wrong unit names file and line" contains "$work/unit.err" "badsensor.ini:2"

echo "$pass passed, $fail failed"
test "$fail" -eq 0
