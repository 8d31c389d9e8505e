#include "jointlab/modal/stepped_sine_output.h"

#include <algorithm>
#include <numeric>

#include "jointlab/data/atomic_file.h"
#include "jointlab/data/json_writer.h"
#include "jointlab/data/table_writer.h"

namespace jointlab::modal {

SteppedSineFileResult extract_stepped_sine_file(const std::filesystem::path& file,
                                                std::optional<Quantity> quantity,
                                                const SteppedSineOptions& opt) {
  SteppedSineFileResult r;
  r.source = file.string();
  r.tables = data::read_stepped_sine(file.string(), quantity);
  r.points.resize(r.tables.size());
  for (size_t i = 0; i < r.tables.size(); ++i) {
    if (r.tables[i].control == data::SineControl::kResponse)
      r.points[i] = extract_backbone_point(r.tables[i], opt);
  }
  const ModalConstant q = response_modal_constant(r.points);
  for (size_t i = 0; i < r.tables.size(); ++i) {
    if (r.tables[i].control == data::SineControl::kForce)
      r.points[i] = extract_backbone_point(r.tables[i], opt, q);
  }
  return r;
}

std::string sine_backbone_file_name(const std::string& source) {
  return std::filesystem::path(source).stem().string() + ".backbone.csv";
}

int usable_points(const SteppedSineFileResult& result) {
  return static_cast<int>(
      std::count_if(result.points.begin(), result.points.end(),
                    [](const SineBackbonePoint& p) { return p.status == SineStatus::kOk; }));
}

void write_sine_backbone(const std::filesystem::path& dir, const SteppedSineFileResult& r) {
  std::vector<size_t> rows;
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (r.points[i].status == SineStatus::kOk) rows.push_back(i);
  }
  if (rows.empty()) return;
  std::stable_sort(rows.begin(), rows.end(), [&](size_t a, size_t b) {
    return r.points[a].amplitude < r.points[b].amplitude;
  });
  const auto n = static_cast<Eigen::Index>(rows.size());
  auto column = [&](auto get) {
    Eigen::VectorXd v(n);
    for (Eigen::Index i = 0; i < n; ++i) v(i) = get(rows[static_cast<size_t>(i)]);
    return v;
  };
  const auto& p = r.points;
  data::Table t;
  t.add("amplitude", column([&](size_t i) { return p[i].amplitude; }));
  t.add("frequency_hz", column([&](size_t i) { return p[i].frequency_hz; }));
  t.add("damping_ratio", column([&](size_t i) { return p[i].damping_ratio; }));
  t.add("frequency_std_hz", column([&](size_t i) { return p[i].frequency_std_hz; }));
  t.add("damping_std", column([&](size_t i) { return p[i].damping_std; }));
  t.add("level", column([&](size_t i) { return static_cast<double>(r.tables[i].index); }));
  t.add("response_controlled", column([&](size_t i) {
          return r.tables[i].control == data::SineControl::kResponse ? 1.0 : 0.0;
        }));
  t.add("points", column([&](size_t i) { return static_cast<double>(r.tables[i].size()); }));
  t.add("fit_rms", column([&](size_t i) { return p[i].fit.rms; }));
  t.add("displacement_m", column([&](size_t i) { return p[i].displacement_m; }));
  t.add("force_n", column([&](size_t i) { return p[i].force_n; }));
  t.add("damping_direct", column([&](size_t i) { return p[i].damping_direct ? 1.0 : 0.0; }));
  data::write_table(dir / sine_backbone_file_name(r.source), t);
}

void write_sine_summary(const std::filesystem::path& dir,
                        const std::vector<SteppedSineFileResult>& results,
                        const SteppedSineOptions& options) {
  data::JsonWriter j;
  j.begin_object();
  j.key("program").value("jointlab stepped-sine");
  j.key("amplitude_quantity").value(quantity_name(options.amplitude));
  j.key("amplitude_unit").value(si_unit(options.amplitude));
  j.key("coverage_factor").value(options.coverage_factor);
  j.key("damping_model")
      .value(options.damping == SineDamping::kHysteretic ? "hysteretic" : "viscous");
  j.key("residual_terms").value(options.residual_terms);
  j.key("files").begin_array();
  for (const SteppedSineFileResult& r : results) {
    j.begin_object();
    j.key("file").value(r.source);
    if (usable_points(r) > 0) {
      j.key("output").value(sine_backbone_file_name(r.source));
    } else {
      j.key("output").null();
    }
    j.key("levels").begin_array();
    for (size_t i = 0; i < r.tables.size(); ++i) {
      const data::SteppedSineTable& t = r.tables[i];
      const SineBackbonePoint& p = r.points[i];
      j.begin_object();
      j.key("level").value(t.index);
      j.key("label").value(t.label);
      j.key("control").value(data::control_name(t.control));
      j.key("response_quantity").value(quantity_name(t.response_quantity));
      j.key("points").value(static_cast<long>(t.size()));
      j.key("low_hz").value(t.frequency_hz(0));
      j.key("high_hz").value(t.frequency_hz(t.size() - 1));
      if (p.status == SineStatus::kOk) {
        j.key("amplitude").value(p.amplitude);
        j.key("frequency_hz").value(p.frequency_hz);
        j.key("damping_ratio").value(p.damping_ratio);
        j.key("frequency_std_hz").value(p.frequency_std_hz);
        j.key("damping_std").value(p.damping_std);
        j.key("displacement_m").value(p.displacement_m);
        j.key("force_n").value(p.force_n);
        j.key("frequency_method")
            .value(t.control == data::SineControl::kResponse ? "single-mode fit"
                                                             : "phase resonance");
        j.key("damping_method")
            .value(p.damping_direct       ? "single-mode fit"
                   : p.own_modal_constant ? "energy balance at phase resonance with this "
                                            "sweep's own modal constant (less direct; biased "
                                            "when the amplitude varies much)"
                                          : "energy balance at phase resonance with the "
                                            "response-controlled levels' modal constant "
                                            "(less direct)");
        if (!p.message.empty()) j.key("note").value(p.message);
      } else {
        j.key("reason").value(p.message);
      }
      if (p.fit.converged) {
        j.key("fit").begin_object();
        j.key("frequency_hz").value(p.fit.frequency_hz);
        j.key("damping_ratio").value(p.fit.damping_ratio);
        j.key("frequency_sigma_hz").value(p.fit.frequency_sigma_hz);
        j.key("damping_sigma").value(p.fit.damping_sigma);
        j.key("modal_constant_re").value(p.fit.modal_constant.real());
        j.key("modal_constant_im").value(p.fit.modal_constant.imag());
        j.key("residual0_re").value(p.fit.residual0.real());
        j.key("residual0_im").value(p.fit.residual0.imag());
        j.key("residual1_re").value(p.fit.residual1.real());
        j.key("residual1_im").value(p.fit.residual1.imag());
        j.key("rms").value(p.fit.rms);
        j.key("iterations").value(p.fit.iterations);
        j.end_object();
      }
      j.end_object();
    }
    j.end_array();
    j.end_object();
  }
  j.end_array();
  j.end_object();
  data::write_file_atomically(dir / "summary.json", j.str());
}

}  // namespace jointlab::modal
