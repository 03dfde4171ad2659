/* The firmware's side of `sinscal export --format c-header`, written from the header's comments
 * alone: reads raw outputs, applies the exported compensation in the stated order, prints
 * omega_ib_b and f_ib_b. Compiled and run by tests/test_export.cpp against the simulator's truth.
 *
 * Usage: apply < raw.txt > compensated.txt (SINSCAL_EXPORT_HEADER: the header, given by -D)
 *   raw.txt: a line "N dt", then N lines "t y_g[3] y_a[3]" (rates: rad/s, m/s^2; t: s since the
 *   start of the session, the middle of each sample's interval)
 *   compensated.txt: N lines "omega[3] f[3]" */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include SINSCAL_EXPORT_HEADER

static void mul(const double m[3][3], const double v[3], double out[3]) {
  int i;
  for (i = 0; i < 3; ++i) out[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
}

static void cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

int main(void) {
  const struct sinscal_imu_terms* c = &sinscal_calibration.value;
  long n, k;
  double dt;
  double *t, (*yg)[3], (*ya)[3], (*y)[3], (*w)[3];
  int i;
  if (scanf("%ld %lf", &n, &dt) != 2 || n < 3 || !(dt > 0.0)) return 2;
  t = malloc(sizeof *t * (size_t)n);
  yg = malloc(sizeof *yg * (size_t)n);
  ya = malloc(sizeof *ya * (size_t)n);
  y = malloc(sizeof *y * (size_t)n);
  w = malloc(sizeof *w * (size_t)n);
  if (!t || !yg || !ya || !y || !w) return 2;
  for (k = 0; k < n; ++k)
    if (scanf("%lf %lf %lf %lf %lf %lf %lf", &t[k], &yg[k][0], &yg[k][1], &yg[k][2], &ya[k][0],
              &ya[k][1], &ya[k][2]) != 7)
      return 2;
  for (k = 0; k < n; ++k) {
    double u[3], v[3], r[3], f0[3], gf[3];
    /* 0. the accelerometer output at t + tau, linearly interpolated */
    double pos = (double)k + c->time_delay / dt;
    long j = (long)floor(pos);
    double frac;
    if (j < 0) j = 0;
    if (j > n - 2) j = n - 2;
    frac = pos - (double)j;
    for (i = 0; i < 3; ++i) y[k][i] = ya[j][i] + frac * (ya[j + 1][i] - ya[j][i]);
    /* 1. gyros, the g-sensitivity on the accelerometers' linear estimate f0 */
    for (i = 0; i < 3; ++i) u[i] = y[k][i] - c->accel.bias[i] - c->accel.bias_drift[i] * t[k];
    mul(c->accel.correction, u, f0);
    mul(c->gyro_g_sensitivity, f0, gf);
    for (i = 0; i < 3; ++i)
      u[i] = yg[k][i] - c->gyro.bias[i] - c->gyro.bias_drift[i] * t[k] - gf[i];
    mul(c->gyro.correction, u, v);
    for (i = 0; i < 3; ++i) r[i] = u[i] - c->gyro.scale_asym[i] * fabs(v[i]);
    mul(c->gyro.correction, r, w[k]);
  }
  for (k = 0; k < n; ++k) {
    long a = k > 0 ? k - 1 : 0, b = k < n - 1 ? k + 1 : n - 1;
    double wd[3], s[3], p[3], q[3], e[3], u[3], v[3], r[3], f[3];
    int m;
    /* 2. the size effect, omega_dot from the central difference */
    for (i = 0; i < 3; ++i) wd[i] = (w[b][i] - w[a][i]) / ((double)(b - a) * dt);
    for (m = 0; m < 3; ++m) {
      const double* r_m = c->accel_lever_arm[m];
      cross(wd, r_m, p);
      cross(w[k], r_m, q);
      cross(w[k], q, e);
      s[m] = 0.0;
      for (i = 0; i < 3; ++i) s[m] += c->accel.model[m][i] * (p[i] + e[i]);
    }
    /* 3. accelerometers */
    for (i = 0; i < 3; ++i)
      u[i] = y[k][i] - c->accel.bias[i] - c->accel.bias_drift[i] * t[k] - s[i];
    mul(c->accel.correction, u, v);
    for (i = 0; i < 3; ++i)
      r[i] = u[i] - c->accel.scale_asym[i] * fabs(v[i]) - c->accel_k2[i] * v[i] * v[i];
    mul(c->accel.correction, r, f);
    printf("%.17g %.17g %.17g %.17g %.17g %.17g\n", w[k][0], w[k][1], w[k][2], f[0], f[1], f[2]);
  }
  return 0;
}
