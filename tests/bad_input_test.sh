#!/usr/bin/env bash
# The bad-input corpus, end to end: every command (simulate, navigate, calibrate --method
# closed-form, kf and table-free, compare, export, report, plot-convergence, allan) and every input file
# type (plan, sensor profile, session.ini with or without a plan, native log, custom log, split,
# one file per dwell, NovAtel, result JSON, monitor JSONL). Each case is one bad input, made in its
# own folder from small bundled ones, and must end with the documented exit code (2: data, 1:
# usage), a message on standard error holding the cause, the file's name and :LINE where there is
# a line, and every input file unchanged (sha256sum of the case's folder before and after; outputs
# go to its out/ subfolder).
#
# Controls (the same files without the fault, which must work) show that each case fails for its
# own fault. Cases whose fix belongs outside the input readers are in the KNOWN section at the end:
# their failures print "known (not fixed yet)" and do not fail the run; a KNOWN case that passes
# prints "known case now passes: move it" and fails the run, so the list cannot rot.
#
# Usage: bad_input_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR
set -u
bin=$(cd "$(dirname "$1")" && pwd)/$(basename "$1"); src=$(cd "$2" && pwd); work=$3
gen=$(cd "$(dirname "$4")" && pwd)/$(basename "$4")  # tests/apophis_like_writer
rm -rf "$work"; mkdir -p "$work/base" "$work/c"; work=$(cd "$work" && pwd)
S() { "$bin" "$@"; }
die() { echo "bad_input_test: setup failed: $*" >&2; exit 1; }

fixed_ok=0; fixed_failed=0; known_open=0; known_passing=0; controls_ok=0; controls_failed=0
failures=()

# new NAME: a fresh folder for one case; $d is its path, outputs go to $d/out.
new() { cur=$1; d=$work/c/$1; [ -e "$d" ] && die "case name $1 used twice"; mkdir -p "$d/out"; POST=""; }
sums() { (cd "$d" && find . -path ./out -prune -o -type f -print0 | LC_ALL=C sort -z | xargs -0 -r sha256sum); }
# lno FILE REGEX: line number of the first line matching
lno() { grep -n -m1 -E -- "$2" "$1" | cut -d: -f1; }
# set_key FILE KEY VALUE: replaces the first line 'KEY = ...' of FILE; L = its line number.
set_key() {
  L=$(lno "$1" "^$2 *=") || true
  [ -n "$L" ] || die "$cur: no key $2 in $1"
  awk -v n="$L" -v t="$2 = $3" 'NR == n { $0 = t } { print }' "$1" > "$1.tmp" && mv "$1.tmp" "$1"
}
# add_line FILE TEXT: appends a line; L = its line number.
add_line() { printf '%s\n' "$2" >> "$1"; L=$(wc -l < "$1"); }
# set_field FILE LINE FIELD VALUE: replaces a comma-separated field of one line.
set_field() {
  awk -F, -v OFS=, -v n="$2" -v f="$3" -v v="$4" 'NR == n { $f = v } { print }' "$1" > "$1.tmp" &&
    mv "$1.tmp" "$1"
}

row() { printf '%-40s %-58s %-30s %s\n' "$1" "$2" "$3" "$4"; }

