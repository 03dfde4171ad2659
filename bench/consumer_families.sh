#!/bin/bash
# Consumer MEMS on a table (issue 34, docs/measured/consumer-mems.md): bench/consumer_mc.sh's
# sessions (bench/consumer.ini and bench/consumer-mems.ini on rot19 and seed8, seeds 1..N) with
# four runs each: --method closed-form, --method kf (its default single pass), kf --passes 3 and
# kf --passes 0 (automatic). Per cell: right (exit 0, every estimate within 4 sigma of the truth),
# refused (exit 2, the gate checks named), exit-0-wrong, other exits; then, per coefficient family
# over the runs that exit 0, the RMS of (estimate - truth) / sigma and how many |z| exceed 3 and 4.
# The table's attitude error per dwell is simulated as the calibration assumes it (TABLE_SIGMA,
# arcsec, default 2.5: calibrate's default --table-sigma); with a perfect table (TABLE_SIGMA=0)
# the sigmas of the families it dominates (seed8's accelerometer misalignments) are conservative.
# Usage: [TABLE_SIGMA=2.5] bench/consumer_families.sh BUILD/apps/sinscal SOURCE_DIR OUT_DIR
#        [SEEDS (30)] [PROFILES] [METHODS ("closed-form kf kf3 kf0")]
# A run already done (its .rc file) is not run again: delete OUT_DIR to start afresh.
set -uo pipefail
sinscal=$1 src=$2 out=$3 seeds=${4:-30} profiles=${5:-"consumer consumer-mems"}
methods=${6:-"closed-form kf kf3 kf0"} table_sigma=${TABLE_SIGMA:-2.5}
mkdir -p "$out"
for profile in $profiles; do
  for plan in rot19 seed8; do
    for seed in $(seq 1 "$seeds"); do
      d="$out/$profile-$plan-$seed"
      [ -f "$d/session.ini" ] || "$sinscal" simulate --plan "$src/config/plans/$plan.ini" \
        --sensor "$src/bench/$profile.ini" --seed "$seed" \
        --table-attitude-sigma "$table_sigma" --out "$d" > /dev/null
      for method in $methods; do
        [ -f "$d.$method.rc" ] && continue
        case $method in
          closed-form) args=(--method closed-form) ;;
          kf) args=(--method kf) ;;
          kf3) args=(--method kf --passes 3) ;;
          kf0) args=(--method kf --passes 0) ;;
        esac
        "$sinscal" calibrate "${args[@]}" --session "$d/session.ini" --out "$d.$method.json" \
          > /dev/null 2> "$d.$method.err"
        echo $? > "$d.$method.rc"
      done
    done
  done
done
python3 - "$out" "$seeds" "$profiles" "$methods" <<'PY'
import json, math, os, re, sys
out, seeds, profiles, methods = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4].split()
plans = ["rot19", "seed8"]
print("| profile | plan | method | runs | right (worst err/sigma) | refused (cause) | exit-0-wrong | other |")
print("|---|---|---|---|---|---|---|---|")
families = {}
for profile in profiles:
  for plan in plans:
    for method in methods:
      right, wrong, other, worst, causes, runs = 0, [], 0, 0.0, {}, 0
      for s in range(1, seeds + 1):
        d = f"{out}/{profile}-{plan}-{s}"
        if not os.path.exists(f"{d}.{method}.rc"):
          continue  # not run (yet)
        runs += 1
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
        zs = {n: (c["value"] - t[n]["value"]) / c["sigma"] for n, c in r.items()
              if n in t and c.get("sigma")}
        z = max(abs(v) for v in zs.values())
        if z <= 4.0:
          right += 1
          worst = max(worst, z)
        else:
          n = max(zs, key=lambda k: abs(zs[k]))
          wrong.append(f"{s}: {n} {zs[n]:+.2f}")
        for n, v in zs.items():
          families.setdefault((profile, plan, method, n.rsplit(".", 1)[0]), []).append(v)
      cause = "; ".join(f"{n}: {k}" for k, n in sorted(causes.items())) or "-"
      if runs == 0:
        continue
      print(f"| {profile} | {plan} | {method} | {runs} | {right} ({worst:.2f}) | "
            f"{sum(causes.values())} ({cause}) | {len(wrong)} {'; '.join(wrong)} | {other} |")
print()
print("| profile | plan | method | family | estimates | RMS z | mean z | \\|z\\| > 3 | \\|z\\| > 4 |")
print("|---|---|---|---|---|---|---|---|---|")
for (profile, plan, method, family), zs in families.items():
  rms = math.sqrt(sum(v * v for v in zs) / len(zs))
  mean = sum(zs) / len(zs)
  flag = "" if 0.8 <= rms <= 1.25 else " **"
  print(f"| {profile} | {plan} | {method} | {family} | {len(zs)} | {rms:.2f}{flag} | {mean:+.2f} | "
        f"{sum(abs(v) > 3 for v in zs)} | {sum(abs(v) > 4 for v in zs)} |")
PY
