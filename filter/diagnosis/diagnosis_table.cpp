#include "filter/diagnosis/diagnosis_table.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

#include "filter/diagnosis/pair_separation.hpp"
#include "filter/diagnosis/time_structure.hpp"
#include "filter/thermal/soak_fit.hpp"
#include "models/coefficient_families.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

namespace {

// The candidate families: the options' or every extended family of the family table.
std::vector<std::string> candidate_families(const DiagnosisOptions& o) {
  std::vector<std::string> out = o.candidates;
  if (out.empty())
    for (const auto& f : coefficient_families())
      if (!f.base && (o.thermal || !f.thermal())) out.push_back(f.name);
  for (const auto& f : out)
    if (coefficient_family_info(f).base)
      throw std::invalid_argument("diagnosis: " + f + " is a base family, not a candidate");
  return out;
}

// A thermal family that acts during the turns: the gyros' scale factor or misalignment against
// the temperature (a turn's angle times T - T0). At rest the dwells see it only through the
// earth's rate (15 deg/h times 100 ppm: far below their noise), so the components the dwells
// "separate" carry no power there; the turns' test takes it whatever the dwells say (issue 33).
bool thermal_acts_in_turns(const std::string& family) {
  if (!coefficient_family_info(family).thermal()) return false;
  const std::string base = thermal_family_parts(family).first;
  return base == "gyro.scale" || base == "gyro.misalignment";
}

// The library's model columns: the dwells' model `confirmed` and the components of the findings
// of the turns (the library's turns' test judges the final model, as the contest does:
// library_contest), but for a finding paired with a library term the plan cannot tell it from
// (TableFinding::alternative_term: the library reports the term on what the model without the
// family leaves) unless its family is thermal and acts during the turns (thermal_acts_in_turns:
// the dwells have their columns, through the earth's rate). With the thermal families only, a
// turns' finding of the MEMS accel.scale_asym was left out of the model the turns' residual was
// tested against, and the turns "rejected" it on 24 of 30 rot19 seeds (issue 33); with the
// library's rate columns along the table's motion, a named MEMS gyro.scale_asym left out left its
// turns "unexplained" along omega_i^2 on 10 of 10 rot19 seeds.
std::vector<int> with_turn_findings(std::vector<int> confirmed,
                                    const std::vector<TableFinding>& findings) {
  for (const auto& f : findings) {
    if (f.source != TableFinding::Source::Turns) continue;
    if (f.alternative_term && !thermal_acts_in_turns(f.family)) continue;
    for (int c : f.components)
      if (std::find(confirmed.begin(), confirmed.end(), c) == confirmed.end())
        confirmed.push_back(c);
  }
  return confirmed;
}

// The model the final checks judge (the dwells' and the held-out dwells' noise model, where the
// dwells' residual shows, the library's turns): `parameters` with every component of each dwell
// finding's family, as the filter's model holds it. The dwells name the components they separate
// alone; a family's others can be aliased with base coefficients whose weak prior (the grade's)
// cannot take them. On seed8 the body y axis is vertical or east-west in every dwell, so the
// earth's rate along y is sin(lat) Omega / g times f_y: the MEMS gyro.g_sensitivity column of f_y
// is the gyro scale and misalignment's y column at 4-5 (400-500 %), far beyond their 1.5 % prior.
// Left out, the regularized held-out dwells did not fit the true family (predictive chi2 919 on
// 48 inputs, its 99 % quantile 86.5; with it 59.8) and the residual was "unexplained" on 30 of 30
// seeds (issue 33). The stage-2 fit is unchanged (an aliased column adds no rank).
std::vector<int> with_whole_family(std::vector<int> parameters, const std::string& family) {
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k) {
    const int c = static_cast<int>(k);
    if (cat[k].family == family &&
        std::find(parameters.begin(), parameters.end(), c) == parameters.end())
      parameters.push_back(c);
  }
  return parameters;
}

std::vector<int> with_whole_families(std::vector<int> parameters,
                                     const std::vector<TableFinding>& findings) {
  for (const auto& f : findings)
    if (f.source == TableFinding::Source::Dwells)
      parameters = with_whole_family(std::move(parameters), f.family);
  return parameters;
}

// The dwells separate the family but do not find it this round (none of its candidates below
// the dwells' own Bonferroni level), and its signature follows the specific force or the rate,
// which the turns sweep (not a drift in time, not a thermal family). The dwells may hold far
// less of it than the turns: MEMS gyro.g_sensitivity on rot19, whose dwells' sigmas are wide
// under the bias wander while the filter's are 1.2e-6 rad/s per m/s^2; at 5-10 of the filter's
// sigmas the dwells' test missed it on 1-4 seeds of 30 (chi2 5.4 on 6 dof) with the turns never
// asked (issue 33).
// The level is the round's family-wise one at its largest (round: alpha over the dwells' tests
// and the turns' together, here every turn candidate counted), so that a family the round does
// not name on the dwells is never kept from the turns.
bool dwells_miss(const std::string& family, const std::vector<CandidateTest>& dwell_round,
                 double alpha, std::ptrdiff_t turn_candidates) {
  const CoefficientFamily& info = coefficient_family_info(family);
  if (info.thermal() || info.term == "bias_drift") return false;
  const auto tested = std::count_if(dwell_round.begin(), dwell_round.end(),
                                    [](const CandidateTest& c) { return c.dof > 0; });
  const double level =
      alpha / static_cast<double>(std::max<std::ptrdiff_t>(1, tested + turn_candidates));
  bool any = false;
  for (const auto& c : dwell_round) {
    if (c.family != family || c.dof <= 0) continue;
    if (c.p_value < level) return false;
    any = true;
  }
  return any;
}

// The families the turns' test takes this round: candidates with no component the dwells
// separate, those the dwells separate but miss (dwells_miss), and the thermal families that act
// during the turns (thermal_acts_in_turns), not yet in the filter's model.
std::vector<std::string> turn_families(const std::vector<std::string>& candidates,
                                       const std::vector<CandidateTest>& dwell_round,
                                       const CalibratorOptions& model, double alpha) {
  std::vector<std::string> out;
  const auto open = std::count_if(candidates.begin(), candidates.end(),
                                  [&](const std::string& f) { return !model.layout.on(f); });
  for (const auto& f : candidates) {
    if (model.layout.on(f)) continue;
    const bool seen = std::any_of(dwell_round.begin(), dwell_round.end(), [&](const auto& c) {
      return c.family == f && !c.separable.empty();
    });
    if (!seen || thermal_acts_in_turns(f) || dwells_miss(f, dwell_round, alpha, open))
      out.push_back(f);
  }
  return out;
}

// The dwells' candidates of families the turns found (in the filter's model, not in the dwells'):
// the model has them already.
void drop_turn_found(std::vector<CandidateTest>& dwell_round, const CalibratorOptions& model,
                     const std::vector<int>& current) {
  const auto found = [&](const CandidateTest& c) {
    if (!model.layout.on(c.family)) return false;
    const auto& cat = coefficient_catalog();
    for (std::size_t k = 0; k < cat.size(); ++k)
      if (cat[k].family == c.family &&
          std::find(current.begin(), current.end(), static_cast<int>(k)) != current.end())
        return false;
    return true;
  };
  dwell_round.erase(std::remove_if(dwell_round.begin(), dwell_round.end(), found),
                    dwell_round.end());
}

