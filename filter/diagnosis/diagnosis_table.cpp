#include "filter/diagnosis/diagnosis_table.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "models/coefficient_families.hpp"

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

// The families the turns' test takes this round: candidates with no component the dwells
// separate, not yet in the filter's model.
std::vector<std::string> turn_families(const std::vector<std::string>& candidates,
                                       const std::vector<CandidateTest>& dwell_round,
                                       const CalibratorOptions& model) {
  std::vector<std::string> out;
  for (const auto& f : candidates) {
    if (model.layout.on(f)) continue;
    const bool seen = std::any_of(dwell_round.begin(), dwell_round.end(), [&](const auto& c) {
      return c.family == f && !c.separable.empty();
    });
    if (!seen) out.push_back(f);
  }
  return out;
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

TurnModel turn_model_of(const Session& session, const SensorProfile& profile, double table_sigma) {
  TurnModel t;
  t.session = &session;
  t.base = calibrator_options_from_profile(profile);
  t.base.attitude_sigma = table_sigma;
  t.base.time_offset = session.time_offset;
  return t;
}

namespace {

// The dwells' model: the base coefficients plus the profile's extended families (the model
// both tests use).
Stage2Options dwells_model(const Stage2Options& base, const TurnModel* turn_model) {
  Stage2Options model = base;
  if (!turn_model) return model;
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k) {
    const int c = static_cast<int>(k);
    if (!coefficient_family_info(cat[k].family).base && turn_model->base.layout.on(cat[k].family) &&
        std::find(model.parameters.begin(), model.parameters.end(), c) == model.parameters.end())
      model.parameters.push_back(c);
  }
  return model;
}

// A dwell finding from the member that extends the model.
TableFinding dwell_finding(const CandidateTest& member) {
  TableFinding f;
  f.source = TableFinding::Source::Dwells;
  f.family = member.family;
  f.components = member.separable;
  for (const auto& c : member.ambiguous_with)
    if (c.family != member.family && std::find(f.ambiguous_with.begin(), f.ambiguous_with.end(),
                                               c.family) == f.ambiguous_with.end())
      f.ambiguous_with.push_back(c.family);
  f.picked_by = member.picked_by;
  f.test = member.test;
  f.statistic = member.statistic;
  f.dof = member.dof;
  f.dof2 = member.dof2;
  f.p_value = member.p_value;
  f.log10_p = member.log10_p;
  f.threshold = member.threshold;
  f.base_shift_sigma = member.base_shift_sigma;
  f.dwells_after = member.with;
  return f;
}

TableFinding turn_finding(const KalmanCandidateTest& c) {
  TableFinding f;
  f.source = TableFinding::Source::Turns;
  f.family = c.family;
  f.components = c.catalog;
  f.test = "wald";
  f.statistic = c.wald;
  f.dof = c.dof;
  f.p_value = c.p_value;
  f.log10_p = c.log10_p;
  f.threshold = c.threshold;
  f.base_shift_sigma = c.base_shift_sigma;
  return f;
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

// The rounds of one diagnosis: both tests against one current model.
class TableRounds {
 public:
  TableRounds(const std::vector<EquivalentInputs>& inputs, const Site& site,
              const Stage2Options& base, const TableDiagnosisOptions& o, const TurnModel* tm)
      : o_(o),
        families_(candidate_families(o.dwells)),
        dwells_(inputs, site, dwells_model(base, tm), o.dwells) {
    DiagnosisReport& rep = d_.dwells;
    rep.alpha = o.dwells.alpha;
    rep.inputs = dwells_.inputs();
    rep.initial_parameters = dwells_.base().parameters;
    rep.initial = dwells_.fit(rep.initial_parameters);
    current_ = rep.initial_parameters;
    now_ = rep.initial;
    if (tm && tm->session && tm->run_filter) {
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
    if (turns_) kround = turns_->round(turn_families(families_, dround, turns_->model()));
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
    if (best_d)  // the dwells first (see the header)
      f = extend_dwells(*best_d, dround);
    else if (best_k)
      f = extend_turns(*best_k);
    d_.dwells.rounds.push_back(dround);
    if (turns_) d_.turns->rounds.push_back(kround);
    last_turn_round_ = kround;
    ++d_.rounds;
    if (!f) return false;
    f->round = d_.rounds;
    f->separated_by.push_back(coefficient_family_info(f->family).separated_by);
    for (const auto& a : f->ambiguous_with)
      f->separated_by.push_back(coefficient_family_info(a).separated_by);
    extend_filter(*f);
    d_.findings.push_back(std::move(*f));
    return true;
  }

  TableDiagnosis finish() {
    DiagnosisReport& rep = d_.dwells;
    if (!rep.rounds.empty()) rep.not_separable = diagnosis_detail::not_separable(rep.rounds.back());
    rep.final_parameters = current_;
    rep.final_fit = now_;
    rep.residuals = dwells_.residuals(rep.initial_parameters, rep.final_parameters);
    for (auto& f : d_.findings)
      final_magnitudes(f, turns_ ? &turns_->now() : nullptr, rep.final_fit.fit);
    if (turns_) {
      for (const auto& c : last_turn_round_)
        if (c.dof == 0) d_.turns->not_separable.push_back(c);
      d_.turns->final_run = turns_->now();
    }
    return std::move(d_);
  }

  int findings() const { return static_cast<int>(d_.findings.size()); }

 private:
  // The family of an ambiguous set the turns pick: each run in the filter, the best innovation
  // log-likelihood (the turns sweep each axis through every specific-force level between the
  // dwells' and so tell K2 from the scale asymmetry). Empty: no set, no filter, or the user's pick.
  std::string turns_pick(const CandidateTest& best) {
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
    std::string pick;
    double best_ll = -std::numeric_limits<double>::infinity();
    for (const auto& c : turns_->round(set))
      if (c.failed.empty() && c.log_likelihood > best_ll) {
        best_ll = c.log_likelihood;
        pick = c.family;
      }
    return pick;
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
    turns_->extend(f.family);
    f.nis_after = turns_->now().nis_per_dof;
    f.log_likelihood_after = turns_->now().log_likelihood;
    if (o_.heldout_turns) {
      heldout_now_ = turns_->heldout();
      f.turns_after = heldout_now_;
    }
  }

  const TableDiagnosisOptions& o_;
  std::vector<std::string> families_;
  DwellTests dwells_;
  std::optional<TurnTests> turns_;
  TableDiagnosis d_;
  std::vector<int> current_;
  FitFigures now_;
  std::optional<HeldoutTurns> heldout_now_;
  std::vector<KalmanCandidateTest> last_turn_round_;
};

}  // namespace

std::optional<ImuErrorModel> linearize(TurnModel& model, int passes, std::string* failed) {
  if (!model.session || passes == 1) return std::nullopt;
  KalmanRunOptions run;
  run.nis_alarm_z = std::numeric_limits<double>::infinity();
  if (passes == 0) {
    const KalmanRun one = run_kalman(*model.session, model.base, nullptr, run);
    if (!one.stopped.empty() || !one.diverged.empty() || one.nis_per_dof <= kRelinearizeNis)
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
