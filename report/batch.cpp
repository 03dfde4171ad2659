#include "report/batch.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "report/output.hpp"

namespace sinscal {

namespace fs = std::filesystem;

std::vector<std::string> find_sessions(const std::string& path) {
  if (!fs::exists(path)) throw std::runtime_error(path + ": no such file or directory");
  if (!fs::is_directory(path)) return {path};
  if (fs::exists(fs::path(path) / "session.ini"))
    return {(fs::path(path) / "session.ini").string()};
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(path))
    if (entry.is_directory() && fs::exists(entry.path() / "session.ini"))
      out.push_back((entry.path() / "session.ini").string());
  std::sort(out.begin(), out.end());
  if (out.empty())
    throw std::runtime_error(path + ": no session.ini in this directory nor in its subdirectories");
  return out;
}

std::vector<std::string> read_session_list(const std::string& list_path) {
  std::ifstream in(list_path);
  if (!in) throw std::runtime_error(list_path + ": cannot open");
  const fs::path dir = fs::path(list_path).parent_path();
  std::vector<std::string> out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    line = line.substr(first, line.find_last_not_of(" \t\r") - first + 1);
    const fs::path entry(line);
    try {
      for (auto& s : find_sessions((entry.is_absolute() ? entry : dir / entry).string()))
        out.push_back(std::move(s));
    } catch (const std::exception& e) {
      throw std::runtime_error(list_path + ":" + std::to_string(number) + ": " + e.what());
    }
  }
  if (out.empty()) throw std::runtime_error(list_path + ": the list names no session");
  return out;
}

std::vector<std::string> result_stems(const std::vector<std::string>& sessions) {
  std::vector<std::string> stems;
  std::set<std::string> used;
  for (const auto& s : sessions) {
    const fs::path p(s);
    std::string stem = p.filename() == "session.ini" && p.has_parent_path()
                           ? p.parent_path().filename().string()
                           : p.stem().string();
    if (stem.empty() || stem == ".") stem = "session";
    std::string name = stem;
    for (int n = 2; used.count(name); ++n) name = stem + "-" + std::to_string(n);
    used.insert(name);
    stems.push_back(name);
  }
  return stems;
}

void set_status(const KalmanRun& run, SessionSummary& row) {
  row.status = "ok";
  if (run.interrupted) {
    row.status = "interrupted";
    row.message = run.stopped;
  } else if (!run.stopped.empty()) {
    row.status = "stopped";
    row.message = "input stopped: " + run.stopped;
  } else if (!run.diverged.empty()) {
    row.status = "diverged";
    row.message = run.diverged;
  }
}

namespace {
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s)
    q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' || c == '\r' ? ' ' : c);
  return q + "\"";
}
std::string number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}
std::string number(const std::optional<double>& v) { return v ? number(*v) : std::string(); }
}  // namespace

void write_summary_csv(const std::string& path, const std::vector<SessionSummary>& rows) {
  std::vector<const CoefficientInfo*> columns;  // catalog order, those any row has
  for (const auto& info : coefficient_catalog())
    for (const auto& r : rows)
      if (r.coefficients.count(info.name)) {
        columns.push_back(&info);
        break;
      }
  write_atomically(path, [&](std::ostream& out) {
    out << "session,name,status,result,samples,duration_s,nis_per_dof,converged_at_s,"
           "max_abs_error_over_sigma,message";
    for (const auto* c : columns)
      out << "," << c->name << " [" << c->unit << "]," << c->name << ".sigma [" << c->unit << "]";
    out << "\n";
    for (const auto& r : rows) {
      out << csv_field(r.session) << "," << csv_field(r.name) << "," << r.status << ","
          << csv_field(r.result) << "," << r.samples << "," << number(r.duration) << ","
          << number(r.nis_per_dof) << "," << number(r.converged_at) << ","
          << number(r.max_error_over_sigma) << "," << csv_field(r.message);
      for (const auto* c : columns) {
        const auto it = r.coefficients.find(c->name);
        std::string value, sigma;
        if (it != r.coefficients.end()) {
          const ResultCoefficient& e = it->second;
          if (e.fixed_by_convention)
            value = "0";
          else if (e.observable)
            value = number(e.value);
          if (!e.fixed_by_convention) sigma = number(e.sigma);
        }
        out << "," << value << "," << sigma;
      }
      out << "\n";
    }
  });
}

std::vector<SessionSummary> run_batch(
    const std::vector<std::string>& sessions, unsigned jobs,
    const std::function<SessionSummary(std::size_t)>& calibrate_one, const std::atomic<bool>* stop,
    const std::function<void(std::size_t, const SessionSummary&)>& done) {
  std::vector<SessionSummary> rows(sessions.size());
  std::atomic<std::size_t> next{0};
  std::mutex done_mutex;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < sessions.size();) {
      SessionSummary& row = rows[i];
      if (stop && stop->load()) {
        row.session = sessions[i];
        row.status = "interrupted";
        row.message = "not started: interrupted";
        continue;
      }
      try {
        row = calibrate_one(i);
      } catch (const std::exception& e) {
        row.session = sessions[i];
        row.status = "failed";
        row.message = e.what();
      }
      if (done) {
        const std::lock_guard<std::mutex> lock(done_mutex);
        done(i, row);
      }
    }
  };
  jobs = std::max(1u, std::min<unsigned>(jobs, static_cast<unsigned>(sessions.size())));
  std::vector<std::thread> threads;
  for (unsigned k = 1; k < jobs; ++k) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  return rows;
}

}  // namespace sinscal
