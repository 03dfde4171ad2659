#!/usr/bin/env bash
# End-to-end checks of the hand-held commands: `calibrate --method table-free` and `allan` on the
# real recordings of data/ (read in place by the sessions of config/measured), exit codes, result
# fields and the messages of bad input. The recordings are part of the repository: never skipped.
# Usage: handheld_cli_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR
set -u
bin=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
. "$src/tests/cli/check.sh"

measured=$src/config/measured
data=$src/data
xsens=$measured/xsens-mti-handheld/session.ini

# The Xsens MTi session: 38 poses, both triads, the raw-count view near imu_tk's figures
# (accelerometers 414.5, 412.0, 414.7 counts/(m/s^2); gyros 4778, 4764, 4774 counts/(rad/s)).
"$bin" calibrate --method table-free --session "$xsens" --out "$work/xsens.json" > "$work/xsens.txt" 2> "$work/xsens.err"
check "table-free on the Xsens session exits 0" test $? -eq 0
check "table-free prints the poses found" contains "$work/xsens.txt" "Poses found: 38"
check "table-free prints chi2/dof" contains "$work/xsens.txt" "chi2/dof"
check "table-free prints the raw view" contains "$work/xsens.txt" "Raw-count view"
check "result names the method" contains "$work/xsens.json" '"name": "table-free"'
check "result has chi2_per_dof" contains "$work/xsens.json" '"chi2_per_dof"'
check "result has the gravity used" contains "$work/xsens.json" '"value": 9.81744'
check "result has 38 poses" test "$(json_number "$work/xsens.json" poses_found)" = 38
check "result has a pose's mean specific force" contains "$work/xsens.json" '"specific_force_m_per_s2"'
check "result has a pose's mean rate" contains "$work/xsens.json" '"rate_deg_per_s"'
check "result has the noise" contains "$work/xsens.json" '"noise"'
check "result fixes the accelerometer-triad convention" contains "$work/xsens.json" '"fixed_by_convention": true'
check "result has sigmas" contains "$work/xsens.json" '"sigma"'
check "raw view: accelerometer sensitivity unit" contains "$work/xsens.json" '"unit": "counts/(m/s^2)"'
check "raw view: gyro sensitivity unit" contains "$work/xsens.json" '"unit": "counts/(rad/s)"'
ax=$(grep -A1 '"accel.sensitivity.x"' "$work/xsens.json" | json_number /dev/stdin value)
gz=$(grep -A1 '"gyro.sensitivity.z"' "$work/xsens.json" | json_number /dev/stdin value)
check "accel.sensitivity.x near imu_tk's 414.5 ($ax)" within "$ax" 413.5 415.5
check "gyro.sensitivity.z near imu_tk's 4774 ($gz)" within "$gz" 4750 4800
check "raw view: offsets in counts" contains "$work/xsens.json" '"gyro.offset.z"'

