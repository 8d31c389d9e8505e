#include "jointlab/campaign/update_figures.h"

#include <algorithm>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "jointlab/campaign/figures.h"
#include "jointlab/correlate/update_tables.h"

namespace jointlab::campaign {
namespace {

namespace fs = std::filesystem;

// The MAC of one evaluation with its pairs framed; columns up to those update_tables.h writes.
void mac_figure(const correlate::LinearEvaluation& e, int cols, const std::string& title,
                const fs::path& file) {
  const Eigen::MatrixXd& mac = e.mac;
  cols = std::min(cols, static_cast<int>(mac.cols()));
  if (mac.rows() == 0 || cols <= 0) return;
  std::vector<std::string> rows, columns;
  for (Eigen::Index i = 0; i < mac.rows(); ++i)
    rows.push_back(fmt::format("test {} ({:.4g} Hz)", i + 1, e.measured_frequency_hz(i)));
  for (int j = 0; j < cols; ++j)
    columns.push_back(fmt::format("{} ({:.4g} Hz)", j + 1, e.all_model_frequency_hz(j)));
  std::vector<MacCell> marked;
  for (const correlate::ModePair& p : e.pairing.pairs)
    if (p.model < cols) marked.emplace_back(p.measured, p.model);
  plot_mac(mac.leftCols(cols), rows, columns, title, file, {1150, 700}, marked);
}

}  // namespace

void write_linear_figures(const correlate::LinearUpdateSummary& s, const fs::path& dir) {
  // Figure 2: the objective and every stiffness per iteration.
  if (!s.history.empty()) {
    LinePanel objective{"objective 1/2 sum r_i^2 per iteration",
                        "iteration",
                        "objective [-]",
                        false,
                        true,
                        {},
                        {},
                        ""};
    LineSeries cost{"objective", {}, {}};
    for (size_t i = 0; i < s.history.size(); ++i) {
      cost.x.push_back(static_cast<double>(i));
      cost.y.emplace_back(s.history[i]);
    }
    objective.series.push_back(std::move(cost));
    LinePanel stiffness{"stiffness of every set",
                        "iteration",
                        "stiffness [N/m or N m/rad]",
                        false,
                        true,
                        {},
                        {},
                        ""};
    for (size_t k = 0; k < s.parameters.size(); ++k) {
      LineSeries v{s.parameters[k].name, {}, {}};
      for (size_t i = 0; i < s.theta_history.size(); ++i) {
        if (static_cast<Eigen::Index>(k) >= s.theta_history[i].size()) continue;
        v.x.push_back(static_cast<double>(i));
        v.y.emplace_back(s.theta_history[i](static_cast<Eigen::Index>(k)));
      }
      stiffness.series.push_back(std::move(v));
    }
    plot_panels({objective, stiffness}, fmt::format("linear update ({}): history", s.rule),
                dir / "history.png");
  }
  // Figure 3: one-at-a-time sweeps, every paired mode followed by its shape.
  std::vector<LinePanel> sweeps;
  for (const correlate::ParameterReport& p : s.parameters) {
    if (p.sweep_factor.empty()) continue;
    LinePanel panel{fmt::format("{} (result {:.4g})", p.name, p.value),
                    "stiffness / result [-]",
                    "frequency error [%]",
                    true,
                    false,
                    {},
                    {1.0},
                    "result"};
    const size_t m = static_cast<size_t>(s.final.measured_frequency_hz.size());
    for (size_t i = 0; i < m; ++i) {
      // Every mode in every panel (a mode never followed has no line), so that colours and the
      // shared legend agree.
      LineSeries line{fmt::format("test mode {}", i + 1), p.sweep_factor, {}};
      for (size_t k = 0; k < p.sweep_factor.size(); ++k) {
        std::optional<double> v;
        if (k < p.sweep_errors.size() && i < p.sweep_errors[k].size() && p.sweep_errors[k][i])
          v = 100 * *p.sweep_errors[k][i];
        line.y.push_back(v);
      }
      panel.series.push_back(std::move(line));
    }
    if (!panel.series.empty()) sweeps.push_back(std::move(panel));
  }
  if (!sweeps.empty())
    plot_panels(sweeps, "one-at-a-time sweeps: each mode followed by its shape", dir / "sweeps.png",
                {1150, sweeps.size() > 2 ? 900 : 600});
  // Figure 4: the MAC at the start and at the result.
  const int cols = correlate::mac_columns(s);
  mac_figure(s.start, cols, "MAC at the start", dir / "mac_start.png");
  mac_figure(s.final, cols, "MAC at the result", dir / "mac.png");
}

}  // namespace jointlab::campaign
