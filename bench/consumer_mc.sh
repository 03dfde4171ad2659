#!/bin/bash
# Consumer MEMS on a table (issue 34, docs/accuracy.md "Consumer MEMS on a table"): rot19 and seed8
# simulated with N seeds of a consumer unit (bench/consumer.ini: gyro biases 0.5-1 deg/s, scale
# factors 1-5 %, misalignments 1000-3600 arcsec, white noise; and bench/consumer-mems.ini, the
# same with the MEMS profile's K2, g-sensitivity and bias instability), calibrated with
# --method closed-form and --method kf --passes 0 (automatic passes). Per cell: the runs right
# (exit 0, every estimate within 4 sigma of the truth), refused (exit 2, by the gate check
# named), exit-0-wrong, other exits.
# Usage: bench/consumer_mc.sh BUILD/apps/sinscal SOURCE_DIR OUT_DIR [SEEDS (30)] [PROFILES]
set -uo pipefail
sinscal=$1 src=$2 out=$3 seeds=${4:-30} profiles=${5:-"consumer consumer-mems"}
mkdir -p "$out"
for profile in $profiles; do
  for plan in rot19 seed8; do
    for seed in $(seq 1 "$seeds"); do
      d="$out/$profile-$plan-$seed"
      [ -f "$d/session.ini" ] || "$sinscal" simulate --plan "$src/config/plans/$plan.ini" \
        --sensor "$src/bench/$profile.ini" --seed "$seed" --out "$d" > /dev/null
      for method in closed-form kf; do
        passes=()
        [ "$method" = kf ] && passes=(--passes 0)  # the filter's automatic passes
        "$sinscal" calibrate --method "$method" "${passes[@]}" --session "$d/session.ini" \
          --out "$d.$method.json" > /dev/null 2> "$d.$method.err"
        echo $? > "$d.$method.rc"
      done
    done
  done
done
python3 - "$out" "$seeds" "$profiles" <<'PY'
import json, re, sys
out, seeds, profiles = sys.argv[1], int(sys.argv[2]), sys.argv[3].split()
print("| profile | plan | method | runs | right (worst err/sigma) | refused (cause) | exit-0-wrong | other |")
print("|---|---|---|---|---|---|---|---|")
for profile in profiles:
  for plan in ["rot19", "seed8"]:
    for method in ["closed-form", "kf"]:
      right, wrong, other, worst, causes = 0, [], 0, 0.0, {}
      for s in range(1, seeds + 1):
        d = f"{out}/{profile}-{plan}-{s}"
        rc = int(open(f"{d}.{method}.rc").read())
        if rc == 2:
          err = open(f"{d}.{method}.err").read()
          gate = err.split("plausibility gate", 1)[-1]
          key = ", ".join(sorted(set(re.findall(r"^([a-z0-9 -]+): ", gate, re.M)))) \
              or err.strip().splitlines()[-1][:80]
          causes[key] = causes.get(key, 0) + 1
          continue
        if rc != 0:
          other += 1
          continue
        r = json.load(open(f"{d}.{method}.json"))["coefficients"]
        t = json.load(open(f"{d}/truth.json"))["coefficients"]
        z = max(abs(c["value"] - t[n]["value"]) / c["sigma"] for n, c in r.items()
                if n in t and c.get("sigma"))
        if z <= 4.0:
          right += 1
          worst = max(worst, z)
        else:
          wrong.append(f"{s}: {z:.2f}")
      cause = "; ".join(f"{n}: {k}" for k, n in sorted(causes.items())) or "-"
      print(f"| {profile} | {plan} | {method} | {seeds} | {right} ({worst:.2f}) | "
            f"{sum(causes.values())} ({cause}) | {len(wrong)} {' '.join(wrong)} | {other} |")
PY