# run KIND CODES SUBSTRINGS COMMAND...: KIND control | fixed | known; CODES e.g. "2" or "0,1,2";
# SUBSTRINGS separated by '|', each must appear on standard error. $POST, when set, is a further
# check run in the case folder.
run() {
  local kind=$1 codes=$2 subs=$3; shift 3
  local before after got problems="" s verdict parts=()
  before=$(sums)
  (cd "$d" && "$@") > "$d/out/stdout" 2> "$d/out/stderr"
  got=$?
  after=$(sums)
  case ",$codes," in *",$got,"*) ;; *) problems+="exit $got; " ;; esac
  if [ -n "$subs" ]; then
    IFS='|' read -r -a parts <<< "$subs"
    for s in "${parts[@]}"; do
      grep -qF -- "$s" "$d/out/stderr" || problems+="no '$s'; "
    done
  fi
  [ "$before" == "$after" ] || problems+="an input file changed; "
  if [ -n "$POST" ] && ! (cd "$d" && eval "$POST") > /dev/null 2>&1; then
    problems+="check failed: $POST; "
  fi
  case $kind in
    control | fixed)
      if [ -z "$problems" ]; then
        verdict=ok
        if [ "$kind" == control ]; then controls_ok=$((controls_ok + 1)); else fixed_ok=$((fixed_ok + 1)); fi
      else
        verdict=FAIL
        if [ "$kind" == control ]; then controls_failed=$((controls_failed + 1)); else fixed_failed=$((fixed_failed + 1)); fi
        failures+=("$cur")
      fi ;;
    known)
      if [ -z "$problems" ]; then
        verdict="known case now passes: move it"; known_passing=$((known_passing + 1)); failures+=("$cur")
      else
        verdict="known (not fixed yet)"; known_open=$((known_open + 1))
      fi ;;
  esac
  local expected="$codes${subs:+: $subs}"
  [ ${#expected} -gt 58 ] && expected="${expected:0:55}..."
  row "$cur" "$expected" "$got${problems:+ ($problems)}" "$verdict"
  if [ "$verdict" == FAIL ] || [ "$verdict" == "known case now passes: move it" ]; then
    sed -n '1,3s/^/      stderr: /p' "$d/out/stderr"
  fi
}
control() { run control "$@"; }
fixed() { run fixed "$@"; }
known() { run known "$@"; }

# ---------------------------------------------------------------------------------------------
# Small bundled inputs: a 3-orientation plan at 10 Hz (98 s), seed8 at 10 Hz (1489 s), and logs
# in every format made from them.
cd "$work/base" || die "cd"
cat > mini.ini <<'EOF'
[plan]
name = mini
type = orientations
move_rate = 30 deg/s
move_acceleration = 30 deg/s^2

[site]
latitude = 55.75 deg
longitude = 37.62 deg
height = 150 m

[orientation.1]
heading = 0 deg
pitch = 0 deg
roll = 0 deg
dwell = 30 s

[orientation.2]
heading = 90 deg
pitch = 0 deg
roll = 0 deg
dwell = 30 s

[orientation.3]
heading = 0 deg
pitch = 0 deg
roll = 90 deg
dwell = 30 s
EOF
fog=$src/config/sensors/nav-fog.ini
S simulate --plan mini.ini --sensor "$fog" --out mini --rate 10 > /dev/null || die "simulate mini"
S simulate --plan mini.ini --sensor "$fog" --out mini_t --rate 10 --table-angles > /dev/null ||
  die "simulate mini --table-angles"
S simulate --plan "$src/config/plans/seed8.ini" --sensor "$fog" --out s8 --rate 10 > /dev/null ||
  die "simulate seed8"
# A consumer MEMS unit (bench/consumer.ini: gyro biases 0.5-1 deg/s, scale factors 1-5 %) on seed8.
S simulate --plan "$src/config/plans/seed8.ini" --sensor "$src/bench/consumer.ini" --out c8 --rate 10 \
  > /dev/null || die "simulate seed8, consumer"
S navigate --session mini/session.ini --out mini/nav.csv > /dev/null || die "navigate mini"
S calibrate --method closed-form --session s8/session.ini --out s8/cf.json > /dev/null ||
  die "closed form s8"
S calibrate --method kf --session mini/session.ini --out mini/kf.json --monitor mini/monitor.jsonl \
  > /dev/null 2>&1 || die "kf mini"
# The paper's two channels leave the common accelerometer scale factor undetermined (export).
S calibrate --method closed-form --session s8/session.ini --stage1 point --model uncoupled \
  --channels north,east --out s8/paper.json > /dev/null || die "closed form s8, paper's method"
# Custom: rates in deg/s and g, accelerometers first, one header line.
awk -F, 'BEGIN { pi = atan2(0, -1); print "time,ax,ay,az,gx,gy,gz" }
  NR > 3 { printf "%.10g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", $1, $5 * 10 / 9.80665,
           $6 * 10 / 9.80665, $7 * 10 / 9.80665, $2 * 1800 / pi, $3 * 1800 / pi, $4 * 1800 / pi }' \
  mini/imu.csv > imu.txt
# Split (imu_tk style): t x y z per triad, whitespace.
awk -F, 'NR > 1 { print $1, $2, $3, $4 }' imu.txt > acc.txt
awk -F, 'NR > 1 { print $1, $5, $6, $7 }' imu.txt > gyr.txt
# With a temperature column (deg C, one per unit, drifting 1 mC per sample): custom and split.
awk -F, -v OFS=, 'NR == 1 { print $0, "temp"; next } { print $0, 25 + NR * 0.001 }' imu.txt > imu_temp.txt
awk '{ print $0, 25 + NR * 0.001 }' acc.txt > acc_temp.txt
# One file per dwell: the samples of each dwell (times from navigate's output), native format.
for k in 1 2 3; do
  read -r t0 t1 < <(awk -F, -v k="$k" '$1 == k { if (!n++) a = $2; b = $2 } END { print a, b }' mini/nav.csv)
  { head -n 3 mini/imu.csv
    awk -F, -v a="$t0" -v b="$t1" 'NR > 3 && $1 > a + 0.01 && $1 <= b + 0.01' mini/imu.csv; } > "pos$k.csv"
done
cp "$src/tests/data/novatel/rawimusxa.asc" imu.asc

base=$work/base
mini() { cp "$base"/mini/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/"; }
mini_t() { cp "$base"/mini_t/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/"; }
s8() { cp "$base"/s8/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/"; }
c8() { cp "$base"/c8/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/"; }
custom() {
  cp "$base"/mini/{plan.ini,sensor.ini} "$base/imu.txt" "$d/"
  printf '%s\n' "[session]" "name = custom" "rate = 10 Hz" "plan = plan.ini" "sensor = sensor.ini" "" \
    "[log]" "file = imu.txt" "format = custom" "header_lines = 1" "columns = t ax ay az gx gy gz" \
    "gyro = rate" "gyro_unit = deg/s" "accel = rate" "accel_unit = g" > "$d/session.ini"
}
split() {
  cp "$base"/mini/{plan.ini,sensor.ini} "$base/acc.txt" "$base/gyr.txt" "$d/"
  printf '%s\n' "[session]" "name = split" "rate = 10 Hz" "plan = plan.ini" "sensor = sensor.ini" "" \
    "[log]" "format = custom" "accel_file = acc.txt" "gyro_file = gyr.txt" "delimiter = whitespace" \
    "gyro = rate" "gyro_unit = deg/s" "accel = rate" "accel_unit = g" > "$d/session.ini"
}
segments() {
  cp "$base"/mini/{plan.ini,sensor.ini} "$base"/pos{1,2,3}.csv "$d/"
  printf '%s\n' "[session]" "name = segments" "rate = 10 Hz" "plan = plan.ini" "sensor = sensor.ini" "" \
    "[log]" "format = sinscal" "files = pos1.csv pos2.csv pos3.csv" "dwells = 1 2 3" > "$d/session.ini"
}
novatel() {
  cp "$base"/mini/{plan.ini,sensor.ini} "$base/imu.asc" "$d/"
  printf '%s\n' "[session]" "name = novatel" "rate = 100 Hz" "plan = plan.ini" "time_offset = 604799.96 s" "" \
    "[log]" "file = imu.asc" "format = novatel" "gyro_scale = 1e-9" "accel_scale = 0.001" \
    "accel_unit = mm/s" > "$d/session.ini"
}
custom_temp() {
  custom; cp "$base/imu_temp.txt" "$d/imu.txt"; set_key "$d/session.ini" columns "t ax ay az gx gy gz temp"
}
split_temp() { split; cp "$base/acc_temp.txt" "$d/acc.txt"; add_line "$d/session.ini" "accel_columns = t x y z temp"; }
# native_temp FILE: the native log FILE with both temperature columns (25 C).
native_temp() { sed -i '3s/$/,temperature_accel [C],temperature_gyro [C]/; 4,$s/$/,25,25/' "$1"; }
nav() { S navigate --session session.ini --out out/nav.csv; }
cf() { S calibrate --method closed-form --session session.ini --out out/result.json "$@"; }
kf() { S calibrate --method kf --session session.ini --out out/result.json "$@"; }
sim() { S simulate --plan plan.ini --sensor sensor.ini --out out/sim --rate 10 "$@"; }

echo "bad-input corpus: $bin"
row "case" "expected (exit: message parts)" "got" "ok"

# --- controls: the unaltered inputs work ------------------------------------------------------
new control-simulate; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
control 0 "" sim
new control-navigate-native; mini; control 0 "" nav
new control-navigate-table-angles; mini_t; control 0 "" nav
new control-navigate-custom; custom; control 0 "" nav
new control-navigate-split; split; control 0 "" nav
new control-navigate-segments; segments; control 0 "" nav
new control-closed-form; s8; control 0 "" cf
# Issue 34: the closed form on a consumer unit. With the two horizontal channels the
# accelerometers are not all determined, so not relinearized about: their inputs drive the
# navigator's velocity beyond stage 1's linear range (140 m/s against 26 m/s), named.
new closed-form-consumer-accel-range; c8
fixed 2 "closed-form linear range|the accelerometers' equivalent inputs drive the navigator's velocity" cf --channels north,east
new control-closed-form-consumer; c8; control 0 "" cf
# The Kalman filter on the consumer unit (issue 34): one pass (the default) linearized about zero
# neglects the products of 5 % scale factors and 1 deg misalignments beyond their sigmas; refused,
# named. The automatic passes (--passes 0) run until it holds.
new kf-consumer-one-pass; c8
fixed 2 "kf linear range|imu.csv: the filter's pass 1 (--passes 1)|--passes 0" kf
new control-kf-consumer-automatic-passes; c8; control 0 "" kf --passes 0
# The Kalman filter on a log noisier than its profile says (densities 10-20x): the divergence
# names the noise at rest as its cause (the APOPHIS BMI160 table log, issue 34).
new kf-noise-beyond-profile; s8
set_key "$d/sensor.ini" arw "0.0001 deg/sqrt(h)"; set_key "$d/sensor.ini" vrw "0.5 ug/sqrt(Hz)"
fixed 2 "filter diverging|the outputs' noise density is beyond 3 times the sensor profile's" S calibrate --method kf --session session.ini --out out/r.json
new control-kf; mini; control 0 "" kf
new control-compare; cp "$base/s8/cf.json" "$d/a.json"; cp "$base/s8/cf.json" "$d/b.json"
control 0 "" S compare a.json b.json
new control-plot; cp "$base/mini/monitor.jsonl" "$d/"
control 0 "" S plot-convergence --monitor monitor.jsonl --out out/conv.png
# NovAtel: the bundled lines read; the run then stops on the plan (a few samples of a 98 s plan).
new control-novatel; novatel; control 2 "plan does not match the data" nav

# --- plan INI (simulate) ----------------------------------------------------------------------
plan_case() { new "$1"; cp "$src/config/plans/seed8.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"; }
plan_case plan-latitude-90; set_key "$d/plan.ini" latitude "90 deg"
fixed 2 "plan.ini:$L: 'site.latitude'|within -89 and 89 deg" sim
plan_case plan-latitude-1000-deg; set_key "$d/plan.ini" latitude "1000 deg"
fixed 2 "plan.ini:$L: 'site.latitude'|got 1000 deg" sim
plan_case plan-latitude-in-rad; set_key "$d/plan.ini" latitude "55.75 rad"
fixed 2 "plan.ini:$L: 'site.latitude'|within -89 and 89 deg" sim
plan_case plan-height-1e9; set_key "$d/plan.ini" height "1e9 m"
fixed 2 "plan.ini:$L: 'site.height'|-12000 and 100000 m" sim
plan_case plan-longitude-1e6; set_key "$d/plan.ini" longitude "1e6 deg"
fixed 2 "plan.ini:$L: 'site.longitude'" sim
plan_case plan-site-without-latitude; awk '!/^latitude/' "$d/plan.ini" > "$d/p" && mv "$d/p" "$d/plan.ini"
L=$(lno "$d/plan.ini" "^longitude")
fixed 2 "plan.ini:$L: 'site.longitude'|without 'latitude'" sim
plan_case plan-section-plus-sign; L=$(( $(lno "$d/plan.ini" '^\[orientation.8\]') + 1 ))
sed -i 's/^\[orientation.8\]/[orientation.+8]/' "$d/plan.ini"
fixed 2 "plan.ini:$L: section [orientation.+8]|expected [orientation.N]" sim
plan_case plan-section-huge-number; L=$(( $(lno "$d/plan.ini" '^\[orientation.8\]') + 1 ))
sed -i 's/^\[orientation.8\]/[orientation.99999999999]/' "$d/plan.ini"
fixed 2 "plan.ini:$L: section [orientation.99999999999]" sim
plan_case plan-section-gap; sed -i 's/^\[orientation.8\]/[orientation.9]/' "$d/plan.ini"
fixed 2 "plan.ini|missing [orientation.8]" sim
plan_case plan-unknown-section; add_line "$d/plan.ini" "[orientations.9]"; add_line "$d/plan.ini" "dwell = 5 s"
fixed 2 "plan.ini:$L: 'orientations.9.dwell'|unknown section" sim
plan_case plan-duplicate-key; L=$(( $(lno "$d/plan.ini" '^dwell') + 1 ))
awk -v n="$L" 'NR == n { print "dwell = 10 s" } { print }' "$d/plan.ini" > "$d/p" && mv "$d/p" "$d/plan.ini"
fixed 2 "plan.ini:$L: key 'dwell'|given twice" sim
plan_case plan-key-before-section; { echo "name = x"; cat "$src/config/plans/seed8.ini"; } > "$d/plan.ini"
fixed 2 "plan.ini:1: key 'name' before the first [section]" sim
plan_case plan-dwell-nan; set_key "$d/plan.ini" dwell "nan s"
fixed 2 "plan.ini:$L: 'orientation.1.dwell'|not a finite number" sim
plan_case plan-dwell-zero; set_key "$d/plan.ini" dwell "0 s"
fixed 2 "plan.ini:$L: 'orientation.1.dwell'|must be positive" sim
plan_case plan-heading-1000-deg; set_key "$d/plan.ini" heading "1000 deg"
fixed 2 "plan.ini:$L: 'orientation.1.heading'|within -360 and 360 deg" sim
plan_case plan-unknown-type; set_key "$d/plan.ini" type circles
fixed 2 "plan.ini:$L: 'plan.type'|expected 'orientations' or 'rotations'" sim
plan_case plan-dwell-wrong-unit; set_key "$d/plan.ini" dwell "180 deg"
fixed 2 "plan.ini:$L: 'orientation.1.dwell'|unit 'deg'" sim
plan_case plan-dwell-8-days; set_key "$d/plan.ini" dwell "192 h"
fixed 2 "plan.ini:$L: 'orientation.1.dwell'|plan limit of 7 days" sim
new plan-rotations-start-dwell-negative; cp "$src/config/plans/rot19.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
set_key "$d/plan.ini" dwell "-10 s"
fixed 2 "plan.ini:$L: 'start.dwell'|must be positive" sim
new plan-rotations-pause-negative; cp "$src/config/plans/rot19.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
set_key "$d/plan.ini" pause "-20 s"
fixed 2 "plan.ini:$L: 'rotations.pause'|must not be negative" sim
new plan-rotations-bad-axis; cp "$src/config/plans/rot19.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
set_key "$d/plan.ini" axes "+y +w"
fixed 2 "plan.ini:$L: 'rotations.axes'|axis '+w'" sim
new plan-missing; cp "$fog" "$d/sensor.ini"
fixed 2 "nope.ini: cannot open plan file" S simulate --plan nope.ini --sensor sensor.ini --out out/sim
new plan-is-a-directory; cp "$fog" "$d/sensor.ini"; mkdir -p "$d/dir.ini"
fixed 2 "dir.ini: is a directory" S simulate --plan dir.ini --sensor sensor.ini --out out/sim

# --- sensor profile (simulate, calibrate --method kf) -------------------------------------------
sensor_case() { new "$1"; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"; }
sensor_case sensor-arw-negative; set_key "$d/sensor.ini" arw "-0.001 deg/sqrt(h)"
fixed 2 "sensor.ini:$L: 'gyro.arw'|must not be negative" sim
sensor_case sensor-gyro-range-negative; set_key "$d/sensor.ini" range "-400 deg/s"
fixed 2 "sensor.ini:$L: 'gyro.range'|must not be negative" sim
sensor_case sensor-vrw-negative; set_key "$d/sensor.ini" vrw "-10 ug/sqrt(Hz)"
fixed 2 "sensor.ini:$L: 'accel.vrw'|must not be negative" sim
sensor_case sensor-correlation-time-zero; add_line "$d/sensor.ini" "correlation_time = 0 s"
fixed 2 "sensor.ini:$L: 'accel.correlation_time'|must be positive" sim
sensor_case sensor-unknown-key; add_line "$d/sensor.ini" "bais = 100 ug"
fixed 2 "sensor.ini:$L: 'accel.bais': unknown key in [accel]" sim
sensor_case sensor-wrong-unit; set_key "$d/sensor.ini" bias "0.1 0.3 m/s"
fixed 2 "sensor.ini:$L: 'gyro.bias'|unit 'm/s'" sim
sensor_case sensor-range-reversed; set_key "$d/sensor.ini" bias "0.3 0.1 deg/h"
fixed 2 "sensor.ini:$L: 'gyro.bias'|0 <= lo <= hi" sim
sensor_case sensor-unknown-section; add_line "$d/sensor.ini" "[magnetometer]"; add_line "$d/sensor.ini" "bias = 1"
fixed 2 "sensor.ini:$L: 'magnetometer.bias'|unknown section" sim
sensor_case sensor-target-zero; add_line "$d/sensor.ini" "[targets]"; add_line "$d/sensor.ini" "gyro.bias = 0 deg/h"
fixed 2 "sensor.ini:$L: 'targets.gyro.bias'|must be positive" sim
new kf-session-sensor-arw-negative; mini; set_key "$d/sensor.ini" arw "-0.001 deg/sqrt(h)"
fixed 2 "sensor.ini:$L: 'gyro.arw'|must not be negative" kf
new simulate-rate-negative; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
fixed 1 "--rate must be above 0" S simulate --plan plan.ini --sensor sensor.ini --out out/sim --rate -5

# --- session.ini (navigate, calibrate, plot-convergence) ----------------------------------------
new session-latitude-90; mini; set_key "$d/session.ini" latitude "90 deg"
fixed 2 "session.ini:$L: 'site.latitude'|within -89 and 89 deg" nav
new session-latitude-1000-deg; mini; set_key "$d/session.ini" latitude "1000 deg"
fixed 2 "session.ini:$L: 'site.latitude'|got 1000 deg" nav
new session-latitude-in-rad; mini; set_key "$d/session.ini" latitude "55.75 rad"
fixed 2 "session.ini:$L: 'site.latitude'" cf
new session-height-1e9; mini; set_key "$d/session.ini" height "1e9 m"
fixed 2 "session.ini:$L: 'site.height'|-12000 and 100000 m" kf
new session-site-without-latitude; mini; awk '!/^latitude/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
L=$(lno "$d/session.ini" "^longitude")
fixed 2 "session.ini:$L: 'site.longitude'|without 'latitude'" nav
new session-unknown-section; mini; add_line "$d/session.ini" "[extra]"; add_line "$d/session.ini" "note = x"
fixed 2 "session.ini:$L: 'extra.note'|unknown section [extra]" nav
new session-unknown-empty-section; mini; add_line "$d/session.ini" "[sites]"
fixed 2 "session.ini|unknown section [sites]" nav
new session-plan-empty; mini; set_key "$d/session.ini" plan ""
fixed 2 "session.ini:$L: 'session.plan'|no file name given" nav
new session-plan-missing; mini; set_key "$d/session.ini" plan "nope.ini"
fixed 2 "session.ini:$L: 'session.plan'|'nope.ini': no such file" cf
new session-truth-missing; mini; set_key "$d/session.ini" truth "nope.json"
fixed 2 "session.ini:$L: 'session.truth'|no such file" nav
new session-sensor-empty; mini; set_key "$d/session.ini" sensor ""
fixed 2 "session.ini:$L: 'session.sensor'|no file name given" kf
new session-no-plan-key; mini; awk '!/^plan/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
fixed 2 "session.ini|no 'plan'" nav
new session-rate-zero; mini; set_key "$d/session.ini" rate "0 Hz"
fixed 2 "session.ini:$L: 'session.rate'|must be above 0" nav
new session-rate-1e9; mini; set_key "$d/session.ini" rate "1e9 Hz"
fixed 2 "session.ini:$L: 'session.rate'|100 kHz" nav
new session-rate-wrong; mini; set_key "$d/session.ini" rate "4 Hz"
fixed 2 "imu.csv:5: samples 0.100000 s apart|wrong rate" nav
new session-time-offset-1e300; mini; add_line "$d/session.ini" "[session]"; add_line "$d/session.ini" "time_offset = 1e300 s"
fixed 2 "session.ini:$L: 'session.time_offset'" nav
new session-unknown-key; mini; add_line "$d/session.ini" "colour = red"
fixed 2 "session.ini:$L: 'log.colour': unknown key in [log]" nav
new session-duplicate-key; mini; add_line "$d/session.ini" "file = imu.csv"
fixed 2 "session.ini:$L: key 'file'|given twice" nav
new session-log-format-unknown; mini; set_key "$d/session.ini" format csv
fixed 2 "session.ini:$L: 'log.format'|expected 'sinscal', 'custom' or 'novatel'" nav
new session-max-gap-1e300; mini; add_line "$d/session.ini" "max_gap = 1e300"
fixed 2 "session.ini:$L: 'log.max_gap'|1 to 1000" nav
new session-log-missing; mini; set_key "$d/session.ini" file nope.csv
fixed 2 "nope.csv:0: cannot open log file" nav
new plot-session-latitude-90; mini; cp "$base/mini/monitor.jsonl" "$d/"; set_key "$d/session.ini" latitude "90 deg"
fixed 2 "session.ini:$L: 'site.latitude'" S plot-convergence --monitor monitor.jsonl --session session.ini --out out/c.png
# The fuzzing run's reproducers (tests/fuzz/crashes/fuzz_session), with their log.
for f in log-time-unit-error-without-file log-table-unit-error-without-file empty-plan-key-error-without-file \
  plan-name-too-long; do
  new "fuzz-$f"; mini; cp "$src/tests/fuzz/crashes/fuzz_session/$f.ini" "$d/session.ini"
  case $f in
    log-time*) fixed 2 "session.ini:$(lno "$d/session.ini" '^time_unit'): 'log.time_unit'|parsec" nav ;;
    log-table*) fixed 2 "session.ini:$(lno "$d/session.ini" '^table_unit'): 'log.table_unit'|furlong" nav ;;
    plan-name*) fixed 2 "session.ini:$(lno "$d/session.ini" '^plan'): 'session.plan'|no such file" nav ;;
    *) fixed 2 "session.ini:$(lno "$d/session.ini" '^plan'): 'session.plan'|no file name given" nav ;;
  esac
done

# --- native log -------------------------------------------------------------------------------
new log-gyro-1e300; mini; set_field "$d/imu.csv" 100 3 1e300
fixed 2 "imu.csv:100: gyro log axis y reads 1e+300|beyond any sensor" nav
new log-accel-1e300; mini; set_field "$d/imu.csv" 100 6 -1e300
fixed 2 "imu.csv:100: accel log axis y|beyond any sensor" cf
new log-gyro-1e300-kf; mini; set_field "$d/imu.csv" 100 2 1e300
POST='test -s out/result.json'  # the estimates up to there are written
fixed 2 "input stopped: ./imu.csv:100: gyro log axis x|beyond any sensor" kf
new log-time-1e300; mini; set_field "$d/imu.csv" 100 1 1e300
fixed 2 "imu.csv:100: time t = 1e+300 s is beyond 1e10 s" nav
new log-first-time-1e300; mini; set_field "$d/imu.csv" 4 1 1e300
fixed 2 "imu.csv:4: time t = 1e+300 s" kf
new log-nan; mini; set_field "$d/imu.csv" 200 3 nan
fixed 2 "imu.csv:200: field 3 is NaN" nav
new log-infinite; mini; set_field "$d/imu.csv" 200 5 -inf
fixed 2 "imu.csv:200: field 5 is infinite" cf
new log-not-a-number; mini; set_field "$d/imu.csv" 200 4 oops
fixed 2 "imu.csv:200: field 4 'oops' is not a number" nav
new log-time-backwards; mini; set_field "$d/imu.csv" 200 1 5
fixed 2 "imu.csv:200: time goes backwards" kf
new log-time-repeats; mini; set_field "$d/imu.csv" 200 1 19.6
fixed 2 "imu.csv:200: time repeats" nav
new log-gap; mini; sed -i '200,220d' "$d/imu.csv"
fixed 2 "imu.csv:200: gap in the data" nav
new log-extra-field; mini; set_field "$d/imu.csv" 300 8 0
fixed 2 "imu.csv:300: expected 7 fields, found 8" nav
new log-truncated; mini; head -c -20 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv:$(wc -l < "$base/mini/imu.csv"): truncated line" nav
new log-header-only; mini; head -n 3 "$base/mini/imu.csv" > "$d/imu.csv"
POST='! grep -q "e+300" out/stderr'
fixed 2 "imu.csv:3: no samples" nav
new log-header-only-kf; mini; head -n 3 "$base/mini/imu.csv" > "$d/imu.csv"
POST='! grep -q "e+300" out/stderr'
fixed 2 "imu.csv:3: no samples" kf
new log-header-only-closed-form; mini; head -n 3 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv:3: no samples" cf
new log-empty-file; mini; : > "$d/imu.csv"
fixed 2 "imu.csv:0: file ends before the column header" nav
new log-wrong-header; mini; sed -i '3s/dv_z/dv_w/' "$d/imu.csv"
fixed 2 "imu.csv:3: not a sinscal log" nav
new log-long-line; mini; { head -n 3 "$base/mini/imu.csv"; head -c 70000 /dev/zero | tr '\0' '1'; echo; } > "$d/imu.csv"
fixed 2 "imu.csv:4: line longer than 65536 bytes" nav
new log-ends-early; mini; head -n 400 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv: the log ends at t = 39.7 s|plan does not match the data" kf
new log-table-angle-1e300; mini_t; set_field "$d/imu.csv" 100 8 1e300
fixed 2 "imu.csv:100: table angle|beyond 1e6 rad" kf

# --- custom log -------------------------------------------------------------------------------
new custom-gyro-1e300; custom; set_field "$d/imu.txt" 50 5 1e300
fixed 2 "imu.txt:50: gyro log axis x reads 1e+300|beyond any sensor" nav
new custom-time-reaches-infinity; custom; add_line "$d/session.ini" "time_unit = h"
awk -F, -v OFS=, 'NR == 2 { $1 = 1e-6 } NR == 3 { $1 = 1.7e308 } NR <= 3' "$base/imu.txt" > "$d/imu.txt"
fixed 2 "imu.txt:3: time t = inf s" nav
new custom-header-only; custom; head -n 1 "$base/imu.txt" > "$d/imu.txt"
fixed 2 "imu.txt:1: no samples" kf
new custom-all-bad-skipped; custom; awk -F, -v OFS=, 'NR == 1 { print; next } NR <= 5 { $2 = "x"; print }' "$base/imu.txt" > "$d/imu.txt"
fixed 2 "imu.txt:5: no good samples: all 4 samples were bad" kf --on-bad-sample skip
new custom-header-lines-negative; custom; set_key "$d/session.ini" header_lines -1
fixed 2 "session.ini:$L: 'log.header_lines'|out of range" nav
new custom-header-lines-fraction; custom; set_key "$d/session.ini" header_lines 1.5
fixed 2 "session.ini:$L: 'log.header_lines'|whole number" nav
new custom-header-lines-past-end; custom; set_key "$d/session.ini" header_lines 100000
fixed 2 "imu.txt:$(wc -l < "$base/imu.txt"): file ends inside the 100000 header lines" nav
new custom-time-unit-unknown; custom; add_line "$d/session.ini" "time_unit = parsec"
fixed 2 "session.ini:$L: 'log.time_unit'|'parsec'" nav
new custom-table-unit-unknown; custom; set_key "$d/session.ini" columns "t ax ay az gx gy gz outer inner"
add_line "$d/session.ini" "table_unit = furlong"
fixed 2 "session.ini:$L: 'log.table_unit'|'furlong'" nav
new custom-gyro-axes-four; custom; add_line "$d/session.ini" "gyro_axes = x y z w"
fixed 2 "session.ini:$L: 'log.gyro_axes'|expected three axes" nav
new custom-accel-axes-repeated; custom; add_line "$d/session.ini" "accel_axes = x -x z"
fixed 2 "session.ini:$L: 'log.accel_axes'|permutation" nav
new custom-gyro-scale-1e300; custom; add_line "$d/session.ini" "gyro_scale = 1e300"
fixed 2 "session.ini:$L: 'log.gyro_scale'|beyond any sensor" nav
new custom-accel-scale-zero; custom; add_line "$d/session.ini" "accel_scale = 0"
fixed 2 "session.ini:$L: 'log.accel_scale'|must not be zero" nav
new custom-gyro-offset-1e300; custom; add_line "$d/session.ini" "gyro_offset = 1e300"
fixed 2 "imu.txt:2: gyro log axis x|beyond any sensor" nav
new custom-saturated; custom; add_line "$d/session.ini" "gyro_saturation = 10"
fixed 2 "imu.txt:|saturated sample: gyro log axis" nav
new custom-unknown-column; custom; set_key "$d/session.ini" columns "t ax ay az gx gy gq"
fixed 2 "session.ini:$L: 'log.columns'|unknown column 'gq'" nav
new custom-column-missing; custom; set_key "$d/session.ini" columns "t ax ay az gx gy"
fixed 2 "session.ini:$L: 'log.columns'|column 'gz' missing" nav
new custom-delimiter-unknown; custom; add_line "$d/session.ini" "delimiter = pipe"
fixed 2 "session.ini:$L: 'log.delimiter'" nav
new custom-rate-unit-for-increments; custom; set_key "$d/session.ini" gyro increment
fixed 2 "session.ini:$(lno "$d/session.ini" '^gyro_unit'): 'log.gyro_unit'|'deg/s'" nav
new custom-field-count; custom; set_field "$d/imu.txt" 40 8 1
fixed 2 "imu.txt:40: expected 7 fields, found 8" nav

# --- split log (one file per triad) -----------------------------------------------------------
new split-different-lengths; split; sed -i '$d' "$d/gyr.txt"
fixed 2 "acc.txt:$(wc -l < "$base/acc.txt"): the files of a split log have different lengths|gyr.txt" nav
new split-times-differ; split; awk 'NR == 30 { $1 = $1 + 0.05 } { print }' "$base/gyr.txt" > "$d/gyr.txt"
fixed 2 "acc.txt:30:|gyr.txt:30: the files' times differ" nav
new split-gyro-1e300; split; awk 'NR == 30 { $3 = "1e300" } { print }' "$base/gyr.txt" > "$d/gyr.txt"
fixed 2 "gyr.txt:30: gyro log axis y reads 1e+300" nav
new split-gyro-file-missing; split; set_key "$d/session.ini" gyro_file nope.txt
fixed 2 "nope.txt:0: cannot open log file" nav
new split-with-columns; split; add_line "$d/session.ini" "columns = t gx gy gz ax ay az"
fixed 2 "session.ini:$L: 'log.columns'|accel_columns and gyro_columns" nav
new split-unknown-column; split; add_line "$d/session.ini" "accel_columns = t x y q"
fixed 2 "session.ini:$L: 'log.accel_columns'|unknown column 'q'" nav
new split-time-tolerance-negative; split; add_line "$d/session.ini" "time_tolerance = -1 ms"
fixed 2 "session.ini:$L: 'log.time_tolerance'|must not be negative" nav

# --- one file per dwell -----------------------------------------------------------------------
new segments-dwell-not-in-plan; segments; set_key "$d/session.ini" dwells "1 2 5"
fixed 2 "session.ini:$L: 'log.dwells'|assigned to dwell 5|has 3 dwells" nav
new segments-two-files-one-dwell; segments; set_key "$d/session.ini" dwells "1 2 2"
fixed 2 "session.ini:$L: 'log.dwells'|both assigned to dwell 2" nav
new segments-count-mismatch; segments; set_key "$d/session.ini" dwells "1 2"
fixed 2 "session.ini:$L: 'log.dwells'|2 dwells for 3 files" nav
new segments-file-and-files; segments; add_line "$d/session.ini" "file = pos1.csv"
fixed 2 "session.ini:$L: 'log.file'|not both" nav
new segments-file-missing; segments; set_key "$d/session.ini" files "pos1.csv nope.csv pos3.csv"
fixed 2 "session.ini:$L: 'log.files'|'nope.csv': no such file" nav
new segments-empty-file; segments; : > "$d/pos2.csv"
fixed 2 "pos2.csv:0: file ends before the column header" nav
new segments-file-past-dwell; segments; { cat "$base/pos1.csv"; tail -n +4 "$base/pos1.csv" | awk -F, -v OFS=, '{ $1 = $1 + 30; print }'; } > "$d/pos1.csv"
fixed 2 "pos1.csv:304: this file's data reach|past the end of dwell 1" nav
new segments-gyro-1e300; segments; set_field "$d/pos2.csv" 10 4 1e300
fixed 2 "pos2.csv:10: gyro log axis z reads 1e+300" nav
new segments-kf-jump; segments
fixed 2 "the data jump from t =" kf

# --- temperature columns (custom, split, one file per dwell) -----------------------------------
new control-navigate-custom-temperature; custom_temp; control 0 "" nav
new control-navigate-split-temperature; split_temp; control 0 "" nav
new control-navigate-segments-temperature; segments; for k in 1 2 3; do native_temp "$d/pos$k.csv"; done
control 0 "" nav
new temp-nan; custom_temp; set_field "$d/imu.txt" 50 8 nan
fixed 2 "imu.txt:50: field 8 (temperature) is NaN" nav
new temp-text; custom_temp; set_field "$d/imu.txt" 50 8 warm
fixed 2 "imu.txt:50: field 8 (temperature) 'warm' is not a number" nav
new temp-kelvin-declared-celsius; custom_temp
awk -F, -v OFS=, 'NR > 1 { $8 = $8 + 273.15 } { print }' "$base/imu_temp.txt" > "$d/imu.txt"
fixed 2 "imu.txt:2: temperature reads 298.152|read as K it would be 25 C (temperature_unit = K?)" nav
new temp-out-of-range; custom_temp; set_field "$d/imu.txt" 2 8 150
fixed 2 "imu.txt:2: temperature reads 150|outside -60 ... 130 C" nav
new temp-jump; custom_temp; set_field "$d/imu.txt" 60 8 35
fixed 2 "imu.txt:60: temperature jumps to 35 C|(line 59)" nav
new temp-column-missing; custom_temp; cp "$base/imu.txt" "$d/imu.txt"
fixed 2 "imu.txt:2: expected 8 fields, found 7" nav
new temp-key-without-column; custom; add_line "$d/session.ini" "temperature_unit = K"
fixed 2 "session.ini:$L: 'log.temperature_unit'|a temperature key without a temperature column" nav
new temp-unit-unknown; custom_temp; add_line "$d/session.ini" "temperature_unit = Celsius"
fixed 2 "session.ini:$L: 'log.temperature_unit'|expected C, K or F" nav
new temp-scale-zero; custom_temp; add_line "$d/session.ini" "temperature_scale = 0"
fixed 2 "session.ini:$L: 'log.temperature_scale'|must not be zero" nav
new temp-one-triad-only; custom_temp; set_key "$d/session.ini" columns "t ax ay az gx gy gz temp_a"
fixed 2 "session.ini:$L: 'log.columns'|both per-triad temperature columns" nav
new temp-native-key; mini; add_line "$d/session.ini" "temperature_unit = K"
fixed 2 "session.ini:$L: 'log.temperature_unit': unknown key in [log]" nav
new split-temp-nan; split_temp; awk 'NR == 30 { $5 = "nan" } { print }' "$base/acc_temp.txt" > "$d/acc.txt"
fixed 2 "acc.txt:30: field 5 (temperature) is NaN" nav
new split-temp-key-without-column; split; add_line "$d/session.ini" "temperature_offset = 273.15"
fixed 2 "session.ini:$L: 'log.temperature_offset'|neither accel_columns nor gyro_columns names temp" nav
new segments-temp-in-one-file; segments; native_temp "$d/pos2.csv"
fixed 2 "pos2.csv:4: this file has temperature columns but|pos1.csv has none" nav

# --- NovAtel ----------------------------------------------------------------------------------
new novatel-crc-mismatch; novatel; sed -i '2s/,3000,/,3009,/' "$d/imu.asc"
fixed 2 "imu.asc:2: CRC-32 mismatch" nav
new novatel-scale-missing; novatel; awk '!/^gyro_scale/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
fixed 2 "session.ini: [log] format = novatel: missing 'gyro_scale'" nav
new novatel-gyro-scale-1e300; novatel; set_key "$d/session.ini" gyro_scale 1e300
fixed 2 "session.ini:$L: 'log.gyro_scale'|beyond any sensor" nav
new novatel-status-mask-not-hex; novatel; add_line "$d/session.ini" "status_mask = 0xzz"
fixed 2 "session.ini:$L: 'log.status_mask'|hexadecimal" nav
new novatel-no-raw-imu-log; novatel; grep -v RAWIMU "$base/imu.asc" > "$d/imu.asc"
fixed 2 "imu.asc:$(grep -vc RAWIMU "$base/imu.asc"): no RAWIMUSA" nav
new novatel-unknown-key; novatel; add_line "$d/session.ini" "columns = t gx gy gz ax ay az"
fixed 2 "session.ini:$L: 'log.columns': unknown key in [log]" nav

# --- calibrate: options -----------------------------------------------------------------------
new calibrate-unknown-method; mini
fixed 1 "--method' must be closed-form | kf | table-free | six-face | rate-table, not 'magic'" S calibrate --method magic --session session.ini --out out/r.json
new calibrate-channels-one; s8
fixed 1 "--channels' must be a list with at least north,east" cf --channels north
new calibrate-stream-closed-form; mini
fixed 1 "--stream acts in --method kf only" cf --stream
new calibrate-passes-negative; mini
fixed 1 "--passes must be 0 (automatic) to 20" kf --passes -1
new calibrate-kf-without-sensor; mini; awk '!/^sensor/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
fixed 1 "session.ini: --method kf needs the session's sensor profile" kf
new calibrate-min-dwell-too-long; mini
fixed 2 "shorter than the 300" cf --min-dwell 300
# --misalignment-frame (issue 36.3): a known frame, the table's only with attitude updates.
new calibrate-frame-unknown; mini
fixed 1 "--misalignment-frame: unknown misalignment frame 'case' (table or triad)" kf --misalignment-frame case
new calibrate-frame-table-without-attitude; mini
fixed 1 "--misalignment-frame: the table frame is not observable without table-attitude updates" kf --misalignment-frame table --attitude none
new calibrate-frame-six-face; mini
fixed 1 "--misalignment-frame is an option of the table methods (kf, closed-form)" S calibrate --method six-face --session session.ini --out out/r.json --misalignment-frame triad

# --- hand-held: calibrate --method table-free, allan (session.ini without a plan, [site] gravity)
tf() { S calibrate --method table-free --session session.ini --out out/result.json "$@"; }
al() { S allan --session session.ini --out out/allan "$@"; }
# A hand-held session: mini's log without its plan, the local gravity given.
handheld() {
  cp "$base"/mini/imu.csv "$d/"
  printf '%s\n' "[session]" "name = handheld" "rate = 10 Hz" "" "[site]" "gravity = 9.81 m/s^2" "" \
    "[log]" "file = imu.csv" "format = sinscal" > "$d/session.ini"
}
new handheld-control-allan; handheld
control 0 "" al --longest-pose
new handheld-too-few-poses; handheld
fixed 2 "needs at least 10 static poses|found 3" tf
new handheld-not-static; handheld
fixed 2 "imu.csv: the record is not static" al
new handheld-pose-beyond; handheld
fixed 2 "imu.csv: pose 9 does not exist: the detector found 3 poses" al --pose 9
new handheld-two-selections; handheld
fixed 1 "give one of --all, --longest-pose, --pose N" al --all --pose 1
new handheld-pose-zero; handheld
fixed 1 "--pose must be 1 or more" al --pose 0
new handheld-no-plan-for-kf; handheld
fixed 2 "session.ini: [session] has no 'plan'|table-free" kf
new handheld-gravity-for-closed-form; mini; add_line "$d/session.ini" "[site]"; add_line "$d/session.ini" "gravity = 9.81 m/s^2"
fixed 2 "session.ini:$L: 'site.gravity'|read by 'calibrate --method table-free' and 'allan' only" cf
new handheld-gravity-off-earth; handheld; set_key "$d/session.ini" gravity "98.1 m/s^2"
fixed 2 "session.ini:$L: 'site.gravity'|within 9.7 and 9.9" tf
new handheld-gravity-option-off-earth; handheld
fixed 1 "--gravity must be within 9.7 and 9.9" tf --gravity 0
new handheld-no-gravity-no-site; handheld; awk '!/^gravity/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
fixed 2 "session.ini: no local gravity" tf
new handheld-kf-option; handheld
fixed 1 "--passes is an option of the table methods" tf --passes 2
new handheld-option-in-kf; mini
fixed 1 "--pose-window acts in --method table-free only" kf --pose-window 2
# diagnose on a hand-held session: the calibration itself fails (3 poses), the table's options
# and an unknown candidate refused. (Temperature without a column and a candidate the poses are too
# few for need a calibratable session: tests/handheld_cli_test.sh, on the real recordings.)
dg() { S diagnose --session session.ini --out out/d --no-plot "$@"; }
new handheld-diagnose-too-few-poses; handheld
fixed 2 "needs at least 10 static poses|found 3" dg
new handheld-diagnose-table-sigma; handheld
fixed 1 "--table-sigma, --min-dwell, --prefer, --passes and --no-kalman act on table" dg --table-sigma 3
new handheld-diagnose-unknown-candidate; handheld
fixed 1 "--candidates: 'accel.nonsense' is not an extended family" dg --candidates accel.nonsense
new handheld-diagnose-base-candidate; handheld
fixed 1 "--candidates: 'gyro.bias' is not an extended family" dg --candidates gyro.bias
new diagnose-handheld-option-on-table; mini
fixed 1 "--candidates acts on hand-held sessions (no plan)" S diagnose --session session.ini --out out/d --no-plot --candidates accel.k2

# --- compare (result JSON) --------------------------------------------------------------------
new compare-missing-file; cp "$base/s8/cf.json" "$d/a.json"
fixed 2 "nope.json: cannot open" S compare a.json nope.json
new compare-not-json; cp "$base/s8/cf.json" "$d/a.json"; echo "not json" > "$d/b.json"
fixed 2 "b.json: not a sinscal result file" S compare a.json b.json
new compare-no-coefficients-key; cp "$base/s8/cf.json" "$d/a.json"; echo '{"x": 1}' > "$d/b.json"
fixed 2 "b.json: not a sinscal result file" S compare a.json b.json
new compare-value-not-a-number; cp "$base/s8/cf.json" "$d/a.json"
sed 's/"value": [-0-9.e]*/"value": "abc"/' "$base/s8/cf.json" > "$d/b.json"
fixed 2 "b.json: coefficient 'accel.bias.x' has no finite value" S compare a.json b.json
new compare-one-file; cp "$base/s8/cf.json" "$d/a.json"
fixed 1 "give two result files" S compare a.json

# --- export (result JSON to a firmware's compensation) -----------------------------------------
new control-export; cp "$base/s8/cf.json" "$d/r.json"
POST='grep -q "correction_matrix" out/e.json'
control 0 "" S export --result r.json --format json --out out/e.json
new export-missing-file
fixed 2 "nope.json: cannot open" S export --result nope.json --format json
new export-not-json; echo "not json" > "$d/r.json"
fixed 2 "r.json: not a sinscal result file (not JSON" S export --result r.json --format yaml
new export-no-coefficients-key; echo '{"method": {"name": "kf"}}' > "$d/r.json"
fixed 2 "r.json: not a sinscal result file (no \"coefficients\" object)" S export --result r.json --format json
new export-truth-file; cp "$base/s8/truth.json" "$d/"
fixed 2 "truth.json: a truth file (simulate's), not a calibration result" S export --result truth.json --format json
new export-unknown-coefficient; sed 's/"gyro.bias.x"/"gyro.wobble.x"/' "$base/s8/cf.json" > "$d/r.json"
fixed 2 "r.json: unknown coefficient 'gyro.wobble.x'" S export --result r.json --format json
new export-missing-coefficient
awk '/"accel.scale.y": \{/ { skip = 1; next } skip && /\}/ { skip = 0; next } !skip' "$base/s8/cf.json" > "$d/r.json"
fixed 2 "r.json: coefficients missing (accel.scale.y)" S export --result r.json --format c-header
new export-value-not-a-number; sed '0,/"value": [-0-9.e]*/s//"value": "abc"/' "$base/s8/cf.json" > "$d/r.json"
fixed 2 "r.json: coefficient 'gyro.bias.x' has no finite value" S export --result r.json --format json
new export-unobservable; cp "$base/s8/paper.json" "$d/r.json"
fixed 2 "r.json: 3 coefficients are not determined by the data|accel.scale.x, accel.scale.y, accel.scale.z|--force" \
  S export --result r.json --format json --out out/e.json
new export-unobservable-forced; cp "$base/s8/paper.json" "$d/r.json"
POST='grep -A1 unobservable_exported_as_zero out/e.json | grep -q accel.scale.x'
fixed 0 "WARNING (--force)|not determined by the data exported as zero" \
  S export --result r.json --format json --out out/e.json --force
new export-failed-verdict; sed '$ s/}$/, "diverged": {"reason": "filter diverging at t = 5 s"}}/' "$base/s8/cf.json" > "$d/r.json"
POST='! test -e out/e.h'
fixed 2 "r.json: the calibration failed its own checks: the filter diverged (filter diverging at t = 5 s)|--force" \
  S export --result r.json --format c-header --out out/e.h
new export-failed-verdict-forced; sed '$ s/}$/, "stopped": {"reason": "imu.csv:30: NaN"}}/' "$base/s8/cf.json" > "$d/r.json"
POST='grep -q "WARNING (--force): the run stopped" out/e.h'
fixed 0 "WARNING (--force)" S export --result r.json --format c-header --out out/e.h --force
new export-out-is-the-input; cp "$base/s8/cf.json" "$d/r.json"
fixed 1 "--out r.json is the result: an output never replaces an input" S export --result r.json --format json --out r.json
new export-out-directory-missing; cp "$base/s8/cf.json" "$d/r.json"
POST='! test -e out/no/e.yaml'
fixed 2 "out/no/e.yaml: cannot create" S export --result r.json --format yaml --out out/no/e.yaml
new export-unknown-format; cp "$base/s8/cf.json" "$d/r.json"
fixed 1 "--format: export format must be json | yaml | c-header, not 'xml'" S export --result r.json --format xml
new export-no-format; cp "$base/s8/cf.json" "$d/r.json"
fixed 1 "'--format' is required" S export --result r.json

# --- report (result JSON and a diagnosis directory to a certificate) ---------------------------
new control-report; cp "$base/s8/cf.json" "$d/r.json"
POST='grep -q "<td>gyro.bias.x</td>" out/r.html'
control 0 "" S report --result r.json --out out/r.html
new report-missing-file
POST='! test -e out/r.html'
fixed 2 "nope.json: cannot open" S report --result nope.json --out out/r.html
new report-not-json; echo "not json" > "$d/r.json"
fixed 2 "r.json: not a sinscal result file (not JSON" S report --result r.json --out out/r.html
new report-no-coefficients-key; echo '{"method": {"name": "kf"}}' > "$d/r.json"
fixed 2 "r.json: not a sinscal result file (no \"coefficients\" object)" S report --result r.json --out out/r.html
new report-truth-file; cp "$base/s8/truth.json" "$d/"
fixed 2 "truth.json: a truth file (simulate's), not a calibration result" S report --result truth.json --out out/r.html
new report-unknown-coefficient; sed 's/"gyro.bias.x"/"gyro.wobble.x"/' "$base/s8/cf.json" > "$d/r.json"
fixed 2 "r.json: unknown coefficient 'gyro.wobble.x'" S report --result r.json --out out/r.html
new report-value-not-a-number; sed '0,/"value": [-0-9.e]*/s//"value": "abc"/' "$base/s8/cf.json" > "$d/r.json"
fixed 2 "r.json: coefficient 'gyro.bias.x' has no finite value" S report --result r.json --out out/r.html
new report-diagnosis-without-json; cp "$base/s8/cf.json" "$d/r.json"; mkdir -p "$d/diag"
POST='! test -e out/r.html'
fixed 2 "diag/diagnosis.json: cannot open|sinscal diagnose" S report --result r.json --diagnosis diag --out out/r.html
new report-diagnosis-not-a-diagnosis; cp "$base/s8/cf.json" "$d/r.json"; mkdir -p "$d/diag"; echo '{"session": "s"}' > "$d/diag/diagnosis.json"
fixed 2 "diag/diagnosis.json: not a sinscal diagnosis (no \"findings\" array)" S report --result r.json --diagnosis diag --out out/r.html
new report-diagnosis-not-json; cp "$base/s8/cf.json" "$d/r.json"; mkdir -p "$d/diag"; echo 'findings' > "$d/diag/diagnosis.json"
fixed 2 "diag/diagnosis.json: not a sinscal diagnosis (not JSON" S report --result r.json --diagnosis diag --out out/r.html
new report-diagnosis-is-a-file; cp "$base/s8/cf.json" "$d/r.json"; cp "$base/s8/cf.json" "$d/diag"
fixed 2 "diag: not a directory" S report --result r.json --diagnosis diag --out out/r.html
new report-out-exists; cp "$base/s8/cf.json" "$d/r.json"; echo "kept" > "$d/out/r.html"
POST='grep -q kept out/r.html'
fixed 1 "--out out/r.html: exists|--force" S report --result r.json --out out/r.html
new report-out-is-the-input; cp "$base/s8/cf.json" "$d/r.json"
fixed 1 "is the result: an output never replaces an input" S report --result r.json --out r.json --force

# --- what leaves the tool: every coefficient against its family's physical range ---------------
# (models/coefficient_families.cpp plausible_max; report/result_read.cpp). export, report and
# compare refuse (exit 2, naming the file, the coefficient and the cause) a bias of 1e308, a scale
# factor of -1 (-100 %), a misalignment or sigma of 1e308, a missing sigma, a unit of rad/s where
# deg/h belongs; --force records the override in the output. compare refuses a mistyped name.
# implausible NAME SED-EXPR MESSAGE: a copy of the closed-form result edited by SED-EXPR, refused by
# export, report and compare with MESSAGE and nothing written.
implausible() {
  local name=$1 expr=$2 msg=$3 cmd
  for cmd in export report compare; do
    new "$cmd-$name"; sed "$expr" "$base/s8/cf.json" > "$d/r.json"; cp "$base/s8/cf.json" "$d/a.json"
    POST='test -z "$(ls out | grep -v -e stdout -e stderr)"'
    case $cmd in
      export) fixed 2 "r.json: $msg" S export --result r.json --format c-header --out out/e.h ;;
      report) fixed 2 "r.json: $msg" S report --result r.json --out out/r.html ;;
      compare) fixed 2 "r.json: $msg" S compare a.json r.json ;;
    esac
  done
}
implausible bias-1e308 '0,/"value": [-0-9.e]*/s//"value": 1e308/' \
  "coefficient 'gyro.bias.x': value 1e+308 deg/h is beyond the physical range of gyro.bias"