# Allan deviation: the Xsens record is not static (refused by default), its longest pose is; the
# MPU-6050 static record whole.
"$bin" allan --session "$xsens" --out "$work/allan_x" > /dev/null 2> "$work/allan_all.err"
check "allan on a moving record exits 2" test $? -eq 2
check "allan on a moving record says so" contains "$work/allan_all.err" "the record is not static"
"$bin" allan --session "$xsens" --longest-pose --out "$work/allan_x" > "$work/allan_x.txt"
check "allan --longest-pose exits 0" test $? -eq 0
check "allan --longest-pose takes pose 1" contains "$work/allan_x.txt" "pose 1 of 38"
check "allan.csv has the columns" contains "$work/allan_x/allan.csv" "^tau \[s\],gyro.x adev \[deg/h\],gyro.x lower \[deg/h\],gyro.x upper \[deg/h\],gyro.x fit \[deg/h\]"
check "allan.csv has rows" test "$(wc -l < "$work/allan_x/allan.csv")" -ge 8
check "profile fragment has the gyro ARW" contains "$work/allan_x/profile-fragment.ini" "^arw = "
check "profile fragment has the accelerometer VRW" contains "$work/allan_x/profile-fragment.ini" "^vrw = "
check "allan draws a PNG" cmp -s -n 4 "$work/allan_x/allan.png" <(printf '\x89PNG')
check "allan keeps its gnuplot script" contains "$work/allan_x/allan.gp" "set multiplot"
"$bin" allan --session "$xsens" --pose 39 --out "$work/x" > /dev/null 2> "$work/allan_pose.err"
check "allan --pose beyond the poses exits 2" test $? -eq 2
check "allan --pose beyond the poses says how many" contains "$work/allan_pose.err" "found 38 poses"
"$bin" allan --session "$measured/mpu6050-static/session.ini" --out "$work/allan_m" > /dev/null
check "allan on the MPU-6050 static record exits 0" test $? -eq 0
"$bin" allan --session "$xsens" --all --longest-pose --out "$work/x" 2> /dev/null
check "allan with two selections is a usage error" test $? -eq 1
# An output that is an input is refused.
mkdir -p "$work/ow"
cp "$data/mpu6050-handheld/imu_static_test.csv" "$work/ow/allan.csv"
sed -e "s#^file = .*#file = allan.csv#" -e "s#^sensor = .*#sensor = $src/config/sensors/mpu6050.ini#" \
  "$measured/mpu6050-static/session.ini" > "$work/ow/session.ini"
"$bin" allan --session "$work/ow/session.ini" --out "$work/ow" 2> "$work/ow.err"
check "allan refuses to overwrite its input" test $? -eq 1
check "allan names the input it will not overwrite" contains "$work/ow.err" "an output never replaces an input"
check "the input is unchanged" cmp -s "$work/ow/allan.csv" "$data/mpu6050-handheld/imu_static_test.csv"

# MPU-6050: held in the hand, so the accelerometers find the poses; validation records corrected
# with the calibration.
"$bin" calibrate --method table-free --pose-accel-only --session "$measured/mpu6050-calibration/session.ini" \
  --validate "$measured/mpu6050-static/session.ini" --out "$work/mpu.json" > "$work/mpu.txt"
check "table-free on the MPU-6050 session exits 0" test $? -eq 0
check "validation section written" contains "$work/mpu.json" '"gravity_error_rms_m_per_s2"'
check "validation printed" contains "$work/mpu.txt" "Validation 'mpu6050-static'"
# The session's [table_free] carries pose_accel_only: the session file alone gives the same.
"$bin" calibrate --method table-free --session "$measured/mpu6050-calibration/session.ini" \
  --out "$work/mpu-session.json" > /dev/null
check "the MPU-6050 session calibrates with its session file alone" test $? -eq 0
"$bin" compare "$work/mpu.json" "$work/mpu-session.json" --max-relative 1e-12 > /dev/null
check "and gives the same coefficients as --pose-accel-only" test $? -eq 0
# Without it, the error suggests the option: the accelerometers alone find the poses.
sed -e '/^\[table_free\]/,$d' -e "s#^file = \.\./#file = $measured/mpu6050-calibration/../#" \
  -e "s#^sensor = \.\./#sensor = $measured/mpu6050-calibration/../#" \
  "$measured/mpu6050-calibration/session.ini" > "$work/mpu-nogyro.ini"
"$bin" calibrate --method table-free --session "$work/mpu-nogyro.ini" --out "$work/mpu-ng.json" \
  2> "$work/mpu-ng.err"
check "without pose_accel_only the MPU-6050 session exits 2" test $? -eq 2
check "the error suggests the accelerometers alone" contains "$work/mpu-ng.err" "pose_accel_only = true"