// The member of an ambiguous set that extends the model: the user's preferred family (the best
// fit among its candidates), else the data's pick, the best fit (`best` itself).
CandidateTest pick_member(const CandidateTest& best, const std::vector<std::string>& prefer) {
  std::vector<const CandidateTest*> set = {&best};
  for (const auto& c : best.ambiguous_with) set.push_back(&c);
  const CandidateTest* member = &best;
  std::string by = "data";
  for (const auto& family : prefer) {
    const CandidateTest* found = nullptr;
    for (const auto* c : set)
      if (c->family == family && (!found || c->with.chi2 < found->with.chi2)) found = c;
    if (found) {
      member = found;
      by = "user";
      break;
    }
  }
  CandidateTest out = *member;
  out.ambiguous_with.clear();
  for (const auto* c : set)
    if (c != member) {
      CandidateTest other = *c;
      other.ambiguous_with.clear();
      out.ambiguous_with.push_back(std::move(other));
    }
  const bool other_family = std::any_of(out.ambiguous_with.begin(), out.ambiguous_with.end(),
                                        [&](const auto& c) { return c.family != out.family; });
  out.picked_by = other_family ? by : "";
  out.named = true;
  return out;
}

// The family's coefficients in the extended calibration: the filter's where it observes them,
// else the dwells' fit where it determines them.
std::vector<FindingCoefficient> extended_coefficients(const std::string& family,
                                                      const KalmanRun* filter,
                                                      const Stage2Result& dwells) {
  std::vector<FindingCoefficient> out;
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k) {
    if (cat[k].family != family) continue;
    FindingCoefficient c;
    c.catalog = static_cast<int>(k);
    if (filter && filter->estimates[k].observed()) {
      c.value = filter->estimates[k].value;
      c.sigma = filter->estimates[k].sigma;
      c.source = "kalman";
    } else {
      const auto& p = dwells.parameters;
      const auto it = std::find(p.begin(), p.end(), c.catalog);
      const auto i = it - p.begin();
      if (it != p.end() && dwells.observable[static_cast<std::size_t>(i)]) {
        c.value = dwells.theta(i);
        c.sigma = std::sqrt(dwells.cov(i, i));
        c.source = "dwells";
      }
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace

namespace {

// The base family of the triad whose grade an extended family's prior follows ("": none).
std::string grade_reference(const CoefficientFamily& f) {
  if (f.base || f.output == FamilyOutput::Delay) return "";
  const std::string triad = f.output == FamilyOutput::Gyro ? "gyro." : "accel.";
  const auto has = [&](const char* word) { return f.name.find(word) != std::string::npos; };
  if (has("misalignment")) return triad + "misalignment";
  if (has("scale") || has("k2")) return triad + "scale";
  if (has("bias") || has("g_sensitivity")) return triad + "bias";
  return "";
}

// The largest prior the model gives a family's coefficients (0: none).
double model_prior(const CalibratorOptions& model, const std::string& family) {
  const auto& cat = coefficient_catalog();
  double s = 0.0;
  for (std::size_t k = 0; k < cat.size() && k < model.initial_sigma.size(); ++k)
    if (cat[k].family == family) s = std::max(s, model.initial_sigma[k]);
  return s;
}

}  // namespace

std::vector<double> grade_priors(const CalibratorOptions& model) {
  const auto& cat = coefficient_catalog();
  std::vector<double> out(cat.size(), 0.0);
  for (std::size_t k = 0; k < cat.size(); ++k) {
    const CoefficientFamily& info = coefficient_family_info(cat[k].family);
    const std::string ref = grade_reference(info);
    const double grade =
        ref.empty()
            ? 1.0
            : std::max(1.0, model_prior(model, ref) / coefficient_family_info(ref).default_prior);
    const double own = k < model.initial_sigma.size() ? model.initial_sigma[k] : 0.0;
    out[k] = std::max(own, grade * info.default_prior);
  }
  return out;
}

TurnModel turn_model_of(const Session& session, const SensorProfile& profile, double table_sigma) {
  TurnModel t;
  t.session = &session;
  t.base = calibrator_options_from_profile(profile);
  // The families the profile lacks (the candidates) with priors of the sensor's grade.
  const std::vector<double> graded = grade_priors(t.base);
  for (std::size_t k = 0; k < graded.size() && k < t.base.initial_sigma.size(); ++k)
    if (!(t.base.initial_sigma[k] > 0.0)) t.base.initial_sigma[k] = graded[k];
  t.base.attitude_sigma = table_sigma;
  t.base.time_offset = session.time_offset;
  return t;
}

Stage2Options dwells_model(const Stage2Options& base, const TurnModel* turn_model) {
  Stage2Options model = base;
  if (!turn_model) return model;
  model.bias_wander = turn_model->base.noise;
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k) {
    const int c = static_cast<int>(k);
    if (!coefficient_family_info(cat[k].family).base && turn_model->base.layout.on(cat[k].family) &&
        std::find(model.parameters.begin(), model.parameters.end(), c) == model.parameters.end())
      model.parameters.push_back(c);
  }
  return model;
}

namespace {

// A finding of `source`: the family, the components that joined the model, its test.
TableFinding finding_of(TableFinding::Source source, const std::string& family,
                        const std::vector<int>& components, const TestVerdict& test) {
  TableFinding f;
  static_cast<TestVerdict&>(f) = test;
  f.source = source;
  f.family = family;
  f.components = components;
  return f;
}

// A dwell finding from the member that extends the model.
TableFinding dwell_finding(const CandidateTest& member) {
  TableFinding f =
      finding_of(TableFinding::Source::Dwells, member.family, member.separable, member);
  for (const auto& c : member.ambiguous_with)
    if (c.family != member.family && std::find(f.ambiguous_with.begin(), f.ambiguous_with.end(),
                                               c.family) == f.ambiguous_with.end())
      f.ambiguous_with.push_back(c.family);
  f.picked_by = member.picked_by;
  f.dwells_after = member.with;
  return f;
}

TableFinding turn_finding(const KalmanCandidateTest& c) {
  return finding_of(TableFinding::Source::Turns, c.family, c.catalog, c);
}

// The family's coefficients in the final extended calibration, and the dwells' combinations of
// those neither determines alone.
void final_magnitudes(TableFinding& f, const KalmanRun* filter, const Stage2Result& fit) {
  f.coefficients = extended_coefficients(f.family, filter, fit);
  f.combinations = determined_combinations(fit, f.components);
  const auto undetermined = [&](int k) {
    return std::any_of(
        f.coefficients.begin(), f.coefficients.end(),
        [&](const FindingCoefficient& c) { return c.catalog == k && c.source.empty(); });
  };
  f.combinations.erase(std::remove_if(f.combinations.begin(), f.combinations.end(),
                                      [&](const DeterminedCombination& c) {
                                        return std::none_of(
                                            c.weights.begin(), c.weights.end(),
                                            [&](const auto& w) { return undetermined(w.first); });
                                      }),
                       f.combinations.end());
}

// The final model against its noise model: the dwells' chi-square at its quantile, the
// filter's NIS per dof.
ResidualCheck residual_check(const FitFigures& fit, const KalmanRun* filter) {
  ResidualCheck c;
  c.dwells_dof = fit.fit.dof;
  c.dwells_chi2 = fit.chi2;
  if (c.dwells_dof > 0) {
    c.dwells_quantile =
        boost::math::quantile(boost::math::chi_squared(c.dwells_dof), kResidualLevel);
    c.dwells_hold = c.dwells_chi2 <= c.dwells_quantile;
    if (!c.dwells_hold) c.dwells_sigma_scale = std::sqrt(c.dwells_chi2 / c.dwells_dof);
  }
  // Few dwells fit a large model closely: their held-out prediction shows what the fit absorbs.
  c.heldout_chi2 = fit.heldout_predictive_chi2;
  c.heldout_inputs = fit.heldout_inputs;
  if (c.heldout_inputs > 0) {
    c.heldout_quantile = heldout_predictive_quantile(fit, kResidualLevel);
    c.heldout_hold = c.heldout_chi2 <= c.heldout_quantile;
    if (!c.heldout_hold) c.heldout_sigma_scale = std::sqrt(c.heldout_chi2 / c.heldout_inputs);
  }
  if (filter) {
    c.filter = true;
    c.nis_per_dof = filter->nis_per_dof;
    // The innovations' tests (whiteness hook, issue 33): per channel, not a fixed NIS limit.
    c.innovations = filter->innovations;
    c.filter_holds = c.innovations.consistent;
    if (!c.filter_holds) c.filter_sigma_scale = std::max(1.0, std::sqrt(c.nis_per_dof));
  }
  return c;
}

const char* const kInputNames[6] = {"accel north", "accel east", "accel down",
                                    "gyro north",  "gyro east",  "gyro down"};

// Where the dwells' residual shows: each input whose whitened residual exceeds its chi-square
// quantile, with its largest dwells.
std::vector<std::string> dwell_signature(const std::vector<DwellResidual>& residuals) {
  std::vector<std::string> out;
  for (int i = 0; i < 6; ++i) {
    double chi2 = 0.0;
    int n = 0;
    std::vector<std::pair<double, std::string>> z;
    for (const auto& r : residuals) {
      if (!std::isfinite(r.after(i)) || !(r.sigma(i) > 0.0)) continue;
      const double zi = r.after(i) / r.sigma(i);
      chi2 += zi * zi;
      ++n;
      z.emplace_back(std::abs(zi), r.label.empty() ? std::to_string(r.dwell) : r.label);
    }
    if (n == 0 || chi2 <= boost::math::quantile(boost::math::chi_squared(n), kResidualLevel))
      continue;
    std::sort(z.begin(), z.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    char b[160];
    std::snprintf(b, sizeof b, "dwells, %s: chi2 %.4g on %d dwells; largest at", kInputNames[i],
                  chi2, n);
    std::string s = b;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, z.size()); ++k) {
      std::snprintf(b, sizeof b, "%s %s (%.1f sigma)", k ? "," : "", z[k].second.c_str(),
                    z[k].first);
      s += b;
    }
    out.push_back(s);
  }
  return out;
}

Unexplained unexplained_of(const TableDiagnosis& d, const std::vector<DwellResidual>& residuals) {
  Unexplained u;
  u.present = !d.check.holds() || !d.rejected.empty();
  if (!u.present) return u;
  char b[200];
  if (!d.check.dwells_hold || !d.check.heldout_hold) {
    std::snprintf(b, sizeof b,
                  "dwells: chi2 %.4g on %d dof (its 99 %% quantile %.4g); held-out predictive "
                  "chi2 %.4g on %d inputs (%.4g)",
                  d.check.dwells_chi2, d.check.dwells_dof, d.check.dwells_quantile,
                  d.check.heldout_chi2, d.check.heldout_inputs, d.check.heldout_quantile);
    u.signature.emplace_back(b);
    const auto where = dwell_signature(residuals);
    u.signature.insert(u.signature.end(), where.begin(), where.end());
  }
  if (!d.check.filter_holds)  // whiteness hook (issue 33): where the innovations fail
    for (const auto& f : d.check.innovations.failures) u.signature.push_back("filter: " + f);
  for (const auto& r : d.rejected)
    if (r.reason.rfind(kTimeOrOrientation, 0) == 0) u.signature.push_back(r.reason);
  for (const auto& r : d.rejected)
    u.signature.push_back("the residual " + r.finding.family + " would have taken (" +
                          (r.finding.source == TableFinding::Source::Dwells ? "dwells" : "turns") +
                          "), refused by the held-out data");
  return u;
}

// The finding's sigmas scaled by the unexplained residual: the largest scale of the data that
// reject the final model (ResidualCheck::sigma_scale).
void scale_sigmas(TableFinding& f, const ResidualCheck& c) {
  for (auto& k : f.coefficients) k.sigma *= c.sigma_scale;
  for (auto& k : f.combinations) k.sigma *= c.sigma_scale;
}

// The turns' test of the final model (the library's, `lib`) joins the check.
void turns_check(ResidualCheck& c, const LibraryFit& lib) {
  if (lib.turn_segments <= 0) return;
  c.turns_tested = true;
  c.turns_chi2 = lib.turns_chi2;
  c.turns_dof = lib.turns_dof;
  c.turns_hold = !lib.turns_reject;
  if (!c.turns_hold && c.turns_dof > 0.0)
    c.turns_sigma_scale = std::max(1.0, std::sqrt(c.turns_chi2 / c.turns_dof));
}

// The sigmas' scale: the largest of the rejecting data's; they hold only if nothing rejects the
// model at the stop (`cap_left`: the findings cap left a significant candidate; `refused`: a
// finding refused).
void honest_sigmas(ResidualCheck& c, const std::string& cap_left, bool refused) {
  c.sigma_scale = std::max(
      {c.dwells_sigma_scale, c.heldout_sigma_scale, c.filter_sigma_scale, c.turns_sigma_scale});
  std::vector<std::string> why;
  if (!c.dwells_hold) why.emplace_back("the dwells reject the noise model");
  if (!c.heldout_hold) why.emplace_back("the held-out dwells reject it");
  if (!c.filter_holds) why.emplace_back("the filter's innovations reject it");
  if (!c.turns_hold) why.emplace_back("the turns' attitude residual rejects it");
  if (refused) why.emplace_back("a finding was refused by the held-out data");
  if (!cap_left.empty()) why.push_back("the findings cap left " + cap_left + " significant");
  c.sigmas_hold = why.empty();
  if (c.sigmas_hold) return;
  std::string s;
  for (const auto& w : why) s += (s.empty() ? "" : "; ") + w;
  char b[160];
  std::snprintf(b, sizeof b,
                ": the model is incomplete, the sigmas (scaled x%.3g) are a lower bound and do "
                "not hold",
                c.sigma_scale);
  c.sigmas_note = s + b;
}

// The plan cannot tell the finding's family from a library term (HeldoutContest::alternative):
// the finding becomes a set the plan cannot separate, reported as an ambiguous set of families is
// (the term beside the family, with what separates it), the model extended with the family (the
// catalog's: the model holds no library term), not as the family alone.
void pair_with_term(TableFinding& f, const HeldoutContest& c) {
  f.library_alternative = c.reason();
  f.alternative_term = c.term;
  f.ambiguous_with.push_back(c.term.name());
  f.separated_by.push_back(c.term.separated_by);
  for (const auto& t : c.others) {  // every term the contest finds as good: one set
    f.ambiguous_with.push_back(t.name());
    f.separated_by.push_back(t.separated_by);
  }
  if (f.picked_by.empty()) f.picked_by = "catalog";
}

// The held-out turns gain at least q with the finding: their chi-square falls by q or more, in
// their residual's scale where it exceeds 1 per dof (as heldout_refusal scales the dwells').
bool turns_confirm(const TableFinding& f, double q) {
  if (!f.filter || !f.turns_before || !f.turns_after || f.turns_before->turns == 0 ||
      f.turns_after->turns == 0 || f.turns_after->dof == 0)
    return false;
  const double scale = std::max(1.0, f.turns_after->chi2 / f.turns_after->dof);
  return (f.turns_before->chi2 - f.turns_after->chi2) / scale >= q;
}

// Why the held-out data refuse the finding `f` (empty: they do not). The extension must gain on
// the held-out dwells (a dwell finding: their chi-square falls by more than the chi-square
// quantile of its dof at 1 - alpha, the gain the in-sample test itself asks for), must not lose
// the filter's log-likelihood (by more than half that quantile), and must not worsen the
// held-out turns (a turn finding: must improve them by the same quantile, turns_confirm; a gain of
// any size let MEMS turns' families be named on a few hundredths of a sigma while the held-out
// velocity got worse, issue 33). `before` and `after` (a dwell finding): the dwells' fits before
// and with the finding.
std::string refusal_of(const TableFinding& f, double alpha, const FitFigures* before = nullptr,
                       const FitFigures* after = nullptr) {
  const double q = boost::math::quantile(boost::math::chi_squared(std::max(1, f.dof)), 1.0 - alpha);
  char b[200];
  if (f.source == TableFinding::Source::Dwells && before && after) {
    const std::string dwells = diagnosis_detail::heldout_refusal(*before, *after, f.dof, alpha);
    // A plan of few dwells (seed8's 8) cannot predict a left-out dwell's share of a large family;
    // the held-out turns, which the effect acts in too, then confirm it by the same quantile.
    if (!dwells.empty() && !turns_confirm(f, q)) return "on the dwells, " + dwells;
  }
  if (!f.filter) return "";
  const double dll = f.log_likelihood_after - f.log_likelihood_before;
  if (dll < -0.5 * q) {
    std::snprintf(b, sizeof b, "the filter's log-likelihood falls by %.3g", -dll);
    return b;
  }
  if (f.turns_before && f.turns_after && f.turns_before->turns > 0 && f.turns_after->turns > 0) {
    const double gain = f.turns_before->chi2 - f.turns_after->chi2;
    const bool turns = f.source == TableFinding::Source::Turns;
    if (turns ? !turns_confirm(f, q) : gain < -q) {
      std::snprintf(b, sizeof b,
                    "the held-out turns' chi-square goes from %.4g to %.4g (velocity %.3g -> %.3g "
                    "mm/s)",
                    f.turns_before->chi2, f.turns_after->chi2, f.turns_before->velocity * 1e3,
                    f.turns_after->velocity * 1e3);
      return b;
    }
  }
  return "";
}

// The turns' pick is close (`scored`: each member's held-out turns' chi-square, lowest first):
// the runner-up within the chi-square quantile of one dof at 1 - alpha. The statement, else "".
std::string close_pick_note(const std::vector<std::pair<double, std::string>>& scored,
                            double alpha) {
  if (scored.size() < 2) return "";
  const double need = boost::math::quantile(boost::math::chi_squared(1), 1.0 - alpha);
  const double gap = scored[1].first - scored[0].first;
  if (gap >= need) return "";
  char b[400];
  std::snprintf(b, sizeof b,
                "close: the held-out turns' chi2 is %.4g with %s and %.4g with %s (%.3g apart, "
                "%.3g needed to choose); the turns do not tell them apart on this session",
                scored[0].first, scored[0].second.c_str(), scored[1].first,
                scored[1].second.c_str(), gap, need);
  return b;
}

// The rounds of one diagnosis: both tests against one current model.
class TableRounds {
 public:
  TableRounds(const std::vector<EquivalentInputs>& inputs, const Site& site,
              const Stage2Options& base, const TableDiagnosisOptions& o, const TurnModel* tm)
      : o_(o),
        tm_(tm),
        families_(candidate_families(o.dwells)),
        dwells_(inputs, site, dwells_model(base, tm), graded(o.dwells, tm)) {
    DiagnosisReport& rep = d_.dwells;
    rep.alpha = o.dwells.alpha;
    rep.inputs = dwells_.inputs();
    rep.initial_parameters = dwells_.base().parameters;
    rep.initial = dwells_.fit(rep.initial_parameters);
    current_ = rep.initial_parameters;
    now_ = rep.initial;
    if (tm && tm->session && tm->run_filter) {
      session_ = tm->session;
      turns_.emplace(*tm->session, tm->base, o.turns);
      KalmanDiagnosis k;
      k.alpha = o.dwells.alpha;
      k.initial_families.assign(tm->base.layout.extended.begin(), tm->base.layout.extended.end());
      k.initial_nis_per_dof = turns_->now().nis_per_dof;
      k.initial_log_likelihood = turns_->now().log_likelihood;
      d_.turns = std::move(k);
    }
  }

  // One round; false when nothing was significant.
  bool round() {
    std::vector<CandidateTest> dround = dwells_.round(current_, now_);
    std::vector<KalmanCandidateTest> kround;
    if (turns_) {
      drop_turn_found(dround, turns_->model(), current_);
      kround = turns_->round(turn_families(families_, dround, turns_->model(), o_.dwells.alpha));
    }
    // One family-wise level over both tests.
    const auto tested_d = std::count_if(dround.begin(), dround.end(),
                                        [](const CandidateTest& c) { return c.dof > 0; });
    const auto tested_k = std::count_if(kround.begin(), kround.end(),
                                        [](const KalmanCandidateTest& c) { return c.dof > 0; });
    const double threshold =
        o_.dwells.alpha / static_cast<double>(std::max<std::ptrdiff_t>(1, tested_d + tested_k));
    CandidateTest* best_d = diagnosis_detail::choose(
        dround, threshold * static_cast<double>(std::max<std::ptrdiff_t>(1, tested_d)));
    KalmanCandidateTest* best_k = most_significant(kround, threshold);
    std::optional<TableFinding> f;
    if (best_d) {  // the dwells first (see the header)
      std::string verdict;
      const bool pair = time_or_temperature(*best_d, verdict);
      f = extend_dwells(*best_d, dround);
      f->time_temperature = verdict;
      if (pair && f->picked_by == "data") f->picked_by = "temperature first (ramp)";
    } else if (best_k)
      f = extend_turns(*best_k);
    d_.dwells.rounds.push_back(dround);
    if (turns_) d_.turns->rounds.push_back(kround);
    last_turn_round_ = kround;
    ++d_.rounds;
    if (!f) return false;
    bool heldout = false;
    std::string refused = judge(*f, heldout);
    if (refused.empty()) {
      named(std::move(*f));
      return true;
    }
    withdraw(*f);
    // A dwell finding the held-out data refuse while the round holds a significant turns'
    // candidate: the refusal may be the turns' effect the model lacks (a MEMS gyro.scale_asym
    // worsens the held-out turns of a model extended with the true gyro.bias_drift alone on seed8:
    // 7 of 30 seeds ended there, issue 33). The next candidate, the turns', is judged; the
    // refused finding is judged again in the next round, with the turns' finding in the model.
    KalmanCandidateTest* next =
        heldout && f->source == TableFinding::Source::Dwells && best_k &&
                best_k->family != f->family
            ? &d_.turns->rounds.back()[static_cast<std::size_t>(best_k - kround.data())]
            : nullptr;
    if (!next) {
      if (deferred_ && deferred_->finding.family == f->family) deferred_.reset();  // judged again
      d_.rejected.push_back({std::move(*f), refused});
      return false;
    }
    if (deferred_ && deferred_->finding.family != f->family) {  // another, not judged again
      deferred_->reason += "; not judged again after the turns' findings (another was refused)";
      d_.rejected.push_back(std::move(*deferred_));
    }
    deferred_ = RejectedFinding{std::move(*f), refused};
    TableFinding g = extend_turns(*next);
    refused = judge(g, heldout);
    if (!refused.empty()) {
      withdraw(g);
      d_.rejected.push_back({std::move(g), refused});
      return false;
    }
    named(std::move(g));
    return true;
  }

  TableDiagnosis finish() {
    if (deferred_) {  // refused, and the diagnosis stopped before judging it again
      deferred_->reason += "; not judged again after the turns' findings (the diagnosis stopped)";
      d_.rejected.push_back(std::move(*deferred_));
      deferred_.reset();
    }
    DiagnosisReport& rep = d_.dwells;
    if (!rep.rounds.empty()) rep.not_separable = diagnosis_detail::not_separable(rep.rounds.back());
    rep.final_parameters = current_;
    rep.final_fit = now_;
    // The checks judge the findings' whole families (with_whole_families); the calibration the
    // report gives stays the dwells' fit of what they separate.
    const std::vector<int> judged = with_whole_families(current_, d_.findings);
    rep.residuals = dwells_.residuals(rep.initial_parameters, judged);
    if (turns_) {
      for (const auto& c : last_turn_round_)
        if (c.dof == 0) d_.turns->not_separable.push_back(c);
      d_.turns->final_run = turns_->now();
    }
    d_.check = residual_check(judged == current_ ? now_ : dwells_.fit(judged),
                              turns_ ? &turns_->now() : nullptr);
    for (auto& f : d_.findings) {
      final_magnitudes(f, turns_ ? &turns_->now() : nullptr, rep.final_fit.fit);
      if (f.picked_by == "turns" && f.pick_gap) try {
          separability(f);
        } catch (const std::exception& e) {  // a statement, never the diagnosis's stop
          f.separability =
              std::string("whether the plan separates the pair: not computed (") + e.what() + ")";
        }
    }
    const std::vector<int> confirmed = demote_unexplaining();
    d_.unexplained = unexplained_of(d_, rep.residuals);
    library(with_whole_families(confirmed, d_.findings));
    const std::string cap_left = state_stops();
    honest_sigmas(d_.check, cap_left, !d_.rejected.empty());
    for (auto& f : d_.findings) scale_sigmas(f, d_.check);
    for (auto& r : d_.rejected) scale_sigmas(r.finding, d_.check);
    return std::move(d_);
  }

  int findings() const { return static_cast<int>(d_.findings.size()); }

 private:
  // The finding `f` of this round joins the filter's model and is judged by the held-out data
  // (refusal_of; `heldout` true when they refuse it), then by the time-or-orientation check and
  // the library's contest. The refusal, else "".
  std::string judge(TableFinding& f, bool& heldout) {
    f.round = d_.rounds;
    f.separated_by.push_back(coefficient_family_info(f.family).separated_by);
    for (const auto& a : f.ambiguous_with)
      f.separated_by.push_back(coefficient_family_info(a).separated_by);
    extend_filter(f);
    // The round judges a dwell finding's fits of this round (its separable components); the final
    // checks judge whole families. Judging whole families here too refused a hidden seed8
    // g-sensitivity in the dwells-only diagnosis, where no turns confirm it (the Monte Carlo of
    // tests/test_diagnosis.cpp: named first 29 -> 26 of 30), and did not change the table
    // diagnosis's one seed8 MEMS miss (seed 21009, refused by the final check).
    std::string refused =
        refusal_of(f, o_.dwells.alpha, f.dwells_before ? &*f.dwells_before : nullptr,
                   f.dwells_after ? &*f.dwells_after : nullptr);
    heldout = !refused.empty();
    if (refused.empty()) refused = time_or_orientation_checked(f);
    if (refused.empty()) refused = library_contest(f);
    return refused;
  }

  // The finding `f`, judged, joins the story; a finding refused in an earlier round before a
  // turns' finding joined the model says so.
  void named(TableFinding f) {
    if (deferred_ && deferred_->finding.family == f.family) {
      f.refused_before =
          "round " + std::to_string(deferred_->finding.round) + ": " + deferred_->reason;
      deferred_.reset();
    }
    d_.findings.push_back(std::move(f));
  }

  // What the library needs of the turns (the session's log read again): none without a session
  // or without attitude updates (no table attitude to integrate against).
  std::optional<LibraryTurns> library_turns() const {
    if (!tm_ || !tm_->session || tm_->base.attitude == CalibratorOptions::AttitudeUpdates::None)
      return std::nullopt;
    LibraryTurns lt;
    lt.session = tm_->session;
    lt.attitude_sigma = tm_->base.attitude_sigma;
    lt.noise = tm_->base.noise;
    lt.about = tm_->base.initial_model ? &*tm_->base.initial_model : nullptr;
    lt.thermal = o_.dwells.thermal;  // the temperature terms of the turns (a ramp)
    lt.reference_temperature_c = tm_->base.reference_temperature_c;
    if (!motion_) motion_ = with_motion(lt).motion;  // once per session
    lt.motion = motion_;
    return lt;
  }

  // Why a time family's finding (a bias drift) is not named although the held-out data confirm a
  // gain: the residual's time structure may be the orientation's, since a plan orders its
  // orientations in time. Dwells revisiting an orientation later in time decide (revisit_check:
  // the drift the dwells fitted predicts its trend between the visits, an effect of the
  // orientation none); without revisits (or none with an input estimated at both visits), with the
  // turns, the library's orientation terms contest it (orientation_rival). Empty: named. Issue 33:
  // a MEMS f_y f_z on seed8 and timing jitter on nav-fog rot19 were named accel.bias_drift first on
  // 5 and 7 seeds of 30.
  std::string time_or_orientation(const TableFinding& f) const {
    if (f.source != TableFinding::Source::Dwells || !is_time_family(f.family) || !f.dwells_after)
      return "";
    const Stage2Result& fit = f.dwells_after->fit;
    Eigen::VectorXd values = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(f.components.size()));
    for (std::size_t k = 0; k < f.components.size(); ++k) {
      const auto it = std::find(fit.parameters.begin(), fit.parameters.end(), f.components[k]);
      const auto i = it - fit.parameters.begin();
      if (it != fit.parameters.end() && fit.observable[static_cast<std::size_t>(i)])
        values(static_cast<Eigen::Index>(k)) = fit.theta(i);
    }
    const RevisitCheck r = revisit_check(dwells_.dwell_inputs(), dwells_.site(), dwells_.base(),
                                         f.components, values, o_.dwells.alpha);
    const std::string set =
        std::string(kTimeOrOrientation) + " (" + f.family + " or an effect of the orientation): ";
    if (r.pairs > 0 && r.rows > 0)
      return r.contradicts ? set + r.text() +
                                 " (a drift predicts its trend between the visits of an "
                                 "orientation, an effect of the orientation none)"
                           : "";
    return orientation_rival(f, set, r.pairs > 0);
  }

  // time_or_orientation, whose failure (a revisits' covariance that does not factor) is the
  // finding's refusal with its cause, never the diagnosis's stop: unchecked, the time structure
  // is not shown to be time's.
  std::string time_or_orientation_checked(const TableFinding& f) const {
    try {
      return time_or_orientation(f);
    } catch (const std::exception& e) {
      return std::string(kTimeOrOrientation) + " (" + f.family +
             " or an effect of the orientation): not computed (" + e.what() + ")";
    }
  }

  // A plan that visits each orientation once: the drift is not named when a function of the
  // orientation alone (a library product of the specific force) predicts its share of the
  // held-out dwells and turns as well (contest_family, orientation terms only). Issue 33: on seed8
  // the eight orientations' order in time makes accel x's drift, with the y misalignment
  // projected out, the f_y f_z product on the four roll dwells (+1, -1, +1, -1 in time); a
  // hidden MEMS f_y f_z x3 was named accel.bias_drift first on 5 seeds of 30.
  // Without the turns the held-out dwells alone do not hold the rival (dwells only, a true
  // gyro.bias_drift on seed8 lost to a product on 11 of 30 seeds): the drift is named.
  std::string orientation_rival(const TableFinding& f, const std::string& set,
                                bool revisits) const {
    const auto lt = library_turns();
    if (!lt) return "";
    const HeldoutContest c = contest_family(dwells_, contest_base(f), f.components, o_.dwells.alpha,
                                            lt ? &*lt : nullptr, true);
    if (!c.replaced && !c.alternative) return "";
    return set + c.reason() +
           (revisits ? "; no input is estimated at both visits of an orientation (dwells "
                       "revisiting an orientation later in time, with that input, separate them)"
                     : "; the plan visits each orientation once (dwells revisiting an orientation "
                       "later in time separate them)");
  }

  // The model a contest of the finding `f` extends: the dwells' before the finding, with the turn
  // findings named.
  std::vector<int> contest_base(const TableFinding& f) const {
    std::vector<int> base = current_;
    if (f.source == TableFinding::Source::Dwells)
      base.resize(base.size() - std::min(base.size(), f.components.size()));
    for (const auto& g : d_.findings)
      if (g.source == TableFinding::Source::Turns)
        for (int k : g.components)
          if (std::find(base.begin(), base.end(), k) == base.end()) base.push_back(k);
    return base;
  }

  // Why the finding `f` is not named although the held-out data confirm a gain: a library term
  // explains its share of the held-out dwells and turns better (contest_family; empty: none
  // does; one that explains it as well is stated as its alternative). The model the contest
  // extends: the dwells' before the finding, with the turn findings named.
  std::string library_contest(TableFinding& f) const {
    const auto lt = library_turns();
    const HeldoutContest c = contest_family(dwells_, contest_base(f), f.components, o_.dwells.alpha,
                                            lt ? &*lt : nullptr);
    if (c.alternative) pair_with_term(f, c);
    return c.replaced ? c.reason() : "";
  }

  // The out-of-catalog library (term_library.hpp) on what the model leaves: its turns' test
  // (with a session) makes the residual unexplained too.
  void library(const std::vector<int>& confirmed) {
    const auto lt = library_turns();
    LibraryFit fit = fit_term_library(dwells_, with_turn_findings(confirmed, d_.findings),
                                      o_.dwells.alpha, lt ? &*lt : nullptr, d_.unexplained.present);
    turns_check(d_.check, fit);
    if (fit.turns_reject) {
      d_.unexplained.present = true;
      d_.unexplained.signature.push_back(fit.turns_signature);
    }
    if (d_.unexplained.present) d_.unexplained.library = std::move(fit);
  }

  // A finding whose data still reject the noise model with it (the dwells' findings against the
  // dwells' residual, the turns' against the filter's NIS) does not explain the evidence: it is
  // moved to `rejected`, not named. Returns the dwells' model without them (the library fits
  // what that model leaves).
  std::vector<int> demote_unexplaining() {
    std::vector<int> confirmed = d_.dwells.initial_parameters;
    std::vector<TableFinding> kept;
    char b[200];
    for (auto& f : d_.findings) {
      const bool dwells = f.source == TableFinding::Source::Dwells;
      // The held-out dwells' rejection stands unless the held-out turns, which a dwell effect
      // acts in too, confirm the finding (as refusal_of: few dwells cannot predict a left-out
      // dwell's share of a large family held by a weak prior).
      const double q = boost::math::quantile(boost::math::chi_squared(std::max(1, f.dof)),
                                             1.0 - o_.dwells.alpha);
      const bool holds =
          dwells ? d_.check.dwells_hold && (d_.check.heldout_hold || turns_confirm(f, q))
                 : d_.check.filter_holds;
      if (holds) {
        if (dwells) confirmed.insert(confirmed.end(), f.components.begin(), f.components.end());
        kept.push_back(std::move(f));
        continue;
      }
      if (dwells && !d_.check.dwells_hold)
        std::snprintf(b, sizeof b,
                      "with the findings the dwells' residual still rejects the noise model "
                      "(chi2 %.4g on %d dof, 99 %% quantile %.4g)",
                      d_.check.dwells_chi2, d_.check.dwells_dof, d_.check.dwells_quantile);
      else if (dwells)
        std::snprintf(b, sizeof b,
                      "with the findings the held-out dwells still reject the noise model "
                      "(predictive chi2 %.4g on %d inputs, 99 %% quantile %.4g)",
                      d_.check.heldout_chi2, d_.check.heldout_inputs, d_.check.heldout_quantile);
      d_.rejected.push_back({std::move(f), dwells
                                               ? std::string(b)
                                               : "with the findings the filter's innovations are " +
                                                     d_.check.innovations.verdict});
    }
    d_.findings = std::move(kept);
    return confirmed;
  }

 public:
 private:
  // Every stop and limit of the search (TableDiagnosis::stops). Returns the candidate the
  // findings cap left significant ("": none).
  std::string state_stops() {
    std::string cap_left;
    for (const auto& r : d_.rejected)
      d_.stops.push_back(refused_stop(r.finding.round, r.finding.family, r.finding.p_value,
                                      r.reason, "its residual is unexplained"));
    if (findings() >= o_.dwells.max_findings) {
      std::vector<CandidateTest> more = dwells_.round(current_, now_);
      const CandidateTest* best = diagnosis_detail::best_of(more, o_.dwells.alpha);
      if (best) cap_left = best->family;
      d_.stops.push_back(findings_cap_stop(o_.dwells.max_findings, "on the dwells", cap_left));
    }
    if (!o_.dwells.thermal && o_.dwells.candidates.empty())
      d_.stops.emplace_back(
          "thermal families not tested: the log's temperature does not vary (a chamber or a ramp "
          "tests them)");
    if (!turns_)
      d_.stops.emplace_back(
          "the effects of the turns (families the dwells do not separate) not tested: no filter "
          "run (no sensor profile, or --no-kalman)");
    return cap_left;
  }

 public:
 private:
  // The family of an ambiguous set the turns pick: each run in the filter, the best innovation
  // log-likelihood (the turns sweep each axis through every specific-force level between the
  // dwells' and so tell K2 from the scale asymmetry). Empty: no set, no filter, or the user's pick.
  std::string turns_pick(const CandidateTest& best) {
    pick_note_.clear();
    pick_gap_.reset();
    std::vector<std::string> set = {best.family};
    for (const auto& c : best.ambiguous_with)
      if (std::find(set.begin(), set.end(), c.family) == set.end()) set.push_back(c.family);
    if (!turns_ || set.size() < 2) return "";
    for (const auto& f : o_.dwells.prefer)
      if (std::find(set.begin(), set.end(), f) != set.end()) return "";
    set.erase(std::remove_if(set.begin(), set.end(),
                             [&](const std::string& f) { return turns_->model().layout.on(f); }),
              set.end());
    if (set.size() < 2) return "";
    return heldout_pick(set);
  }

  // The member whose model predicts the held-out turns best (the lowest chi-square of the first
  // update after each held-out turn, learnt from the other turns and the dwells: a turn sweeps
  // each axis through the specific-force levels the dwells lack); where no member's held-out turns
  // can be scored, the best innovation log-likelihood of the filter run with it. When the
  // runner-up's held-out chi-square is within the chi-square quantile of one dof at 1 - alpha of
  // the pick's, the turns do not choose: `pick_note_` says so with both figures (MEMS K2 against
  // the scale asymmetry on rot19 at 5-10 sigmas: K2 picked on 13 seeds of 29, issue 33).
  std::string heldout_pick(const std::vector<std::string>& set) {
    std::string pick;
    std::vector<std::pair<double, std::string>> scored;
    for (const auto& f : set) {
      CalibratorOptions m = turns_->model();
      m.layout.set(f, true);
      const HeldoutTurns h = heldout_turns(*session_, m);
      if (h.turns > 0) scored.emplace_back(h.chi2, f);
    }
    std::sort(scored.begin(), scored.end());
    pick_note_ = close_pick_note(scored, o_.dwells.alpha);
    pick_gap_.reset();
    if (scored.size() >= 2) pick_gap_ = scored[1].first - scored[0].first;
    if (!scored.empty()) return scored.front().second;
    double best_ll = -std::numeric_limits<double>::infinity();
    for (const auto& c : turns_->round(set))
      if (c.failed.empty() && c.log_likelihood > best_ll) {
        best_ll = c.log_likelihood;
        pick = c.family;
      }
    return pick;
  }

  // The turns' pick of a pair: whether this plan can tell the pair apart at all, from its
  // information at the size found (pair_separation), and what the plan with its turns split in
  // halves gives (tilted dwells); a pick the plan cannot make is stated so however far apart
  // this session's held-out figures are (MEMS K2 on rot19: 3 of 29 "decided" beyond 6.63, all
  // for the asymmetry, wrongly). Only the first member of the set with as many components.
  void separability(TableFinding& f) const {
    if (!session_ || !session_->plan.has_site) return;
    const auto& cat = coefficient_catalog();
    std::vector<double> size;
    for (std::size_t k = 0; k < cat.size(); ++k)
      if (cat[k].family == f.family) {
        double v = 0.0;
        for (const auto& c : f.coefficients)
          if (c.catalog == static_cast<int>(k)) v = c.value;
        size.push_back(v);
      }
    const auto n = static_cast<std::ptrdiff_t>(size.size());
    for (const auto& other : f.ambiguous_with) {
      if (std::count_if(cat.begin(), cat.end(),
                        [&](const CoefficientInfo& c) { return c.family == other; }) != n)
        continue;
      const CalibratorOptions& m = turns_->model();
      f.separation = pair_separation(session_->plan, m, f.family, other, size);
      const Plan split = split_turns(session_->plan);
      if (split.steps.size() > session_->plan.steps.size())
        f.separating = pair_separation(split, m, f.family, other, size, false);
      const double need = boost::math::quantile(boost::math::chi_squared(1), 1.0 - o_.dwells.alpha);
      f.separability = separation_statement(*f.separation, f.separating ? &*f.separating : nullptr,
                                            need, *f.pick_gap);
      return;
    }
  }

  // A bias's degree-1 temperature term against a drift of the same bias in time (a session whose
  // temperature varies; the drift waits for the temperature term, candidate_components). On a
  // ramp time and temperature rise together, so the round's order is no verdict: the held-out
  // dwells decide. The temperature term stands alone when it predicts them better than the drift
  // by more than the chi-square quantile of one dof at 1 - alpha; otherwise the pair is reported
  // as an ambiguous set (the model extended with the temperature term, or the turns' pick). The
  // drift is not named alone even where it predicts better: with every thermal family hidden a
  // line in time predicted an all-hidden ramp's quadratic in temperature better than the line
  // in temperature (seed 1), and the findings it led to were all refused (issue 33). True when
  // the pair was made; the statement in `verdict`.
  bool time_or_temperature(CandidateTest& best, std::string& verdict) {
    const std::string tail = ".bias_temp1";
    if (!o_.dwells.thermal || best.family.size() <= tail.size() ||
        best.family.compare(best.family.size() - tail.size(), tail.size(), tail) != 0 ||
        best.with.heldout_inputs == 0)
      return false;
    const std::string drift =
        best.family.substr(0, best.family.size() - tail.size()) + ".bias_drift";
    std::vector<int> with = current_, added;
    const auto& cat = coefficient_catalog();
    for (std::size_t k = 0; k < cat.size(); ++k)
      if (cat[k].family == drift && std::find(with.begin(), with.end(), k) == with.end())
        added.push_back(static_cast<int>(k));
    if (added.empty()) return false;
    with.insert(with.end(), added.begin(), added.end());
    CandidateTest d;
    d.family = drift;
    d.separable = added;
    d.with = dwells_.fit(with);
    if (d.with.heldout_inputs == 0) return false;
    const double need = boost::math::quantile(boost::math::chi_squared(1), 1.0 - o_.dwells.alpha);
    const double ht = best.with.heldout_predictive_chi2, hd = d.with.heldout_predictive_chi2;
    const bool pair = ht + need >= hd;
    char b[400];
    std::snprintf(b, sizeof b,
                  "held-out dwells' predictive chi2 %.4g with %s, %.4g with %s instead (%.3g "
                  "needed to choose)%s",
                  ht, best.family.c_str(), hd, drift.c_str(), need,
                  pair ? ": time and temperature not told apart on this session (a soak, "
                         "temperature held while time runs, separates them)"
                       : ": the temperature term");
    verdict = b;
    if (!pair) return false;
    best.ambiguous_with.push_back(std::move(d));
    best.named = false;
    return true;
  }

  // Back to the model before the finding `f` (extend_dwells, extend_filter), which the held-out
  // data refuse.
  void withdraw(const TableFinding& f) {
    if (f.source == TableFinding::Source::Dwells) {
      d_.dwells.findings.pop_back();
      current_.resize(current_.size() - f.components.size());
      now_ = *f.dwells_before;
      for (auto& c : d_.dwells.rounds.back()) c.named = false;
    } else {
      d_.turns->findings.pop_back();
      for (auto& c : d_.turns->rounds.back()) c.named = false;
    }
    if (turns_ && before_) turns_->restore(std::move(*before_));
    heldout_now_ = f.turns_before;
  }

  TableFinding extend_dwells(CandidateTest& best, std::vector<CandidateTest>& round) {
    DiagnosisReport& rep = d_.dwells;
    if (!best.named) rep.ambiguous.push_back(best);
    const std::string by_turns = turns_pick(best);
    CandidateTest member =
        pick_member(best, by_turns.empty() ? o_.dwells.prefer : std::vector<std::string>{by_turns});
    if (!by_turns.empty()) member.picked_by = "turns";
    for (auto& c : round) c.named = c.family == member.family && c.separable == member.separable;
    TableFinding f = dwell_finding(member);
    if (!by_turns.empty()) {
      f.pick_note = pick_note_;
      f.pick_gap = pick_gap_;
    }
    f.dwells_before = now_;
    rep.findings.push_back(member);
    current_.insert(current_.end(), member.separable.begin(), member.separable.end());
    now_ = member.with;
    return f;
  }

  TableFinding extend_turns(KalmanCandidateTest& best) {
    best.named = true;
    d_.turns->findings.push_back(best);
    return turn_finding(best);
  }

  // The filter's model extended with the finding, its gain before and after.
  void extend_filter(TableFinding& f) {
    if (!turns_) return;
    f.filter = true;
    f.nis_before = turns_->now().nis_per_dof;
    f.log_likelihood_before = turns_->now().log_likelihood;
    if (o_.heldout_turns && !heldout_now_) heldout_now_ = turns_->heldout();
    f.turns_before = heldout_now_;
    before_ = turns_->state();
    turns_->extend(f.family);
    f.nis_after = turns_->now().nis_per_dof;
    f.log_likelihood_after = turns_->now().log_likelihood;
    if (o_.heldout_turns) {
      heldout_now_ = turns_->heldout();
      f.turns_after = heldout_now_;
    }
  }

  // The dwells' options with priors of the session's grade (grade_priors).
  static DiagnosisOptions graded(const DiagnosisOptions& o, const TurnModel* tm) {
    DiagnosisOptions g = o;
    if (tm && g.prior_sigma.empty()) g.prior_sigma = grade_priors(tm->base);
    return g;
  }

  const TableDiagnosisOptions& o_;
  const TurnModel* tm_ = nullptr;
  const Session* session_ = nullptr;
  std::vector<std::string> families_;
  DwellTests dwells_;
  std::optional<TurnTests> turns_;
  TableDiagnosis d_;
  std::vector<int> current_;
  FitFigures now_;
  std::optional<HeldoutTurns> heldout_now_;
  std::optional<TurnTests::State> before_;
  // A dwell finding refused by the held-out data while a turns' candidate was taken instead, to be
  // judged again (round()).
  std::optional<RejectedFinding> deferred_;
  std::vector<KalmanCandidateTest> last_turn_round_;
  std::string pick_note_;           // heldout_pick's close_pick_note
  std::optional<double> pick_gap_;  // heldout_pick's runner-up's chi2 minus the pick's
  // The table's known motion for the library's turns, built at the first library fit (a cache:
  // the session's plan does not change).
  mutable std::shared_ptr<const Motion> motion_;
};

}  // namespace