implausible scale-minus-100-percent '/"gyro.scale.x"/,/value/s/"value": [-0-9.e]*/"value": -1000000/' \
  "coefficient 'gyro.scale.x': value -1e+06 ppm is beyond the physical range of gyro.scale"
implausible misalignment-1e308 '/"accel.misalignment.zy"/,/value/s/"value": [-0-9.e]*/"value": 1e308/' \
  "coefficient 'accel.misalignment.zy': value 1e+308 arcsec is beyond"
implausible sigma-1e308 '/"accel.bias.y"/,/sigma/s/"sigma": [-0-9.e]*/"sigma": 1e308/' \
  "coefficient 'accel.bias.y': sigma 1e+308 ug is beyond the physical range of accel.bias"
implausible sigma-zero '/"accel.bias.y"/,/sigma/s/"sigma": [-0-9.e]*/"sigma": 0/' \
  "coefficient 'accel.bias.y': sigma 0"
implausible missing-sigma '/"gyro.bias.z"/,/sigma/{/"sigma"/d}' \
  "coefficient 'gyro.bias.z': no sigma"
implausible unit-rad-per-s '0,/"unit": "deg\/h"/s//"unit": "rad\/s"/' \
  "coefficient 'gyro.bias.x' is in 'rad/s', results give it in 'deg/h'"
