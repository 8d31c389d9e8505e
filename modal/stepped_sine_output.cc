#include "jointlab/modal/stepped_sine_output.h"

#include <algorithm>
#include <numeric>

#include "jointlab/data/json_writer.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/modal/summary_json.h"

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

data::Table sine_backbone_table(const SteppedSineFileResult& r) {
  std::vector<size_t> rows;
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (r.points[i].status == SineStatus::kOk) rows.push_back(i);
  }
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
  return t;
}

void write_sine_backbone(const std::filesystem::path& dir, const SteppedSineFileResult& r) {
  if (usable_points(r) == 0) return;
  data::write_table(dir / sine_backbone_file_name(r.source), sine_backbone_table(r));
}

namespace {

// One sweep level's entry of "levels": its data, backbone point and single-mode fit.
void write_level(data::JsonWriter& j, const data::SteppedSineTable& t, const SineBackbonePoint& p) {
  j.key("level").value(t.index);
  j.key("label").value(t.label);
  j.key("control").value(data::control_name(t.control));
  j.key("response_quantity").value(quantity_name(t.response_quantity));
  j.key("points").value(static_cast<long>(t.size()));
  j.numbers({{"low_hz", t.frequency_hz(0)}, {"high_hz", t.frequency_hz(t.size() - 1)}});
  if (p.status == SineStatus::kOk) {
    j.numbers({{"amplitude", p.amplitude},
               {"frequency_hz", p.frequency_hz},
               {"damping_ratio", p.damping_ratio},
               {"frequency_std_hz", p.frequency_std_hz},
               {"damping_std", p.damping_std},
               {"displacement_m", p.displacement_m},
               {"force_n", p.force_n}});
    j.key("frequency_method")
        .value(t.control == data::SineControl::kResponse ? "single-mode fit" : "phase resonance");
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
    const SineFit& f = p.fit;
    j.key("fit").begin_object();
    j.numbers({{"frequency_hz", f.frequency_hz},
               {"damping_ratio", f.damping_ratio},
               {"frequency_sigma_hz", f.frequency_sigma_hz},
               {"damping_sigma", f.damping_sigma},
               {"modal_constant_re", f.modal_constant.real()},
               {"modal_constant_im", f.modal_constant.imag()},
               {"residual0_re", f.residual0.real()},
               {"residual0_im", f.residual0.imag()},
               {"residual1_re", f.residual1.real()},
               {"residual1_im", f.residual1.imag()},
               {"rms", f.rms}});
    j.key("iterations").value(f.iterations);
    j.end_object();
  }
}

}  // namespace

void write_sine_summary(const std::filesystem::path& dir,
                        const std::vector<SteppedSineFileResult>& results,
                        const SteppedSineOptions& options) {
  auto header = [&](data::JsonWriter& j) {
    j.key("program").value("jointlab stepped-sine");
    write_amplitude_keys(j, options.amplitude, options.coverage_factor);
    j.key("damping_model")
        .value(options.damping == SineDamping::kHysteretic ? "hysteretic" : "viscous");
    j.key("residual_terms").value(options.residual_terms);
  };
  auto file = [&](data::JsonWriter& j, size_t k) {
    const SteppedSineFileResult& r = results[k];
    j.key("file").value(r.source);
    if (usable_points(r) > 0) {
      j.key("output").value(sine_backbone_file_name(r.source));
    } else {
      j.key("output").null();
    }
    j.key("levels").begin_array();
    for (size_t i = 0; i < r.tables.size(); ++i) {
      j.begin_object();
      write_level(j, r.tables[i], r.points[i]);
      j.end_object();
    }
    j.end_array();
  };
  write_summary_json(dir, header, results.size(), file);
}

}  // namespace jointlab::modal
