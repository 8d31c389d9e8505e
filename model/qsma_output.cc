#include "jointlab/model/qsma_output.h"

#include <Eigen/Core>

#include "jointlab/data/table_writer.h"

namespace jointlab::model {

data::Table qsma_table(const std::vector<QsmaPoint>& curve) {
  const auto n = static_cast<Eigen::Index>(curve.size());
  Eigen::VectorXd f(n), q(n), hz(n), zeta(n), slip(n), rd_hz(n), rd_zeta(n), h_zeta(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const QsmaPoint& p = curve[static_cast<size_t>(i)];
    f(i) = p.force_amplitude, q(i) = p.modal_amplitude, hz(i) = p.frequency_hz;
    zeta(i) = p.damping_ratio, slip(i) = p.max_slip;
    rd_hz(i) = p.ringdown_frequency_hz, rd_zeta(i) = p.ringdown_damping_ratio;
    h_zeta(i) = p.harmonic_damping_ratio;
  }
  data::Table table;
  table.add("force_amplitude", f);
  table.add("modal_amplitude", q);
  table.add("frequency_hz", hz);
  table.add("damping_ratio", zeta);
  table.add("max_slip", slip);
  table.add("ringdown_frequency_hz", rd_hz);
  table.add("ringdown_damping_ratio", rd_zeta);
  table.add("harmonic_damping_ratio", h_zeta);
  return table;
}

void write_qsma_csv(const std::filesystem::path& path, const std::vector<QsmaPoint>& curve) {
  data::write_table(path, qsma_table(curve));
}

}  // namespace jointlab::model