# --force: written, the override recorded in the output (header comment, JSON field, page).
new export-bias-1e308-forced; sed '0,/"value": [-0-9.e]*/s//"value": 1e308/' "$base/s8/cf.json" > "$d/r.json"
POST='grep -q "WARNING (--force): implausible coefficient exported as given: gyro.bias.x: value 1e+308" out/e.h'
fixed 0 "WARNING (--force)|gyro.bias.x" S export --result r.json --format c-header --out out/e.h --force
new export-json-sigma-1e308-forced; sed '/"accel.bias.y"/,/sigma/s/"sigma": [-0-9.e]*/"sigma": 1e308/' "$base/s8/cf.json" > "$d/r.json"
POST='grep -A3 "\"warnings\"" out/e.json | grep -q "accel.bias.y: sigma 1e+308"'
fixed 0 "WARNING (--force)" S export --result r.json --format json --out out/e.json --force
new export-yaml-scale-forced; sed '/"gyro.scale.x"/,/value/s/"value": [-0-9.e]*/"value": -1000000/' "$base/s8/cf.json" > "$d/r.json"
POST='grep -A3 "^warnings:" out/e.yaml | grep -q "gyro.scale.x: value -1e+06 ppm"'
fixed 0 "WARNING (--force)" S export --result r.json --format yaml --out out/e.yaml --force
new report-bias-1e308-forced; sed '0,/"value": [-0-9.e]*/s//"value": 1e308/' "$base/s8/cf.json" > "$d/r.json"
POST='grep -q "Certified with --force" out/r.html && grep -q "Implausible coefficients (certified with --force)" out/r.html'
fixed 0 "WARNING (--force)|gyro.bias.x" S report --result r.json --out out/r.html --force
new compare-bias-1e308-forced; sed '0,/"value": [-0-9.e]*/s//"value": 1e308/' "$base/s8/cf.json" > "$d/r.json"; cp "$base/s8/cf.json" "$d/a.json"
POST='grep -q "WARNING (--force): B: gyro.bias.x: value 1e+308" out/stdout'
fixed 0 "WARNING (--force)" S compare a.json r.json --force
# The unit and a mistyped name are never overridden.
new export-unit-rad-per-s-forced; sed '0,/"unit": "deg\/h"/s//"unit": "rad\/s"/' "$base/s8/cf.json" > "$d/r.json"
fixed 2 "r.json: coefficient 'gyro.bias.x' is in 'rad/s'" S export --result r.json --format json --out out/e.json --force
new compare-mistyped-names; sed 's/"gyro.bias.x"/"gyro.bais.x"/' "$base/s8/cf.json" > "$d/a.json"; cp "$d/a.json" "$d/b.json"
fixed 2 "a.json: unknown coefficient 'gyro.bais.x'" S compare a.json b.json
new compare-mistyped-name-forced; cp "$base/s8/cf.json" "$d/a.json"; sed 's/"accel.scale.z"/"accel.scael.z"/' "$base/s8/cf.json" > "$d/b.json"
fixed 2 "b.json: unknown coefficient 'accel.scael.z'" S compare a.json b.json --force
# A coefficient in one file only is named (not silently left out of the comparison).
new compare-coefficient-in-one-file; cp "$base/s8/cf.json" "$d/a.json"
sed '/"gyro.bias.x": {/,/}/d' "$base/s8/cf.json" > "$d/b.json"
fixed 0 "coefficients only in a.json, not compared: gyro.bias.x" S compare a.json b.json

