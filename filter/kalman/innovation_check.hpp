// Whether the filter's innovations are those its noise model predicts: per measurement channel
// (a kind of update and a navigation axis), the normalized innovations z_i / sqrt(S_ii) of the
// updates are recorded in bounded memory (filter/noise/autocorrelation.hpp), and tested at the
// end: their NIS against chi-square(updates) (upper tail: more residual than the noise model
// holds), and their whiteness by Ljung-Box against chi-square(lags) where the update's sigma is
// the noise (the dwells' zero velocity, not a bound), Bonferroni over every test
// (docs/methods/kalman-filter.md "Innovation consistency").
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "filter/noise/autocorrelation.hpp"

namespace sinscal {

/// The family-wise level of the innovation tests (Bonferroni over the channels' tests).
constexpr double kInnovationAlpha = 0.01;
/// Lags of the Ljung-Box test (fewer for short channels: n / 5).
constexpr int kInnovationLags = 10;

/// The kinds of update rows: zero velocity while the table turns, zero velocity in a dwell, the
/// known position, the table's attitude.
enum class InnovationKind { VelocityTurns = 0, VelocityDwells = 1, Position = 2, Attitude = 3 };

/// The normalized innovations of every update row, by channel (kind and north/east/down axis).
class InnovationRecord {
 public:
  void add(InnovationKind kind, int axis, double normalized);
  /// "velocity (turns) north", "attitude down", ...
  static std::string channel_name(int channel);
  static constexpr int kChannels = 12;
  const std::optional<AutocorrelationSums>& channel(int c) const {
    return channels_[static_cast<std::size_t>(c)];
  }

 private:
  std::array<std::optional<AutocorrelationSums>, kChannels> channels_;
};

/// One channel's tests.
struct ChannelCheck {
  std::string channel;
  long updates = 0;
  double nis = 0.0;          // sum of the squared normalized innovations
  double nis_per_dof = 0.0;  // nis / updates (1 expected)
  double nis_p = 1.0;        // upper tail of chi-square(updates) at nis
  double mean = 0.0;         // the normalized innovations' mean
  int lags = 0;              // Ljung-Box lags (0: too short, not tested)
  double ljung_box_q = 0.0;
  double ljung_box_p = 1.0;  // upper tail of chi-square(lags) at Q
  int largest_lag = 0;       // the lag of the largest |autocorrelation|
  double largest_autocorrelation = 0.0;
  /// The update's sigma is a bound, not the noise: every kind but the dwells' zero velocity (the
  /// known position's 1 mm, the table's 0.1 arcsec hold, the turns' 0.1 mm/s), or a NIS below
  /// the lower tail of chi-square(updates) at the threshold. Its innovations are then the
  /// filter's own state error seen through a gain made for more noise than there is, correlated
  /// by construction: their whiteness is not tested (white stays true), their NIS is.
  bool sigma_bound = false;
  bool nis_holds = true;  // nis_p at or above the Bonferroni threshold
  bool white = true;      // ljung_box_p at or above it (or not tested)
};

/// The innovations' verdict: every channel's NIS and whiteness at the family-wise alpha.
struct InnovationCheck {
  double alpha = kInnovationAlpha;
  int tests = 0;           // the channels' tests (Bonferroni's count)
  double threshold = 0.0;  // alpha / tests: a p-value below it fails
  std::vector<ChannelCheck> channels;
  bool consistent = true;
  /// "consistent", or "not consistent: velocity (dwells) down NIS per dof 3.2 (p 1e-40);
  /// attitude north innovations correlated at lag 1 (r 0.31, Ljung-Box p 2e-09)".
  std::string verdict = "consistent";
  /// The channels that fail, one line each (the verdict's parts).
  std::vector<std::string> failures;
  bool tested() const { return tests > 0; }
};

/// The tests of a record at the family-wise level `alpha`.
InnovationCheck innovation_check(const InnovationRecord& record, double alpha = kInnovationAlpha);

}  // namespace sinscal
