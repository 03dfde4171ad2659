#!/usr/bin/env python3
"""An independent recomputation (pure Python, written from the algorithm's description) of the
accelerometer stage of the OpenAXES authors' imu_tk run: imu_tk_matlab's calibrate.m as their
patch (calibration/matlab/patches/ of OpenAXES-IMU/OpenAXES) leaves it:
- the still-phase variance var_3D: samples 100..range of the log, range grown from 3000 in steps
  of 100 while the sum of the three axes' squared variances stays below 10 times its minimum;
- the static detector: the variance of each axis over a 101-sample window, their squares summed,
  below 4 k var_3D, k = 1..15 (one run per k);
- per k: intervals shorter than 100 samples dropped, an interval whose first reading points along
  the last selected one's (1 - cos < 0.01) dropped as a duplicate, 100 readings spread over each
  selected interval (99 at floor(n/100) steps from its start, plus its end);
- the fit: residual g^2 - |T K a - b|^2 per reading, unweighted, g = 9.81744 m/s^2, T = [1 -t1 t2;
  0 1 -t3; 0 0 1], K = diag(s), starting from T = K = I, b = 0 (a Levenberg-Marquardt here,
  lsqnonlin there: the same minimum);
- the choice of k: the most usable intervals; among ties the least mean squared residual, but
  calibrate.m then takes that position in the list of tied k as k itself (z = find(...) indexes
  the tied list), reproduced as is; --intended takes the tied k it meant.
Prints the table per k and the chosen coefficients as imu_tk's 12 accelerometer numbers
(column-major T K, then b), and the 36-number line with the authors' other 24 for
compare_imu_tk.py. usage: imu_tk_recompute.py log.csv adxl|bmi [--intended]"""
import math, sys

AUTHORS = ("0.96276 0 0 0.0015751 0.96732 0 -0.00018891 0.000859 0.97079 0.064447 0.011034 "
           "0.034253 0.95418 0 0 0.0031573 0.96061 0 0.009235 0.00049713 0.9501 -0.033224 "
           "0.080497 0.01579 0.97288 0.0076747 -0.0063582 -0.011829 1.0062 -0.00033403 0.010087 "
           "0.00029571 1.0068 -0.00020494 0.00063007 -0.00036962")

def read(path, which):
    cols = {"adxl": (8, 9, 10), "bmi": (11, 12, 13)}[which]
    acc = [[], [], []]
    with open(path) as f:
        next(f)
        for line in f:
            p = line.rstrip("\n").split(";")
            for k in range(3):
                acc[k].append(float(p[cols[k]]))
    return acc

def var(x, a, b):  # MATLAB var(x(a:b)), 1-based inclusive, N-1
    s = x[a - 1:b]; n = len(s); m = sum(s) / n
    return sum((v - m) ** 2 for v in s) / (n - 1)

def init_var3d(acc):
    begin, rng = 100, 3000
    f = lambda r: sum(var(acc[k], begin, r) ** 2 for k in range(3))
    new, v3, sel = f(rng), math.inf, None
    while new < 10 * v3:
        if new < v3: sel, v3 = rng, new
        rng += 100; new = f(rng)
    return v3, sel

def window_var(x, half):
    """normal(i) for 1-based i = half+1 .. N-(half+1) (MATLAB's loop), else 0; list index i-1."""
    n, w = len(x), 2 * half + 1
    out = [0.0] * n
    for i in range(half + 1, n - (half + 1) + 1):
        s = x[i - 1 - half:i + half]; m = sum(s) / w
        out[i - 1] = sum((v - m) ** 2 for v in s) / (w - 1)
    return out

def intervals(filt):
    res, flag, start, samples = [], filt[0], 1 if filt[0] else 0, 0
    for i1, v in enumerate(filt, 1):
        if flag == 1 and v == 1: samples += 1
        elif flag == 1 and v == 0: res.append((start, i1 - 1, samples)); flag = 0
        elif flag == 0 and v == 1: start, samples, flag = i1, 1, 1
    return res

def select(acc, ivs, num=100):
    prev, data, segs, short, dup = [0.0, 0.0, 0.0], [], [], 0, 0
    for (s, e, n) in ivs:
        cur = [acc[k][s - 1] for k in range(3)]
        dn = sum(p * c for p, c in zip(prev, cur)) / sum(c * c for c in cur)
        if 1 - dn < 0.01: dup += 1
        elif n < num: short += 1
        else:
            prev = cur; segs.append((s, e, n)); step = n // num
            for i in range(1, num):
                data.append([acc[k][s + (i - 1) * step - 1] for k in range(3)])
            data.append([acc[k][e - 1] for k in range(3)])
    return data, segs, len(ivs) - short - dup, short, dup

