// sinscal diagnose: the table session's findings printed (apps/cmd_diagnose.cpp).
#include <cstdio>

#include "apps/diagnose.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "models/coefficient_families.hpp"
#include "report/diagnosis_report.hpp"

namespace sinscal::cli {

namespace {

// The dwells' residual chi2 per dof above which the output cautions that the noise model does
// not hold (a clean nav-fog session: 0.7-1.2; a clean MEMS session, bias instability unmodelled
// by the dwells: 5).
constexpr double kNoiseModelCaution = 2.5;

}  // namespace

void print_diagnosis(const TableDiagnosis& d) {
  const DiagnosisReport& r = d.dwells;
  std::printf("Calibrated model: %zu coefficients, residual chi2 per dof %.3f over %zu dwells",
              r.initial_parameters.size(), r.initial.fit.chi2_per_dof, r.residuals.size());
  if (d.turns) std::printf("; the filter's NIS per dof %.3f", d.turns->initial_nis_per_dof);
  std::printf("\n");
  if (r.final_fit.fit.chi2_per_dof > kNoiseModelCaution)
    std::printf(
        "Caution: with the findings, the dwells' residual is still %.1f times its noise model "
        "(unmodelled noise such "
        "as bias instability, or errors beyond the linearization): the tests rescale by it, "
        "but a finding without a held-out gain is doubtful\n",
        r.final_fit.fit.chi2_per_dof);
  if (d.findings.empty())
    std::printf("Findings: none (no candidate significant at the family-wise level %g)\n", r.alpha);
  int number = 0;
  for (const auto& f : d.findings) {
    std::printf("%d. %s: %s\n", ++number, finding_title(f).c_str(), finding_summary(f).c_str());
    const CoefficientFamily& info = coefficient_family_info(f.family);
    int undetermined = 0;
    for (const auto& c : f.coefficients) {
      if (c.source.empty()) {
        ++undetermined;
        continue;
      }
      std::printf("     %-26s %12.4g +- %-10.3g %s\n",
                  coefficient_catalog()[static_cast<std::size_t>(c.catalog)].name.c_str(),
                  c.value / info.si_per_unit(), c.sigma / info.si_per_unit(), info.unit().c_str());
    }
    for (const auto& c : f.combinations)
      std::printf("     %s = %.4g +- %.3g %s\n", c.text().c_str(), c.value / info.si_per_unit(),
                  c.sigma / info.si_per_unit(), info.unit().c_str());
    if (undetermined > 0 && f.combinations.empty())
      std::printf("     (%d components not determined on this plan)\n", undetermined);
    if (!f.ambiguous_with.empty()) {
      std::printf("   Separated by: %s: %s", f.family.c_str(), f.separated_by.front().c_str());
      for (std::size_t i = 0; i < f.ambiguous_with.size(); ++i)
        std::printf("; %s: %s", f.ambiguous_with[i].c_str(), f.separated_by[i + 1].c_str());
      std::printf("\n");
    }
  }
  for (const auto& c : r.not_separable) {
    bool turns_tested = false;
    if (d.turns)
      for (const auto& round : d.turns->rounds)
        for (const auto& k : round)
          turns_tested = turns_tested || (k.family == c.family && k.dof > 0);
    if (turns_tested) continue;  // the turns separate it
    std::printf("Not separable on this plan: %s (%zu of its components); separated by %s\n",
                c.family.c_str(), c.aliased.size(), c.separated_by.c_str());
  }
}

}  // namespace sinscal::cli