# --- plot-convergence (monitor JSONL) -----------------------------------------------------------
new plot-monitor-missing
fixed 2 "nope.jsonl: cannot open" S plot-convergence --monitor nope.jsonl --out out/c.png
new plot-monitor-bad-line; cp "$base/mini/monitor.jsonl" "$d/"; sed -i '2s/.*/{"t": oops}/' "$d/monitor.jsonl"
fixed 2 "monitor.jsonl:2:" S plot-convergence --monitor monitor.jsonl --out out/c.png
new plot-monitor-empty; : > "$d/monitor.jsonl"
fixed 2 "monitor.jsonl: no monitor records" S plot-convergence --monitor monitor.jsonl --out out/c.png
new plot-monitor-time-not-increasing; cp "$base/mini/monitor.jsonl" "$d/"; sed -n '1p' "$base/mini/monitor.jsonl" >> "$d/monitor.jsonl"
fixed 2 "monitor.jsonl:$(wc -l < "$d/monitor.jsonl"):|does not increase" S plot-convergence --monitor monitor.jsonl --out out/c.png
new plot-monitor-unknown-coefficient; cp "$base/mini/monitor.jsonl" "$d/"; sed -i '1s/"gyro.bias.x"/"gyro.bias.w"/' "$d/monitor.jsonl"
fixed 2 "monitor.jsonl:1:|unknown coefficient 'gyro.bias.w'" S plot-convergence --monitor monitor.jsonl --out out/c.png
new plot-family-unknown; cp "$base/mini/monitor.jsonl" "$d/"
fixed 2 "family 'gyro.colour'" S plot-convergence --monitor monitor.jsonl --out out/c.png --family gyro.colour
new plot-width-too-small; cp "$base/mini/monitor.jsonl" "$d/"
fixed 1 "--width must be 200 to 20000 px" S plot-convergence --monitor monitor.jsonl --out out/c.png --width 10

# --- outputs and options (apps/, report/) -----------------------------------------------------
# An output that is an input: refuse before writing (exit 1, naming the file).
new calibrate-out-is-the-log; mini
fixed 1 "imu.csv" S calibrate --method closed-form --session session.ini --out imu.csv
new calibrate-out-is-session-ini; mini
fixed 1 "session.ini" S calibrate --method kf --session session.ini --out session.ini
new calibrate-monitor-is-the-log; mini
fixed 1 "imu.csv" S calibrate --method kf --session session.ini --out out/r.json --monitor imu.csv
new navigate-out-is-the-log; mini
fixed 1 "imu.csv" S navigate --session session.ini --out imu.csv
new plot-out-is-the-monitor; cp "$base/mini/monitor.jsonl" "$d/"
fixed 1 "monitor.jsonl" S plot-convergence --monitor monitor.jsonl --out monitor.jsonl
# A batch: x/a, y/a and z/a-2 must give three result files (y/a and z/a-2 both write a-2.json).
new batch-result-names-collide
# (each log one sample apart: the same data twice is refused, see batch-session-copied)
k=0; for s in x/a y/a z/a-2; do mkdir -p "$d/runs/$s"; cp "$base"/mini/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/runs/$s/"; k=$((k + 1)); set_field "$d/runs/$s/imu.csv" 200 2 "${k}e-12"; done
POST='test "$(ls out/batch/*.json | wc -l)" -eq 3'
fixed 0 "" S calibrate --method closed-form --session runs/x/a --session runs/y/a --session runs/z/a-2 --out out/batch
# A monitor file name with a newline must not put a command into the gnuplot script.
new plot-monitor-name-with-newline; nl_name=$'m\nsystem "touch pwned"\n#.jsonl'
cp "$base/mini/monitor.jsonl" "$d/$nl_name"
POST='! grep -q "^system" out/conv.gp && ! test -e pwned'
fixed "0,1,2" "" S plot-convergence --monitor "$nl_name" --out out/conv.png
# compare: a negative sigma is not a result (exit 2 naming the file); a name that is not a
# coefficient is refused (exit 2).
new compare-negative-sigma; cp "$base/s8/cf.json" "$d/a.json"
sed '0,/"sigma": [0-9.e-]*/s//"sigma": -1/' "$base/s8/cf.json" > "$d/b.json"
fixed 2 "b.json|sigma" S compare a.json b.json --max-sigma 3
new compare-no-known-coefficients
echo '{"coefficients": {"foo": {"value": 1, "sigma": 1}}}' > "$d/a.json"; cp "$d/a.json" "$d/b.json"
fixed 2 "a.json: unknown coefficient 'foo'" S compare a.json b.json --max-sigma 3
# Options a method does not use must be refused (exit 1), not silently ignored.
new kf-arw-vrw-ignored; mini
fixed 1 "--arw" kf --arw 0.5 --vrw 50
new closed-form-static-from-data-ignored; s8
fixed 1 "--static-from" cf --static-from data
new kf-lever-arm-reference-observable; mini
fixed 1 "zero velocity at rest only" kf --lever-arm-reference x
# diagnose: too few dwells for the model, a session that fails the gate, a bad option.
new diagnose-too-few-dwells; mini
fixed 2 "too few dwells" S diagnose --session session.ini --out out/d --no-plot
new diagnose-flipped-axis; s8
awk -F, -v OFS=, 'NR > 3 { $6 = -$6 } { print }' "$base/s8/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv: dwell|gravity direction" S diagnose --session session.ini --out out/d --no-plot
new diagnose-alpha-zero; mini
fixed 1 "--alpha must be in (0, 0.5)" S diagnose --session session.ini --out out/d --alpha 0
# A plan/log mismatch in navigate and the closed form must name the log (the Kalman filter does).
new navigate-mismatch-names-the-log; mini; head -n 400 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv|plan does not match the data" nav
new closed-form-mismatch-names-the-log; mini; head -n 400 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv|plan does not match the data" cf


# The plausibility gate (filter/plausibility/plausibility.hpp): before any estimate each static dwell is
# compared with gravity, the Earth rate and the plan's attitude; a failure names the log, the dwell
# and the likely cause, exit 2.
new closed-form-constant-data; s8
awk -F, -v OFS=, 'NR <= 3 { print; next } { print $1, 0, 0, 0, 0, 0, -0.980665 }' "$base/s8/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv: dwell|plausibility gate|Earth rate|no signal" cf
new closed-form-flipped-accel-axis; s8
awk -F, -v OFS=, 'NR > 3 { $6 = -$6 } { print }' "$base/s8/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv: dwell|gravity direction|wrong axis map or sign" cf
new closed-form-wrong-plan; s8
awk '/^\[orientation.2\]/ { o = 1 } /^\[orientation.3\]/ { o = 0 }
     o && /^heading/ { $0 = "heading = 270 deg" } o && /^pitch/ { $0 = "pitch = 315 deg" } { print }' \
  "$base/s8/plan.ini" > "$d/plan.ini"
fixed 2 "imu.csv: dwell 2|gravity direction|the wrong plan" cf
# Velocity increments in mm/s declared as m/s; gyro increments in rad declared as deg.
new closed-form-mm-per-s-as-m-per-s; s8
awk -F, -v OFS=, 'NR > 3 { $5 *= 1000; $6 *= 1000; $7 *= 1000; print }' "$base/s8/imu.csv" > "$d/imu.txt"
printf '%s\n' "[log]" "file = imu.txt" "format = custom" "columns = t gx gy gz ax ay az" "accel_unit = m/s" \
  > "$d/log.part"
awk '/^\[log\]/ { exit } { print }' "$base/s8/session.ini" > "$d/session.ini"; cat "$d/log.part" >> "$d/session.ini"; rm "$d/log.part"
fixed 2 "imu.txt: dwell|gravity magnitude|mm/s" cf
new closed-form-rad-as-deg; s8
awk -F, -v OFS=, 'NR > 3' "$base/s8/imu.csv" > "$d/imu.txt"
awk '/^\[log\]/ { exit } { print }' "$base/s8/session.ini" > "$d/session.ini"
printf '%s\n' "[log]" "file = imu.txt" "format = custom" "columns = t gx gy gz ax ay az" "gyro_unit = deg" >> "$d/session.ini"
fixed 2 "imu.txt: dwell|Earth rate|rad declared as deg" cf
# Clipped data (every sample at the profile's 0.6 g range): samples at the sensor profile's range
# are saturated samples (exit 2, naming the log and line), not coefficients with exit 0.
new closed-form-clipped; sed 's/^range = 20 g/range = 0.6 g/' "$fog" > "$d/clip.ini"
S simulate --plan "$src/config/plans/seed8.ini" --sensor "$d/clip.ini" --out "$d/s" --rate 10 > /dev/null
rm "$d/clip.ini"
fixed 2 "imu.csv:|saturated|clipped data" S calibrate --method closed-form --session s/session.ini --out out/r.json
# --force runs past the gate and records the failed checks in the result.
new closed-form-constant-data-forced; s8
awk -F, -v OFS=, 'NR <= 3 { print; next } { print $1, 0, 0, 0, 0, 0, -0.980665 }' "$base/s8/imu.csv" > "$d/imu.csv"
POST='grep -q "\"plausibility\"" out/result.json && grep -q "\"passed\": false" out/result.json'
fixed 0 "" cf --force

# --- design (issue 17): table descriptions and plans beyond the table
tab="$src/config/tables/two-axis-20.ini"
dz() { S design --plan "$src/config/plans/rot19.ini" --sensor "$fog" --table table.ini "$@"; }
new design-control; cp "$tab" "$d/table.ini"
control 0 "" dz
new design-table-unknown-key; cp "$tab" "$d/table.ini"; add_line "$d/table.ini" "max_speed = 3 deg/s"
fixed 2 "table.ini:$L: 'table.max_speed': unknown key" dz
new design-table-rate-in-m-per-s; cp "$tab" "$d/table.ini"; set_key "$d/table.ini" max_rate "20 m/s"; L=$(lno "$d/table.ini" '^max_rate')
fixed 2 "table.ini:$L: 'table.max_rate'" dz
new design-table-negative-accuracy; cp "$tab" "$d/table.ini"; set_key "$d/table.ini" attitude_accuracy "-2.5 arcsec"; L=$(lno "$d/table.ini" '^attitude_accuracy')
fixed 2 "table.ini:$L: 'table.attitude_accuracy'|positive" dz
new design-table-no-rate; grep -v '^max_rate' "$tab" > "$d/table.ini"
fixed 2 "table.ini|max_rate" dz
new design-table-is-a-directory; mkdir "$d/table.ini"
fixed 2 "table.ini: is a directory" dz
new design-plan-beyond-table; cp "$tab" "$d/table.ini"; set_key "$d/table.ini" max_acceleration "5 deg/s^2"
fixed 2 "the plan asks more than the table|angular acceleration 10.000 deg/s^2 above the table's 5.000 deg/s^2" dz
new design-plan-dwell-shorter-than-settling; cp "$tab" "$d/table.ini"; set_key "$d/table.ini" settling_time "25 s"
fixed 2 "shorter than the table's settling time 25.000 s" dz
new design-rate-zero; cp "$tab" "$d/table.ini"
fixed 1 "--rate must be within 1 and 10000 Hz" dz --rate 0

new design-optimize-without-table; cp "$tab" "$d/table.ini"
fixed 1 "--optimize needs --table" S design --optimize --plan "$src/config/plans/rot19.ini" --sensor "$fog" --out out/o
new design-targets-unknown-family; cp "$tab" "$d/table.ini"
fixed 2 "--targets, item 2: 'targets.gyro.drift'|in [targets]" dz --optimize --out out/o --targets "gyro.scale = 3 ppm; gyro.drift = 1 deg/h"
new design-targets-not-positive; cp "$tab" "$d/table.ini"
fixed 2 "'targets.gyro.scale'|must be positive" dz --optimize --out out/o --targets "gyro.scale = 0 ppm"
new design-robustness-one-seed; cp "$tab" "$d/table.ini"
fixed 1 "--robustness must be within 2 and 1000 seeds" dz --robustness 1
new design-targets-without-optimize; cp "$tab" "$d/table.ini"
fixed 1 "belong to --optimize" dz --targets "gyro.scale = 3 ppm"
new design-require-not-estimated; cp "$tab" "$d/table.ini"
fixed 1 "--require: required family 'gyro.g_sensitivity' is not estimated" dz --optimize --out out/o --require gyro.g_sensitivity
new design-require-unknown-family; cp "$tab" "$d/table.ini"
fixed 1 "--require: required family 'gyro.drift' is not estimated" dz --optimize --out out/o --require gyro.scale gyro.drift
new design-require-without-optimize; cp "$tab" "$d/table.ini"
fixed 1 "belong to --optimize" dz --require accel.lever_arm

