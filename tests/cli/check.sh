# The checks the end-to-end scripts share (tests/*_test.sh source it after setting bin, src and
# work). Each check counts as passed, failed or skipped; `finish LABEL` prints the counts and
# exits 1 on a failure, 77 (ctest: skipped) when a check needed an optional program that is not
# installed (tests/optional-packages), else 0.
pass=0; fail=0; skipped=0
# skip NAME WHY: a check that needs an optional program which is not installed.
skip() { skipped=$((skipped + 1)); echo "SKIPPED: $1${2:+ ($2)}"; }
check() {  # check NAME CONDITION...
  local name=$1; shift
  if { [ "$1" = python3 ] || [ "$1" = json ]; } && ! command -v python3 > /dev/null; then
    skip "$name" "python3 is not installed"; return
  fi
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAILED: $name"; fi
}
contains() { grep -q -- "$2" "$1"; }
lacks() { ! grep -q -- "$2" "$1"; }
# json FILE EXPR: the Python expression on the document `r` is true.
json() { python3 -c "import json,sys; r=json.load(open('$1')); sys.exit(not ($2))"; }
# The number after "key": in a JSON file (the first occurrence).
json_number() { grep -o "\"$2\": [-0-9.e+]*" "$1" | head -n 1 | sed 's/.*: //'; }
within() { awk -v x="$1" -v lo="$2" -v hi="$3" 'BEGIN { exit !(x >= lo && x <= hi) }'; }
finish() {  # finish [LABEL]
  echo "${1:+$1: }$pass passed, $fail failed, $skipped skipped"
  [ "$fail" -eq 0 ] || exit 1
  [ "$skipped" -eq 0 ] || exit 77
  exit 0
}