def solve(a, b):
    n = len(b); m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c])); m[c], m[p] = m[p], m[c]
        for r in range(n):
            if r != c:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[i][n] / m[i][i] for i in range(n)]

def model(t, a):
    t1, t2, t3, s1, s2, s3, b1, b2, b3 = t
    x = s1 * a[0] - t1 * s2 * a[1] + t2 * s3 * a[2] - b1
    y = s2 * a[1] - t3 * s3 * a[2] - b2
    z = s3 * a[2] - b3
    return x, y, z

def residual_jac(t, a, g):
    t1, t2, t3, s1, s2, s3 = t[:6]
    x, y, z = model(t, a)
    r = g * g - (x * x + y * y + z * z)
    d = [[-s2 * a[1], 0, 0], [s3 * a[2], 0, 0], [0, -s3 * a[2], 0], [a[0], 0, 0],
         [-t1 * a[1], a[1], 0], [t2 * a[2], -t3 * a[2], a[2]], [-1, 0, 0], [0, -1, 0], [0, 0, -1]]
    j = [-2 * (x * dv[0] + y * dv[1] + z * dv[2]) for dv in d]
    return r, j

def fit(data, g=9.81744, t=None):
    t = t or [0, 0, 0, 1, 1, 1, 0, 0, 0]
    lam = 1e-3
    def cost(t): return sum(residual_jac(t, a, g)[0] ** 2 for a in data)
    c = cost(t)
    for _ in range(200):
        H = [[0.0] * 9 for _ in range(9)]; gr = [0.0] * 9
        for a in data:
            r, j = residual_jac(t, a, g)
            for p in range(9):
                gr[p] += j[p] * r
                for q in range(9): H[p][q] += j[p] * j[q]
        while True:
            Hl = [[H[p][q] * (1 + lam if p == q else 1) for q in range(9)] for p in range(9)]
            step = solve(Hl, [-x for x in gr])
            tn = [x + s for x, s in zip(t, step)]; cn = cost(tn)
            if cn < c: t, lam = tn, lam / 10; break
            lam *= 10
            if lam > 1e12: return t, c
        if abs(c - cn) < 1e-15 * max(c, 1e-30) or max(abs(s) for s in step) < 1e-13:
            c = cn; break
        c = cn
    return t, c

def main():
    path, which = sys.argv[1], sys.argv[2]
    acc = read(path, which)
    v3, sel = init_var3d(acc)
    print(f"var_3D {v3:.4g} (range 100..{sel})")
    nv = [window_var(acc[k], 50) for k in range(3)]
    s2 = [nv[0][i] ** 2 + nv[1][i] ** 2 + nv[2][i] ** 2 for i in range(len(acc[0]))]
    N = len(acc[0]); filt = [0] * N; table = []
    for k in range(1, 16):
        thr = 4 * k * v3
        for i1 in range(50, N - 51 + 1):
            if s2[i1 - 1] < thr: filt[i1 - 1] = 1
        ivs = intervals(filt)
        data, segs, usable, short, dup = select(acc, ivs)
        if usable < 20 or dup > usable:
            t, mse = [0, 0, 0, 1, 1, 1, 0, 0, 0], 1e9
        else:
            t, rs = fit(data); mse = rs / len(data)
        table.append((k, thr, usable, short, dup, len(segs), mse, t, segs))
        print(f"k {k:2d} thr {thr:.3g} intervals {len(ivs)} usable {usable} short {short} dup {dup}"
              f" selected {len(segs)} mse {mse:.4g}")
    best = max(r[2] for r in table)
    z = [i for i, r in enumerate(table) if r[2] == best]
    if len(z) != 1:  # calibrate.m's tie-break: an index into the tied list (reproduced as is)
        lst = [table[i][6] for i in z]
        zz = lst.index(min(lst))
        print(f"tie {[table[i][0] for i in z]}: least mse at k = {table[z[zz]][0]}, list position"
              f" {zz + 1}, which calibrate.m takes as k = {zz + 1}")
        z = z[zz] if "--intended" in sys.argv else zz
    else:
        z = z[0]
    k, thr, usable, short, dup, nsel, mse, t, segs = table[z]
    t1, t2, t3, s1, s2_, s3, b1, b2, b3 = t
    TK = [[s1, -t1 * s2_, t2 * s3], [0, s2_, -t3 * s3], [0, 0, s3]]
    print(f"chosen k {k}: {nsel} segments, mse {mse:.4g}")
    mine = [f"{TK[r][c]:.5g}" for c in range(3) for r in range(3)] + [f"{x:.5g}" for x in (b1, b2, b3)]
    print("T K (column-major) and b:", " ".join(mine))
    authors = AUTHORS.split()
    line = mine + authors[12:] if which == "adxl" else authors[:12] + mine + authors[24:]
    print("36 coefficients for compare_imu_tk.py:", " ".join(line))

if __name__ == "__main__":
    main()