# Bad input. Too few poses: the first 90 s of the Xsens files (the initial rest and 3 poses).
mkdir -p "$work/few"
head -n 9000 "$data/xsens-mti-handheld/xsens_acc.txt" > "$work/few/acc.txt"
head -n 9000 "$data/xsens-mti-handheld/xsens_gyro.txt" > "$work/few/gyro.txt"
sed -e "s#^accel_file = .*#accel_file = acc.txt#" -e "s#^gyro_file = .*#gyro_file = gyro.txt#" "$xsens" > "$work/few/session.ini"
"$bin" calibrate --method table-free --session "$work/few/session.ini" --out "$work/few/r.json" 2> "$work/few.err"
check "too few poses exits 2" test $? -eq 2
check "too few poses says how many are needed" contains "$work/few.err" "needs at least 10 static poses"
check "too few poses says how many were found" contains "$work/few.err" "found 4"
# Poses too short for their means once 1.9 s are cut at each end (the shortest lasts 4.3 s).
"$bin" calibrate --method table-free --edge-trim 1.9 --session "$xsens" --out "$work/x.json" 2> "$work/short.err"
check "poses too short exits 2" test $? -eq 2
check "poses too short names them" contains "$work/short.err" "poses too short for their means"
# A two-file log whose time columns disagree on one row.
mkdir -p "$work/tdis"
head -n 3000 "$data/xsens-mti-handheld/xsens_acc.txt" > "$work/tdis/acc.txt"
head -n 3000 "$data/xsens-mti-handheld/xsens_gyro.txt" | awk 'NR == 1500 { $1 = $1 + 0.5 } { print }' > "$work/tdis/gyro.txt"
cp "$work/few/session.ini" "$work/tdis/session.ini"
"$bin" calibrate --method table-free --session "$work/tdis/session.ini" --out "$work/tdis/r.json" 2> "$work/tdis.err"
check "disagreeing time columns exit 2" test $? -eq 2
check "disagreeing time columns name both files and the line" contains "$work/tdis.err" "acc.txt:1500: t = 15.0181 s here but 15.5181 s in .*gyro.txt:1500"
# A session without a plan for the table methods; the table methods' options for table-free and
# the other way round.
"$bin" calibrate --method kf --session "$xsens" --out "$work/x.json" 2> "$work/noplan.err"
check "kf on a session without a plan exits 2" test $? -eq 2
check "kf on a session without a plan says which methods take one" contains "$work/noplan.err" "has no 'plan'.*table-free"
"$bin" calibrate --method table-free --passes 2 --session "$xsens" --out "$work/x.json" 2> "$work/opt.err"
check "a kf option in table-free is a usage error" test $? -eq 1
check "a kf option in table-free is named" contains "$work/opt.err" "\-\-passes is an option of the table methods"
"$bin" calibrate --method closed-form --gravity 9.8 --session "$xsens" --out "$work/x.json" 2> "$work/opt2.err"
check "a table-free option in closed-form is a usage error" test $? -eq 1
check "a table-free option in closed-form is named" contains "$work/opt2.err" "\-\-gravity acts in --method table-free only"
"$bin" calibrate --method table-free --gravity 98.1 --session "$xsens" --out "$work/x.json" 2> /dev/null
check "a gravity off the Earth is a usage error" test $? -eq 1
# Without gravity and site.
sed "/^gravity = /d" "$work/few/session.ini" > "$work/few/nograv.ini"
"$bin" calibrate --method table-free --session "$work/few/nograv.ini" --out "$work/x.json" 2> "$work/nograv.err"
check "no gravity and no site exits 2" test $? -eq 2
check "no gravity and no site says so" contains "$work/nograv.err" "no local gravity"

