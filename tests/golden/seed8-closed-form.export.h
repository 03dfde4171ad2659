/* sinscal firmware export (format 1), sinscal 0.1.0
 * Source: tests/golden/seed8-closed-form.json (14098 bytes), method closed-form
 * Body frame: table platform: the table platform's axes as the plan draws them: the misalignments
 *    include the IMU's mounting on the platform (docs/conventions.md "Table base and mounting")
 * Misalignment frame: table: relative to the table's platform axes (the table frame: includes the
 *    IMU's mounting on the table, bounded by the table's attitude accuracy)
 * Units: SI (rad/s, m/s^2, s, m; k2 in 1/(m/s^2), g-sensitivity in rad/s per m/s^2, bias drift in
 *    rad/s^2 and m/s^3).
 * Terms estimated: gyro.bias, gyro.scale, gyro.misalignment, accel.bias, accel.scale,
 *    accel.misalignment; every other term is zero here and its SINSCAL_HAS_ macro 0.
 *
 * Formula (what the firmware computes, in this order):
 *   inputs: raw gyro output y_g (rad/s) and accelerometer output y_a (m/s^2) of one sample, body
 *      axes, as the calibrated log gave them to sinscal (its columns converted to SI by the
 *      session's [log] units, scales and axis map); increments (rad, m/s over the interval dt):
 *      divide by dt first, multiply the results by dt
 *   C = correction_matrix = A^-1, A = model_matrix = I + diag(scale) + misalignment; .* and |.| per
 *      component
 *   1. gyros: omega_ib_b = C_g (y_g - b_g)
 *   2. size effect: none (no lever arms in the result)
 *   3. accelerometers: f_ib_b = C_a (y_a - b_a)
 *
 * Field names: value.gyro.bias = b_g, .correction = C_g = A_g^-1, .model = A_g, .scale_asym = a_g,
 *    .bias_drift = d_g; value.gyro_g_sensitivity = G; value.accel_k2 = k2; value.accel_lever_arm[i]
 *    = r_i; value.time_delay = tau. sigma: the 1-sigma of each (0: none; sigma.correction is the
 *    model's, to first order).
 * Accuracy: evaluated at the linear estimate v (first order); error per axis at most (|a| + 2 |k2|
 *    |x|) (|a| |x| + |k2| x^2) against the exact inverse; 0.0 m/s^2 at 1 g.
 */
#pragma once
#ifndef SINSCAL_IMU_CALIBRATION_H
#define SINSCAL_IMU_CALIBRATION_H

#define SINSCAL_EXPORT_FORMAT_VERSION 1
#define SINSCAL_MISALIGNMENT_FRAME "table"
#define SINSCAL_HAS_ACCEL_K2 0
#define SINSCAL_HAS_GYRO_SCALE_ASYM 0
#define SINSCAL_HAS_ACCEL_SCALE_ASYM 0
#define SINSCAL_HAS_GYRO_G_SENSITIVITY 0
#define SINSCAL_HAS_ACCEL_LEVER_ARM 0
#define SINSCAL_HAS_TIME_DELAY 0
#define SINSCAL_HAS_GYRO_BIAS_DRIFT 0
#define SINSCAL_HAS_ACCEL_BIAS_DRIFT 0

struct sinscal_triad_terms {
  double bias[3];          /* b: rad/s (gyro), m/s^2 (accel) */
  double correction[3][3]; /* C = A^-1, [row][column], dimensionless */
  double model[3][3];      /* A = I + diag(scale) + misalignment (accel: used by the size effect) */
  double scale_asym[3];    /* a, dimensionless */
  double bias_drift[3];    /* d: rad/s^2 (gyro), m/s^3 (accel); t from the session's start */
};

struct sinscal_imu_terms {
  struct sinscal_triad_terms gyro;
  struct sinscal_triad_terms accel;
  double gyro_g_sensitivity[3][3]; /* G[i][j]: gyro i per specific force along j, rad/s per m/s^2 */
  double accel_k2[3];              /* 1/(m/s^2) */
  double accel_lever_arm[3][3];    /* [i]: r_i, accelerometer i's proof mass, m */
  double time_delay;               /* tau, s: accelerometers late is positive */
};