# --- six-face (issue 18): imucal's labelled session, its declaration or its log changed
sf_session="$src/config/measured/imucal-ferraris/session.ini"
sf_log="$src/data/imucal/annotated_session.csv"
# sfnew NAME: the session in $d, its log named by absolute path.
sfnew() { new "$1"; sed "s|^file = .*|file = $sf_log|" "$sf_session" > "$d/session.ini"; }
sf() { S calibrate --method six-face --session session.ini --out out/result.json "$@"; }
sfnew six-face-control
control 0 "" sf
sfnew six-face-part-not-in-log; set_key "$d/session.ini" faces "x_p x_a y_p y_a z_p z_down"
fixed 2 "no part labelled 'z_down' (the face with -z up); the log's parts: x_a x_p x_rot" sf
sfnew six-face-faces-swapped; set_key "$d/session.ini" faces "x_a x_p y_p y_a z_p z_a"
fixed 2 "face 'x_a' is declared +x up, but its specific force (|points along -x: labels swapped" sf
sfnew six-face-turn-other-direction; set_key "$d/session.ini" turn_angle "-360 deg"
fixed 2 "turn 'x_rot' integrates to 367.|declared -360.0 deg" sf
sfnew six-face-turn-half; set_key "$d/session.ini" turn_angle "180 deg"
fixed 2 "turn 'x_rot' integrates to 367.|declared 180.0 deg" sf
sfnew six-face-face-too-short; add_line "$d/session.ini" "min_rest = 4 s"
fixed 2 "face 'y_p' lasts 3.58 s, shorter than the minimum rest of 4.00 s" sf
sfnew six-face-five-faces; set_key "$d/session.ini" faces "x_p x_a y_p y_a z_p"
fixed 2 "session.ini:$L: 'six_face.faces'|needs 6 labels, found 5" sf
sfnew six-face-label-face-and-turn; set_key "$d/session.ini" turns "x_rot y_rot z_p"
fixed 2 "label 'z_p' is both a face and a turn" sf
sfnew six-face-no-label-column; set_key "$d/session.ini" columns "- - ax ay az gx gy gz"
fixed 2 "annotated_session.csv:2: a six-face log needs a label column" sf
sfnew six-face-no-section; grep -v -E '^(\[six_face\]|faces|turns|turn_angle)' "$sf_session" | sed "s|^file = .*|file = $sf_log|" > "$d/session.ini"
fixed 2 "needs a [six_face] section" sf
sfnew six-face-unknown-key; add_line "$d/session.ini" "placement = 2 deg"
fixed 2 "session.ini:$L: 'six_face.placement'|unknown key" sf
sfnew six-face-accuracy-zero; add_line "$d/session.ini" "face_accuracy = 0 deg"
fixed 2 "session.ini:$L: 'six_face.face_accuracy'|must be within" sf
sfnew six-face-out-is-input; 
fixed 1 "--out session.ini is the session: an output never replaces an input" S calibrate --method six-face --session session.ini --out session.ini
sfnew six-face-diagnose-no-label-column; set_key "$d/session.ini" columns "- - ax ay az gx gy gz"
fixed 2 "annotated_session.csv:2: a six-face log needs a label column" S diagnose --session session.ini --out out/diag
sfnew six-face-diagnose-turn-other-direction; set_key "$d/session.ini" turn_angle "-360 deg"
fixed 2 "turn 'x_rot' integrates to 367.|declared -360.0 deg" S diagnose --session session.ini --out out/diag
sfnew six-face-table-option; 
fixed 1 "--table-sigma is an option of the table methods (closed-form, kf), not of --method six-face" sf --table-sigma 3

# --- issue 34: rate-table segments, three-axis tables, calibrate --method rate-table
# rtnew NAME: the rate-mixed plan and the tactical-rate profile in $d.
rtnew() { new "$1"; cp "$src/config/plans/rate-mixed.ini" "$d/plan.ini"; cp "$src/config/sensors/tactical-rate.ini" "$d/sensor.ini"; }
rtsim() { S simulate --plan plan.ini --sensor sensor.ini --rate 20 --out sim; }
rtcal() { S calibrate --method rate-table --session sim/session.ini --out out/r.json "$@"; }
rtnew rate-table-control; (cd "$d" && rtsim > /dev/null) || die "rate-table simulation"
control 0 "" rtcal
rtnew rate-table-angle-and-revolutions; L=$(( $(lno "$d/plan.ini" '^revolutions') ))
sed -i "${L}a angle = 90 deg" "$d/plan.ini"; L=$((L + 1))
fixed 2 "plan.ini:$((L - 1)): 'step.1.revolutions'|a turn with an 'angle' has no 'hold' or 'revolutions'" sim
rtnew rate-table-half-revolution; set_key "$d/plan.ini" revolutions "2.5"
fixed 2 "plan.ini:$L: 'step.1.revolutions'|expected whole revolutions" sim
rtnew rate-table-hold-and-revolutions; L=$(lno "$d/plan.ini" '^revolutions'); sed -i "${L}a hold = 10 s" "$d/plan.ini"
fixed 2 "plan.ini: [step.1]: a rate-table segment (no 'angle') needs 'rate' and exactly one of" sim
rtnew rate-table-no-rate; L=$(lno "$d/plan.ini" '^rate = 25'); sed -i "${L}d" "$d/plan.ini"
fixed 2 "plan.ini: [step.1]: a rate-table segment (no 'angle') needs 'rate'" sim
rtnew rate-table-rotations-angle-and-hold; cp "$src/config/plans/rate-table.ini" "$d/plan.ini"; add_line "$d/plan.ini" "angle = 90 deg"
fixed 2 "plan.ini: [rotations]: rate-table segments need 'rate' (or 'rates') and exactly one of" sim
rtnew rate-table-rotations-revolutions-count; cp "$src/config/plans/rate-table.ini" "$d/plan.ini"; set_key "$d/plan.ini" revolutions "1 2 3"
fixed 2 "plan.ini:$L: 'rotations.revolutions'|expected 1 or 12 values" sim
rtnew three-axis-axes-4; cp "$src/config/plans/six-face-3axis.ini" "$d/plan.ini"; set_key "$d/plan.ini" axes "4"
fixed 2 "plan.ini:$L: 'table.axes'" sim
rtnew three-axis-plan-on-two-axes; cp "$src/config/plans/six-face-3axis.ini" "$d/plan.ini"; set_key "$d/plan.ini" axes "2"
fixed 2 "plan.ini: [orientation.5]: orientation not reachable by the two-axis table" sim
rtnew rate-table-segment-not-in-log; (cd "$d" && rtsim > /dev/null) || die "rate-table simulation"
set_key "$d/sim/plan.ini" rate "80 deg/s"
fixed 2 "imu.csv: segment 2 (rate 1 (+z)) not found in the log|rate of 80" rtcal
rtnew rate-table-faces-swapped; cp "$src/config/plans/six-face-3axis.ini" "$d/plan.ini"; (cd "$d" && rtsim > /dev/null) || die "rate-table simulation"
L=$(lno "$d/sim/plan.ini" '^roll = 180'); awk -v n="$L" 'NR == n { $0 = "roll = 0 deg" } { print }' "$d/sim/plan.ini" > "$d/p" && mv "$d/p" "$d/sim/plan.ini"
fixed 2 "rate table: accel.scale.z comes out at|the plan's attitudes, axes or rates are not what the data show" rtcal
rtnew three-axis-plan-two-axis-table; cp "$src/config/plans/six-face-3axis.ini" "$d/plan.ini"; cp "$src/config/tables/two-axis-20.ini" "$d/table.ini"
fixed 2 "plan.ini: a plan for a three-axis table ([table] axes = 3), and table.ini has 2 axes" S design --plan plan.ini --sensor sensor.ini --table table.ini
# A plan without a start rest ([start] dwell = 0): only when its first turn is a rate-table
# segment, and only the rate-table method reads it.
rtnew start-dwell-zero-angle-first; cp "$src/config/plans/rot19.ini" "$d/plan.ini"; set_key "$d/plan.ini" dwell "0 s"
fixed 2 "plan.ini:$L: 'start.dwell'|0 only when the plan begins in a rate-table segment" sim
rtnew start-dwell-zero-simulate; set_key "$d/plan.ini" dwell "0 s"
fixed 2 "plan.ini: [start] dwell = 0|only --method rate-table reads such a plan" sim
rtnew rate-table-kf-option
fixed 1 "--passes is not an option of --method rate-table" rtcal --passes 2
# Irregular sample intervals (issue 34, item 4): the integrating methods refuse them, naming the
# log and the spread; the means-only rate table runs. jitter FILE: times moved by up to 15 % of
# the 10 Hz interval (intervals 70-130 ms).
jitter() { awk -F, -v OFS=, 'NR > 3 { $1 = sprintf("%.10g", $1 + 0.015 * sin(37 * $1)) } { print }' "$1" > "$1.j" && mv "$1.j" "$1"; }
new kf-irregular-intervals; mini; jitter "$d/imu.csv"
fixed 2 "plausibility gate|imu.csv: sample intervals|spread|use --method rate-table" kf
new closed-form-irregular-intervals; s8; jitter "$d/imu.csv"
fixed 2 "imu.csv: sample intervals|spread|use --method rate-table" cf
new kf-no-time-column; custom; set_key "$d/session.ini" columns "- ax ay az gx gy gz"
fixed 0 "Assumption: ./imu.txt: no time column|rate of 10 Hz" kf
rtnew rate-table-irregular-intervals; (cd "$d" && rtsim > /dev/null) || die "rate-table simulation"
awk -F, -v OFS=, 'NR > 3 { $1 = sprintf("%.10g", $1 + 0.0075 * sin(37 * $1)) } { print }' "$d/sim/imu.csv" > "$d/j" && mv "$d/j" "$d/sim/imu.csv"
control 0 "" rtcal
# The rate table's fit gate (issue 34, item 5): a gyro offset of 0.005 deg/s on every gyro while
# the table turns (increments above 0.3 deg per 20 Hz sample), which the model lacks, is refused;
# --force runs and records the check.
rtnew rate-table-fit-refused; (cd "$d" && rtsim > /dev/null) || die "rate-table simulation"
awk -F, -v OFS=, 'NR > 3 && sqrt($2*$2+$3*$3+$4*$4) > 0.005 { for (i = 2; i <= 4; i++) $i = sprintf("%.12g", $i + 4.4e-6) } { print }' "$d/sim/imu.csv" > "$d/j" && mv "$d/j" "$d/sim/imu.csv"
fixed 2 "rate-table fit|imu.csv: the gyros' chi2 per dof|a gyro offset while turning" rtcal
POST='grep -q "rate-table fit" out/r.json'
fixed 0 "" rtcal --force
# Generated sessions of the APOPHIS logs' structure (tests/apophis_like.hpp: 12-18 Hz readings
# without a time column, outputs toggling between two levels). A rate test whose gyro y toggles
# slowly: the means' sigmas from their own autocorrelation, the fit's gate passes; a wrong unit
# is refused. Turns about the vertical alone: the integrating methods cannot check the log's time.
apnew() { new "$1"; "$gen" "$d" "$2" > /dev/null || die "apophis_like_writer $2"; }
apcal() { S calibrate --session session.ini --out out/r.json "$@"; }
apnew apophis-like-rate-test-control rate-test
control 0 "" apcal --method rate-table
apnew apophis-like-rate-test-gyro-unit rate-test; set_key "$d/session.ini" gyro_unit "rad/s"
fixed 2 "log.csv: segment 1 (start) not found in the log|no run of readings at its rest" apcal --method rate-table
apnew apophis-like-rate-test-swapped-gyro-axes rate-test; set_key "$d/session.ini" columns "ax ay az gx gz gy"
fixed 2 "log.csv: segment|not found in the log|rate of 25" apcal --method rate-table
apnew apophis-like-cross-asymmetry-kf z-turns
fixed 1 "--cross-asymmetry acts in --method rate-table only, not in --method kf" apcal --method kf --cross-asymmetry
# A tumble whose gyro biases drift over the log (board 2's drift, no time column): the gyros' fit
# is refused naming them; --gyro-drift models the drift and passes; the option is the rate
# table's only.
apnew apophis-like-tumble-drift-refused tumble
fixed 2 "rate-table fit|log.csv: the gyros' chi2 per dof" apcal --method rate-table
apnew apophis-like-tumble-gyro-drift tumble
control 0 "" apcal --method rate-table --gyro-drift
apnew apophis-like-gyro-drift-kf tumble
fixed 1 "--gyro-drift acts in --method rate-table only, not in --method kf" apcal --method kf --gyro-drift
# A rest that is not a rest (APOPHIS board 3's last rest): gyro y changes level within the last
# z-up rest: left out and named, the fit passes; with --keep-unsteady-rests kept and said so; in
# the only x-down face leaving it out leaves accelerometer x's K2 undetermined: refused, named;
# the option is the rate table's only.
apnew apophis-like-tumble-step-control tumble-step
POST='grep -q "not a rest, left out of the fit" out/r.json'
control 0 "" apcal --method rate-table --gyro-drift
apnew apophis-like-tumble-step-kept tumble-step
POST='grep -q "not a rest, kept" out/r.json'
control 0 "" apcal --method rate-table --gyro-drift --keep-unsteady-rests
apnew apophis-like-tumble-step-face tumble-step-face
fixed 2 "log.csv: segment 2 (2), readings|gyro y level change|not a rest|do not determine|accel.k2.x|--keep-unsteady-rests" apcal --method rate-table --gyro-drift
apnew apophis-like-keep-unsteady-kf tumble-step
fixed 1 "--keep-unsteady-rests acts in --method rate-table only, not in --method kf" apcal --method kf --keep-unsteady-rests
apnew apophis-like-z-turns-kf z-turns
fixed 2 "turn timing|log.csv: the log's time cannot be checked|none of the 1 turns|--method rate-table" apcal --method kf
apnew apophis-like-z-turns-closed-form z-turns
fixed 2 "turn timing|log.csv: the log's time cannot be checked|--method rate-table" apcal --method closed-form
apnew apophis-like-z-turns-rate-table z-turns
control 0 "" apcal --method rate-table
# Hand-held tumbles with the APOPHIS logs' timing (issue 34, item 4): the table-free fit
# integrates its turns between poses. With the readings' true times (12-18 Hz) it measures their
# spread and refuses it; without a time column (readings at 9-12 Hz taken as 15 Hz) the turns
# against gravity show the rate is wrong.
apnew apophis-like-hand-tumble-irregular-time hand-tumble-timed
fixed 2 "sample intervals|log.csv: sample intervals|spread|the table-free fit integrates its turns" apcal --method table-free
apnew apophis-like-hand-tumble-no-time hand-tumble
fixed 2 "turn timing|log.csv: the log's time does not match the nominal rate" apcal --method table-free