namespace {

// The gyro bias of a pass turns the dwells' navigation beyond small angles: its largest
// component times the plan's longest dwell above kSmallAngle (a MEMS unit's 0.1-0.5 deg/s over
// 30 s dwells is 3-15 deg; stage 1 linearizes the attitude error about zero).
bool beyond_small_angles(const KalmanRun& pass, const Session& session) {
  double longest = 0.0;
  for (const auto& d : PlanTimeline::of(session.plan, session.site).dwells)
    longest = std::max(longest, d.t_end - d.t_start);
  const auto& cat = coefficient_catalog();
  double bias = 0.0;
  for (std::size_t k = 0; k < cat.size() && k < pass.estimates.size(); ++k)
    if (cat[k].family == "gyro.bias") bias = std::max(bias, std::abs(pass.estimates[k].value));
  return bias * longest > kSmallAngle;
}

}  // namespace

std::optional<ImuErrorModel> linearize(TurnModel& model, int passes, std::string* failed) {
  if (!model.session || passes == 1) return std::nullopt;
  KalmanRunOptions run;
  run.nis_alarm_z = std::numeric_limits<double>::infinity();
  if (passes == 0) {
    const KalmanRun one = run_kalman(*model.session, model.base, nullptr, run);
    if (!one.stopped.empty() || !one.diverged.empty() ||
        (one.nis_per_dof <= kRelinearizeNis && !beyond_small_angles(one, *model.session)))
      return std::nullopt;  // a run that stops is reported by the diagnosis' own first run
    passes = 3;
  }
  run.passes = passes;
  const KalmanRun r = run_kalman(*model.session, model.base, nullptr, run);
  if (!r.stopped.empty() || !r.diverged.empty()) {
    if (failed) *failed = r.stopped + r.diverged;
    return std::nullopt;
  }
  model.base.initial_model = r.model;
  if (r.installation.base_estimated) model.base.initial_base_n = r.installation.base_n;
  return r.model;
}

TableDiagnosis diagnose_table(const std::vector<EquivalentInputs>& inputs, const Site& site,
                              const Stage2Options& base, const TableDiagnosisOptions& o,
                              const TurnModel* turn_model) {
  TableRounds rounds(inputs, site, base, o, turn_model);
  while (rounds.findings() < o.dwells.max_findings && rounds.round()) {
  }
  return rounds.finish();
}

}  // namespace sinscal
