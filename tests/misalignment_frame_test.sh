#!/usr/bin/env bash
# --misalignment-frame table|triad (issue 36.3) end to end: calibrate (kf and closed form) writes
# the frame into the result; the certificate says it in words; every export format carries it
# with the same values; compare refuses results in different frames; design predicts in it; a
# result written before the field reads as its mode's default. Small sessions at 10 Hz.
# Usage: misalignment_frame_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR
set -u
bin=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
. "$src/tests/cli/check.sh"
fog=$src/config/sensors/nav-fog.ini

"$bin" simulate --plan "$src/config/plans/rot19.ini" --sensor "$fog" --out "$work/r19" --rate 10 \
  > /dev/null || { echo "simulate rot19 failed"; exit 1; }
"$bin" simulate --plan "$src/config/plans/seed8.ini" --sensor "$fog" --out "$work/s8" --rate 10 \
  > /dev/null || { echo "simulate seed8 failed"; exit 1; }

# --- kf with attitude updates: the triad frame by conversion, the table frame by default --------
"$bin" calibrate --method kf --session "$work/r19/session.ini" --misalignment-frame triad \
  --out "$work/triad.json" > "$work/triad.txt"
check "kf --misalignment-frame triad exits 0" test $? -eq 0
check "... the result states the triad frame, converted from the table's" json "$work/triad.json" \
  "r['misalignment_frame'] == 'triad' and r['method']['body_frame'] == 'accelerometer triad'
   and r['method']['body_frame_converted_from'] == 'table'"
check "... accel.misalignment.xy, .xz, .yz are zero by the convention" json "$work/triad.json" \
  "all(r['coefficients']['accel.misalignment.' + k].get('fixed_by_convention') for k in ('xy', 'xz', 'yz'))
   and 'accel.misalignment.xy' in r['method']['fixed_by_convention']"
check "... the terminal says the frame" contains "$work/triad.txt" \
  "Misalignment frame: triad (estimated relative to the table, converted)"
# The truth converted to the triad frame (load_truth): the converted estimates agree with it.
check "... every estimate within 4 sigma of the triad-frame truth" \
  grep -qE "Against the injected truth: every one of the [0-9]+ estimates within [0-3]\.[0-9]+ sigma" \
  "$work/triad.txt"
"$bin" calibrate --method kf --session "$work/r19/session.ini" --out "$work/table.json" \
  > "$work/table.txt"
check "kf by default exits 0" test $? -eq 0
check "... in the table frame" json "$work/table.json" \
  "r['misalignment_frame'] == 'table' and r['method']['body_frame'] == 'table'
   and 'fixed_by_convention' not in r['coefficients']['accel.misalignment.xy']"
# Coefficients of the sensor axes alone are the same in both frames (the same run).
check "... the biases are the same in both frames" python3 -c "
import json, sys
a = json.load(open('$work/triad.json'))['coefficients']; b = json.load(open('$work/table.json'))['coefficients']
sys.exit(not all(abs(a[k]['value'] - b[k]['value']) <= 1e-9 * max(1, abs(b[k]['value']))
                 and abs(a[k]['sigma'] - b[k]['sigma']) <= 1e-9 * b[k]['sigma']
                 for k in ('gyro.bias.x', 'accel.bias.z')))"

# --- compare: different frames refused, naming both ---------------------------------------------
"$bin" compare "$work/triad.json" "$work/table.json" > /dev/null 2> "$work/compare.err"
check "compare refuses results in different frames" test $? -ne 0
check "... naming which is which" contains "$work/compare.err" \
  "different misalignment frames (A: triad frame, B: table frame)"

# --- certificate ---------------------------------------------------------------------------------
"$bin" report --result "$work/triad.json" --out "$work/triad.html" > /dev/null 2>&1
check "report exits 0" test $? -eq 0
check "... the certificate states the frame in words" contains "$work/triad.html" \
  "are given within the triads (the triad frame: the accelerometer triad is the body frame"
"$bin" report --result "$work/table.json" --out "$work/table.html" > /dev/null 2>&1
check "... and the table frame for the default" contains "$work/table.html" \
  "are given relative to the table&#39;s platform axes (the table frame"

