#include "jointlab/correlate/update_files.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "jointlab/data/atomic_file.h"

namespace jointlab::correlate {
namespace {

std::string num(double x) {
  if (!std::isfinite(x)) throw std::logic_error("update files: non-finite result");
  return fmt::format("{:.10g}", x);
}

// A CSV cell for a name: quoted when it holds a comma or a quote.
std::string cell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

void write_linear_parameters(const std::filesystem::path& path, const LinearUpdateSummary& s) {
  std::string t =
      "name,initial,final,relative_std,sensitivity,identifiable,smallest_within_tolerance\n";
  for (const ParameterReport& p : s.parameters) {
    t += fmt::format("{},{},{},{},{},{},{}\n", cell(p.name), num(p.start), num(p.value),
                     num(p.relative_std), num(p.sensitivity), p.flat ? 0 : 1,
                     num(p.smallest_within_tolerance));
  }
  data::write_file_atomically(path, t);
}

void write_linear_history(const std::filesystem::path& path, const LinearUpdateSummary& s) {
  std::string t = "iteration,objective\n";
  for (size_t i = 0; i < s.history.size(); ++i) t += fmt::format("{},{}\n", i, num(s.history[i]));
  data::write_file_atomically(path, t);
}

void write_iwan_parameters(const std::filesystem::path& path, const IwanUpdateSummary& s,
                           double identifiable_std) {
  const char* names[] = {"Fs", "Kt", "chi", "beta"};
  const double start[] = {s.start.Fs, s.start.Kt, s.start.chi, s.start.beta};
  const double best[] = {s.best.Fs, s.best.Kt, s.best.chi, s.best.beta};
  std::string t = "name,initial,final,relative_std,identifiable\n";
  for (int k = 0; k < 4; ++k) {
    const double r = s.relative_std(k);
    t += fmt::format("{},{},{},{},{}\n", names[k], num(start[k]), num(best[k]), num(r),
                     r > 0 && r <= identifiable_std ? 1 : 0);
  }
  data::write_file_atomically(path, t);
}

void write_iwan_history(const std::filesystem::path& path, const IwanUpdateSummary& s) {
  std::string t = "evaluation,objective,best\n";
  for (const IwanHistoryEntry& h : s.history) {
    t += fmt::format("{},{},{}\n", h.evaluation, num(h.cost), num(h.best));
  }
  data::write_file_atomically(path, t);
}

void write_pareto(const std::filesystem::path& path, const std::vector<ParetoPoint>& front) {
  std::string t = "gamma,Fs,Kt,chi,beta,linear_error,backbone_cost,dominated\n";
  for (const ParetoPoint& p : front) {
    t += fmt::format("{},{},{},{},{},{},{},{}\n", num(p.gamma), num(p.params.Fs), num(p.params.Kt),
                     num(p.params.chi), num(p.params.beta), num(p.linear_error),
                     num(p.backbone_cost), p.dominated ? 1 : 0);
  }
  data::write_file_atomically(path, t);
}

}  // namespace jointlab::correlate
