// sinscal diagnose: the hand-held path (apps/diagnose_handheld.cpp) of the command
// (apps/cmd_diagnose.cpp).
#pragma once

#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "filter/table_free/handheld_run.hpp"

namespace sinscal::cli {

struct HandheldDiagnoseOptions {
  std::string out_dir;
  double alpha = 0.01;
  bool plot = true;
  std::string candidates;             // --candidates, comma separated (empty: all)
  std::vector<std::string> validate;  // held-out validation sessions
  TableFreeRunOptions run;            // gravity, pose detector, edge trim
  bool force = false;                 // run even when the gate fails (apps/handheld_gate.hpp)
};

/// Calibrates a hand-held session table-free, diagnoses it, writes the files and prints the
/// summary; a temperature candidate without a temperature column, or a requested candidate the
/// poses are too few for, throws (exit 2) after the files are written.
int diagnose_handheld_session(const Session& session, const HandheldDiagnoseOptions& o);

/// A table session's diagnosis as `sinscal diagnose --session S` runs it (apps/cmd_diagnose.cpp).
struct TableDiagnoseOptions {
  std::string out_dir;
  DiagnosisOptions dwells;   // alpha, prefer (thermal: set from the log's temperatures)
  double table_sigma = 2.5;  // arcsec
  double min_dwell = 20.0;   // s
  int passes = 0;            // 0: automatic
  bool kalman = true;        // the filter's test of the effects of the turns
  bool plot = true;
  bool force = false;  // run when the plausibility gate fails
};

/// Calibrates and diagnoses a table session, prints the findings and writes DIR/diagnosis.json,
/// report.md (and residuals.png with `plot`); returns the diagnosis.
TableDiagnosis diagnose_table_session(const std::string& session_path,
                                      const TableDiagnoseOptions& o);

/// A chamber session (`[thermal] soaks`): the thermal families the model lacks, tested on the
/// soaks (apps/diagnose_chamber.cpp); DIR/diagnosis.json.
struct ChamberDiagnoseOptions {
  std::string out_dir;
  double alpha = 0.01;
  double table_sigma = 2.5;  // arcsec
  std::string sensor;        // the model's profile (empty: the first soak's)
};
int diagnose_chamber(const std::string& chamber_path, const ChamberDiagnoseOptions& o);

/// Whether a table session's log has temperature columns that move by 2 C or more (the thermal
/// families are then candidates); said on the terminal either way.
bool log_temperature_varies(const Session& session);

/// The table session's findings on the terminal (apps/print_diagnosis.cpp).
void print_diagnosis(const TableDiagnosis& d);

/// A six-face session ([six_face]): the gyro g-sensitivity test on its rests
/// (apps/diagnose_six_face.cpp); DIR/diagnosis.json when `out_dir` is given.
int diagnose_six_face_session(const Session& session, const std::string& out_dir, double alpha);

}  // namespace sinscal::cli