# --- export: every format carries the frame, with the result's values ---------------------------
"$bin" export --result "$work/triad.json" --format json --out "$work/triad.export.json" > /dev/null
check "export json exits 0" test $? -eq 0
check "... carries the triad frame and the result's misalignments" python3 -c "
import json, math, sys
e = json.load(open('$work/triad.export.json')); c = json.load(open('$work/triad.json'))['coefficients']
arcsec = math.pi / 180 / 3600
ok = e['misalignment_frame'] == 'triad' and e['body_frame'] == 'accelerometer triad'
ok = ok and e['accel']['model_matrix'][0][1] == 0 and e['accel']['model_matrix'][1][2] == 0
ok = ok and abs(e['gyro']['model_matrix'][0][1] - c['gyro.misalignment.xy']['value'] * arcsec) <= 1e-12
ok = ok and abs(e['accel']['model_matrix'][1][0] - c['accel.misalignment.yx']['value'] * arcsec) <= 1e-12
sys.exit(not ok)"
"$bin" export --result "$work/triad.json" --format yaml > "$work/triad.export.yaml"
check "... YAML carries it" grep -q '^misalignment_frame: "\?triad"\?$' "$work/triad.export.yaml"
"$bin" export --result "$work/triad.json" --format c-header > "$work/triad.export.h"
check "... the C header carries it" contains "$work/triad.export.h" \
  '#define SINSCAL_MISALIGNMENT_FRAME "triad"'
check "... and says it in words" contains "$work/triad.export.h" "Misalignment frame: triad: within"

# --- a result written before the field: its mode's default --------------------------------------
python3 -c "
import json
r = json.load(open('$work/table.json')); del r['misalignment_frame']
json.dump(r, open('$work/old.json', 'w'), indent=2)" 2> /dev/null
if [ -s "$work/old.json" ]; then
  "$bin" export --result "$work/old.json" --format json --out "$work/old.export.json" > /dev/null
  check "an old result with attitude updates exports as the table frame" json \
    "$work/old.export.json" "r['misalignment_frame'] == 'table'"
  python3 -c "
import json
r = json.load(open('$work/triad.json')); del r['misalignment_frame']
r['method']['body_frame'] = 'table'; r['method']['attitude'] = 'none'; del r['method']['body_frame']
json.dump(r, open('$work/old_none.json', 'w'), indent=2)"
  "$bin" export --result "$work/old_none.json" --format json --out "$work/old_none.export.json" \
    > /dev/null
  check "an old result of --attitude none exports as the triad frame" json \
    "$work/old_none.export.json" "r['misalignment_frame'] == 'triad'"
fi

# --- closed form ---------------------------------------------------------------------------------
"$bin" calibrate --method closed-form --session "$work/s8/session.ini" --misalignment-frame triad \
  --out "$work/cf.json" > "$work/cf.txt"
check "closed-form --misalignment-frame triad exits 0" test $? -eq 0
check "... the result states the triad frame" json "$work/cf.json" \
  "r['misalignment_frame'] == 'triad' and r['coefficients']['accel.misalignment.yz']['fixed_by_convention']
   and r['method']['body_frame_converted_from'] == 'table'"
# The coefficient table's err/sig column against the truth converted to the triad frame.
check "... every estimate within 4 sigma of the triad-frame truth" awk '
  /^coefficient +estimate/ { on = 1; next } on && NF == 0 { on = 0 }
  on && $NF ~ /^-?[0-9.]+$/ && NF == 7 { n++; e = $NF < 0 ? -$NF : $NF; if (e > 4) bad++ }
  END { exit !(n >= 21 && bad == 0) }' "$work/cf.txt"

# --- design ----------------------------------------------------------------------------------------
"$bin" design --plan "$src/config/plans/rot19.ini" --sensor "$fog" --rate 10 \
  --misalignment-frame triad --out "$work/design" > "$work/design.txt"
check "design --misalignment-frame triad exits 0" test $? -eq 0
check "... says the frame it compares in" contains "$work/design.txt" \
  "Misalignment frame: triad (converted from the table frame): sigmas and targets are compared in it"
check "... design.json states it" json "$work/design/design.json" "r['misalignment_frame'] == 'triad'"
"$bin" design --plan "$src/config/plans/rot19.ini" --sensor "$fog" --rate 10 \
  --misalignment-frame table --attitude none > /dev/null 2> "$work/design.err"
check "design refuses the table frame without attitude updates" test $? -eq 1
check "... with the cause" contains "$work/design.err" "not observable without table-attitude updates"

finish "misalignment frame"
