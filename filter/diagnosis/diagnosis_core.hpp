// The machinery the five diagnoses share (the table's dwells, diagnosis.hpp; the table's filter,
// diagnosis_kalman.hpp; hand-held, handheld_diagnosis.hpp; six-face, filter/six_face/six_face.hpp;
// a chamber's soaks, thermal_diagnosis.hpp): the options of a search, the record of one
// significance test with its p-value, the round's most significant candidate, the merging of a
// round's single components into their families' candidates, the statement of a findings cap, and
// the Ljung-Box test of an innovation sequence's whiteness.
// docs/methods/diagnosis.md.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace sinscal {

/// The options every diagnosis's search takes.
struct DiagnosisSearch {
  DiagnosisSearch() = default;
  explicit DiagnosisSearch(int findings) : max_findings(findings) {}
  /// Family-wise false-alarm level of one round of tests (Bonferroni over the candidates).
  double alpha = 0.01;
  int max_findings = 6;
  /// Candidate families; empty: the diagnosis's default set (each says which).
  std::vector<std::string> candidates;
};

/// One significance test of a candidate against the current model.
struct TestVerdict {
  /// "chi2": a likelihood ratio (or a statistic) against chi-square(dof); "F": against
  /// F(dof, dof2) (the likelihood ratio over the residual's scale); "wald": an estimate against
  /// zero by its covariance, chi-square(dof).
  std::string test;
  double statistic = 0.0;
  int dof = 0;             // extra parameters fitted (0: not tested)
  int dof2 = 0;            // F: the extended fit's degrees of freedom
  double p_value = 1.0;    // upper tail of the statistic's distribution
  double log10_p = 0.0;    // log10 of p_value, finite where p underflows (ranks across tests)
  double threshold = 0.0;  // p below this is significant (alpha / candidates)
  bool significant = false;
  bool named = false;             // the candidate joined the model as a finding
  double base_shift_sigma = 0.0;  // largest move of a coefficient already in the model, in sigma
};

/// log10 of the upper tail of chi-square(dof) at x, finite where the tail underflows (the
/// leading term of the incomplete gamma function's asymptotic expansion): p-values of different
/// tests and dof ranked on one scale.
double log10_chi2_tail(double x, int dof);
/// log10 of the upper tail of F(dof1, dof2) at f; where it underflows, that of chi-square(dof1)
/// at dof1 f (the limit of a large dof2).
double log10_f_tail(double f, int dof1, int dof2);

/// `statistic` against chi-square(v.dof): sets v's test name, statistic, dof2 (0), p_value and
/// log10_p (1 and 0 when v.dof is 0: nothing tested).
void chi2_verdict(TestVerdict& v, const std::string& test, double statistic);
/// A likelihood ratio over the extended fit's residual scale (chi-square per dof, `scale`) against
/// F(v.dof, dof2): sets v's test ("F"), statistic, dof2, p_value and log10_p.
void f_verdict(TestVerdict& v, double likelihood_ratio, double scale, int dof2);

/// The Ljung-Box portmanteau test of a series' whiteness (the filter's normalized innovations of
/// one update channel, in time order): Q = n (n + 2) sum over k = 1..lags of r_k^2 / (n - k),
/// r_k the sample autocorrelation at lag k about the series' mean, against chi-square(lags):
/// test "ljung-box", statistic Q, dof the lags (lags 0: min(10, n / 5)). dof 0 (not tested) when
/// the series is too short for one lag (n <= lags + 1) or constant.
TestVerdict ljung_box(const std::vector<double>& series, int lags = 0);

/// Marks `v` significant below `threshold` (tested: dof > 0, and p_value below it).
inline void mark_significant(TestVerdict& v, double threshold) {
  v.threshold = threshold;
  v.significant = v.dof > 0 && v.p_value < threshold;
}

/// Marks each test of `round` (Tests derive from TestVerdict) significant below `threshold` and
/// returns the most significant one (smallest log10 p; among equals the first, unless
/// `better(a, b)` prefers a later a), or nullptr.
template <class Test, class Better>
Test* most_significant_of(std::vector<Test>& round, double threshold, Better better) {
  Test* best = nullptr;
  for (auto& c : round) {
    mark_significant(c, threshold);
    if (c.significant &&
        (!best || c.log10_p < best->log10_p || (c.log10_p == best->log10_p && better(c, *best))))
      best = &c;
  }
  return best;
}
template <class Test>
Test* most_significant_of(std::vector<Test>& round, double threshold) {
  return most_significant_of(round, threshold, [](const Test&, const Test&) { return false; });
}

/// Appends to `round`, whose entries are single-component candidates (family, separable,
/// separated_by), one candidate per family with two or more separable components: all of them
/// together (an effect on every axis at once shows only partly in each one alone). `admit(family,
/// k)` may refuse a family of k components (false: none added); `test` tests the merged candidate
/// before it is appended.
template <class Candidate>
void add_family_candidates(std::vector<Candidate>& round,
                           const std::function<bool(const std::string& family, int k)>& admit,
                           const std::function<void(Candidate&)>& test) {
  const std::size_t singles = round.size();
  for (std::size_t i = 0; i < singles; ++i) {
    const bool first_of_family =
        std::none_of(round.begin(), round.begin() + static_cast<std::ptrdiff_t>(i),
                     [&](const Candidate& c) { return c.family == round[i].family; });
    if (!first_of_family) continue;
    Candidate all;
    for (std::size_t j = i; j < singles; ++j)
      if (round[j].family == round[i].family)
        all.separable.insert(all.separable.end(), round[j].separable.begin(),
                             round[j].separable.end());
    const int k = static_cast<int>(all.separable.size());
    if (k < 2 || (admit && !admit(round[i].family, k))) continue;
    all.family = round[i].family;
    all.separated_by = round[i].separated_by;
    test(all);
    round.push_back(std::move(all));
  }
}

/// The stop of a search that named `cap` findings: "the findings cap (6) was reached", and
/// "; still significant <where>: <family>" when a candidate still is (`family` not empty).
std::string findings_cap_stop(int cap, const std::string& where, const std::string& family);
/// The stop of a round whose most significant candidate `family` (p value `p`) the held-out data
/// refuse: "round 2: F was the most significant candidate (p 1e-05), but <reason>: not named,
/// <then>".
std::string refused_stop(int round, const std::string& family, double p, const std::string& reason,
                         const std::string& then);

}  // namespace sinscal