# diagnose on hand-held sessions (no plan): the table-free calibration, then model discovery on the
# poses and turns, with the files of the table diagnosis's schema.
"$bin" diagnose --session "$xsens" --out "$work/dx" > "$work/dx.txt" 2> "$work/dx.err"
check "diagnose on the Xsens session exits 0" test $? -eq 0
check "diagnose prints the calibration's residuals" contains "$work/dx.txt" "Table-free calibration: 38 poses, 37 turns"
check "diagnose names the method" contains "$work/dx/diagnosis.json" '"name": "hand-held poses (table-free, linearized refit)"'
check "diagnosis has findings" contains "$work/dx/diagnosis.json" '"findings"'
check "diagnosis has the residual unit" contains "$work/dx/diagnosis.json" '"residual_unit"'
check "diagnosis has not_separable with the lever arms" contains "$work/dx/diagnosis.json" '"effect": "accel.lever_arm"'
check "diagnosis has the per-pose residuals" contains "$work/dx/diagnosis.json" '"gravity_before"'
check "diagnosis has the noise candidates" contains "$work/dx/diagnosis.json" '"noise.bias_instability"'
check "diagnosis has the calibration" contains "$work/dx/diagnosis.json" '"calibration"'
check "diagnosis draws the residuals" cmp -s -n 4 "$work/dx/residuals.png" <(printf '\x89PNG')
check "diagnosis draws the Allan deviation" cmp -s -n 4 "$work/dx/allan.png" <(printf '\x89PNG')
check "diagnosis writes the report" contains "$work/dx/report.md" "## Not separable on this session"
# MPU-6050 with the validation records: before and after the findings.
"$bin" diagnose --pose-accel-only --session "$measured/mpu6050-calibration/session.ini" \
  --validate "$measured/mpu6050-x-turns/session.ini" --out "$work/dm" > "$work/dm.txt"
check "diagnose on the MPU-6050 session exits 0" test $? -eq 0
check "diagnosis has the validation" contains "$work/dm/diagnosis.json" '"turn_rms_after_deg"'
check "10 poses are too few for the accelerometer terms" contains "$work/dm/diagnosis.json" "needs at least 11 poses"
# calibrate and diagnose gate a session alike (one gate function): accelerometers scaled 40 % off
# are refused by both with the same cause, and both run with --force.
mkdir -p "$work/gate"
sed -e "s#^accel_scale = .*#accel_scale = 0.0035#" -e "s#\.\./\.\./\.\./data#$data#" "$xsens" > "$work/gate/session.ini"
"$bin" calibrate --method table-free --session "$work/gate/session.ini" --out "$work/gate/r.json" > /dev/null 2> "$work/gate/cal.err"
check "calibrate refuses a mis-scaled hand-held session" test $? -eq 2
"$bin" diagnose --session "$work/gate/session.ini" --out "$work/gate/d" --no-plot > /dev/null 2> "$work/gate/diag.err"
check "diagnose refuses it too" test $? -eq 2
check "calibrate names the gravity magnitude" contains "$work/gate/cal.err" "gravity magnitude: .*|f| = 13.03 m/s^2 at rest"
check "diagnose gives the same cause" test "$(sed 's/^sinscal [a-z]*: //' "$work/gate/cal.err")" = "$(sed 's/^sinscal [a-z]*: //' "$work/gate/diag.err")"
"$bin" diagnose --force --session "$work/gate/session.ini" --out "$work/gate/df" --no-plot > /dev/null 2>&1
check "diagnose --force runs it" test $? -eq 0
check "the Xsens fit gate prints its bounds" contains "$work/xsens.txt" "Fit gate (bias wander from the"
check "converged says what it means" contains "$work/xsens.txt" "converged (the last step"

# Bad requests: reported after the other findings are written, exit 2.
"$bin" diagnose --pose-accel-only --session "$measured/mpu6050-calibration/session.ini" \
  --candidates accel.k2 --out "$work/dk" > /dev/null 2> "$work/dk.err"