# --- issue 21: the plausibility gate without a table (filter/plausibility/rest_plausibility.hpp),
# simulate's output directory, and the messages the probe found weak. The real recordings of
# data/ through the sessions of config/measured (their paths made absolute).
data=$src/data
# meas NAME MEASURED: the measured session in $d.
meas() {
  new "$1"
  sed -e "s|\.\./\.\./\.\./data/|$data/|" -e "s|^sensor = \.\./\.\./sensors|sensor = $src/config/sensors|" \
    "$src/config/measured/$2/session.ini" > "$d/session.ini"
}
meas handheld-mpu-control mpu6050-calibration
control 0 "" tf --pose-accel-only
# The session's [table_free] (issue 20): its options checked like the command line's.
meas handheld-mpu-session-options-control mpu6050-calibration
control 0 "" tf
meas table-free-session-pose-window-zero mpu6050-calibration; add_line "$d/session.ini" "pose_window = 0 s"
fixed 2 "session.ini:$L: 'table_free.pose_window'|must be above 0 and at most 60 s" tf
meas table-free-session-unknown-key mpu6050-calibration; add_line "$d/session.ini" "window = 1 s"
fixed 2 "session.ini:$L: 'table_free.window'|unknown key" tf
meas table-free-session-accel-only-not-bool mpu6050-calibration; set_key "$d/session.ini" pose_accel_only "maybe"
fixed 2 "session.ini:$L: 'table_free.pose_accel_only'|expected true or false" tf
meas table-free-session-edge-trim-negative mpu6050-calibration; add_line "$d/session.ini" "edge_trim = -1 s"
fixed 2 "session.ini:$L: 'table_free.edge_trim'|must be 0 to 60 s" tf
meas handheld-xsens-control xsens-mti-handheld
control 0 "" tf
meas allan-mpu-control mpu6050-long-static
POST='grep -q "449.29 s at the declared 100 Hz (no time column" out/stdout'
control 0 "" al
# The three that exited 0 with numbers nobody should trust.
meas handheld-mpu-gyro-rad-per-s mpu6050-calibration; set_key "$d/session.ini" gyro_unit "rad/s"
fixed 2 "plausibility gate|rate at rest|example_data_calibration.csv: pose 1|values in deg declared as rad" tf --pose-accel-only
meas handheld-xsens-accel-file-as-gyro-file xsens-mti-handheld; set_key "$d/session.ini" gyro_file "$data/xsens-mti-handheld/xsens_acc.txt"
fixed 2 "same signal|xsens_acc.txt: given as both accel_file and gyro_file" tf
meas allan-rate-1000-hz-without-time mpu6050-long-static; set_key "$d/session.ini" rate "1000 Hz"
POST='grep -q "44.929 s at the declared 1000 Hz (no time column" out/stdout && ! test -e out/allan'
fixed 2 "noise|sample interval 0.001 s|outside it|without a time column" al
# The same signal in another file; --force runs and records the failed checks: a fit thousands
# of times off its noise model fails the fit gate ("converged" is the solver's own test and says
# so).
meas handheld-xsens-accel-copy-as-gyro-file xsens-mti-handheld; cp "$data/xsens-mti-handheld/xsens_acc.txt" "$d/copy.txt"
set_key "$d/session.ini" gyro_file copy.txt
fixed 2 "same signal|gyro x and accelerometer x are one signal|same file given for both triads" tf
meas handheld-xsens-accel-file-twice-forced xsens-mti-handheld; set_key "$d/session.ini" gyro_file "$data/xsens-mti-handheld/xsens_acc.txt"
POST='grep -A1 "\"check\": \"fit\"" out/result.json | grep -q false && grep -q "\"termination\"" out/result.json && grep -q "Fit gate (bias wander from the" out/stdout'
fixed 0 "" tf --force
meas handheld-mpu-gyro-rad-per-s-forced mpu6050-calibration; set_key "$d/session.ini" gyro_unit "rad/s"
POST='grep -q "\"plausibility\"" out/result.json && grep -A1 "\"check\": \"rate at rest\"" out/result.json | grep -q false'
fixed 0 "" tf --pose-accel-only --force
# Units, scales, offsets and columns of the hand-held sessions.
meas handheld-mpu-accel-mg-as-g mpu6050-calibration; set_key "$d/session.ini" accel_unit "mg"
fixed 2 "gravity magnitude|example_data_calibration.csv: pose|declared as mm/s" tf --pose-accel-only
meas handheld-mpu-accel-g-as-m-per-s2 mpu6050-calibration; set_key "$d/session.ini" accel_unit "m/s^2"
fixed 2 "gravity magnitude|values in g declared as m/s^2" tf --pose-accel-only
meas handheld-mpu-gyro-deg-per-h mpu6050-calibration; set_key "$d/session.ini" gyro_unit "deg/h"
fixed 2 "noise|sensor profile 'mpu6050'|outside it" tf --pose-accel-only
meas handheld-mpu-accel-scale-16g mpu6050-calibration; set_key "$d/session.ini" accel_scale 0.00048828125
fixed 2 "gravity magnitude|71.28 m/s^2|a wrong unit, scale or column" tf --pose-accel-only
meas handheld-mpu-gyro-scale-2000dps mpu6050-calibration; set_key "$d/session.ini" gyro_scale 0.06103515625
fixed 2 "noise|outside it" tf --pose-accel-only
# Gyro columns swapped (issue 34): the turns no longer turn the poses into each other. x and y:
# the turns' chi2 34.9 times the bound their timing allows; y and z: no convergence.
meas handheld-mpu-gyro-x-y-swapped mpu6050-calibration; set_key "$d/session.ini" columns "ax ay az gy gx gz"
fixed 2 "did not converge|gyro columns, unit or sample rate" tf --pose-accel-only
meas handheld-mpu-gyro-y-z-swapped mpu6050-calibration; set_key "$d/session.ini" columns "ax ay az gx gz gy"
fixed 2 "did not converge|gyro columns, unit or sample rate" tf --pose-accel-only
meas handheld-mpu-gyro-x-y-swapped-diagnose mpu6050-calibration; set_key "$d/session.ini" columns "ax ay az gy gx gz"
fixed 2 "did not converge|gyro columns, unit or sample rate" S diagnose --session session.ini --out out/diag --no-plot --pose-accel-only
meas handheld-xsens-no-gyro-offset xsens-mti-handheld; awk '!/^gyro_offset/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
fixed 2 "rate at rest|xsens_gyro.txt: pose 1" tf
meas handheld-xsens-no-accel-offset xsens-mti-handheld; awk '!/^accel_offset/' "$d/session.ini" > "$d/s" && mv "$d/s" "$d/session.ini"
fixed 2 "gravity magnitude|xsens_acc.txt" tf
meas handheld-xsens-files-swapped xsens-mti-handheld
set_key "$d/session.ini" accel_file "$data/xsens-mti-handheld/xsens_gyro.txt"; set_key "$d/session.ini" gyro_file "$data/xsens-mti-handheld/xsens_acc.txt"
fixed 2 "gravity magnitude|xsens_gyro.txt + |swapped: the gyros' mean turns" tf
meas handheld-mpu-columns-swapped mpu6050-calibration; set_key "$d/session.ini" columns "gx gy gz ax ay az"
fixed 2 "example_data_calibration.csv|swapped" tf --pose-accel-only
meas handheld-mpu-log-is-a-directory mpu6050-calibration; mkdir "$d/logdir"; set_key "$d/session.ini" file logdir
fixed 2 "logdir:0: is a directory" tf --pose-accel-only
meas allan-mpu-gyro-rad-per-s mpu6050-long-static; set_key "$d/session.ini" gyro_unit "rad/s"
fixed 2 "rate at rest|example_data_tinit_calc.csv: the stretch analysed|values in deg declared as rad" al
meas allan-rate-1000-hz-forced mpu6050-long-static; set_key "$d/session.ini" rate "1000 Hz"
POST='grep -q "^# plausibility gate failed (--force): noise" out/allan/profile-fragment.ini'
fixed 0 "" al --force
meas allan-xsens-files-swapped xsens-mti-handheld
set_key "$d/session.ini" accel_file "$data/xsens-mti-handheld/xsens_gyro.txt"; set_key "$d/session.ini" gyro_file "$data/xsens-mti-handheld/xsens_acc.txt"
fixed 2 "gravity magnitude|the stretch analysed" al --pose 1
new allan-three-samples; handheld; head -n 6 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv: the record is too short for an Allan deviation: 3 samples" al
new allan-twenty-samples; handheld; head -n 23 "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv: whether the record is static cannot be told|too short for the pose detector" al
# Six-face: the gate on the faces before the fit.
sfnew six-face-gyro-rad-per-s; set_key "$d/session.ini" gyro_unit "rad/s"
fixed 2 "plausibility gate|noise|annotated_session.csv|face 'z_p'|the gyros' outside it|values in deg declared as rad" sf
sfnew six-face-accel-mg-as-g; set_key "$d/session.ini" accel_unit "mg"
fixed 2 "gravity magnitude|face 'x_p'|declared as mm/s" sf
sfnew six-face-accel-scale-2g; set_key "$d/session.ini" accel_scale 0.00006103515625
fixed 2 "gravity magnitude|face" sf
sfnew six-face-columns-swapped; set_key "$d/session.ini" columns "label - gx gy gz ax ay az"
fixed 2 "annotated_session.csv|swapped" sf
sfnew six-face-gyro-columns-as-accel-too; set_key "$d/session.ini" columns "label - ax ay az - - -"
fixed 2 "session.ini:$(lno "$d/session.ini" '^columns'): 'log.columns': column 'gx' missing" sf
sfnew six-face-accel-mg-forced; set_key "$d/session.ini" accel_unit "mg"
POST='grep -A1 "\"check\": \"gravity magnitude\"" out/result.json | grep -q false'
fixed "0,2" "" sf --force
# simulate --out: a new or empty directory, or an earlier simulation replaced whole; anything
# else refused unless --force.
simcase() { new "$1"; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"; }
simcase simulate-into-foreign-directory; mkdir -p "$d/out/sim"; echo notes > "$d/out/sim/notes.txt"
POST='test -s out/sim/notes.txt && ! test -e out/sim/imu.csv'
fixed 1 "--out out/sim: not empty and not an earlier simulate output (it holds notes.txt)|--force" sim
simcase simulate-replaces-earlier-whole; (cd "$d" && sim > /dev/null) && cp "$d/out/sim/truth.json" "$d/out/old-truth.json"
POST='test -s out/sim/.sinscal-simulation && ! cmp -s out/sim/truth.json out/old-truth.json && test -z "$(ls -d out/sim.sinscal-* 2> /dev/null)"'
control 0 "" sim --seed 2
simcase simulate-earlier-with-a-result; (cd "$d" && sim > /dev/null) && echo '{}' > "$d/out/sim/result.json"
POST='test -s out/sim/result.json'
fixed 1 "not empty and not an earlier simulate output (it holds result.json)" sim --seed 2
simcase simulate-force-into-foreign-directory; mkdir -p "$d/out/sim"; echo notes > "$d/out/sim/notes.txt"
POST='test -s out/sim/notes.txt && test -s out/sim/imu.csv && test -s out/sim/truth.json'
fixed 0 "" sim --force
simcase simulate-out-is-a-file; echo x > "$d/out/f"
fixed 1 "--out out/f: not empty and not an earlier simulate output" S simulate --plan plan.ini --sensor sensor.ini --out out/f --rate 10
# Samples out of order: a time ahead whose next line goes back is not a gap.
new native-samples-out-of-order; mini
awk 'NR == 20 { held = $0; next } NR == 21 { print; print held; next } { print }' "$base/mini/imu.csv" > "$d/imu.csv"
fixed 2 "imu.csv:21: time goes backwards|samples out of order: line 20 jumps ahead" nav
new split-samples-out-of-order; split
for f in acc gyr; do awk 'NR == 30 { held = $0; next } NR == 31 { print; print held; next } { print }' "$base/$f.txt" > "$d/$f.txt"; done
fixed 2 "acc.txt:31: time goes backwards|samples out of order" nav
new native-log-is-a-directory; mini; rm "$d/imu.csv"; mkdir "$d/imu.csv"
fixed 2 "imu.csv:0: is a directory, not a log file" nav

# --- issue 19: thermal calibration (chamber files, chamber sessions, soaks, thermal profiles) ----
# The mini plan in three soaks (-20, 20, 60 C) of nav-fog-thermal, settled; and unsettled (the
# plan starts 60 s after the air got there, the sensor lagging by 600 s).
therm=$src/config/sensors/nav-fog-thermal.ini
printf '[chamber]\ntype = soaks\nstart = 20 C\nsoaks = -20 20 60 C\nsettle = 3600 s\n' > "$base/soaks3.ini"
printf '[chamber]\ntype = soaks\nstart = 20 C\nsoaks = -20 20 60 C\nsettle = 60 s\n' > "$base/soaks3-short.ini"
S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber "$base/soaks3.ini" --out "$base/soaks" --rate 10 > /dev/null ||
  die "simulate soaks"
S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber "$base/soaks3-short.ini" --out "$base/soaks-short" --rate 10 > /dev/null ||
  die "simulate soaks, short settling"
S thermal --chamber "$base/soaks/chamber.ini" --out "$base/thermal" > /dev/null || die "thermal soaks"
new export-thermal-result; cp "$base/thermal/result.json" "$d/r.json"
fixed 2 "r.json|thermal coefficients (gyro.bias_temp1|does not carry a temperature compensation yet" S export --result r.json --format c-header
new control-thermal-soaks; cp -r "$base/soaks" "$d/soaks"
POST='test -s out/t/result.json && test -s out/t/thermal_table.csv'
control 0 "" S thermal --chamber soaks/chamber.ini --out out/t
new control-simulate-chamber-again; cp -r "$base/soaks" "$d/soaks"
POST='test -s soaks/soak-3/imu.csv'
control 0 "" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber "$base/soaks3.ini" --out soaks --rate 10
new simulate-chamber-over-foreign; cp -r "$base/soaks" "$d/soaks"; mkdir "$d/soaks/mine"
fixed 1 "--out soaks|not empty and not an earlier simulate output|mine" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber "$base/soaks3.ini" --out soaks --rate 10
new kf-lever-arm-reference-attitude-none; mini
fixed 1 "zero velocity at rest only" kf --lever-arm-reference x --attitude none
new simulate-table-servo-damping; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
fixed 1 "servo_damping must be within 0 and 1" sim --table-servo 2,1.5
new simulate-table-servo-not-a-number; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
fixed 1 "--table-servo takes one or two comma-separated numbers|2,x" sim --table-servo 2,x
new simulate-table-settles-into-next-move; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
fixed 2 "still settle|after the next move begins" sim --table-servo 0.2,0.9
new table-file-smoothing-and-servo; cp "$base/mini.ini" "$d/plan.ini"; cp "$fog" "$d/sensor.ini"
printf '[table]\nname = t\nmax_rate = 20 deg/s\nmax_acceleration = 20 deg/s^2\nattitude_accuracy = 2.5 arcsec\nsmoothing = 0.3 s\nservo_frequency = 2 Hz\n' > "$d/t.ini"
fixed 1 "t.ini|a smoothing and a servo or structural mode exclude each other" sim --table t.ini
new thermal-soak-shorter-than-settling; cp -r "$base/soaks-short" "$d/soaks"
fixed 2 "soak-1/imu.csv:|the temperature moves by|the soak had not settled" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-one-soak; cp -r "$base/soaks" "$d/soaks"; set_key "$d/soaks/chamber.ini" soaks "soak-1/session.ini"
fixed 2 "chamber.ini:|a thermal fit needs at least 2 soaks, got 1" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-soak-missing; cp -r "$base/soaks" "$d/soaks"; rm -r "$d/soaks/soak-2"
fixed 2 "soak-2/session.ini" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-soak-no-temperature; cp -r "$base/soaks" "$d/soaks"; cp "$base/mini/imu.csv" "$d/soaks/soak-2/imu.csv"
fixed 2 "soak-2/imu.csv:|no temperature column" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-chamber-unknown-key; cp -r "$base/soaks" "$d/soaks"; add_line "$d/soaks/chamber.ini" "tolerance = 2 C"
fixed 2 "chamber.ini:$L: 'thermal.tolerance'" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-profile-log-without-temperature; mini; cp "$therm" "$d/sensor.ini"; set_key "$d/session.ini" sensor sensor.ini
fixed 2 "thermal coefficients are estimated|no temperature column" S calibrate --method kf --session session.ini --out out/r.json
new chamber-type-unknown; printf '[chamber]\ntype = soak\nsoaks = 0 C\n' > "$d/c.ini"
fixed 2 "c.ini:2: 'chamber.type'|expected 'soaks' or 'ramp'" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber c.ini --out out/s --rate 10
new chamber-soak-kelvin; printf '[chamber]\ntype = soaks\nsoaks = 253 293 C\n' > "$d/c.ini"
fixed 2 "c.ini:3: 'chamber.soaks'|expected -60 ... 130 C" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber c.ini --out out/s --rate 10
new chamber-ramp-without-rate; printf '[chamber]\ntype = ramp\nfrom = 0 C\nto = 40 C\n' > "$d/c.ini"
fixed 2 "c.ini|type = ramp needs 'rate'" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber c.ini --out out/s --rate 10
new chamber-ramp-rate-zero; printf '[chamber]\ntype = ramp\nfrom = 0 C\nto = 40 C\nrate = 0 C/min\n' > "$d/c.ini"
fixed 2 "c.ini:5: 'chamber.rate'|above 0" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber c.ini --out out/s --rate 10
new chamber-soaks-with-ramp-key; printf '[chamber]\ntype = soaks\nsoaks = 0 40 C\nrate = 1 C/min\n' > "$d/c.ini"
fixed 2 "c.ini:4: 'chamber.rate'|a key of type = ramp in type = soaks" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber c.ini --out out/s --rate 10
new diagnose-chamber-unsettled-soak; cp -r "$base/soaks-short" "$d/soaks"
fixed 2 "soak-1/imu.csv:|the soak had not settled" S diagnose --session soaks/chamber.ini --out out/d
new diagnose-sensor-on-a-table-session; mini
fixed 1 "--sensor acts on chamber sessions" S diagnose --session session.ini --out out/d --sensor "$therm"
new diagnose-chamber-sensor-missing; cp -r "$base/soaks" "$d/soaks"
fixed 2 "nope.ini" S diagnose --session soaks/chamber.ini --out out/d --sensor nope.ini
new diagnose-chamber-table-option; cp -r "$base/soaks" "$d/soaks"
fixed 1 "--no-kalman acts on table sessions|is a chamber" S diagnose --session soaks/chamber.ini --out out/d --no-kalman
new control-diagnose-chamber; cp -r "$base/soaks" "$d/soaks"
POST='test -s out/d/diagnosis.json'
control 0 "" S diagnose --session soaks/chamber.ini --out out/d
new profile-reference-temperature-kelvin; cp "$therm" "$d/p.ini"; set_key "$d/p.ini" reference_temperature "293 C"
fixed 2 "p.ini:$L: 'thermal.reference_temperature'|expected a temperature within -60 ... 130 C" S simulate --plan "$base/mini.ini" --sensor p.ini --out out/s --rate 10

# --- issue 35: outputs a lab can trust --------------------------------------------------------
# Duplicates: the same soak or session given twice (same path, a link to it, a copied folder) is
# refused before any fit, naming both (one data set fitted as two: sigmas sqrt(2) too small).
new thermal-soak-listed-twice; cp -r "$base/soaks" "$d/soaks"; set_key "$d/soaks/chamber.ini" soaks "soak-1/session.ini, soak-2/session.ini, soak-1/session.ini"
fixed 1 "chamber.ini|soak 3 (|and soak 1 (|are the same data|the same file" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-soak-through-a-link; cp -r "$base/soaks" "$d/soaks"; ln -s soak-2 "$d/soaks/again"; set_key "$d/soaks/chamber.ini" soaks "soak-1/session.ini, soak-2/session.ini, again/session.ini"
fixed 1 "again/session.ini|soak-2/session.ini|are the same data" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-soak-copied-folder; cp -r "$base/soaks" "$d/soaks"; cp -r "$d/soaks/soak-3" "$d/soaks/soak-4"; set_key "$d/soaks/chamber.ini" soaks "soak-1/session.ini, soak-2/session.ini, soak-3/session.ini, soak-4/session.ini"
fixed 1 "soak 4 (|and soak 3 (|the same bytes (SHA-256" S thermal --chamber soaks/chamber.ini --out out/t
new batch-session-copied; for s in a b; do mkdir -p "$d/runs/$s"; cp "$base"/mini/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/runs/$s/"; done
fixed 1 "batch: runs/b/session.ini and runs/a/session.ini are the same data|the same bytes (SHA-256" S calibrate --method closed-form --session runs/a --session runs/b --out out/batch
new batch-session-twice-through-a-link; mkdir -p "$d/runs/a"; cp "$base"/mini/{session.ini,plan.ini,sensor.ini,truth.json,imu.csv} "$d/runs/a/"; ln -s a "$d/runs/b"
fixed 1 "are the same data|the same file" S calibrate --method closed-form --session runs/a --session runs/b --out out/batch
# Bounded work: absurd options refused when parsed (--grid-step 1e-5 wrote 4.6 GB; 1e-9 converted
# 1e11 to int).
new thermal-grid-step-tiny; cp -r "$base/soaks" "$d/soaks"
fixed 1 "--grid-step must be from 0.01 to 100 C" S thermal --chamber soaks/chamber.ini --out out/t --grid-step 1e-5
new thermal-grid-step-1e-9; cp -r "$base/soaks" "$d/soaks"
fixed 1 "--grid-step must be from 0.01 to 100 C" S thermal --chamber soaks/chamber.ini --out out/t --grid-step 1e-9
new design-optimize-targets-empty; cp "$tab" "$d/table.ini"
fixed 1 "--targets is empty" dz --optimize --out out/o --targets ""
new design-optimize-targets-1e-9; cp "$tab" "$d/table.ini"
fixed 1 "target of gyro.scale|no plan can meet it" dz --optimize --out out/o --targets "gyro.scale = 1e-9 ppm"
new design-optimize-table-very-slow; cp "$tab" "$d/table.ini"; set_key "$d/table.ini" max_rate "0.01 deg/s"; set_key "$d/table.ini" max_acceleration "0.01 deg/s^2"
fixed 1 "table turns 90 deg in|longer than the search's longest plan" dz --optimize --out out/o --targets "gyro.scale = 3 ppm"
new design-structure-moves-negative; cp "$tab" "$d/table.ini"
fixed 1 "--structure-moves must be within 0 and 100000 passes" dz --optimize --out out/o --budget-s 300 --structure-moves -1
new design-structure-moves-without-optimize; cp "$tab" "$d/table.ini"
fixed 1 "belong to --optimize" dz --structure-moves 10
new design-anneal-negative; cp "$tab" "$d/table.ini"
fixed 1 "--anneal must be within 0 and 1000000 iterations" dz --optimize --out out/o --budget-s 300 --anneal -1
new design-anneal-without-optimize; cp "$tab" "$d/table.ini"
fixed 1 "belong to --optimize" dz --anneal 10
new design-targets-missing-file; cp "$tab" "$d/table.ini"
fixed 1 "--targets /nonexistent/targets.ini: no such file" dz --optimize --out out/o --targets /nonexistent/targets.ini
# No output overwrites an input, the calibration's own inputs included (resolved through links).
new report-out-is-the-session-log; mini; (cd "$d" && S calibrate --method kf --session session.ini --out r.json > /dev/null 2>&1)
fixed 1 "--out imu.csv is the log|an output never replaces an input" S report --result r.json --out imu.csv --force
new report-pdf-is-session-ini; mini; (cd "$d" && S calibrate --method kf --session session.ini --out r.json > /dev/null 2>&1)
fixed 1 "--pdf session.ini is the session|an output never replaces an input" S report --result r.json --out out/r.html --pdf session.ini --force
new report-out-is-the-log-through-a-link; mini; (cd "$d" && S calibrate --method kf --session session.ini --out r.json > /dev/null 2>&1); ln -s ../imu.csv "$d/out/page.html"
fixed 1 "is the log|an output never replaces an input" S report --result r.json --out out/page.html --force
new report-pdf-directory-missing; cp "$base/s8/cf.json" "$d/r.json"
fixed 1 "--pdf nodir/r.pdf: cannot create: its directory nodir does not exist" S report --result r.json --out out/r.html --pdf nodir/r.pdf
new control-thermal-into-its-earlier-output; cp -r "$base/soaks" "$d/soaks"; cp -r "$base/thermal" "$d/out/t"
POST='test -s out/t/result.json && grep -qx result.json out/t/.sinscal-thermal'
control 0 "" S thermal --chamber soaks/chamber.ini --out out/t
new thermal-out-is-the-chamber; cp -r "$base/soaks" "$d/soaks"
fixed 1 "--out soaks holds the|an output never replaces an input" S thermal --chamber soaks/chamber.ini --out soaks
new thermal-out-holds-an-earlier-result; cp -r "$base/soaks" "$d/soaks"; mkdir -p "$d/res"; cp "$base/s8/cf.json" "$d/res/result.json"
fixed 1 "--out res: not empty and not an earlier thermal output (it holds result.json)" S thermal --chamber soaks/chamber.ini --out res
new simulate-chamber-over-a-file-it-did-not-write; cp -r "$base/soaks" "$d/soaks"; echo "my notes" > "$d/soaks/soak-1/notes.txt"
fixed 1 "--out soaks|not an earlier simulate output|soak-1/notes.txt" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber "$base/soaks3.ini" --out soaks --rate 10
new simulate-chamber-over-an-empty-folder-it-did-not-make; cp -r "$base/soaks" "$d/soaks"; mkdir "$d/soaks/soak-1/mine"
fixed 1 "--out soaks|not an earlier simulate output|soak-1/mine/" S simulate --plan "$base/mini.ini" --sensor "$therm" --chamber "$base/soaks3.ini" --out soaks --rate 10
# Smaller ones: a complete last line without a line end is a line; a '%' in a real file name;
# the real cause of a file that cannot be written; six-face errors name the log.
new control-log-last-line-without-line-end; mini; truncate -s -1 "$d/imu.csv"
control 0 "" nav
new control-log-last-line-without-line-end-stream; mini; truncate -s -1 "$d/imu.csv"
control 0 "" sh -c "'$bin' calibrate --method kf --session session.ini --stream --out out/r.json < imu.csv"
new log-last-number-cut-without-line-end; mini; truncate -s -10 "$d/imu.csv"
fixed 2 "imu.csv:$(wc -l < "$base/mini/imu.csv"): truncated line|fewer digits" nav
new control-percent-in-a-file-name; mini; mv "$d/session.ini" "$d/50%.ini"
control 0 "" S navigate --session "50%.ini" --out out/nav.csv
new argument-with-a-placeholder; mini
fixed 1 "contains a '%name%' placeholder" S navigate --session "%value%.ini" --out out/nav.csv
new calibrate-out-directory-missing; mini
fixed 2 "out/no/r.json: cannot create: its directory out/no does not exist" S calibrate --method closed-form --session session.ini --out out/no/r.json
if [ "$(id -u)" != 0 ]; then  # root writes into a read-only folder: these run as a user only
  new calibrate-out-permission-denied; mini; mkdir -p "$d/out/ro"; chmod a-w "$d/out/ro"
  fixed 2 "out/ro/r.json: cannot create: its directory out/ro is not writable (Permission denied)" S calibrate --method closed-form --session session.ini --out out/ro/r.json
  new report-pdf-read-only-folder; cp "$base/s8/cf.json" "$d/r.json"; mkdir -p "$d/out/ro"; chmod a-w "$d/out/ro"
  fixed 1 "--pdf out/ro/r.pdf: cannot create: its directory out/ro is not writable" S report --result r.json --out out/r.html --pdf out/ro/r.pdf
  chmod u+w "$work"/c/*/out/ro
fi
sfnew six-face-error-names-the-log; set_key "$d/session.ini" faces "x_p x_a y_p y_a z_p z_down"
fixed 2 "annotated_session.csv (session session.ini): six-face: no part labelled 'z_down'" sf

# =============================================================================================
# KNOWN: bad input still accepted or mishandled; the fix belongs to apps/, filter/ or the result
# and compare code. Each line says the behaviour it needs.
echo "--- KNOWN (fixes outside the input readers; they do not fail the run until they pass) ---"
echo
echo "bad-input corpus: $fixed_ok of $((fixed_ok + fixed_failed)) cases pass, $controls_ok of" \
  "$((controls_ok + controls_failed)) controls pass; KNOWN: $known_open not fixed yet," \
  "$known_passing now pass (move them)"
if [ ${#failures[@]} -gt 0 ]; then
  echo "FAILED: ${failures[*]}"
  exit 1
fi
exit 0
