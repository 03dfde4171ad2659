#!/usr/bin/env python3
"""Compare a sinscal table-free result.json of the OpenAXES imu9 recording with the authors'
imu_tk coefficients (calibration/README.md of OpenAXES-IMU/OpenAXES: the 36 numbers of
--write-calibration-full, MATLAB's column-major (:) of the misalignment*scale matrices T K and
the biases). The authors ran imu_tk_matlab (calibrate.m with their patch), whose models are
  accelerometers: corrected = T K raw - b  (accCostFunctLSQNONLIN.m: b subtracted AFTER T K, so
                  b is in corrected units; sinscal's raw = L f + b_raw has b_raw = (T K)^-1 b)
  gyros:          corrected = T K (raw - b)  (the bias removed before, in raw units).
usage: compare.py result.json adxl|bmi [36 coefficients to compare with instead of the authors']"""
import json, math, sys

C = [float(x) for x in ("0.96276 0 0 0.0015751 0.96732 0 -0.00018891 0.000859 0.97079 0.064447 "
     "0.011034 0.034253 0.95418 0 0 0.0031573 0.96061 0 0.009235 0.00049713 0.9501 -0.033224 "
     "0.080497 0.01579 0.97288 0.0076747 -0.0063582 -0.011829 1.0062 -0.00033403 0.010087 "
     "0.00029571 1.0068 -0.00020494 0.00063007 -0.00036962").split()]
if len(sys.argv) > 3: C = [float(x) for x in sys.argv[3].split()]
def colmajor(v): return [[v[0], v[3], v[6]], [v[1], v[4], v[7]], [v[2], v[5], v[8]]]
TK = {"adxl": colmajor(C[0:9]), "bmi": colmajor(C[12:21])}
B = {"adxl": C[9:12], "bmi": C[21:24]}
GTK, GB = colmajor(C[24:33]), C[33:36]  # the gyro's, calibrated against the BMI160

def inv(m):
    a, b, c = m[0]; d, e, f = m[1]; g, h, i = m[2]
    det = a*(e*i-f*h) - b*(d*i-f*g) + c*(d*h-e*g)
    return [[(e*i-f*h)/det, (c*h-b*i)/det, (b*f-c*e)/det],
            [(f*g-d*i)/det, (a*i-c*g)/det, (c*d-a*f)/det],
            [(d*h-e*g)/det, (b*g-a*h)/det, (a*e-b*d)/det]]
def mul(a, b): return [[sum(a[i][k]*b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
def tr(a): return [list(r) for r in zip(*a)]
def dot(u, v): return sum(x*y for x, y in zip(u, v))
def norm(u): return math.sqrt(dot(u, u))

def lq(a):
    """a = L Q, L lower triangular (positive diagonal), Q orthonormal rows (Gram-Schmidt of a's
    rows: the body frame whose x is sensor x, y in the x-y sensor plane)."""
    q = []
    for r in a:
        v = list(r)
        for e in q: v = [x - dot(r, e)*y for x, y in zip(v, e)]
        n = norm(v); q.append([x/n for x in v])
    return mul(a, tr(q)), q

res = json.load(open(sys.argv[1])); which = sys.argv[2]
co = res["coefficients"]
def val(name): return co[name]["value"], co[name]["sigma"]
rows = []
def row(name, ours, sigma, theirs, unit):
    rows.append((name, ours, sigma, theirs, (ours - theirs)/sigma if sigma > 0 else float("nan"), unit))

A_t = inv(TK[which])             # raw = A_t (x_t + b): rows are the sensors' axes (imu_tk frame)
L, Q = lq(A_t)                   # the same triad in sinscal's frame (lower triangular)
b_raw = [sum(A_t[i][k]*B[which][k] for k in range(3)) for i in range(3)]  # the bias in raw units
ug = 9.80665e-6
for i, ax in enumerate("xyz"):
    v, s = val(f"accel.bias.{ax}"); row(f"accel.bias.{ax}", v, s, b_raw[i]/ug, "ug")
for i, ax in enumerate("xyz"):
    v, s = val(f"accel.scale.{ax}"); row(f"accel.scale.{ax}", v, s, (L[i][i]-1)*1e6, "ppm")
for n, (i, j) in (("yx", (1, 0)), ("zx", (2, 0)), ("zy", (2, 1))):
    v, s = val(f"accel.misalignment.{n}")
    row(f"accel.misalignment.{n}", v, s, L[i][j]*206264.806, "arcsec")
G_t = inv(GTK)                   # raw = G_t w_t + b_g
G_s = mul(G_t, tr(Q))            # in sinscal's frame: w_s = Q w_t
for i, ax in enumerate("xyz"):
    v, s = val(f"gyro.bias.{ax}"); row(f"gyro.bias.{ax}", v, s, GB[i]*180/math.pi*3600, "deg/h")
for i, ax in enumerate("xyz"):
    v, s = val(f"gyro.scale.{ax}")
    if which == "bmi": row(f"gyro.scale.{ax}", v, s, (G_s[i][i]-1)*1e6, "ppm")
    else:  # frame-free: the norm of the sensor's row (the gyro of imu_tk's ADXL run is not published)
        r = [(1 + v/1e6) if k == i else val(f"gyro.misalignment.{ax}{'xyz'[k]}")[0]/206264.806
             for k in range(3)]
        row(f"gyro row norm {ax}", (norm(r)-1)*1e6, s, (norm(G_t[i])-1)*1e6, "ppm")
if which == "bmi":
    for n in ("xy", "xz", "yx", "yz", "zx", "zy"):
        i, j = "xyz".index(n[0]), "xyz".index(n[1])
        v, s = val(f"gyro.misalignment.{n}"); row(f"gyro.misalignment.{n}", v, s, G_s[i][j]*206264.806, "arcsec")
worst = 0.0
print(f"| coefficient | sinscal | sigma | imu_tk (authors) | (sinscal - imu_tk)/sigma |")
print("|---|---|---|---|---|")
for name, ours, sigma, theirs, z, unit in rows:
    worst = max(worst, abs(z))
    print(f"| {name} [{unit}] | {ours:.1f} | {sigma:.1f} | {theirs:.1f} | {z:+.2f} |")
print(f"\nworst |difference|/sigma: {worst:.2f}; RMS {math.sqrt(sum(r[4]**2 for r in rows)/len(rows)):.2f} over {len(rows)}")