check "a candidate the poses are too few for exits 2" test $? -eq 2
check "... saying how many poses are needed and found" contains "$work/dk.err" "needs at least 11 poses.*found 10"
check "... with the findings so far written" test -s "$work/dk/diagnosis.json"
"$bin" diagnose --session "$xsens" --candidates gyro.g_sensitivity,temperature --no-plot --out "$work/dt" > /dev/null 2> "$work/dt.err"
check "temperature without a temperature column exits 2" test $? -eq 2
check "... saying the log has none" contains "$work/dt.err" "needs a temperature column in the log, which has none"
check "... with the other candidates' findings written" contains "$work/dt/diagnosis.json" '"effect": "gyro.g_sensitivity"'
# The same recording with a temperature column in the accelerometer file (25 C, drifting): read,
# and the candidate refused as not tested yet (issue 19's thermal families are to come).
awk '{ printf "%s %.5f\n", $0, 25 + NR * 1e-5 }' "$data/xsens-mti-handheld/xsens_acc.txt" > "$work/xsens_acc_temp.txt"
sed -e "s|^accel_file = .*|accel_file = $work/xsens_acc_temp.txt\naccel_columns = t x y z temp|" \
  -e "s|^gyro_file = .*|gyro_file = $data/xsens-mti-handheld/xsens_gyro.txt|" "$xsens" > "$work/xsens_temp.ini"
"$bin" diagnose --session "$work/xsens_temp.ini" --candidates temperature --no-plot --out "$work/dtt" > /dev/null 2> "$work/dtt.err"
check "temperature with a temperature column exits 2" test $? -eq 2
check "... saying it is not tested yet" contains "$work/dtt.err" "the candidate 'temperature' is not tested yet"
"$bin" diagnose --session "$xsens" --candidates accel.nonsense --out "$work/dn" 2> "$work/dn.err"
check "an unknown candidate is a usage error" test $? -eq 1
"$bin" diagnose --session "$work/few/session.ini" --out "$work/df" 2> "$work/df.err"
check "diagnose with a calibration that fails exits 2" test $? -eq 2
check "... saying why" contains "$work/df.err" "needs at least 10 static poses"

# calibrate --method six-face on imucal's labelled session: the table as a person reads it, and
# the sensitivities against imucal's stored calibration.
"$bin" calibrate --method six-face --session "$src/config/measured/imucal-ferraris/session.ini" \
  --out "$work/six-face.json" > "$work/six-face.txt"
check "six-face calibration exits 0" test $? -eq 0
check "... prints each turn's calibrated angle" grep -qE '^  x_rot +[0-9.]+ s +(359\.9|360\.0)[0-9]* deg$' "$work/six-face.txt"
check "... names what it cannot determine" grep -q "accel.misalignment: relative to the box's faces only to the placement accuracy" "$work/six-face.txt"
check "... sensitivities within 0.1 % (accel) and 0.5 % (gyro) of imucal's" python3 -c "
import json, math, sys
r = json.load(open('$work/six-face.json'))['raw_counts']
ref = json.load(open('$src/data/imucal/example_cal.json'))
ok = all(abs(r['accel']['sensitivity.' + a] / ref['K_a'][i][i] - 1) < 1e-3 and
         abs(r['gyro']['sensitivity.' + a] * math.pi / 180 / ref['K_g'][i][i] - 1) < 5e-3
         for i, a in enumerate('xyz'))
sys.exit(not ok)"

# diagnose on the six-face session: the g-sensitivity test on the rests, its verdict as a person
# reads it, and the file.
"$bin" diagnose --session "$src/config/measured/imucal-ferraris/session.ini" --out "$work/sf-diag" > "$work/sf-diag.txt"
check "six-face diagnose exits 0" test $? -eq 0
check "... states the g-sensitivity verdict with its detection limit" grep -qE '^Wald statistic [0-9.]+ on 9 dof, p = [0-9.e-]+: not detected at alpha 0.01: below the detection limit of [0-9.]+ deg/h/g per term' "$work/sf-diag.txt"
check "... writes K with sigmas" python3 -c "import json,sys; g=json.load(open('$work/sf-diag/diagnosis.json'))['g_sensitivity']; sys.exit(not (len(g['K']) == 3 and all(s > 0 for row in g['K_sigma'] for s in row) and g['detected'] is False))"

finish
