#include "jointlab/correlate/two_chain.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "jointlab/core/error.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {

model::Model twin_chains_structure(double kg, double kc) {
  model::Model m;
  const int n = 3;
  std::vector<Eigen::Triplet<double>> mt, kt;
  for (int i = 0; i < 2 * n; ++i) mt.emplace_back(i, i, i < n ? 1.0 : 1.05);
  for (int c = 0; c < 2; ++c)
    for (int i = c * n; i + 1 < (c + 1) * n; ++i)
      for (const auto& [a, b, v] : {std::tuple{i, i, 1e4}, std::tuple{i + 1, i + 1, 1e4},
                                    std::tuple{i, i + 1, -1e4}, std::tuple{i + 1, i, -1e4}})
        kt.emplace_back(a, b, v);
  m.mass.resize(2 * n, 2 * n);
  m.mass.setFromTriplets(mt.begin(), mt.end());
  m.stiffness.resize(2 * n, 2 * n);
  m.stiffness.setFromTriplets(kt.begin(), kt.end());
  for (const auto& [a, b, element, k] :
       {std::tuple{0, model::kGround, "spring.kg", kg},
        std::tuple{n, model::kGround, "spring.kg", kg},
        std::tuple{n - 1, Eigen::Index{2 * n - 1}, "spring.kc", kc}}) {
    model::Joint j;
    j.a = a;
    j.b = b;
    j.element = element;
    j.stiffness = k;
    m.joints.push_back(j);
  }
  model::validate_model(m, "twin chains");
  return m;
}

model::Model one_mode_structure(double k0, const model::IwanParameters& p, double z) {
  model::Model m;
  m.mass.resize(1, 1);
  m.mass.insert(0, 0) = 1.0;
  m.stiffness.resize(1, 1);
  m.stiffness.insert(0, 0) = k0;
  m.joints.push_back(model::Joint{0, model::kGround, "iwan.j", p.Kt, model::Iwan(p)});
  m.modal_ratio = z;
  return m;
}

model::Model two_chain_structure(const TwoChainParameters& p) {
  const int n = p.n < 6 ? 6 : p.n;
  const int size = 2 * n;
  std::vector<Eigen::Triplet<double>> k, m;
  auto spring = [&](int a, int b, double v) {
    k.emplace_back(a, a, v);
    if (b >= 0) {
      k.emplace_back(b, b, v);
      k.emplace_back(a, b, -v);
      k.emplace_back(b, a, -v);
    }
  };
  model::Model out;
  auto joint = [&](int a, int b, const std::string& element, double v) {
    model::Joint j;
    j.a = a;
    j.b = b;
    j.element = element;
    j.stiffness = v;
    if (element.starts_with("iwan.")) j.iwan = model::Iwan(p.Fs, v, p.chi, p.beta);
    out.joints.push_back(j);
  };
  for (int c = 0; c < 2; ++c) {
    const int o = c * n;
    for (int i = 0; i < n; ++i) m.emplace_back(o + i, o + i, c == 0 ? 0.5 : 0.3);
    spring(o, -1, 2e6);
    for (int i = 0; i + 1 < n; ++i) {
      const int a = o + i, b = o + i + 1;
      if (c == 0 && i == 1) {
        spring(a, b, 2e5);
        joint(a, b, p.iwan ? "iwan.rivet" : "spring.ka", p.ka);
      } else if (c == 0 && i == 3) {
        joint(a, b, "spring.kflat", p.kflat);
      } else if (c == 1 && i == 1) {
        joint(a, b, "spring.kb", p.kb);
      } else {
        spring(a, b, 1e6);
      }
    }
  }
  out.mass.resize(size, size);
  out.mass.setFromTriplets(m.begin(), m.end());
  out.stiffness.resize(size, size);
  out.stiffness.setFromTriplets(k.begin(), k.end());
  model::validate_model(out, "two-chain structure");
  return out;
}

MeasuredBackbone synthetic_backbone(const model::Model& model, int mode,
                                    const std::vector<Sensor>& sensors, int sensor,
                                    AmplitudeQuantity quantity, int points, double top,
                                    double frequency_noise, double damping_noise, unsigned seed,
                                    BackboneKind kind, IwanComparison columns) {
  const model::JointCondensation jc(model);
  model::QsmaSummary qs;
  const auto full = model::qsma(jc, mode, {}, &qs);
  model::QsmaOptions o;
  o.points = points;
  o.q_max = top * full.back().modal_amplitude;
  o.q_min = std::max(full.front().modal_amplitude, 0.01 * o.q_max);
  const auto curve = model::qsma(jc, mode, o, &qs);
  // The sensor sees the static deflection u_d at each point's load (model::QsmaDof), not
  // |phi[d]| q: the joint solution at that load, continued up the curve.
  const model::QsmaMode qm(jc, mode);
  const model::QsmaDof at_sensor(jc, mode, sensors[sensor].dof);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(jc.size());
  const int pw = quantity == AmplitudeQuantity::kDisplacement ? 0
                 : quantity == AmplitudeQuantity::kVelocity   ? 1
                                                              : 2;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const auto n = static_cast<Eigen::Index>(curve.size());
  MeasuredBackbone b = sized_backbone(kind, sensor, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const model::QsmaPoint& p = curve[i];
    const bool secant = columns == IwanComparison::kSecant;
    const double f = secant ? p.frequency_hz : p.ringdown_frequency_hz;
    const double z = secant                               ? p.damping_ratio
                     : kind == BackboneKind::kSteppedSine ? p.harmonic_damping_ratio
                                                          : p.ringdown_damping_ratio;
    const double runaway = 1e6 * (r.lpNorm<Eigen::Infinity>() + jc.smallest_phi_max());
    if (!jc.solve(qm.g, p.force_amplitude, r, runaway, 60).converged)
      throw InputError("synthetic backbone: a static solve on the QSMA curve failed");
    b.amplitude(i) =
        at_sensor.deflection(p.force_amplitude, r) * std::pow(2 * std::numbers::pi * f, pw);
    b.frequency_hz(i) = f * (1 + frequency_noise * g(rng));
    b.damping_ratio(i) = z * (1 + damping_noise * g(rng));
    b.frequency_std_hz(i) = frequency_noise * f;
    b.damping_std(i) = damping_noise * z;
  }
  return b;
}

}  // namespace jointlab::correlate