struct sinscal_imu_calibration {
  struct sinscal_imu_terms value;
  struct sinscal_imu_terms sigma;
};

static const struct sinscal_imu_calibration sinscal_calibration = {
  .value = {
    .gyro = {
      .bias = {1.2954689819347105e-06, -1.0728473373226622e-06, 1.3904787052016864e-06},
      .correction = {{0.9999759639782052, 0.00019523497446095368, 5.9225029975511015e-05}, {1.1401180978252587e-05, 1.0001324239998568, 0.0002687012340610801}, {-0.000215687723035745, 0.00048460012485880045, 0.9995320520684267}},
      .model = {{1.0000240260555446, -0.00019518512883588362, -5.9201709752006324e-05}, {-1.1457923175634949e-05, 0.9998677260094335, -0.00026879079337652364}, {0.00021579944057381164, -0.00048480498739353263, 1.0004682845513306}},
      .scale_asym = {0.0, 0.0, 0.0},
      .bias_drift = {0.0, 0.0, 0.0}},
    .accel = {
      .bias = {0.0020753752838286905, -0.0019229275109679206, 0.0020930904560903145},
      .correction = {{1.0000290440852748, 5.184094343414289e-05, -7.973331825988084e-05}, {0.00011440617260750845, 0.9999655722810014, 0.0001160716254020433}, {-0.00011129498803174325, 6.015322244804478e-05, 1.0000341219393882}},
      .model = {{0.9999709715633623, -5.184601978793976e-05, 7.973430088910915e-05}, {-0.00011441970895802367, 1.0000344418190108, -0.00011608078528150773}, {0.00011129484243057283, -6.0159011694446346e-05, 0.999965895080999}},
      .scale_asym = {0.0, 0.0, 0.0},
      .bias_drift = {0.0, 0.0, 0.0}},
    .gyro_g_sensitivity = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
    .accel_k2 = {0.0, 0.0, 0.0},
    .accel_lever_arm = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
    .time_delay = 0.0},
  .sigma = {
    .gyro = {
      .bias = {7.666299663087783e-09, 7.667610092634682e-09, 7.66629967865914e-09},
      .correction = {{0.0001986373194738943, 0.00017993249356838822, 0.00018329597360175416}, {0.00018328182928031218, 0.00017992720110414291, 0.00018328184938088595}, {0.00018329597388970674, 0.00017993247577779758, 0.00019863728351221025}},
      .model = {{0.0001986373194738943, 0.00017993249356838822, 0.00018329597360175416}, {0.00018328182928031218, 0.00017992720110414291, 0.00018328184938088595}, {0.00018329597388970674, 0.00017993247577779758, 0.00019863728351221025}},
      .scale_asym = {0.0, 0.0, 0.0},
      .bias_drift = {0.0, 0.0, 0.0}},
    .accel = {
      .bias = {5.139639285897593e-06, 3.6478672741223767e-06, 5.139639288905583e-06},
      .correction = {{4.332869756544847e-06, 4.963423580029576e-06, 8.58305846738773e-06}, {4.981986098926003e-06, 4.3007521309307945e-06, 4.981986104649236e-06}, {8.583058500484624e-06, 4.963423585785067e-06, 4.332869756647711e-06}},
      .model = {{4.332869756544847e-06, 4.963423580029576e-06, 8.58305846738773e-06}, {4.981986098926003e-06, 4.3007521309307945e-06, 4.981986104649236e-06}, {8.583058500484624e-06, 4.963423585785067e-06, 4.332869756647711e-06}},
      .scale_asym = {0.0, 0.0, 0.0},
      .bias_drift = {0.0, 0.0, 0.0}},
    .gyro_g_sensitivity = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
    .accel_k2 = {0.0, 0.0, 0.0},
    .accel_lever_arm = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
    .time_delay = 0.0}};

#endif /* SINSCAL_IMU_CALIBRATION_H */
