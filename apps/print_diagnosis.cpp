// sinscal diagnose: the table session's findings printed (apps/cmd_diagnose.cpp).
#include <cstdio>

#include "apps/diagnose.hpp"
#include "apps/print.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "models/coefficient_families.hpp"
#include "report/diagnosis_report.hpp"

namespace sinscal::cli {

namespace {

// The final model against its noise model, what it leaves unexplained, every stop.
void print_verdict(const TableDiagnosis& d) {
  const ResidualCheck& c = d.check;
  std::printf("Residual with the findings: dwells chi2 %.4g on %d dof (99 %% quantile %.4g)%s",
              c.dwells_chi2, c.dwells_dof, c.dwells_quantile,
              c.dwells_hold ? "" : " REJECTS the noise model");
  if (c.heldout_inputs > 0)
    std::printf("; held-out dwells chi2 %.4g on %d inputs (%.4g)%s", c.heldout_chi2,
                c.heldout_inputs, c.heldout_quantile, c.heldout_hold ? "" : " REJECTS");
  if (c.filter)
    std::printf("; filter NIS per dof %.3f%s", c.nis_per_dof,
                c.filter_holds ? "" : " REJECTS the noise model");
  if (c.turns_tested)
    std::printf("; turns' attitude residual chi2 %.4g on %.4g%s", c.turns_chi2, c.turns_dof,
                c.turns_hold ? "" : " REJECTS");
  std::printf("\n");
  if (c.filter) print_innovation_check(c.innovations);
  if (d.unexplained.present) {
    std::printf("Unexplained: what the findings leave (no family of the catalog explains it):\n");
    for (const auto& s : d.unexplained.signature) std::printf("   %s\n", s.c_str());
    if (const auto& lib = d.unexplained.library) {
      if (lib->terms.empty())
        std::printf(
            "   No term of the out-of-catalog library (%d terms) confirmed on held-out dwells and "
            "turns\n",
            lib->candidates);
      for (const auto& t : lib->terms)
        std::printf("   Library term: %s (held-out dwells and turns chi2 %.4g -> %.4g)\n",
                    t.text().c_str(), lib->heldout_before, lib->heldout_after);
      if (!lib->how_to_add.empty()) std::printf("   How: %s\n", lib->how_to_add.c_str());
    }
    if (c.sigma_scale > 1.0)
      std::printf(
          "   The sigmas below are scaled by the unexplained residual: x%.2f, the largest of "
          "dwells x%.2f, held-out dwells x%.2f, filter x%.2f, turns x%.2f\n",
          c.sigma_scale, c.dwells_sigma_scale, c.heldout_sigma_scale, c.filter_sigma_scale,
          c.turns_sigma_scale);
  }
  if (!c.sigmas_hold) std::printf("Sigmas do not hold: %s\n", c.sigmas_note.c_str());
  for (const auto& s : d.stops) std::printf("Stop: %s\n", s.c_str());
}

}  // namespace

void print_diagnosis(const TableDiagnosis& d) {
  const DiagnosisReport& r = d.dwells;
  std::printf("Calibrated model: %zu coefficients, residual chi2 per dof %.3f over %zu dwells",
              r.initial_parameters.size(), r.initial.fit.chi2_per_dof, r.residuals.size());
  if (d.turns) std::printf("; the filter's NIS per dof %.3f", d.turns->initial_nis_per_dof);
  std::printf("\n");
  print_verdict(d);
  if (d.findings.empty())
    std::printf("Findings: none (%s)\n", d.unexplained.present
                                             ? "no family of the catalog explains the residual"
                                             : "no candidate significant at the family-wise level");
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
    if (!f.pick_note.empty()) std::printf("   Pick: %s\n", f.pick_note.c_str());
    if (!f.separability.empty()) std::printf("   Plan: %s\n", f.separability.c_str());
  }
  for (const auto& c : r.not_separable) {
    bool turns_tested = false;
    if (d.turns)
      for (const auto& round : d.turns->rounds)
        for (const auto& k : round)
          turns_tested = turns_tested || (k.family == c.family && k.dof > 0);
    if (turns_tested) continue;  // the turns separate it
    std::printf("Not separable on this plan%s: %s (%zu of its components); separated by %s\n",
                d.unexplained.present ? " (whatever the unexplained residual holds)" : "",
                c.family.c_str(), c.aliased.size(), c.separated_by.c_str());
  }
}

}  // namespace sinscal::cli
