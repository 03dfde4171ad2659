// The machinery the diagnoses share (filter/diagnosis/diagnosis_core.hpp): the round's most
// significant candidate, the family candidates, the stop statements, and the Ljung-Box test of an
// innovation sequence's whiteness.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis_core.hpp"

using namespace sinscal;

namespace {

struct Single : TestVerdict {
  std::string family;
  std::vector<int> separable;
  std::string separated_by;
};

// n samples of an AR(1) sequence x_t = phi x_{t-1} + e_t (phi 0: white), unit-variance e_t.
std::vector<double> ar1(std::mt19937& rng, int n, double phi) {
  std::normal_distribution<double> e(0.0, 1.0);
  std::vector<double> x(static_cast<std::size_t>(n));
  double prev = e(rng) / std::sqrt(1.0 - phi * phi);
  for (auto& v : x) {
    v = phi * prev + e(rng);
    prev = v;
  }
  return x;
}

}  // namespace

TEST_CASE("Diagnosis core: the most significant candidate and its threshold", "[diagnosis]") {
  std::vector<Single> round(3);
  round[0].dof = 2;
  round[0].p_value = 1e-3;
  round[0].log10_p = -3.0;
  round[1].dof = 0;  // not tested: never significant, whatever its p
  round[1].p_value = 1e-9;
  round[1].log10_p = -9.0;
  round[2].dof = 1;
  round[2].p_value = 1e-5;
  round[2].log10_p = -5.0;
  Single* best = most_significant_of(round, 0.01 / 2.0);
  REQUIRE(best == &round[2]);
  CHECK(round[0].significant);
  CHECK_FALSE(round[1].significant);
  CHECK(round[0].threshold == Approx(0.005));
  // Equal p: the first, unless the tie-break prefers a later one.
  round[0].log10_p = round[2].log10_p;
  CHECK(most_significant_of(round, 0.005) == &round[0]);
  CHECK(most_significant_of(
            round, 0.005, [](const Single& a, const Single&) { return a.dof == 1; }) == &round[2]);
  CHECK(most_significant_of(round, 1e-12) == nullptr);
}

TEST_CASE("Diagnosis core: family candidates merge a family's separable components",
          "[diagnosis]") {
  std::vector<Single> round(4);
  round[0].family = round[1].family = "accel.k2";
  round[0].separable = {10};
  round[1].separable = {11};
  round[2].family = "gyro.g_sensitivity";
  round[2].separable = {20};
  round[3].family = "accel.k2";
  round[3].separable = {12};
  round[0].separated_by = "turns";
  std::vector<std::string> asked;
  int tested = 0;
  add_family_candidates<Single>(
      round,
      [&](const std::string& family, int k) {
        asked.push_back(family + ":" + std::to_string(k));
        return true;
      },
      [&](Single&) { ++tested; });
  REQUIRE(round.size() == 5);  // one merged candidate: gyro.g_sensitivity has one component
  CHECK(round[4].family == "accel.k2");
  CHECK(round[4].separable == std::vector<int>{10, 11, 12});
  CHECK(round[4].separated_by == "turns");
  CHECK(tested == 1);
  CHECK(asked == std::vector<std::string>{"accel.k2:3"});
  // A family the caller refuses is not added.
  round.resize(4);
  add_family_candidates<Single>(
      round, [](const std::string&, int) { return false; }, [](Single&) {});
  CHECK(round.size() == 4);
}

TEST_CASE("Diagnosis core: stop statements", "[diagnosis]") {
  CHECK(findings_cap_stop(6, "on the dwells", "") == "the findings cap (6) was reached");
  CHECK(findings_cap_stop(4, "", "gyro.scale_temp1") ==
        "the findings cap (4) was reached; still significant: gyro.scale_temp1");
  CHECK(findings_cap_stop(6, "on the dwells", "accel.k2") ==
        "the findings cap (6) was reached; still significant on the dwells: accel.k2");
  CHECK(refused_stop(2, "time_delay", 1e-12, "the held-out turns' chi-square goes up",
                     "its residual is unexplained") ==
        "round 2: time_delay was the most significant candidate (p 1e-12), but the held-out "
        "turns' chi-square goes up: not named, its residual is unexplained");
}

TEST_CASE("Diagnosis core: the Ljung-Box statistic by hand", "[diagnosis]") {
  // An alternating series of 10: mean 0, r_1 = -9/10, Q = 10 * 12 * 0.81 / 9 = 10.8 on 1 lag.
  std::vector<double> x;
  for (int t = 0; t < 10; ++t) x.push_back(t % 2 ? -1.0 : 1.0);
  const TestVerdict v = ljung_box(x, 1);
  CHECK(v.test == "ljung-box");
  CHECK(v.dof == 1);
  CHECK(v.statistic == Approx(10.8));
  CHECK(v.p_value == Approx(std::erfc(std::sqrt(10.8 / 2.0))));  // chi-square(1) upper tail
  // Default lags min(10, n / 5); too short or constant: not tested.
  CHECK(ljung_box(std::vector<double>(100, 0.0)).dof == 0);
  CHECK(ljung_box(std::vector<double>(4, 1.0), 3).dof == 0);
  std::mt19937 rng(5);
  CHECK(ljung_box(ar1(rng, 30, 0.0)).dof == 6);
  CHECK(ljung_box(ar1(rng, 300, 0.0)).dof == 10);
}

TEST_CASE("Diagnosis core: Ljung-Box flags coloured innovations, not white ones", "[diagnosis]") {
  // 400 sequences of 500 innovations at alpha 0.01. White: about 4 false alarms, binomial sigma
  // 2, at most 4 + 4 sigma. AR(1) with phi 0.3 (the innovations of a filter whose model misses a
  // correlated error): Q about 50 against the 99 % point 23.2 of chi-square(10), power above 99 %
  // (the noncentral chi-square), so at most 4 + 4 sigma misses as well.
  std::mt19937 rng(11);
  const int runs = 400, n = 500;
  int false_alarms = 0, misses = 0;
  double p_sum = 0.0;
  for (int k = 0; k < runs; ++k) {
    TestVerdict white = ljung_box(ar1(rng, n, 0.0));
    mark_significant(white, 0.01);
    false_alarms += white.significant ? 1 : 0;
    p_sum += white.p_value;
    TestVerdict coloured = ljung_box(ar1(rng, n, 0.3));
    mark_significant(coloured, 0.01);
    misses += coloured.significant ? 0 : 1;
  }
  INFO("false alarms " << false_alarms << ", misses " << misses << " of " << runs);
  CHECK(false_alarms <= 12);
  CHECK(misses <= 12);
  // White noise's p-values are uniform (a test that never fires would not be): their mean is 0.5
  // within 4 sigma, sigma = 1 / sqrt(12 runs).
  CHECK(std::abs(p_sum / runs - 0.5) < 4.0 / std::sqrt(12.0 * runs));
}
