#include "filter/noise/allan_sim.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/units.hpp"

namespace sinscal {

AllanNoiseSource::AllanNoiseSource(const AllanTruth& truth, double tau0, double longest,
                                   std::uint64_t seed, bool fast)
    : truth_(truth), tau0_(tau0), rng_(seed) {
  if (!(tau0 > 0.0) || !(longest > 4.0 * tau0))
    throw std::invalid_argument("Allan noise source: tau0 > 0 and longest > 4 tau0");
  if (truth.bias_instability <= 0.0) return;
  const double variance =
      truth.bias_instability * truth.bias_instability * std::log(2.0) / units::pi;
  const double steps = fast ? 8.0 : 64.0;  // steps per correlation time
  for (double T = fast ? 4.0 * tau0 : tau0 / 64.0; T <= longest; T *= 2.0) {
    Markov m;
    m.T = T;
    m.hold = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(T / (steps * tau0)));
    const double h = static_cast<double>(m.hold) * tau0;
    const double a = std::exp(-h / T);
    m.decay = a;
    m.s_end = std::sqrt(variance * (1.0 - a * a));
    // var w2 = q^2 T^2 (2 h / T - 3 + 4 a - a^2), written for small h / T without cancellation.
    const double u = h / T;
    const double g = u > 1e-3 ? 2.0 * u - 3.0 + 4.0 * a - a * a : u * u * u * 2.0 / 3.0;
    m.s_int = std::sqrt(variance * g) * T / h;
    m.rho = m.s_end > 0.0 && m.s_int > 0.0
                ? variance * T * (1.0 - a) * (1.0 - a) / h / (m.s_end * m.s_int)
                : 0.0;
    m.x = std::sqrt(variance) * normal_(rng_);  // stationary from the start
    flicker_.push_back(m);
  }
}

double AllanNoiseSource::next() {
  double y = truth_.white / std::sqrt(tau0_) * normal_(rng_);
  for (Markov& m : flicker_) {
    if (k_ % m.hold == 0) {
      const double h = static_cast<double>(m.hold) * tau0_;
      const double n1 = normal_(rng_), n2 = normal_(rng_);
      m.mean = m.T * (1.0 - m.decay) / h * m.x +
               m.s_int * (m.rho * n1 + std::sqrt(std::max(0.0, 1.0 - m.rho * m.rho)) * n2);
      m.x = m.decay * m.x + m.s_end * n1;
    }
    y += m.mean;
  }
  if (truth_.random_walk > 0.0) {
    y += walk_;
    walk_ += truth_.random_walk * std::sqrt(tau0_) * normal_(rng_);
  }
  y += truth_.rate_ramp * static_cast<double>(k_) * tau0_;
  ++k_;
  return y;
}

}  // namespace sinscal
