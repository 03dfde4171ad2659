#!/usr/bin/env bash
# The calibration certificate end to end (sinscal report): a Kalman-filter run with its monitor,
# a closed-form run with its diagnosis, the Xsens table-free run (data/); the page loaded in
# headless Chromium (no console error, the coefficient table in the rendered DOM, a screenshot that
# is not blank), the PDF, the refusal to replace files, chromium missing.
# Without Debian's chromium (or python3, which decodes the screenshot) those checks are skipped
# with a message and the script exits with 77 after the others: ctest reports it as skipped.
# Usage: report_test.sh SINSCAL_BINARY SOURCE_DIR WORK_DIR
set -u
bin=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"; work=$(cd "$work" && pwd)
. "$src/tests/cli/check.sh"
chromium=$(command -v chromium || true)

# --- Kalman filter on rot19 with its monitor: the certificate, its PDF --------------------------
"$bin" simulate --plan "$src/config/plans/rot19.ini" --sensor "$src/config/sensors/nav-fog.ini" \
  --out "$work/r19" --seed 3 --rate 20 > /dev/null || { echo "setup: simulate failed"; exit 1; }
"$bin" calibrate --method kf --session "$work/r19/session.ini" --monitor "$work/r19/monitor.jsonl" \
  --out "$work/r19/kf.json" > "$work/kf.txt" || { echo "setup: calibrate failed"; exit 1; }
check "the result records its provenance" contains "$work/r19/kf.json" '"provenance"'
log_hash=$(sha256sum "$work/r19/imu.csv" | cut -d' ' -f1)
check "the result records the log's SHA-256" contains "$work/r19/kf.json" "\"sha256\": \"$log_hash\""
check "the result records the command line" contains "$work/r19/kf.json" '"command_line": ".*calibrate --method kf'
"$bin" report --result "$work/r19/kf.json" --out "$work/r19/report.html" > "$work/report.txt" 2> "$work/report.err"
check "report exits 0" test $? -eq 0
page=$work/r19/report.html
check "the page has the coefficient table" contains "$page" '<td>gyro.bias.x</td>'
check "the page shows units" contains "$page" '<td>deg/h</td>'
check "the page names the unit" contains "$page" 'Calibration certificate: '
check "the page has the log's SHA-256" contains "$page" "$log_hash"
check "the log is unchanged since the calibration" contains "$page" '>unchanged<'
check "the page has the convergence plot inline" contains "$page" 'src="data:image/png;base64,'
check "the page has the installation" contains "$page" 'Table base\|Base level North'
check "the page has the verdict" contains "$page" 'id="verdict"'
check "the page loads nothing" lacks "$page" 'src="http\|href="http\|<script\|<link'
check "the page has a print style for A4" contains "$page" 'size: A4'

# Existing files are not replaced without --force.
"$bin" report --result "$work/r19/kf.json" --out "$page" > /dev/null 2> "$work/exists.err"
check "an existing page is refused (exit 1)" test $? -eq 1
check "the refusal names the file and --force" contains "$work/exists.err" "report.html: exists.*--force"
"$bin" report --result "$work/r19/kf.json" --out "$work/r19/kf.json" --force > /dev/null 2> "$work/self.err"
check "the result is never the output (exit 1)" test $? -eq 1
check "the result file is intact" contains "$work/r19/kf.json" '"coefficients"'

# A changed log is flagged on the page.
cp "$work/r19/kf.json" "$work/r19/kf-copy.json"
echo "# appended" >> "$work/r19/imu.csv"
"$bin" report --result "$work/r19/kf-copy.json" --out "$work/r19/changed.html" > /dev/null 2>&1
check "a log changed since the calibration is flagged" contains "$work/r19/changed.html" 'CHANGED since the calibration'

# Without chromium: the page is written, the PDF is not, exit 4 with a clear message.
mkdir -p "$work/nochromium"; ln -sf "$(command -v gnuplot)" "$work/nochromium/gnuplot"
PATH=$work/nochromium "$bin" report --result "$work/r19/kf.json" --out "$work/r19/nc.html" \
  --pdf "$work/r19/nc.pdf" > /dev/null 2> "$work/nc.err"
check "without chromium the exit code is 4" test $? -eq 4
check "without chromium the message says it is not installed" contains "$work/nc.err" "chromium is not installed"
check "without chromium the message says the HTML was written" contains "$work/nc.err" "the HTML page was written to"
check "without chromium the HTML is written" test -s "$work/r19/nc.html"
check "without chromium no PDF" test ! -e "$work/r19/nc.pdf"

if [ -z "$chromium" ]; then
  skip "chromium is not installed (apt-get install chromium): no PDF, DOM or screenshot checks"
else
  "$bin" report --result "$work/r19/kf.json" --out "$page" --pdf "$work/r19/report.pdf" --force \
    > /dev/null 2> "$work/pdf.err"
  check "report --pdf exits 0" test $? -eq 0
  check "the PDF is a PDF" test "$(head -c 5 "$work/r19/report.pdf")" = "%PDF-"
  check "the PDF is not empty" test "$(stat -c %s "$work/r19/report.pdf")" -gt 20000
  pages=$(grep -aoE '/Count [0-9]+' "$work/r19/report.pdf" | head -n 1 | cut -d' ' -f2)
  check "the PDF has several A4 pages" test "${pages:-0}" -ge 2
  run_chromium() { timeout 120 "$chromium" --headless --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$work/chromium-profile" "$@"; }
  run_chromium --enable-logging=stderr --v=0 --dump-dom "file://$page" > "$work/dom.html" 2> "$work/console.txt"
  check "chromium renders the page" contains "$work/dom.html" '<table class="data coefficients">'
  check "the rendered DOM has every coefficient of the result" test \
    "$(grep -c '<tr><td>[a-z_]*\.[a-z_.]*</td><td class="num">' "$work/dom.html")" -ge \
    "$(grep -c '"unit":' "$work/r19/kf.json")"
  check "no console message from the page" lacks "$work/console.txt" 'CONSOLE\|Uncaught\|Failed to load'
  # ISO/IEC 17025: the expanded uncertainty U = k sigma with its coverage factor beside every
  # value, the conditions, readable method labels, the approval field, in the rendered page.
  check "the rendered page states the coverage factor" contains "$work/dom.html" '<th class="num">U (k = 2)</th>'
  check "the rendered page has the conditions" contains "$work/dom.html" 'Conditions of the calibration'
  check "the rendered page labels the method in words" contains "$work/dom.html" 'Attitude updates taken from'
  check "the rendered page has no raw method key" lacks "$work/dom.html" '<th>attitude_from</th>\|<th>prior_scale</th>'
  check "the rendered page has the approval field" contains "$work/dom.html" 'id="approver"'
  if command -v python3 > /dev/null; then
    # Every estimated coefficient of the result (a value and a sigma) has a row whose U is k
    # times its 1-sigma (each printed to 4 decimals), and no other row has a U.
    python3 - "$work/r19/kf.json" "$work/dom.html" > "$work/u.txt" 2>&1 <<'PY'
import json, re, sys
coefficients = json.load(open(sys.argv[1]))["coefficients"]
want = {n for n, c in coefficients.items() if "value" in c and "sigma" in c and not c.get("fixed_by_convention")}
dom = open(sys.argv[2]).read()
rows = re.findall(r'<tr><td>([a-z_0-9.]+)</td><td class="num">[^<]*</td><td class="num u">± ([^<]*)</td><td class="num sigma">([^<]*)</td>', dom)
bad = [n for n, u, s in rows if abs(float(u) - 2 * float(s)) > 1.5e-4]
print(len(want), len(rows), sorted(want ^ {n for n, _, _ in rows}), bad)
sys.exit(0 if want == {n for n, _, _ in rows} and len(rows) == len(want) and not bad and want else 1)
PY
    u_status=$?
    check "the rendered page shows U (k = 2) = 2 sigma for every coefficient ($(cat "$work/u.txt"))" test "$u_status" -eq 0
  fi
  run_chromium --hide-scrollbars --window-size=1100,1400 --screenshot="$work/r19/screenshot.png" \
    "file://$page" > /dev/null 2>&1
  check "the screenshot is taken" test -s "$work/r19/screenshot.png"
  if command -v python3 > /dev/null; then
    # Decodes the PNG (zlib, the filters undone) and measures how much of it is ink: a blank or
    # unstyled page fails, the certificate's header band and table rows pass.
    python3 - "$work/r19/screenshot.png" > "$work/ink.txt" <<'PY'
import struct, sys, zlib
data = open(sys.argv[1], 'rb').read()
assert data[:8] == b'\x89PNG\r\n\x1a\n'
pos, idat, w = 8, b'', 0
while pos < len(data):
    n, kind = struct.unpack('>I4s', data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    if kind == b'IHDR':
        w, h, depth, color = struct.unpack('>IIBB', body[:10])
        bpp = {2: 3, 6: 4}[color]
    elif kind == b'IDAT':
        idat += body
    pos += 12 + n
raw, stride, prev, rows = zlib.decompress(idat), w * bpp, bytearray(w * bpp), []
for y in range(h):
    f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a = line[i - bpp] if i >= bpp else 0
        b, c = prev[i], prev[i - bpp] if i >= bpp else 0
        p = a + b - c
        pr = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else (b if abs(p - b) <= abs(p - c) else c)
        line[i] = (line[i] + [0, a, b, (a + b) // 2, pr][f]) & 255
    rows.append(line); prev = line
dark = sum(1 for r in rows for x in range(0, stride, bpp) if r[x] + r[x + 1] + r[x + 2] < 300)
band = sum(1 for r in rows for x in range(0, stride, bpp) if r[x + 2] > r[x] + 40 and r[x] < 60)
print(w, h, dark / (w * h), band)
PY
    read -r sw sh ink band < "$work/ink.txt"
    check "the screenshot has the window's size" test "$sw $sh" = "1100 1400"
    check "the screenshot shows text (ink 1-40 %)" awk -v x="$ink" 'BEGIN { exit !(x > 0.01 && x < 0.4) }'
    check "the screenshot shows the dark-blue header band and table heads" test "$band" -gt 5000
  else
    skip "no python3 to decode the screenshot"
  fi
fi

# --- Closed form on seed8 with its diagnosis ------------------------------------------------------
"$bin" simulate --plan "$src/config/plans/seed8.ini" --sensor "$src/config/sensors/nav-fog.ini" \
  --out "$work/s8" --seed 3 --rate 10 > /dev/null || { echo "setup: simulate s8 failed"; exit 1; }
"$bin" calibrate --method closed-form --session "$work/s8/session.ini" --out "$work/s8/cf.json" > /dev/null
"$bin" diagnose --session "$work/s8/session.ini" --out "$work/s8/diag" --no-kalman > /dev/null 2>&1
check "diagnose exits 0" test $? -eq 0
"$bin" report "$work/s8/cf.json" --diagnosis "$work/s8/diag" --out "$work/s8/report.html" > /dev/null 2> "$work/cf.err"
check "report of a closed-form result with a diagnosis exits 0" test $? -eq 0
check "the closed form's per-dwell residuals" contains "$work/s8/report.html" 'Residuals per dwell'
check "the diagnosis summary" contains "$work/s8/report.html" 'Diagnosis: what the calibrated model misses'
check "no convergence section without a monitor (closed form)" lacks "$work/s8/report.html" '<h2>Convergence'
"$bin" report "$work/s8/cf.json" --diagnosis "$work/s8" --out "$work/s8/x.html" > /dev/null 2> "$work/nodiag.err"
check "a directory without diagnosis.json is refused (exit 2)" test $? -eq 2
check "the error names diagnosis.json" contains "$work/nodiag.err" "diagnosis.json: cannot open"

# --- The Xsens session, table-free (the recordings of data/) -------------------------------------
"$bin" calibrate --method table-free --session "$src/config/measured/xsens-mti-handheld/session.ini" \
  --out "$work/xsens.json" > /dev/null 2>&1
check "table-free on the Xsens session exits 0" test $? -eq 0
"$bin" report --result "$work/xsens.json" --out "$work/xsens.html" > /dev/null 2> "$work/xsens.err"
check "report of the Xsens table-free result exits 0" test $? -eq 0
check "the Xsens page has the poses' residuals" contains "$work/xsens.html" 'Residuals per pose'
check "the Xsens page has the noise" contains "$work/xsens.html" 'Noise at rest'
check "the Xsens page hashes both logs" test "$(grep -c '>unchanged<' "$work/xsens.html")" -ge 2
check "the Xsens page says the convergence plot is not for this method" lacks "$work/xsens.html" '<h2>Convergence'

finish "report tests"
