#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <random>

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/core/text.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {
namespace {

constexpr double kPenalty = 1e6;        // cost() of a parameter set the model cannot evaluate
constexpr int kBatch = 50;              // samples evaluated between two progress reports
constexpr int kLocalIterations = 50;    // iterations of a local solve within its share
constexpr int kPolishIterations = 200;  // iterations of the polish of the best point

// Point j's stated one-sigma uncertainties (frequency [Hz], damping ratio; 0: none stated): the
// file's expanded uncertainty over its coverage factor (process's k = 3 was read as sigma, and
// the reduced chi-square came out 9 times too small).
Eigen::Vector2d stated_sigma(const MeasuredBackbone& c, Eigen::Index j) {
  return Eigen::Vector2d(c.frequency_std_hz(j), c.damping_std(j)) / c.coverage_factor;
}

}  // namespace

int amplitude_power(AmplitudeQuantity q) {
  return q == AmplitudeQuantity::kDisplacement ? 0 : q == AmplitudeQuantity::kVelocity ? 1 : 2;
}

IwanBounds default_iwan_bounds(const model::IwanParameters& start) {
  IwanBounds b;
  b.Fs_min = start.Fs / 30;
  b.Fs_max = start.Fs * 30;
  b.gamma_min = 0.05;
  b.gamma_max = 2;
  b.chi_min = -0.95;
  b.chi_max = 0;
  b.beta_min = 0.01;
  b.beta_max = 100;
  return b;
}

std::string IwanUpdateOptions::error() const {
  const IwanBounds& b = bounds;
  if (!(b.Fs_min > 0 && b.Fs_min < b.Fs_max)) return "bounds: 0 < Fs_min < Fs_max";
  if (!(b.gamma_min > 0 && b.gamma_min < b.gamma_max)) return "bounds: 0 < gamma_min < gamma_max";
  if (!(b.chi_min > -1 && b.chi_min < b.chi_max)) return "bounds: -1 < chi_min < chi_max";
  if (!(b.beta_min > 0 && b.beta_min < b.beta_max)) return "bounds: 0 < beta_min < beta_max";
  if (!(fixed_gamma >= 0)) return "fixed_gamma must be >= 0";
  if (fixed_beta && !(*fixed_beta >= 0 && std::isfinite(*fixed_beta)))
    return "fixed_beta must be a finite number >= 0";
  if (samples < 2) return "samples must be >= 2";
  if (!(contraction > 0 && contraction < 1)) return "contraction must be in (0, 1)";
  if (max_evaluations < samples) {
    return fmt::format(
        "the evaluation budget (--evaluations, max_evaluations) {} must be at least the samples "
        "of one round ({})",
        max_evaluations, samples);
  }
  if (fit_linear_damping && !(linear_damping_max > 0 && linear_damping_max < 1))
    return "linear_damping_max must be in (0, 1)";
  if (local_starts < 1) return "local_starts must be >= 1";
  if (threads < 0) return "threads must be >= 0 (0: every core)";
  if (!(frequency_floor > 0) || !(damping_floor > 0)) return "floors must be > 0";
  return "";
}

IwanObjective::IwanObjective(const model::Model& model, const std::string& set,
                             const std::vector<Sensor>& sensors, std::vector<IwanTarget> targets,
                             const IwanUpdateOptions& options)
    : model_(&model),
      set_(set.starts_with("iwan.") ? set : "iwan." + set),
      sensors_(sensors),
      targets_(std::move(targets)),
      amplitude_(options.amplitude),
      f_floor_(options.frequency_floor),
      z_floor_(options.damping_floor),
      comparison_(options.comparison),
      fit_z_(options.fit_linear_damping),
      z_model_(model.modal_ratio),
      z_max_(options.linear_damping_max) {
  if (fit_z_ && !(z_max_ > 0 && z_max_ < 1)) {
    throw InputError(fmt::format(
        "update-iwan: the upper bound of the fitted modal damping ratio, {}, must be in (0, 1)",
        z_max_));
  }
  bool found = false;
  for (const model::Joint& j : model.joints) {
    if (j.element != set_) continue;
    if (!j.iwan) throw InputError(fmt::format("set '{}' is not an Iwan set", set_));
    if (!found) {
      Ks_ = j.stiffness;
      initial_ = {j.iwan->slip_force(), j.iwan->stiffness(), j.iwan->chi(), j.iwan->beta()};
      found = true;
    }
  }
  if (!found) throw InputError(fmt::format("no joint of the model uses the Iwan set '{}'", set_));
  if (targets_.empty()) throw InputError("no measured backbone to update against");
  int curve_index = 0;
  for (const IwanTarget& t : targets_) {
    if (t.mode < 1) throw InputError(fmt::format("mode {} must be >= 1", t.mode));
    if (t.curves.empty()) throw InputError(fmt::format("mode {}: no measured backbone", t.mode));
    for (const MeasuredBackbone& c : t.curves) {
      if (c.modal != t.curves.front().modal) {
        throw InputError(fmt::format(
            "mode {}: backbones of modal amplitude and of a sensor's amplitude cannot be fitted "
            "as one mode's target",
            t.mode));
      }
      if (!c.modal && (c.sensor < 0 || c.sensor >= static_cast<int>(sensors_.size()))) {
        throw InputError(fmt::format("mode {}: backbone sensor index out of range", t.mode));
      }
      const std::string name = !c.source.empty() ? c.source
                               : c.modal         ? std::string("modal amplitude")
                                                 : "channel " + sensors_[c.sensor].channel;
      const Eigen::Index n = c.amplitude.size();
      if (n == 0 || c.frequency_hz.size() != n || c.damping_ratio.size() != n ||
          c.frequency_std_hz.size() != n || c.damping_std.size() != n) {
        throw InputError(
            fmt::format("mode {}, {}: backbone columns empty or of unequal length", t.mode, name));
      }
      if (!(c.coverage_factor >= 1 && std::isfinite(c.coverage_factor))) {
        throw InputError(fmt::format("mode {}, {}: coverage factor {} is not a finite number >= 1",
                                     t.mode, name, c.coverage_factor));
      }
      if ((c.amplitude.array() <= 0).any() || (c.frequency_hz.array() <= 0).any() ||
          !c.amplitude.allFinite() || !c.frequency_hz.allFinite() || !c.damping_ratio.allFinite()) {
        throw InputError(fmt::format(
            "mode {}, {}: amplitudes and frequencies must be finite and > 0", t.mode, name));
      }
      residual_count_ += 2 * static_cast<int>(n);
      residual_curve_.insert(residual_curve_.end(), 2 * static_cast<size_t>(n), curve_index++);
      for (Eigen::Index j = 0; j < n; ++j) {
        residual_amplitude_.push_back(c.amplitude(j));
        residual_amplitude_.push_back(c.amplitude(j));
      }
    }
  }
  // The linear model's set-up shared by every evaluation; a model it cannot serve (a mode
  // it does not have) is evaluated from scratch, which says what is wrong.
  int highest = 0;
  for (const IwanTarget& t : targets_) highest = std::max(highest, t.mode);
  try {
    set_model_ = std::make_shared<const model::IwanSetModel>(model, set_, highest);
  } catch (const InputError&) {
    set_model_.reset();
  }
}

ModelBackbone model_backbone(const model::JointCondensation& jc, int mode,
                             std::optional<Eigen::Index> dof, int power, BackboneKind kind,
                             IwanComparison comparison, double a_lo, double a_hi, int points) {
  if (mode < 1 || mode > jc.elastic_count())
    throw InputError(fmt::format("mode {} does not exist: the model has {}", mode,
                                 counted(jc.elastic_count(), "elastic mode")));
  if (!(a_lo > 0) || !(a_hi >= a_lo) || points < 2)
    throw InputError("model backbone: need 0 < a_lo <= a_hi and two points or more");
  const bool matched = comparison == IwanComparison::kMatched;
  // The amplitude as fitted (evaluate()): q itself, or the deflection at the sensor's DOF.
  std::vector<double> s(static_cast<size_t>(points));
  for (int i = 0; i < points; ++i)
    s[static_cast<size_t>(i)] = a_lo * std::pow(a_hi / a_lo, i / (points - 1.0));
  const std::vector<QsmaAtPoint> at =
      qsma_at(jc, mode, power, s,
              matched ? AmplitudeFrequency::kFirstHarmonic : AmplitudeFrequency::kSecant,
              QsmaAtSolver::kNewton, dof);
  ModelBackbone out;
  std::vector<size_t> keep;
  for (size_t i = 0; i < at.size(); ++i)
    if (at[i].reached) keep.push_back(i);
  out.clipped = keep.size() < s.size();
  const Eigen::Index n = static_cast<Eigen::Index>(keep.size());
  out.amplitude.resize(n);
  out.frequency_hz.resize(n);
  out.damping_ratio.resize(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const model::QsmaPoint& q = at[keep[static_cast<size_t>(j)]].point;
    out.amplitude(j) = s[keep[static_cast<size_t>(j)]];
    out.frequency_hz(j) = matched ? q.ringdown_frequency_hz : q.frequency_hz;
    out.damping_ratio(j) = !matched                             ? q.damping_ratio
                           : kind == BackboneKind::kSteppedSine ? q.harmonic_damping_ratio
                                                                : q.ringdown_damping_ratio;
  }
  return out;
}

std::vector<ModelBackbone> IwanObjective::model_curves(const model::IwanParameters& p, double z,
                                                       int points) const {
  const model::Model m = apply(p, z);
  int highest = 0;
  for (const IwanTarget& t : targets_) highest = std::max(highest, t.mode);
  model::ModesOptions mo;
  mo.elastic_count = highest;
  const model::JointCondensation jc(m, mo);
  std::vector<ModelBackbone> out;
  for (const IwanTarget& t : targets_) {
    double lo = INFINITY, hi = 0;
    for (const MeasuredBackbone& c : t.curves) {
      lo = std::min(lo, c.amplitude.minCoeff());
      hi = std::max(hi, c.amplitude.maxCoeff());
    }
    const MeasuredBackbone& first = t.curves.front();
    const std::optional<Eigen::Index> dof =
        first.modal ? std::nullopt : std::optional<Eigen::Index>(sensors_[first.sensor].dof);
    const int pw = first.modal ? 0 : amplitude_power(amplitude_);
    try {
      out.push_back(model_backbone(jc, t.mode, dof, pw, first.kind, comparison_, lo, hi, points));
    } catch (const InputError&) {
      ModelBackbone none;
      none.clipped = true;
      out.push_back(none);
    }
  }
  return out;
}

model::Model IwanObjective::apply(const model::IwanParameters& p, double z) const {
  model::Model m = apply(p);
  m.modal_ratio = z;
  return m;
}

model::Model IwanObjective::apply(const model::IwanParameters& p) const {
  model::Model m = *model_;
  for (model::Joint& j : m.joints) {
    if (j.element != set_) continue;
    j.stiffness = p.Kt;
    j.iwan = model::Iwan(p);
  }
  return m;
}

bool IwanObjective::residuals(const model::IwanParameters& p, double* r) const {
  return evaluate(p, r, nullptr, false);
}

bool IwanObjective::residuals_from_scratch(const model::IwanParameters& p, double* r) const {
  return evaluate(p, r, nullptr, true);
}

bool IwanObjective::residuals_at(const model::IwanParameters& p, double z, double* r) const {
  return evaluate(p, r, nullptr, false, &z);
}

std::optional<Eigen::Vector2d> IwanObjective::rms_errors(const model::IwanParameters& p,
                                                         double z) const {
  std::vector<double> r(residual_count_), v(residual_count_);
  if (!evaluate(p, r.data(), nullptr, false, &z, nullptr, v.data())) return std::nullopt;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int k = 0;
  for (const IwanTarget& t : targets_) {
    for (const MeasuredBackbone& c : t.curves) {
      for (Eigen::Index j = 0; j < c.amplitude.size(); ++j, k += 2) {
        sum(0) += std::pow(v[k] / c.frequency_hz(j) - 1, 2);
        sum(1) += std::pow(v[k + 1] / c.damping_ratio(j) - 1, 2);
      }
    }
  }
  return (sum / (residual_count_ / 2.0)).cwiseSqrt();
}

Eigen::Vector2d IwanObjective::constant_rms_errors() const {
  // The constant c minimising sum ((c - y_j) / y_j)^2 is sum (1/y_j) / sum (1/y_j^2).
  Eigen::Vector2d out;
  for (int part = 0; part < 2; ++part) {
    double s1 = 0, s2 = 0;
    std::vector<double> y;
    for (const IwanTarget& t : targets_)
      for (const MeasuredBackbone& c : t.curves)
        for (Eigen::Index j = 0; j < c.amplitude.size(); ++j)
          y.push_back(part == 0 ? c.frequency_hz(j) : c.damping_ratio(j));
    for (double v : y) s1 += 1 / v, s2 += 1 / (v * v);
    const double best = s1 / s2;
    double e = 0;
    for (double v : y) e += std::pow(best / v - 1, 2);
    out(part) = std::sqrt(e / static_cast<double>(y.size()));
  }
  return out;
}

std::optional<MisfitEvidence> IwanObjective::misfit_evidence(const model::IwanParameters& p,
                                                             double z) const {
  std::vector<double> r(residual_count_), v(residual_count_);
  if (!evaluate(p, r.data(), nullptr, false, &z, nullptr, v.data())) return std::nullopt;
  const auto median = [](std::vector<double> x) {
    if (x.empty()) return 0.0;
    const auto mid = x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2);
    std::nth_element(x.begin(), mid, x.end());
    return *mid;
  };
  // The model as given (its linear part, K_T at the start): what --mode names. At the result
  // K_T may have run to a bound trying to reach another mode's frequency.
  std::optional<model::LinearModes> modes;
  try {
    modes = model::linear_modes(model_->mass, model_->linear_stiffness());
  } catch (const InputError&) {
    modes.reset();  // no linear modes: no mode is named
  }
  // The model at p: its linear frequencies (K_T as fitted or held), the curve's zero-amplitude
  // limit.
  std::optional<model::LinearModes> fitted_modes;
  try {
    const model::Model m = apply(p);
    fitted_modes = model::linear_modes(m.mass, m.linear_stiffness());
  } catch (const InputError&) {
    fitted_modes.reset();
  }
  std::optional<MisfitEvidence> out;
  std::vector<double> damping_ratios;
  double damping_max = 0;
  // Scatter between curves: per target, each curve's mean normalised residual (frequency and
  // damping apart) against the target's mean; and each curve's mean relative offset.
  double total = 0, between = 0;
  int between_curves = 0;
  double apart_t = 0;
  std::string apart_name;
  Eigen::Vector2d apart_offset = Eigen::Vector2d::Zero(), apart_others = Eigen::Vector2d::Zero();
  bool apart_damping = false;
  int apart_points = 0;
  Eigen::Vector2d apart_amplitude = Eigen::Vector2d::Zero();
  Eigen::Vector2d f_range(INFINITY, -INFINITY), z_range(INFINITY, -INFINITY);
  for (double x : r) total += x * x;
  int k = 0;
  for (const IwanTarget& t : targets_) {
    if (t.curves.size() >= 2) {
      const size_t nc = t.curves.size();
      std::vector<Eigen::Vector2d> mean_r(nc), mean_rel(nc), noise_rel(nc);
      std::vector<double> count(nc);
      Eigen::Vector2d sum_r = Eigen::Vector2d::Zero(), sum_rel = Eigen::Vector2d::Zero();
      double n_all = 0;
      int i = k;
      for (size_t c = 0; c < nc; ++c) {
        const MeasuredBackbone& b = t.curves[c];
        const Eigen::Index n = b.amplitude.size();
        Eigen::Vector2d rr = Eigen::Vector2d::Zero(), rel = Eigen::Vector2d::Zero(),
                        var = Eigen::Vector2d::Zero();
        for (Eigen::Index j = 0; j < n; ++j, i += 2) {
          rr += Eigen::Vector2d(r[static_cast<size_t>(i)], r[static_cast<size_t>(i + 1)]);
          const double fm = v[static_cast<size_t>(i)], zm = v[static_cast<size_t>(i + 1)];
          rel += Eigen::Vector2d(fm > 0 ? b.frequency_hz(j) / fm - 1 : 0,
                                 zm > 0 ? b.damping_ratio(j) / zm - 1 : 0);
          const Eigen::Vector2d stated = stated_sigma(b, j);
          const double sf = std::max(stated(0), f_floor_ * b.frequency_hz(j));
          const double sz = std::max(stated(1), z_floor_ * std::abs(b.damping_ratio(j)));
          var +=
              Eigen::Vector2d(fm > 0 ? std::pow(sf / fm, 2) : 0, zm > 0 ? std::pow(sz / zm, 2) : 0);
        }
        count[c] = static_cast<double>(n);
        mean_r[c] = rr / std::max(1.0, count[c]);
        mean_rel[c] = rel / std::max(1.0, count[c]);
        noise_rel[c] = var.cwiseSqrt() / std::max(1.0, count[c]);
        sum_r += rr, sum_rel += rel, n_all += count[c];
      }
      const Eigen::Vector2d mr = sum_r / n_all, mrel = sum_rel / n_all;
      for (size_t c = 0; c < nc; ++c) {
        between += count[c] * (mean_r[c] - mr).squaredNorm();
        const Eigen::Vector2d d = mean_rel[c] - mrel;
        f_range = Eigen::Vector2d(std::min(f_range(0), d(0)), std::max(f_range(1), d(0)));
        z_range = Eigen::Vector2d(std::min(z_range(0), d(1)), std::max(z_range(1), d(1)));
      }
      between_curves += static_cast<int>(nc);
      // A curve unlike the others: its offset against the mean of the target's others, in their
      // spread (sample standard deviation s, nc - 2 degrees of freedom) and its own noise. Were
      // the offsets random scatter between hits, (x - mean) / (s sqrt(1 + 1 / (nc - 1))) is
      // Student's t with nc - 2 degrees of freedom; a chance below 1 % over the 2 nc tries
      // (Bonferroni) sets the curve apart. The case of the two joint sets (a bolt pair at each
      // end and rivets at mid-span, three levels struck at mid-span in pairs of hits and one
      // struck at x = 0.375 m where mode 2 slips the same joints): that hit's damping +94 %
      // about the fitted curve against the others' -3.5 to +2.3 % (t 27 at 5 degrees of
      // freedom, where the 1 % point is 7.4); the cluster covariance read it as scatter and
      // stated K_T +/- 0.24 % at z +7.1 and F_S at beta 1 +/- 5.8 % at z -10.
      if (nc >= 4) {
        const boost::math::students_t dist(static_cast<double>(nc) - 2);
        for (size_t c = 0; c < nc; ++c) {
          for (int q = 0; q < 2; ++q) {
            double m = 0, ss = 0;
            for (size_t o = 0; o < nc; ++o)
              if (o != c) m += mean_rel[o](q);
            m /= static_cast<double>(nc - 1);
            Eigen::Vector2d others(INFINITY, -INFINITY);
            for (size_t o = 0; o < nc; ++o) {
              if (o == c) continue;
              ss += std::pow(mean_rel[o](q) - m, 2);
              others = Eigen::Vector2d(std::min(others(0), mean_rel[o](q)),
                                       std::max(others(1), mean_rel[o](q)));
            }
            const double sd = std::sqrt(ss / static_cast<double>(nc - 2));
            const double scale = std::sqrt(sd * sd * (1 + 1.0 / static_cast<double>(nc - 1)) +
                                           std::pow(noise_rel[c](q), 2));
            if (!(scale > 0)) continue;
            const double tc = std::abs(mean_rel[c](q) - m) / scale;
            const double chance = 2 * boost::math::cdf(boost::math::complement(dist, tc));
            if (chance * 2 * static_cast<double>(nc) < 0.01 && tc > apart_t) {
              const MeasuredBackbone& b = t.curves[c];
              apart_t = tc;
              apart_name = !b.source.empty() ? b.source : fmt::format("curve {}", c + 1);
              apart_offset = mean_rel[c] - mrel;
              apart_others = others - Eigen::Vector2d::Constant(mrel(q));
              apart_damping = q == 1;
              apart_points = static_cast<int>(b.amplitude.size());
              apart_amplitude = Eigen::Vector2d(b.amplitude.minCoeff(), b.amplitude.maxCoeff());
            }
          }
        }
      }
    }
    // Each curve's lowest tenth of its points by amplitude (at least 3, at most all): where the
    // model is at its linear limit, K_T and the linear part.
    std::vector<double> f_lo, error, noise, z_lo, z_model_lo, all_z, f_share;
    for (const MeasuredBackbone& c : t.curves) {
      const Eigen::Index n = c.amplitude.size();
      std::vector<Eigen::Index> by_amplitude(static_cast<size_t>(n));
      for (Eigen::Index j = 0; j < n; ++j) by_amplitude[static_cast<size_t>(j)] = j;
      std::sort(by_amplitude.begin(), by_amplitude.end(),
                [&](Eigen::Index a, Eigen::Index b) { return c.amplitude(a) < c.amplitude(b); });
      const Eigen::Index low = std::min<Eigen::Index>(n, std::max<Eigen::Index>(3, n / 10));
      for (Eigen::Index i = 0; i < low; ++i) {
        const Eigen::Index j = by_amplitude[static_cast<size_t>(i)];
        const double f = c.frequency_hz(j);
        f_lo.push_back(f);
        error.push_back(v[static_cast<size_t>(k + 2 * j)] / f - 1);
        noise.push_back(std::max(stated_sigma(c, j)(0), f_floor_ * f) / f);
        z_lo.push_back(c.damping_ratio(j));
        z_model_lo.push_back(v[static_cast<size_t>(k + 2 * j + 1)]);
      }
      // The measured frequency's drop from the lowest fifth of the points by amplitude to the
      // second fifth, over its drop from the lowest fifth to the highest (medians of each): the
      // share of the curve's softening that happens at its low end.
      if (const Eigen::Index fifth = n / 5; fifth >= 2) {
        const auto band = [&](Eigen::Index from) {
          std::vector<double> f;
          for (Eigen::Index i = from; i < from + fifth; ++i)
            f.push_back(c.frequency_hz(by_amplitude[static_cast<size_t>(i)]));
          return median(f);
        };
        const double f1 = band(0), f2 = band(fifth), f5 = band(n - fifth);
        if (f1 > f5) f_share.push_back((f1 - f2) / (f1 - f5));
      }
      for (Eigen::Index j = 0; j < n; ++j) {
        const double model_z = v[static_cast<size_t>(k + 2 * j + 1)];
        if (model_z > 0) damping_ratios.push_back(c.damping_ratio(j) / model_z);
        damping_max = std::max(damping_max, c.damping_ratio(j));
        all_z.push_back(c.damping_ratio(j));
      }
      k += 2 * static_cast<int>(n);
    }
    MisfitEvidence e;
    e.mode = t.mode;
    e.low_frequency_hz = median(f_lo);
    e.low_frequency_error = median(error);
    e.low_frequency_noise = median(noise);
    e.low_damping = median(z_lo);
    e.low_model_damping = median(z_model_lo);
    e.median_damping = median(all_z);
    e.low_softening_share = f_share.empty() ? NAN : median(f_share);
    e.targets = static_cast<int>(targets_.size());
    if (modes && e.low_frequency_hz > 0) {
      // Another elastic mode whose linear frequency lies within a third of mode R's distance
      // from the measured one: the backbone may be that mode's.
      const int col = modes->rigid_count + t.mode - 1;
      if (col < modes->size()) e.mode_hz = modes->frequency_hz(col);
      double best = std::abs(e.mode_hz / e.low_frequency_hz - 1) / 3;
      for (int i = modes->rigid_count; i < modes->size() && e.mode_hz > 0; ++i) {
        const double d = std::abs(modes->frequency_hz(i) / e.low_frequency_hz - 1);
        if (i != col && d < best) {
          best = d;
          e.nearer_mode = i - modes->rigid_count + 1;
          e.nearer_mode_hz = modes->frequency_hz(i);
        }
      }
    }
    if (fitted_modes) {
      const int col = fitted_modes->rigid_count + t.mode - 1;
      if (col < fitted_modes->size()) e.linear_hz = fitted_modes->frequency_hz(col);
    }
    if (!out || std::abs(e.low_frequency_error) > std::abs(out->low_frequency_error)) out = e;
  }
  if (out) {
    out->damping_factor = median(damping_ratios);
    out->damping_max = damping_max;
    if (between_curves > 0 && total > 0) {
      out->between_curves_share = between / total;
      out->curves = between_curves;
      out->frequency_offsets = f_range;
      out->damping_offsets = z_range;
      out->apart_curve = apart_name;
      out->apart_t = apart_t;
      out->apart_offset = apart_offset;
      out->apart_others = apart_others;
      out->apart_in_damping = apart_damping;
      out->apart_points = apart_points;
      out->apart_amplitude = apart_amplitude;
    }
  }
  return out;
}

std::optional<double> IwanObjective::linear_damping(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  double z = 0;
  if (!evaluate(p, r.data(), nullptr, false, nullptr, &z)) return std::nullopt;
  return z;
}

Eigen::Vector2d IwanObjective::slip_range(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  Eigen::Vector2d slip(INFINITY, 0);
  return evaluate(p, r.data(), &slip, false) ? slip : Eigen::Vector2d::Zero();
}

bool IwanObjective::evaluate(const model::IwanParameters& p, double* r, Eigen::Vector2d* slip_range,
                             bool from_scratch, const double* z_fixed, double* z_used,
                             double* values) const {
  ++evaluations_;
  if (!model::iwan_parameter_error(p).empty()) return false;
  const double n_total = residual_count_ / 2.0;
  // The damping residuals are those of the joints alone plus the structure's own Z, added
  // below: r_z,j = (zeta_J,j + Z - zeta_j) / (sigma_z,j sqrt(N)). Their positions and scales.
  std::vector<int> z_index;
  std::vector<double> z_scale;
  z_index.reserve(static_cast<size_t>(n_total));
  z_scale.reserve(static_cast<size_t>(n_total));
  try {
    std::optional<model::JointCondensation> shared;
    if (!from_scratch && set_model_) shared = set_model_->at(p);
    model::JointCondensation& jc = shared ? *shared : shared.emplace(apply(p));
    jc.set_linear_damping(0);
    const model::LinearModes& modes = jc.modes();
    int k = 0;
    for (const IwanTarget& t : targets_) {
      if (t.mode > jc.elastic_count()) return false;
      const int col = modes.rigid_count + t.mode - 1;
      // A modal amplitude is q itself (power 0); a sensor's is |u_d| w^p, u_d the QSMA
      // deflection at its DOF d (not |phi_R[d]| q w^p: once the joints slip the deflected
      // shape leaves the linear mode's, qsma_at.h).
      const bool modal = t.curves.front().modal;
      const int pw = modal ? 0 : amplitude_power(amplitude_);
      // Every point of every curve of this target read at one DOF on one QSMA curve.
      std::map<Eigen::Index, std::vector<std::pair<double, std::pair<size_t, Eigen::Index>>>>
          by_dof;  // DOF (-1: modal) -> (s, (curve, point))
      for (size_t ci = 0; ci < t.curves.size(); ++ci) {
        const MeasuredBackbone& c = t.curves[ci];
        const Eigen::Index dof = modal ? -1 : sensors_[c.sensor].dof;
        // A mode that leaves the sensor still (to rounding: 1e-8 of its largest motion) is
        // not the one measured there.
        const double ph = modal ? 1.0 : std::abs(modes.shapes(dof, col));
        if (!(ph > 1e-8 * modes.shapes.col(col).cwiseAbs().maxCoeff())) return false;
        for (Eigen::Index j = 0; j < c.amplitude.size(); ++j)
          by_dof[dof].push_back({c.amplitude(j), {ci, j}});
      }
      const bool matched = comparison_ == IwanComparison::kMatched;
      std::vector<std::vector<QsmaAtPoint>> curves;  // kept: model_at points into them
      curves.reserve(by_dof.size());
      // Residuals in the order of the curves and their points.
      std::vector<std::vector<const model::QsmaPoint*>> model_at(t.curves.size());
      for (size_t ci = 0; ci < t.curves.size(); ++ci)
        model_at[ci].resize(static_cast<size_t>(t.curves[ci].amplitude.size()));
      for (auto& [dof, order] : by_dof) {
        std::sort(order.begin(), order.end());
        std::vector<double> s(order.size());
        for (size_t i = 0; i < order.size(); ++i) s[i] = order[i].first;
        curves.push_back(
            qsma_at(jc, t.mode, pw, s,
                    matched ? AmplitudeFrequency::kFirstHarmonic : AmplitudeFrequency::kSecant,
                    from_scratch ? QsmaAtSolver::kBracketing : QsmaAtSolver::kNewton,
                    dof < 0 ? std::nullopt : std::optional<Eigen::Index>(dof)));
        const std::vector<QsmaAtPoint>& at = curves.back();
        if (at.size() != s.size()) return false;
        if (slip_range) {
          (*slip_range)(0) = std::min((*slip_range)(0), at.front().point.max_slip);
          (*slip_range)(1) = std::max((*slip_range)(1), at.back().point.max_slip);
        }
        for (size_t i = 0; i < order.size(); ++i)
          model_at[order[i].second.first][static_cast<size_t>(order[i].second.second)] =
              &at[i].point;
      }
      for (size_t ci = 0; ci < t.curves.size(); ++ci) {
        const MeasuredBackbone& c = t.curves[ci];
        for (Eigen::Index j = 0; j < c.amplitude.size(); ++j) {
          const model::QsmaPoint& q = *model_at[ci][static_cast<size_t>(j)];
          const double f = matched ? q.ringdown_frequency_hz : q.frequency_hz;
          const double z = !matched                               ? q.damping_ratio
                           : c.kind == BackboneKind::kSteppedSine ? q.harmonic_damping_ratio
                                                                  : q.ringdown_damping_ratio;
          const Eigen::Vector2d stated = stated_sigma(c, j);
          const double sf = std::max(stated(0), f_floor_ * c.frequency_hz(j));
          const double sz = std::max(stated(1), z_floor_ * std::abs(c.damping_ratio(j)));
          if (values) {
            values[k] = f;
            values[k + 1] = z;
          }
          r[k++] = (f - c.frequency_hz(j)) / (sf * std::sqrt(n_total));
          if (sz > 0) {
            z_index.push_back(k);
            z_scale.push_back(1 / (sz * std::sqrt(n_total)));
          }
          r[k++] = sz > 0 ? (z - c.damping_ratio(j)) / (sz * std::sqrt(n_total)) : 0.0;
        }
      }
    }
  } catch (const InputError&) {
    return false;
  }
  // The structure's own damping: given, the model's, or the best in [0, z_max] (the residuals
  // are linear in Z with slopes z_scale: Z = -sum s_j r_j / sum s_j^2 minimises them).
  double z = z_fixed ? *z_fixed : z_model_;
  if (!z_fixed && fit_z_) {
    double num = 0, den = 0;
    for (size_t i = 0; i < z_index.size(); ++i) {
      num -= z_scale[i] * r[z_index[i]];
      den += z_scale[i] * z_scale[i];
    }
    z = den > 0 ? std::clamp(num / den, 0.0, z_max_) : 0.0;
  }
  for (size_t i = 0; i < z_index.size(); ++i) r[z_index[i]] += z * z_scale[i];
  if (values)
    for (int i = 1; i < residual_count_; i += 2) values[i] += z;
  if (z_used) *z_used = z;
  for (int i = 0; i < residual_count_; ++i) {
    if (!std::isfinite(r[i])) return false;
  }
  return true;
}

bool IwanObjective::residuals_with_structure_stiffness(const model::IwanParameters& p, double z,
                                                       double factor, double* r) const {
  model::Model m = *model_;
  m.stiffness *= factor;
  IwanUpdateOptions o;
  o.amplitude = amplitude_;
  o.comparison = comparison_;
  o.frequency_floor = f_floor_;
  o.damping_floor = z_floor_;
  try {
    const IwanObjective scaled(m, set_, sensors_, targets_, o);
    return scaled.residuals_at(p, z, r);
  } catch (const InputError&) {
    return false;
  }
}

std::optional<double> IwanObjective::try_cost(const model::IwanParameters& p) const {
  std::vector<double> r(residual_count_);
  if (!residuals(p, r.data())) return std::nullopt;
  double s = 0;
  for (double v : r) s += v * v;
  return s;
}

double IwanObjective::cost(const model::IwanParameters& p) const {
  return try_cost(p).value_or(kPenalty);
}

Eigen::Vector2d IwanObjective::frequency_reach(int mode, double gamma) const {
  model::Model m = *model_;
  Eigen::Vector2d out(NAN, NAN);
  try {
    const model::LinearModes as_given = model::linear_modes(m.mass, m.linear_stiffness());
    const int col = as_given.rigid_count + mode - 1;  // the same ordered eigenvalue in both
    for (int side = 0; side < 2; ++side) {
      for (model::Joint& j : m.joints)
        if (j.element == set_) j.stiffness = side == 0 ? 0.0 : gamma * Ks_;
      const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
      if (col < lm.size()) out(side) = std::max(lm.frequency_hz(col), 0.0);
    }
  } catch (const InputError&) {
    return Eigen::Vector2d(NAN, NAN);
  }
  return out;
}

std::string unreachable_frequencies(const IwanObjective& objective,
                                    const IwanUpdateOptions& options) {
  const double gamma = options.fixed_gamma > 0 ? options.fixed_gamma : options.bounds.gamma_max;
  const double kt = gamma * objective.reference_stiffness();
  std::string out;
  for (const IwanTarget& t : objective.targets()) {
    double lo = INFINITY, hi = 0;
    for (const MeasuredBackbone& c : t.curves) {
      lo = std::min(lo, c.frequency_hz.minCoeff());
      hi = std::max(hi, c.frequency_hz.maxCoeff());
    }
    const Eigen::Vector2d reach = objective.frequency_reach(t.mode, gamma);
    if (!reach.allFinite()) continue;
    const std::string stuck =
        fmt::format("stuck at K_T = {:.4g} x K_s = {:.6g} N/m ({})", gamma, kt,
                    options.fixed_gamma > 0 ? "--gamma" : "the top of the gamma range");
    std::string e;
    if (lo > reach(1)) {
      e = fmt::format(
          "mode {}: every measured frequency ({:.6g} to {:.6g} Hz) lies above {:.6g} Hz, the "
          "highest model mode {} reaches (every element of the set {}; slipped, it falls to "
          "{:.6g} Hz)",
          t.mode, lo, hi, reach(1), t.mode, stuck, reach(0));
    } else if (hi < reach(0)) {
      e = fmt::format(
          "mode {}: every measured frequency ({:.6g} to {:.6g} Hz) lies below {:.6g} Hz, the "
          "lowest model mode {} reaches (every element of the set slipped, no stiffness; {}, it "
          "rises to {:.6g} Hz)",
          t.mode, lo, hi, reach(0), t.mode, stuck, reach(1));
    }
    if (!e.empty()) out += (out.empty() ? "" : "; ") + e;
  }
  if (!out.empty()) {
    out +=
        ": no Iwan parameters in the bounds can fit these backbones; check the model's linear "
        "part (update-linear), the mode and the frequency column";
  }
  return out;
}

double IwanObjective::linear_error(const model::IwanParameters& p) const {
  const model::Model m = apply(p);
  const model::LinearModes modes = model::linear_modes(m.mass, m.linear_stiffness());
  double e = 0;
  for (const IwanTarget& t : targets_) {
    if (!(t.linear_frequency_hz > 0)) continue;
    const int col = modes.rigid_count + t.mode - 1;
    if (col >= modes.size()) continue;
    e = std::max(e,
                 std::abs(modes.frequency_hz(col) - t.linear_frequency_hz) / t.linear_frequency_hz);
  }
  return e;
}

void IwanObjective::set_linear_modes(const MeasuredModes& measured, double mac_threshold) {
  if (measured.shapes.rows() != static_cast<Eigen::Index>(sensors_.size()) ||
      measured.shapes.cols() != measured.frequency_hz.size()) {
    throw InputError("measured linear modes: shapes do not match the sensors and frequencies");
  }
  linear_modes_ = measured;
  linear_mac_ = mac_threshold;
}

std::vector<std::optional<double>> IwanObjective::linear_errors(
    const model::IwanParameters& p) const {
  std::vector<std::optional<double>> out;
  if (linear_modes_.frequency_hz.size() == 0) return out;
  const model::Model m = apply(p);
  const StiffnessSets none(m, {});
  const LinearEvaluation e =
      evaluate_linear(none, m, sensors_, linear_modes_, Eigen::VectorXd::Zero(0), linear_mac_);
  out.resize(static_cast<size_t>(linear_modes_.frequency_hz.size()));
  for (const ModePair& q : e.pairing.pairs)
    out[static_cast<size_t>(q.measured)] = e.residuals(q.measured);
  return out;
}

std::vector<std::vector<std::optional<double>>> IwanObjective::linear_errors_along(
    const std::vector<double>& gammas) const {
  const size_t m = static_cast<size_t>(linear_modes_.frequency_hz.size());
  std::vector<std::vector<std::optional<double>>> out(gammas.size());
  if (m == 0) return out;
  const StiffnessSets sets(*model_, {set_});
  const double k0 = sets.initial()(0);
  PairingRules rules;
  rules.mac_threshold = linear_mac_;
  const Eigen::VectorXd theta0 = Eigen::VectorXd::Constant(1, k0);
  const LinearEvaluation at0 =
      evaluate_linear(sets, *model_, sensors_, linear_modes_, theta0, rules);
  std::vector<int> columns(m, -1);
  for (const ModePair& q : at0.pairing.pairs) columns[static_cast<size_t>(q.measured)] = q.model;
  const ElasticModes modes0 = elastic_modes(model_->mass, sets.stiffness(theta0));
  // Walk up from gamma = 1 through the larger gammas in ascending order, then down through the
  // smaller ones in descending order.
  std::vector<size_t> order(gammas.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return gammas[a] < gammas[b]; });
  auto walk = [&](const std::vector<size_t>& along) {
    ElasticModes now = modes0;
    std::vector<int> cols = columns;
    double g_now = 1.0;
    for (size_t i : along) {
      const double g = gammas[i];
      const double a = std::log(g_now), b = std::log(g);
      TrackingOptions t;
      t.substeps = std::max(1, static_cast<int>(std::ceil(std::abs(b - a) / 0.05)));
      const auto path = [&](double s) {
        return sets.stiffness(Eigen::VectorXd::Constant(1, k0 * std::exp(a + s * (b - a))));
      };
      std::optional<FollowedModes> f;
      try {
        f = follow_path(path, model_->mass, now, cols, t);
      } catch (const InputError&) {
      }
      if (!f) return;  // lost: this gamma and those beyond have no followed pairs
      now = std::move(f->modes);
      cols = std::move(f->columns);
      g_now = g;
      const LinearEvaluation e = evaluate_pairs(sets, sensors_, linear_modes_,
                                                Eigen::VectorXd::Constant(1, k0 * g), now, cols);
      out[i].resize(m);
      for (const ModePair& q : e.pairing.pairs)
        out[i][static_cast<size_t>(q.measured)] = e.residuals(q.measured);
    }
  };
  std::vector<size_t> up, down;
  for (size_t i : order) (gammas[i] >= 1.0 ? up : down).push_back(i);
  std::reverse(down.begin(), down.end());
  walk(up);
  walk(down);
  for (auto& v : out) v.resize(m);
  return out;
}

namespace {

// The search vector v = (F_S, gamma, chi, beta).
using Vec4 = Eigen::Vector4d;

model::IwanParameters to_params(const Vec4& v, double Ks) { return {v(0), v(1) * Ks, v(2), v(3)}; }

// Evaluations with bookkeeping: history, best, budget, progress.
struct Tracker {
  const IwanObjective& objective;
  const IwanUpdateOptions& options;
  IwanUpdateSummary& summary;
  int start_evaluations;
  Vec4 best_v = Vec4::Zero();
  double best = INFINITY;

  int used() const { return objective.evaluations() - start_evaluations; }
  bool spent() const { return used() >= options.max_evaluations; }
  void record(const Vec4& v, double c) { record(v, c, used()); }
  void record(const Vec4& v, double c, int evaluation) {
    if (c < best) {
      best = c;
      best_v = v;
    }
    summary.history.push_back({evaluation, c, best, options.fixed_beta.has_value()});
    if (options.progress) options.progress(evaluation, best);
  }
  // Costs of vs (evaluated on options.threads threads, each independent of the others), then
  // recorded in their order: the outcome does not depend on the number of threads.
  std::vector<double> eval(const std::vector<Vec4>& vs) {
    std::vector<double> c(vs.size());
    const int base = used();
    parallel_for(
        vs.size(), static_cast<unsigned>(options.threads), [] { return 0; },
        [&](size_t i, int) {
          // A set the model cannot evaluate costs +inf: never a best, never a number written.
          c[i] = objective.try_cost(to_params(vs[i], objective.reference_stiffness()))
                     .value_or(INFINITY);
        });
    for (size_t i = 0; i < vs.size(); ++i) record(vs[i], c[i], base + static_cast<int>(i) + 1);
    return c;
  }
};

struct Box {
  Vec4 lo, hi;
};

Vec4 sample(const Box& b, bool log_scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Vec4 v;
  for (int i = 0; i < 4; ++i) {
    const double t = u(rng);
    const bool lg = log_scale && i != 2 && b.lo(i) > 0;
    v(i) = lg ? std::exp(std::log(b.lo(i)) + t * (std::log(b.hi(i)) - std::log(b.lo(i))))
              : b.lo(i) + t * (b.hi(i) - b.lo(i));
  }
  return v;
}

// Which of (F_S, gamma, chi, beta) the options hold at a given value.
std::array<bool, 4> held_parameters(const IwanUpdateOptions& o) {
  return {false, o.fixed_gamma > 0, false, o.fixed_beta.has_value()};
}

Box initial_box(const IwanUpdateOptions& o) {
  const IwanBounds& b = o.bounds;
  Box box{Vec4(b.Fs_min, b.gamma_min, b.chi_min, b.beta_min),
          Vec4(b.Fs_max, b.gamma_max, b.chi_max, b.beta_max)};
  if (o.fixed_gamma > 0) box.lo(1) = box.hi(1) = o.fixed_gamma;
  if (o.fixed_beta) box.lo(3) = box.hi(3) = *o.fixed_beta;
  return box;
}

void monte_carlo(Tracker& tr, bool log_scale, std::mt19937& rng) {
  const Box full = initial_box(tr.options);
  Box box = full;
  double previous = INFINITY;
  while (!tr.spent()) {
    const int n = std::min(tr.options.samples, tr.options.max_evaluations - tr.used());
    for (int done = 0; done < n;) {
      std::vector<Vec4> vs;
      for (; done < n && static_cast<int>(vs.size()) < kBatch; ++done)
        vs.push_back(sample(box, log_scale, rng));
      tr.eval(vs);
    }
    ++tr.summary.rounds;
    if (!(tr.best < previous)) {
      tr.summary.status = IwanUpdateStatus::kConverged;
      return;
    }
    previous = tr.best;
    for (int i = 0; i < 4; ++i) {
      const double d = tr.options.contraction * std::max(std::abs(tr.best_v(i)), 1e-3);
      box.lo(i) = std::max(full.lo(i), tr.best_v(i) - d);
      box.hi(i) = std::min(full.hi(i), tr.best_v(i) + d);
    }
  }
  tr.summary.status = IwanUpdateStatus::kBudget;
}

// x = (ln F_S, ln gamma, chi, ln beta).
Vec4 to_x(const Vec4& v) { return Vec4(std::log(v(0)), std::log(v(1)), v(2), std::log(v(3))); }
Vec4 to_v(const double* x) { return Vec4(std::exp(x[0]), std::exp(x[1]), x[2], std::exp(x[3])); }

// Residuals with central-difference Jacobians (QSMA is not templated on the scalar). Not
// ceres::NumericDiffCostFunction: its step is |x| times a relative size, which vanishes for
// ln gamma and ln beta near 0, where the 1e-10 accuracy of qsma_at would swamp the difference;
// a fixed step of 1e-4 in x keeps that error near 1e-6 of the derivative.
class IwanCost : public ceres::CostFunction {
 public:
  IwanCost(Tracker& tr, std::array<bool, 4> held) : tr_(tr), held_(held) {
    set_num_residuals(tr.objective.residual_count());
    mutable_parameter_block_sizes()->push_back(4);
  }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    const double Ks = tr_.objective.reference_stiffness();
    const Vec4 v = with_held(to_v(x[0]));
    if (!tr_.objective.residuals(to_params(v, Ks), r)) {
      tr_.record(v, INFINITY);
      return false;
    }
    double c = 0;
    for (int i = 0; i < num_residuals(); ++i) c += r[i] * r[i];
    tr_.record(v, c);
    if (!jac || !jac[0]) return true;
    const int m = num_residuals();
    // The 2 x 4 shifted residual vectors, each independent: on the option's threads.
    const double h = 1e-4;
    std::vector<std::vector<double>> shifted(8, std::vector<double>(m));
    std::array<char, 8> ok{};
    parallel_for(
        8, static_cast<unsigned>(tr_.options.threads), [] { return 0; },
        [&](size_t j, int) {
          const int k = static_cast<int>(j / 2);
          if (held_[k]) return;
          double xs[4];
          std::copy(x[0], x[0] + 4, xs);
          xs[k] += j % 2 == 0 ? h : -h;
          ok[j] = tr_.objective.residuals(to_params(with_held(to_v(xs)), Ks), shifted[j].data());
        });
    for (int k = 0; k < 4; ++k) {
      if (held_[k]) {
        for (int i = 0; i < m; ++i) jac[0][i * 4 + k] = 0;
        continue;
      }
      if (!ok[2 * k] || !ok[2 * k + 1]) return false;
      const std::vector<double>&rp = shifted[2 * k], &rm = shifted[2 * k + 1];
      for (int i = 0; i < m; ++i) jac[0][i * 4 + k] = (rp[i] - rm[i]) / (2 * h);
    }
    return true;
  }

 private:
  // v with the held parameters at their values: their coordinates in x are placeholders (ln 0
  // of beta held at 0 is no finite coordinate).
  Vec4 with_held(Vec4 v) const {
    const IwanUpdateOptions& o = tr_.options;
    if (held_[1]) v(1) = o.fixed_gamma;
    if (held_[3]) v(3) = *o.fixed_beta;
    return v;
  }

  Tracker& tr_;
  std::array<bool, 4> held_;
};

class BudgetCallback : public ceres::IterationCallback {
 public:
  BudgetCallback(const Tracker& tr, int limit) : tr_(tr), limit_(limit) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return tr_.used() >= limit_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const Tracker& tr_;
  int limit_;
};

// One local solve (Ceres, Levenberg-Marquardt on x = (ln F_S, ln gamma, chi, ln beta) in the
// search box) from v, stopped when the evaluations used reach `limit` or after `iterations`
// iterations; true when it met its tolerance (ceres::CONVERGENCE).
bool local_solve(Tracker& tr, const Vec4& v, int limit, int iterations) {
  const Box full = initial_box(tr.options);
  const std::array<bool, 4> held = held_parameters(tr.options);
  std::vector<int> constant;
  for (int k = 0; k < 4; ++k)
    if (held[k]) constant.push_back(k);
  Vec4 x = to_x(v);
  for (int k = 0; k < 4; ++k)
    if (held[k]) x(k) = 0;  // a placeholder (IwanCost uses the held values)
  ceres::Problem problem;
  problem.AddResidualBlock(new IwanCost(tr, held), nullptr, x.data());
  const Vec4 lo = to_x(full.lo), hi = to_x(full.hi);
  if (!constant.empty()) problem.SetManifold(x.data(), new ceres::SubsetManifold(4, constant));
  for (int k = 0; k < 4; ++k) {
    if (held[k]) continue;
    problem.SetParameterLowerBound(x.data(), k, lo(k));
    problem.SetParameterUpperBound(x.data(), k, hi(k));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = iterations;
  so.logging_type = ceres::SILENT;  // outcomes reach the user through the summary
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-8;
  BudgetCallback cb(tr, limit);
  so.callbacks.push_back(&cb);
  ceres::Solver::Summary cs;
  ceres::Solve(so, &problem, &cs);
  return cs.termination_type == ceres::CONVERGENCE;
}

// `extra` (may be null): a candidate already evaluated with its cost, refined by the local
// solve whatever its rank among the samples (the constant-backbone candidate).
// The budget bounds the exploration: half of it samples the box, the rest is shared among the
// local solves from the best samples, each stopped at its share. The local solve that found the
// best point is then carried on from there to its tolerance (the polish), past the budget if
// need be, by at most another budget: sigmas are taken at a minimum, not where a share ran out.
// (Before, 7 of 12 one-curve fits of the cantilever at the default 1500 stopped mid-descent,
// cost 1.31 where 6000 evaluations reached 0.73, chi 4.6 sigma off, and were reported.)
void global_local(Tracker& tr, std::mt19937& rng, const std::pair<double, Vec4>* extra) {
  const IwanUpdateOptions& o = tr.options;
  const Box full = initial_box(o);
  std::vector<std::pair<double, Vec4>> samples;
  const int n_global =
      std::min(std::max(o.samples, o.max_evaluations / 2), o.max_evaluations - tr.used());
  for (int done = 0; done < n_global;) {
    std::vector<Vec4> vs;
    for (; done < n_global && static_cast<int>(vs.size()) < kBatch; ++done)
      vs.push_back(sample(full, true, rng));
    const std::vector<double> c = tr.eval(vs);
    for (size_t i = 0; i < vs.size(); ++i) samples.emplace_back(c[i], vs[i]);
  }
  std::sort(samples.begin(), samples.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  int starts = o.local_starts;
  if (extra && std::isfinite(extra->first)) {
    samples.insert(samples.begin() + std::min<size_t>(samples.size(), o.local_starts), *extra);
    ++starts;
  }
  // Whether the local solve that last lowered the best met its tolerance (none yet: a sample).
  bool best_converged = false;
  for (int s = 0; s < starts && s < static_cast<int>(samples.size()); ++s) {
    if (!std::isfinite(samples[s].first)) continue;
    const int remaining = o.max_evaluations - tr.used();
    if (remaining <= 9) break;
    const double before = tr.best;
    const bool converged =
        local_solve(tr, samples[s].second, tr.used() + remaining / (starts - s), kLocalIterations);
    ++tr.summary.rounds;
    if (tr.best < before) best_converged = converged;
  }
  tr.summary.polish_evaluations = 0;
  if (!best_converged && std::isfinite(tr.best)) {
    const int used = tr.used();
    best_converged = local_solve(tr, tr.best_v, used + o.max_evaluations, kPolishIterations);
    tr.summary.polish_evaluations = tr.used() - used;
  }
  tr.summary.status = best_converged ? IwanUpdateStatus::kConverged : IwanUpdateStatus::kBudget;
}

// The points of each curve (the index of each point's frequency residual; its damping residual
// follows), ordered by amplitude: the order serial correlation runs in.
std::vector<std::vector<int>> points_by_amplitude(const IwanObjective& objective) {
  const std::vector<int>& curve = objective.residual_curve();
  const std::vector<double>& amp = objective.residual_amplitude();
  const int m = static_cast<int>(curve.size());
  std::vector<std::vector<int>> out;
  for (int begin = 0; begin < m;) {
    int end = begin;
    while (end < m && curve[end] == curve[begin]) ++end;
    std::vector<int>& points = out.emplace_back();
    for (int i = begin; i < end; i += 2) points.push_back(i);
    std::stable_sort(points.begin(), points.end(), [&](int a, int b) { return amp[a] < amp[b]; });
    begin = end;
  }
  return out;
}

// The bandwidth L of hac_scores() and residual_correlation_time() for a curve of n points whose
// residuals have the pooled lag-1 autocorrelation rho: a tenth of the points (a fixed share of
// the amplitude range, the same for the same curve sampled more densely), or Andrews' (1991)
// AR(1) plug-in 1.1447 (alpha n)^(1/3), alpha = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2), where that
// is longer (rho at most 0.97, L at most n / 2): ten lags of noise correlated with rho 0.8 along
// 30 points outlast a tenth of them, and chi's stated sigma came out 0.64 of its spread.
int hac_lags(int n, double rho) {
  const double r = std::clamp(rho, 0.0, 0.97);
  const double alpha = 4 * r * r / ((1 - r) * (1 - r) * (1 + r) * (1 + r));
  const int andrews = static_cast<int>(std::ceil(1.1447 * std::cbrt(alpha * n)));
  return std::max(std::max(1, static_cast<int>(std::ceil(n / 10.0))), std::min(andrews, n / 2));
}

// The pooled lag-1 autocorrelation of the frequency and damping residuals along each curve
// ordered by amplitude.
double lag_one_correlation(const std::vector<std::vector<int>>& curves, const Eigen::VectorXd& r) {
  double c0 = 0, c1 = 0;
  for (const std::vector<int>& points : curves) {
    const int n = static_cast<int>(points.size());
    for (int part = 0; part < 2; ++part) {
      for (int t = 0; t < n; ++t) c0 += r(points[t] + part) * r(points[t] + part);
      for (int t = 1; t < n; ++t) c1 += r(points[t] + part) * r(points[t - 1] + part);
    }
  }
  return c0 > 0 ? c1 / c0 : 0.0;
}

// Each curve's points ordered by amplitude (points_by_amplitude) and its bandwidth (hac_lags at
// the residuals' pooled lag-1 autocorrelation): made once for the residuals at the result, for
// every Jacobian that covariance() weighs with them.
struct SerialOrder {
  std::vector<std::vector<int>> curves;
  std::vector<int> lags;  // per curve
};

SerialOrder serial_order(const IwanObjective& objective, const Eigen::VectorXd& r) {
  SerialOrder out{points_by_amplitude(objective), {}};
  const double rho = lag_one_correlation(out.curves, r);
  for (const std::vector<int>& points : out.curves)
    out.lags.push_back(hac_lags(static_cast<int>(points.size()), rho));
  return out;
}

// Newey-West (HAC) estimate of S = Var(sum of scores) for residuals r with Jacobian J: each
// curve's points ordered by amplitude, the score of a point g_t = J_t^T r_t over its frequency
// and damping residuals, S = sum over curves of sum_t g_t g_t^T + sum_{l=1..L} w_l (g_t g_{t-l}^T
// + g_{t-l} g_t^T), Bartlett weights w_l = 1 - l / (L + 1), L the curve's hac_lags(): at least
// a tenth of its points, a fixed share of the amplitude range, so the same curve sampled ten
// times more densely covers the same correlation length and gives the same S, where the points of
// a curve come from overlapping local fits and model-form error runs in long waves (method.md
// section 2 point 5).
Eigen::MatrixXd hac_scores(const SerialOrder& order, const Eigen::MatrixXd& J,
                           const Eigen::VectorXd& r) {
  const Eigen::Index nf = J.cols();
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(nf, nf);
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const std::vector<int>& points = order.curves[c];
    const int n = static_cast<int>(points.size());
    Eigen::MatrixXd g(nf, n);
    for (int t = 0; t < n; ++t) {
      const int i = points[t];
      g.col(t) = J.row(i).transpose() * r(i) + J.row(i + 1).transpose() * r(i + 1);
    }
    const int lags = order.lags[c];
    S += g * g.transpose();
    for (int l = 1; l <= lags && l < n; ++l) {
      const double w = 1.0 - l / (lags + 1.0);
      const Eigen::MatrixXd G = g.rightCols(n - l) * g.leftCols(n - l).transpose();
      S += w * (G + G.transpose());
    }
  }
  return S;
}

// Integrated autocorrelation time of the residuals along the curves, tau = 1 + 2 sum_{l=1..L}
// w_l rho_l (Bartlett weights and the bandwidth of hac_scores), rho_l the lag-l autocorrelation
// of the frequency and of the damping residuals of each curve ordered by amplitude, pooled: N /
// tau is the effective number of independent points. The same curve sampled ten times more
// densely has tau about ten times larger, so Gauss-Newton times tau does not depend on density.
double residual_correlation_time(const SerialOrder& order, const Eigen::VectorXd& r) {
  double c0 = 0, sum = 0;
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const std::vector<int>& points = order.curves[c];
    const int n = static_cast<int>(points.size());
    const int lags = order.lags[c];
    for (int part = 0; part < 2; ++part) {  // frequency, damping
      for (int t = 0; t < n; ++t) c0 += r(points[t] + part) * r(points[t] + part);
      for (int l = 1; l <= lags && l < n; ++l) {
        double c = 0;
        for (int t = l; t < n; ++t) c += r(points[t] + part) * r(points[t - l] + part);
        sum += 2 * (1.0 - l / (lags + 1.0)) * c;
      }
    }
  }
  return c0 > 0 ? 1 + sum / c0 : 1.0;
}

// The residuals' serial correlation as an AR(1) process along each curve (frequency and damping
// apart), its lag-1 coefficient corrected for what the fit takes out (serial_noise()).
struct SerialNoise {
  double rho = 0;               // AR(1) coefficient of the noise, in [0, kMaxRho]
  double variance = 0;          // marginal variance of a normalised residual's noise
  double effective_points = 0;  // independent points the residuals amount to
  double amplitude_share = 0;   // amplitude_share() of the residuals
};

constexpr double kMaxRho = 0.999;

// The degrees of freedom of the sigmas' Student's t: the effective independent points less the
// parameters fitted to them (as a regression's n - p); 2 or fewer state no sigma.
double t_degrees_of_freedom(double effective_points, int fitted) {
  return effective_points - fitted;
}

// Sigma(rho) X for the AR(1) correlation Sigma_ij = rho^|i-j| within each sequence (a curve's
// frequency residuals, or its damping residuals, ordered by amplitude) and 0 across them: a
// forward and a backward recursion, O(rows) per column.
Eigen::MatrixXd ar1_times(const SerialOrder& order, const Eigen::MatrixXd& X, double rho) {
  Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  for (const std::vector<int>& points : order.curves) {
    const int n = static_cast<int>(points.size());
    for (int part = 0; part < 2; ++part) {
      Eigen::RowVectorXd acc = Eigen::RowVectorXd::Zero(X.cols());
      for (int t = 0; t < n; ++t) {  // sum_{s <= t} rho^(t-s) x_s
        acc = rho * acc + X.row(points[t] + part);
        Y.row(points[t] + part) += acc;
      }
      acc.setZero();
      for (int t = n - 1; t >= 0; --t) {  // sum_{s > t} rho^(s-t) x_s
        Y.row(points[t] + part) += rho * acc;
        acc = rho * acc + X.row(points[t] + part);
      }
    }
  }
  return Y;
}

// W X for the Bartlett weights of hac_scores(): W_ij = 1 - |i-j| / (L+1) within a sequence for
// |i-j| <= L (the curve's bandwidth), else 0; r^T W r / r^T r is residual_correlation_time().
Eigen::MatrixXd bartlett_times(const SerialOrder& order, const Eigen::MatrixXd& X) {
  Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const std::vector<int>& points = order.curves[c];
    const int n = static_cast<int>(points.size()), lags = order.lags[c];
    for (int part = 0; part < 2; ++part) {
      for (int t = 0; t < n; ++t) {
        const int i = points[t] + part;
        Y.row(i) += X.row(i);
        for (int l = 1; l <= lags && l <= t; ++l) {
          const int j = points[t - l] + part;
          const double w = 1.0 - l / (lags + 1.0);
          Y.row(i) += w * X.row(j);
          Y.row(j) += w * X.row(i);
        }
      }
    }
  }
  return Y;
}

// trace(W Sigma(rho)) = sum over sequences of n + 2 sum_{l=1..L} w_l rho^l (n - l).
double bartlett_ar1_trace(const SerialOrder& order, double rho) {
  double sum = 0;
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const int n = static_cast<int>(order.curves[c].size()), lags = order.lags[c];
    double s = n, power = 1;
    for (int l = 1; l <= lags && l < n; ++l) {
      power *= rho;
      s += 2 * (1.0 - l / (lags + 1.0)) * power * (n - l);
    }
    sum += 2 * s;  // frequency and damping
  }
  return sum;
}

// The noise behind residuals r = (I - P) e at the result, P the projection onto the columns of
// J, taken as an AR(1) process of coefficient rho and variance s2 along each sequence:
// E[r r^T] = s2 M(rho), M = (I - P) Sigma(rho) (I - P). The fit absorbs the slow part of the
// noise, so the residuals' correlation time tau (residual_correlation_time(), r^T W r / r^T r)
// understates the noise's: on a 200-point curve with noise of rho 0.98 (correlation time 99)
// the residuals gave tau 25 and a lag-1 coefficient 0.953, and the sigmas of K_T and chi came out
// about half their spread. rho is instead the coefficient whose expected statistic under the
// fit's projection equals the observed one, tr(W M(rho)) / tr(M(rho)) = tau: indirect
// inference (Gourieroux, Monfort & Renault 1993, J. Appl. Econometrics 8:S85), the
// bias correction of Andrews (1993, Econometrica 61:139) for the AR(1) coefficient of
// regression residuals, here on the Bartlett statistic rather than lag 1, so that a curve
// interpolated between fewer independent points (lag-1 correlation near 1, correlation gone
// after the interpolation's span) is read by its correlation time, not its lag-1 coefficient.
// s2 = r^T r / tr(M(rho)) (unbiased under the model; the Gauss-Newton estimate keeps the stated
// noise as a floor). The effective number of independent points is that of the mean of each
// sequence, n^2 / (1^T Sigma 1) (Bayley & Hammersley 1946, J. R. Stat. Soc. Suppl. 8:184),
// summed: n (1 - rho) / (1 + rho) for long sequences, at least 1 per sequence.
// With Q an orthonormal basis of J and C = Q^T Sigma Q: tr(M) = m - tr(C) and tr(W M) =
// tr(W Sigma) - 2 tr((Sigma Q)^T W Q) + tr(Q^T W Q C), each O(m) per column.
SerialNoise serial_noise(const SerialOrder& order, const Eigen::MatrixXd& J,
                         const Eigen::VectorXd& r, double tau) {
  SerialNoise out;
  const Eigen::Index m = J.rows();
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(J).householderQ() *
                            Eigen::MatrixXd::Identity(m, J.cols());
  const Eigen::MatrixXd WQ = bartlett_times(order, Q);
  const Eigen::MatrixXd QWQ = Q.transpose() * WQ;
  // The expected statistic tr(W M) / tr(M) at rho, and tr(M).
  const auto expected = [&](double rho) {
    const Eigen::MatrixXd SQ = ar1_times(order, Q, rho);
    const Eigen::MatrixXd C = Q.transpose() * SQ;
    const double trace_m = static_cast<double>(m) - C.trace();
    const double trace_wm =
        bartlett_ar1_trace(order, rho) - 2 * SQ.cwiseProduct(WQ).sum() + QWQ.cwiseProduct(C).sum();
    return std::pair<double, double>(trace_m > 0 ? trace_wm / trace_m : 0.0, trace_m);
  };
  double lo = 0, hi = kMaxRho;
  if (expected(lo).first >= tau) {
    hi = 0;
  } else if (expected(hi).first <= tau) {
    lo = kMaxRho;
  } else {
    for (int it = 0; it < 50; ++it) {
      const double mid = 0.5 * (lo + hi);
      (expected(mid).first < tau ? lo : hi) = mid;
    }
  }
  out.rho = 0.5 * (lo + hi);
  const double trace_m = expected(out.rho).second;
  out.variance = trace_m > 0 ? r.squaredNorm() / trace_m : 0.0;
  const Eigen::VectorXd sums = ar1_times(order, Eigen::VectorXd::Ones(m), out.rho);
  for (const std::vector<int>& points : order.curves) {
    const double n = static_cast<double>(points.size());
    for (int part = 0; part < 2; ++part) {
      double total = 0;  // 1^T Sigma 1 over the sequence
      for (const int i : points) total += sums(i + part);
      out.effective_points += total > 0 ? n * n / total : 0.0;
    }
  }
  return out;
}

// The largest share of r^T r that one third of the points holds, each curve's points (in order of
// amplitude) cut in thirds and the thirds pooled over curves: about 1/3 for residuals spread
// evenly over the amplitudes, as noise is; a model's misfit gathers where the model bends wrong.
double amplitude_share(const SerialOrder& order, const Eigen::VectorXd& r) {
  double third[3] = {0, 0, 0};
  for (const std::vector<int>& points : order.curves) {
    const size_t n = points.size();
    for (size_t t = 0; t < n; ++t) {
      const int i = points[t];
      third[std::min<size_t>(2, 3 * t / n)] += r(i) * r(i) + r(i + 1) * r(i + 1);
    }
  }
  const double total = third[0] + third[1] + third[2];
  return total > 0 ? std::max({third[0], third[1], third[2]}) / total : 0.0;
}

// The covariance of covariance() (below) from one Jacobian J of the residuals r; none when J^T J
// is singular.
std::optional<Eigen::MatrixXd> sandwich(const IwanObjective& objective, const SerialOrder& order,
                                        const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                        double n_points, double reduced_chi2, double tau,
                                        const SerialNoise& noise,
                                        const Eigen::MatrixXd* pseudo_inverse = nullptr) {
  const Eigen::MatrixXd H = J.transpose() * J;
  Eigen::MatrixXd Hi;
  if (pseudo_inverse) {
    Hi = *pseudo_inverse;
  } else {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(H);
    if (!lu.isInvertible()) return std::nullopt;
    Hi = lu.inverse();
  }
  const Eigen::MatrixXd gauss_newton = Hi / n_points * std::max(1.0, reduced_chi2 * tau);
  // The parametric AR(1) covariance s2 H^-1 J^T Sigma(rho) J H^-1 at the bias-corrected rho
  // (serial_noise()).
  const Eigen::MatrixXd ar1 =
      noise.variance * Hi * (J.transpose() * ar1_times(order, J, noise.rho)) * Hi;
  Eigen::MatrixXd robust = Hi * hac_scores(order, J, r) * Hi;
  const std::vector<int>& curve = objective.residual_curve();
  const int nf = static_cast<int>(J.cols()), m = static_cast<int>(J.rows());
  const int n_curves = curve.empty() ? 0 : curve.back() + 1;
  if (n_curves >= 3) {
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(nf, n_curves);
    for (int i = 0; i < m; ++i) g.col(curve[i]) += J.row(i).transpose() * r(i);
    const Eigen::MatrixXd cluster = Hi * (g * g.transpose() * (n_curves / (n_curves - 1.0))) * Hi;
    // Few curves estimate the scatter between them poorly (G - 1 degrees of freedom): the
    // cluster-robust correlations, each variance the larger of the two.
    Eigen::VectorXd d(nf);
    bool usable = true;
    for (int k = 0; k < nf; ++k) {
      usable = usable && cluster(k, k) > 0;
      d(k) = cluster(k, k) > 0 ? std::sqrt(std::max(1.0, robust(k, k) / cluster(k, k))) : 0.0;
    }
    if (usable) robust = d.asDiagonal() * cluster * d.asDiagonal();
  }
  Eigen::VectorXd d(nf);
  for (int k = 0; k < nf; ++k) {
    const double floor = std::max(gauss_newton(k, k), ar1(k, k));
    d(k) = robust(k, k) > 0 ? std::sqrt(std::max(1.0, floor / robust(k, k))) : 0.0;
  }
  Eigen::MatrixXd cov = d.asDiagonal() * robust * d.asDiagonal();
  for (int k = 0; k < nf; ++k)
    if (!(robust(k, k) > 0)) cov(k, k) = std::max(gauss_newton(k, k), ar1(k, k));
  return cov;
}

// The residuals at x +/- h along each free parameter in turn (x = (ln F_S, ln gamma, chi,
// ln beta), h = 1e-4, as the local solve; Z, index 4, linearly at h = 1e-6), handed to
// column(j, h, r_plus, r_minus); false where the model cannot be evaluated at one of them. The
// covariance's slopes and the linear part's sensitivity take the same steps.
template <typename Column>
bool central_differences(const IwanObjective& objective, const std::vector<int>& free,
                         const Vec4& v, double z, Column&& column) {
  const double Ks = objective.reference_stiffness();
  Eigen::VectorXd rp(objective.residual_count()), rm(objective.residual_count());
  const Vec4 x0 = to_x(v);
  for (int j = 0; j < static_cast<int>(free.size()); ++j) {
    const double h = free[j] == 4 ? 1e-6 : 1e-4;
    Vec4 xp = x0, xm = x0;
    double zp = z, zm = z;
    if (free[j] == 4) {
      zp += h, zm -= h;
    } else {
      xp(free[j]) += h, xm(free[j]) -= h;
    }
    if (!objective.residuals_at(to_params(to_v(xp.data()), Ks), zp, rp.data()) ||
        !objective.residuals_at(to_params(to_v(xm.data()), Ks), zm, rm.data()))
      return false;
    column(j, h, rp, rm);
  }
  return true;
}

// Covariance of x = (ln F_S, ln gamma, chi, ln beta[, Z]) at v and the structure's own damping z
// (ln gamma and ln K_T differ by a constant), over the free parameters `free` (indices 0-3, and 4
// for a fitted Z); empty when unknown. The larger, variance by variance, of
// - the HAC sandwich H^-1 S H^-1, H = J^T J (hac_scores: robust to serially correlated
//   residuals along each curve), with its correlations;
// - Gauss-Newton (J^T J)^-1 / N (residuals are normalised by sigma sqrt(N)) times the reduced
//   chi-square and the residuals' correlation time tau (N / tau independent points), at least
//   times 1 (the stated noise is a floor, never shrunk): steadier than the sandwich for a
//   parameter a few points decide (beta at the knee), and as independent of sampling density;
// - with G >= 3 curves the cluster-robust H^-1 (G/(G-1) sum_c g_c g_c^T) H^-1, g_c = J_c^T r_c
//   over curve c's residuals: points along one hit's backbone share that hit's offset, so the
//   curves, not the points, are the independent samples;
// - the parametric AR(1) covariance at the noise's bias-corrected coefficient (serial_noise(),
//   set in *noise): the HAC and tau read the residuals, from which the fit has taken the slow
//   part of the noise. A linearised Monte Carlo (400 seeds) of a 200-point curve of the
//   riveted beam with AR(1) noise: the z-scores' standard deviation for K_T and chi fell from
//   2.4 and 1.9 to 1.5 and 1.3 at rho 0.98 and from 1.4 and 1.3 to 1.1 and 1.0 at rho 0.9,
//   unchanged (0.9-1.0) for independent noise (full fits: docs/update-iwan.md).
// The whole is then widened by nu / (nu - 2), the variance of Student's t with nu = n_eff - p
// degrees of freedom (t_degrees_of_freedom()), n_eff the effective number of independent points
// (Bayley & Hammersley 1946, J. R. Stat. Soc. Suppl. 8:184), p the parameters fitted to them: a
// sigma estimated from a few effective points is itself uncertain. Where nu <= 2 that variance
// is infinite and the covariance is empty (the caller says so from noise->effective_points).
Eigen::MatrixXd covariance(const IwanObjective& objective, const std::vector<int>& free,
                           const Vec4& v, double z, double* reduced_chi2, SerialNoise* noise,
                           std::array<bool, 4>* fixed_at_kink) {
  fixed_at_kink->fill(false);
  const int m = objective.residual_count(), nf = static_cast<int>(free.size());
  const double Ks = objective.reference_stiffness();
  Eigen::MatrixXd J(m, nf), Jf(m, nf), Jb(m, nf);
  Eigen::VectorXd r(m);
  if (!objective.residuals_at(to_params(v, Ks), z, r.data())) return {};
  const double n_points = m / 2.0;
  *reduced_chi2 = r.squaredNorm() * n_points / std::max(1, m - nf);
  // Central slopes, and the one-sided ones for a kink (below).
  if (!central_differences(
          objective, free, v, z,
          [&](int j, double h, const Eigen::VectorXd& rp, const Eigen::VectorXd& rm) {
            J.col(j) = (rp - rm) / (2 * h);
            Jf.col(j) = (rp - r) / h;
            Jb.col(j) = (r - rm) / h;
          }))
    return {};
  const SerialOrder order = serial_order(objective, r);
  const double tau = residual_correlation_time(order, r);
  *noise = serial_noise(order, J, r, tau);
  noise->amplitude_share = amplitude_share(order, r);
  // The HAC, cluster and Gauss-Newton estimates first, each widened at a kink (below), and the
  // AR(1) floor last: taken inside, a floor that raised the central variance toward a
  // one-sided one could stop that widening and leave a sigma 9 % below what it was without it.
  SerialNoise without_floor = *noise;
  without_floor.variance = 0;
  const std::optional<Eigen::MatrixXd> central =
      sandwich(objective, order, J, r, n_points, *reduced_chi2, tau, without_floor);
  if (!central) return {};
  // At a kink of the model (a measured amplitude at phi_max, where the cost's minimum likes to
  // sit) the one-sided slopes differ and the central one overstates what the data say: each
  // variance is the largest of the central and the two one-sided estimates (7 of 40 three-hit
  // fits had phi_max within 2.5e-5 of a measured amplitude in ln q and stated beta's sigma
  // 3-4 times too small). Elsewhere the three agree to O(h).
  Eigen::MatrixXd cov = *central;
  for (const Eigen::MatrixXd* one_sided : {&Jf, &Jb}) {
    const std::optional<Eigen::MatrixXd> c =
        sandwich(objective, order, *one_sided, r, n_points, *reduced_chi2, tau, without_floor);
    if (!c) continue;
    // Only where a sigma differs by more than 10 %: elsewhere the O(h) differences of the
    // one-sided slopes are no kink and leave the result as it was.
    Eigen::VectorXd d = Eigen::VectorXd::Ones(nf);
    for (int k = 0; k < nf; ++k)
      if (cov(k, k) > 0 && (*c)(k, k) > 1.21 * cov(k, k)) d(k) = std::sqrt((*c)(k, k) / cov(k, k));
    cov = d.asDiagonal() * cov * d.asDiagonal();
  }
  const std::optional<double> t =
      student_t_variance(t_degrees_of_freedom(noise->effective_points, nf));
  if (!t) return {};
  // The AR(1) floor, then Student's t: the covariance as stated.
  const auto stated = [&](Eigen::MatrixXd c) -> Eigen::MatrixXd {
    if (const std::optional<Eigen::MatrixXd> floored =
            sandwich(objective, order, J, r, n_points, *reduced_chi2, tau, *noise)) {
      Eigen::VectorXd d = Eigen::VectorXd::Ones(nf);
      for (int k = 0; k < nf; ++k)
        if (c(k, k) > 0 && (*floored)(k, k) > c(k, k)) d(k) = std::sqrt((*floored)(k, k) / c(k, k));
      c = d.asDiagonal() * c * d.asDiagonal();
    }
    return c * *t;
  };
  // A kink within the stated interval. The slopes above are taken 1e-4 from the result; a point
  // whose slip sits a little past phi_max (0.4 % on the lap joint's six-point table below) lies
  // on the steep branch of the damping there, and its slope pins phi_max as if that branch went
  // on, while 0.4 % away the point is back on the shallow branch: the cost then has another
  // minimum, about as low, beyond the slope's reach. So each free Iwan parameter is moved by two
  // of the sigmas as stated, each way; a residual whose two secants differ by more than half
  // the larger, one of them keeping the slope at the result (a smooth one's curvature moves
  // both, about equally) has its information at a kink, and the covariance without those rows'
  // slopes is the larger where larger (repeated at the wider sigmas, at most three times). The
  // six-point table of mode 1 of a 6-rivet steel lap joint up to 2.7 phi_max: F_S 5.4 % off with
  // 0.74 % stated (z -7.3, the point at the kink alone pinning phi_max; the profile of the cost
  // puts one sigma near 3 %); without that point's slope 2.2 %. Where the rows at a kink alone fix
  // a direction (J^T J without them singular), the parameters along it have no sigma
  // (fixed_at_kink) and the others theirs from the pseudo-inverse, which leaves that direction out.
  std::vector<bool> at_kink(static_cast<size_t>(m), false);
  const Vec4 x0 = to_x(v);
  std::vector<double> rp(m), rm(m);
  for (int pass = 0; pass < 3; ++pass) {
    const Eigen::MatrixXd total = stated(cov);
    if (!total.allFinite()) return {};
    bool more = false;
    for (int j = 0; j < nf; ++j) {
      if (free[j] == 4) continue;  // Z enters linearly: no kink
      // Only a sigma up to 15 % is probed: a wider one is no pin, and over steps past 30 % in
      // ln (F_S, gamma, beta) or 0.3 in chi the secants of smooth residuals part too (the lap
      // joint's mode 2, whose joint barely moves, stated 26-95 % and was then called fixed at a
      // kink). The six-point table's kink showed at beta's step, 12 %.
      const double h = 2 * std::sqrt(std::max(total(j, j), 0.0));
      if (!(h > 1e-3) || h > 0.3) continue;
      Vec4 xp = x0, xm = x0;
      xp(free[j]) += h;
      xm(free[j]) -= h;
      if (!objective.residuals_at(to_params(to_v(xp.data()), Ks), z, rp.data()) ||
          !objective.residuals_at(to_params(to_v(xm.data()), Ks), z, rm.data())) {
        continue;
      }
      const double scale = J.col(j).cwiseAbs().maxCoeff();
      for (int i = 0; i < m; ++i) {
        const double forward = (rp[i] - r(i)) / h, backward = (r(i) - rm[i]) / h;
        const double larger = std::max(std::abs(forward), std::abs(backward));
        // A kink on one side: that side's secant leaves the slope at the result while the other
        // keeps it; a smooth residual's curvature moves both about equally, one up, one down
        // (chi of a barely slipping one-mode joint, stepped 0.12, was taken for a kink).
        const double off_f = std::abs(forward - J(i, j)), off_b = std::abs(backward - J(i, j));
        const bool one_sided = std::min(off_f, off_b) < 0.3 * std::max(off_f, off_b);
        if (!at_kink[i] && larger > 0.05 * scale && std::abs(forward - backward) > 0.5 * larger &&
            one_sided) {
          at_kink[i] = true;
          more = true;
        }
      }
    }
    if (!more) break;
    Eigen::MatrixXd Jk = J;
    for (int i = 0; i < m; ++i)
      if (at_kink[i]) Jk.row(i).setZero();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Jk.transpose() * Jk);
    const Eigen::VectorXd& lambda = eig.eigenvalues();
    Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(nf, nf);
    std::vector<bool> undetermined(static_cast<size_t>(nf), false);
    for (int e = 0; e < nf; ++e) {
      const Eigen::VectorXd u = eig.eigenvectors().col(e);
      if (lambda(e) > 1e-10 * lambda(nf - 1)) {
        pinv += u * u.transpose() / lambda(e);
      } else {
        for (int k = 0; k < nf; ++k) undetermined[k] = undetermined[k] || std::abs(u(k)) > 0.05;
      }
    }
    const std::optional<Eigen::MatrixXd> c =
        sandwich(objective, order, Jk, r, n_points, *reduced_chi2, tau, without_floor, &pinv);
    if (!c || !c->allFinite()) return {};
    Eigen::VectorXd d = Eigen::VectorXd::Ones(nf);
    for (int k = 0; k < nf; ++k) {
      if (undetermined[k] && free[k] < 4) (*fixed_at_kink)[free[k]] = true;
      if (!undetermined[k] && cov(k, k) > 0 && (*c)(k, k) > cov(k, k))
        d(k) = std::sqrt((*c)(k, k) / cov(k, k));
    }
    cov = d.asDiagonal() * cov * d.asDiagonal();
  }
  cov = stated(cov);
  if (!cov.allFinite()) return {};
  return cov;
}

// IwanUpdateSummary::linear_part_sensitivity and frequency_per_stiffness at the result v (the
// search's parameters) and z, over the free parameters `free` (indices 0-3, 4 for a fitted Z):
// at the minimum the cost's gradient J^T r stays 0 as the structure's stiffness K moves by a
// factor e^s, so dx/ds = -(J^T J)^-1 J^T dr/ds (Gauss-Newton: the residuals' second derivatives,
// of the order of the residuals, left out), J and dr/ds central differences (steps 1e-4 in x, as
// the covariance, and 1e-4 in s); divided by d ln f_R / ds, mode R the first target's, at the
// result's K_T. False where a residual or mode cannot be evaluated or J^T J is singular.
bool linear_part_sensitivity(const IwanObjective& objective, const std::vector<int>& free,
                             const Vec4& v, double z, IwanUpdateSummary& s) {
  const int m = objective.residual_count(), nf = static_cast<int>(free.size());
  if (nf == 0 || objective.targets().empty()) return false;
  const double Ks = objective.reference_stiffness();
  const model::IwanParameters p = to_params(v, Ks);
  Eigen::MatrixXd J(m, nf);
  Eigen::VectorXd rp(m), rm(m), dr(m);
  if (!central_differences(
          objective, free, v, z,
          [&](int j, double h, const Eigen::VectorXd& plus, const Eigen::VectorXd& minus) {
            J.col(j) = (plus - minus) / (2 * h);
          }))
    return false;
  const double hs = 1e-4;
  if (!objective.residuals_with_structure_stiffness(p, z, std::exp(hs), rp.data()) ||
      !objective.residuals_with_structure_stiffness(p, z, std::exp(-hs), rm.data())) {
    return false;
  }
  dr = (rp - rm) / (2 * hs);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
  if (qr.rank() < nf) return false;
  const Eigen::VectorXd dx = -qr.solve(dr);
  // Mode R's linear frequency at the result's K_T, K scaled each way.
  const int mode = objective.targets().front().mode;
  double ln_f[2];
  for (int side = 0; side < 2; ++side) {
    model::Model mk = objective.apply(p);
    mk.stiffness *= std::exp(side == 0 ? hs : -hs);
    try {
      const model::LinearModes modes = model::linear_modes(mk.mass, mk.linear_stiffness());
      const int col = modes.rigid_count + mode - 1;
      if (col >= modes.size() || !(modes.frequency_hz(col) > 0)) return false;
      ln_f[side] = std::log(modes.frequency_hz(col));
    } catch (const InputError&) {
      return false;
    }
  }
  const double df = (ln_f[0] - ln_f[1]) / (2 * hs);
  if (!(std::abs(df) > 1e-12) || !dx.allFinite()) return false;
  s.linear_part_sensitivity.setZero();
  for (int j = 0; j < nf; ++j) {
    if (free[j] == 4) continue;
    const double per_f = dx(j) / df;
    s.linear_part_sensitivity(free[j]) = free[j] != 2         ? per_f
                                         : std::abs(v(2)) > 0 ? per_f / std::abs(v(2))
                                                              : 0.0;
  }
  s.sensitivity_mode = mode;
  s.frequency_per_stiffness = df;
  return true;
}

// The free parameters of v that end within 1e-3 of their range (in the search coordinates x) of
// a bound, and a fitted Z that ends at one, e.g. "Fs at its upper bound 2000 N" (the bound itself,
// to rounding) or "Fs 1985 N, near its upper bound 2000 N" (within the tolerance: the search was
// pressing on it); `side` receives -1 / +1 per parameter (F_S, K_T, chi, beta, Z) at or near its
// lower / upper bound.
std::vector<std::string> bounds_reached(const IwanUpdateOptions& options, const Vec4& v,
                                        std::optional<double> z, std::array<int, 5>& side) {
  const Box box = initial_box(options);
  const Vec4 x = to_x(v), lo = to_x(box.lo), hi = to_x(box.hi);
  static const char* names[] = {"Fs", "gamma (Kt/Ks)", "chi", "beta"};
  static const char* units[] = {" N", "", "", ""};
  std::vector<std::string> out;
  side.fill(0);
  for (int k = 0; k < 4; ++k) {
    if (!(hi(k) > lo(k))) continue;  // held
    const double tol = 1e-3 * (hi(k) - lo(k)), exact = 1e-9 * (hi(k) - lo(k));
    const double value = v(k);
    const auto say = [&](const char* which, double bound, double distance) {
      return distance <= exact
                 ? fmt::format("{} at its {} bound {:.6g}{}", names[k], which, bound, units[k])
                 : fmt::format("{} {:.6g}{}, near its {} bound {:.6g}{}", names[k], value, units[k],
                               which, bound, units[k]);
    };
    if (x(k) <= lo(k) + tol) {
      side[k] = -1;
      out.push_back(say("lower", box.lo(k), x(k) - lo(k)));
    } else if (x(k) >= hi(k) - tol) {
      side[k] = 1;
      out.push_back(say("upper", box.hi(k), hi(k) - x(k)));
    }
  }
  // Z is the weighted mean of the damping residuals clamped to [0, zmax] (IwanObjective): at a
  // bound it is the bound itself, so only the bound itself is called one (a tolerance of 1e-3
  // zmax called a fitted 2e-5 "at its lower bound 0" beside its value).
  if (z) {
    const double zmax = options.linear_damping_max;
    if (*z <= 0) {
      side[4] = -1;
      out.push_back("modal_ratio at its lower bound 0 (the joints explain all the damping)");
    } else if (*z >= zmax) {
      side[4] = 1;
      out.push_back(fmt::format("modal_ratio at its upper bound {:.6g}", zmax));
    }
  }
  return out;
}

void set_slips(const IwanObjective& objective, IwanUpdateSummary& s) {
  const Eigen::Vector2d slip = objective.slip_range(s.best);
  s.bottom_slip = slip(0);
  s.top_slip = slip(1);
  s.phi_max = model::Iwan(s.best).phi_max();
}

// The constant-backbone candidate of a fit with Z free: a joint that barely slips over the data
// (F_S at its upper bound, chi at its largest: the microslip damping (a / phi_max)^(chi + 1) is
// then smallest) with K_T placing the frequency (golden-section search of the cost on ln gamma),
// and Z at its best. A linear damping with such a joint contains the constant model, so the fit
// can never end worse than the best constant: this candidate is recorded and refined.
std::pair<double, Vec4> constant_candidate(Tracker& tr) {
  const IwanUpdateOptions& o = tr.options;
  const Box box = initial_box(o);
  const model::IwanParameters start = tr.objective.initial();
  Vec4 v(box.hi(0), box.lo(1), box.hi(2), std::clamp(start.beta, box.lo(3), box.hi(3)));
  if (o.fixed_beta) v(3) = *o.fixed_beta;
  auto at = [&](double ln_gamma) {
    Vec4 w = v;
    w(1) = std::exp(ln_gamma);
    return tr.eval({w}).front();
  };
  if (box.hi(1) > box.lo(1)) {
    const double phi = (std::sqrt(5.0) - 1) / 2;
    double a = std::log(box.lo(1)), b = std::log(box.hi(1));
    double c = b - phi * (b - a), d = a + phi * (b - a);
    double fc = at(c), fd = at(d);
    for (int i = 0; i < 30 && !tr.spent(); ++i) {
      if (fc < fd) {
        b = d, d = c, fd = fc;
        c = b - phi * (b - a);
        fc = at(c);
      } else {
        a = c, c = d, fc = fd;
        d = a + phi * (b - a);
        fd = at(d);
      }
    }
    v(1) = std::exp(fc < fd ? c : d);
  }
  return {tr.eval({v}).front(), v};
}

}  // namespace

Eigen::Vector3i IwanObjective::floored_points() const {
  Eigen::Vector3i out = Eigen::Vector3i::Zero();
  for (const IwanTarget& t : targets_) {
    for (const MeasuredBackbone& c : t.curves) {
      for (Eigen::Index j = 0; j < c.amplitude.size(); ++j) {
        ++out(0);
        const Eigen::Vector2d stated = stated_sigma(c, j);
        out(1) += stated(0) > 0 && stated(0) < f_floor_ * c.frequency_hz(j);
        out(2) += stated(1) > 0 && stated(1) < z_floor_ * std::abs(c.damping_ratio(j));
      }
    }
  }
  return out;
}

double IwanUpdateSummary::linear_part_tolerance(int k) const {
  const IwanSigmaReason why = sigma_reason(k);
  if (why != IwanSigmaReason::kStated && why != IwanSigmaReason::kGivenBetaAsHeld) return 0;
  const double sensitivity = std::abs(linear_part_sensitivity(k));
  return relative_std(k) > 0 && sensitivity > 0 ? relative_std(k) / sensitivity : 0.0;
}

bool IwanUpdateSummary::misfit() const {
  return reduced_chi2 > 1 + 3 * std::sqrt(2.0 / std::max<size_t>(1, residuals));
}

bool IwanUpdateSummary::residuals_look_like_noise() const {
  // A share of chi-square(k) in a sum of three is Beta(k/2, k), of variance (2/9) / (3k/2 + 1),
  // k a third of the points (report(), the note that the stated noise may be too small).
  const double k = static_cast<double>(residuals) / 6;
  return effective_points > 0 && noise_correlation < 0.3 && amplitude_share > 0 &&
         amplitude_share < 1.0 / 3 + 3 * std::sqrt((2.0 / 9) / (1.5 * k + 1));
}

bool IwanUpdateSummary::misfit_sets_the_error() const {
  // A sigma is the spread of the parameters over the noise; where the model does not describe
  // the data the error is what the misfit pulls them to, which no noise statistic measures. On
  // the one-mode model (three 40-point hits, 1e-4 / 2 % noise, 8 seeds each) the sigmas stated
  // before were up to 52 sigma off: the data's linear frequency 0.5 % below the model's with K_T
  // free (reduced chi-square 22-24, serial correlation 0.46, a third of the amplitudes holding
  // 0.97 of the chi-square) F_S -49 % +/- 2.1 % (z -32), K_T -25 % +/- 0.56 % (z -52); another
  // mode adding 0.1 phi_max to the joint's slip (168, 0.93) chi -86 % +/- 6.1 % (z -7.6); the
  // structure's own damping 5e-4 missing (106, 0.93) chi z -7; K_T held 0.5 % off (830, 0.82) F_S
  // z -7.4, chi z -21, beta z +7. Honest fits (reduced chi-square 0.9-1.2, serial correlation
  // below 0.12) are untouched, and so are white residuals of noise stated too small (the note)
  // and random scatter between four or more hits (scatter_explains_misfit()).
  if (!misfit() || !(effective_points > 0)) return false;
  if (!(reduced_chi2 > 1 + 3 * std::sqrt(2.0 / effective_points))) return false;
  if (residuals_look_like_noise()) return false;
  if (scatter_explains_misfit()) return false;
  return true;
}

bool IwanUpdateSummary::scatter_explains_misfit() const {
  // One cluster per curve: the curves, not the points, are the independent samples, and the
  // cluster covariance's variance has the curves less 1 degrees of freedom (Student's t's
  // variance nu / (nu - 2): more than 2 needed, so four curves or more; three stated K_T's sigma
  // from 2). Offsets that follow a hit (apart_curve) are no random scatter: the covariance reads
  // them as such and understates the error.
  return evidence && evidence->curves >= 4 && evidence->between_curves_share >= 0.5 &&
         evidence->apart_curve.empty();
}

// A likelihood-ratio test of the fit against the constant backbone it contains (K_T and Z
// alone): the cost is the chi-square over the points (covariance()), and F_S and chi (and beta,
// when free) are the extra parameters. Their gain is scaled by the reduced chi-square where
// that exceeds 1 (the noise then larger than stated). A flat backbone (frequency and damping
// constant within 0.01 % and 2 %) fitted with Z free ended at the constant's cost, F_S and chi
// at their upper bounds, and the report said "widen it" and "a larger --evaluations".
bool IwanUpdateSummary::joint_hardly_moved() const {
  // At an evaluated result a slip of 0 is a mode that leaves the joint still.
  return status != IwanUpdateStatus::kNoValidPoint && std::isfinite(final_cost) && phi_max > 0 &&
         top_slip >= 0 && top_slip < 1e-3 * phi_max;
}

namespace {

// "its largest slip at the highest measured amplitude, 8.3e-12 m, is 3.6e-08 of phi_max 0.000232
// m" (joint_hardly_moved()), or that it leaves the joint still.
std::string hardly_moved_words(const IwanUpdateSummary& s) {
  if (!(s.top_slip > 0))
    return fmt::format(
        "it leaves the joint still: no slip at any measured amplitude, phi_max {:.3g} m",
        s.phi_max);
  return fmt::format(
      "its largest slip at the highest measured amplitude, {:.3g} m, is {:.2g} of phi_max {:.3g} m",
      s.top_slip, s.top_slip / s.phi_max, s.phi_max);
}

}  // namespace

bool IwanUpdateSummary::no_slip_seen() const {
  // A start no candidate improved on counts too: the constant backbone is a candidate, so the
  // start then fits at least as well as it (a beam's first mode, whose shape leaves its two
  // rivets at 1e-13 m of slip, was told "the result is the start. Widen the bounds or give a
  // better start").
  if (!modal_ratio_fitted || status == IwanUpdateStatus::kNoValidPoint || !(constant_cost > 0) ||
      !std::isfinite(final_cost) || residuals == 0)
    return false;
  const double points = static_cast<double>(residuals) / 2;
  const double gain = (constant_cost - final_cost) * points / std::max(1.0, reduced_chi2);
  const double extra = held[3] ? 2.0 : 3.0;
  return gain < boost::math::quantile(boost::math::chi_squared(extra), 0.95);
}

namespace {

// How far a frequency may lie from the measured low-amplitude one and still match it: ten times
// the noise there, and 0.1 % (a frequency resolution).
double low_frequency_tolerance(const MisfitEvidence& e) {
  return std::max(10 * e.low_frequency_noise, 1e-3);
}

// The fitted curve's linear limit (K_T's and the linear part's) misses the measured low-amplitude
// frequency: no Iwan parameter set bends the curve onto the data there.
bool linear_limit_off(const MisfitEvidence& e) {
  return std::abs(e.low_frequency_error) > low_frequency_tolerance(e);
}

// The model as given (K_T = K_s, gamma 1: the stiffness update-linear fits to the measured linear
// frequencies) has mode R at the measured low-amplitude frequency.
bool model_as_given_matches(const MisfitEvidence& e) {
  return e.mode_hz > 0 && e.low_frequency_hz > 0 &&
         std::abs(e.mode_hz / e.low_frequency_hz - 1) <= low_frequency_tolerance(e);
}

// K_T ended at a bound short of the measured low-amplitude frequency: the linear limit misses it
// on the side the bound kept K_T from (below the data at the upper bound, above at the lower).
bool kt_stopped_short(const IwanUpdateSummary& s) {
  if (!s.evidence || s.held[1] || s.bound_side[1] == 0) return false;
  return linear_limit_off(*s.evidence) && -s.evidence->low_frequency_error * s.bound_side[1] > 0;
}

}  // namespace

model::IwanParameters update_iwan(const IwanObjective& objective, const IwanUpdateOptions& options,
                                  IwanUpdateSummary* summary) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("update-iwan: " + e);
  IwanUpdateSummary local;
  IwanUpdateSummary& s = summary ? *summary : local;
  s = IwanUpdateSummary{};
  s.optimizer = options.optimizer;
  s.start = objective.initial();
  s.held = held_parameters(options);
  s.modal_ratio_start = objective.model_linear_damping();
  s.modal_ratio_fitted = objective.fits_linear_damping();
  s.residuals = static_cast<size_t>(objective.residual_count());
  s.floored = objective.floored_points();
  s.frequency_floor = options.frequency_floor;
  s.damping_floor = options.damping_floor;
  s.reference_stiffness = objective.reference_stiffness();
  s.linear_known = std::any_of(objective.targets().begin(), objective.targets().end(),
                               [](const IwanTarget& t) { return t.linear_frequency_hz > 0; });
  Tracker tr{objective, options, s, objective.evaluations()};
  s.initial_cost = objective.try_cost(s.start).value_or(INFINITY);
  std::mt19937 rng(options.seed);
  std::optional<std::pair<double, Vec4>> constant;
  if (objective.fits_linear_damping()) {
    constant = constant_candidate(tr);
    s.constant_cost = constant->first;
  }
  switch (options.optimizer) {
    case IwanOptimizer::kPaper:
      monte_carlo(tr, false, rng);
      break;
    case IwanOptimizer::kPaperLog:
      monte_carlo(tr, true, rng);
      break;
    case IwanOptimizer::kGlobalLocal:
      global_local(tr, rng, constant ? &*constant : nullptr);
      break;
  }
  s.evaluations = tr.used();
  // The start with the held parameters at their held values: K_T = gamma K_s as asked.
  model::IwanParameters start = s.start;
  if (options.fixed_gamma > 0) start.Kt = options.fixed_gamma * objective.reference_stiffness();
  if (options.fixed_beta) start.beta = *options.fixed_beta;
  if (!std::isfinite(tr.best)) {
    s.status = IwanUpdateStatus::kNoValidPoint;
    s.improved = false;
    s.best = start;
    s.final_cost = objective.try_cost(start).value_or(INFINITY);
    s.modal_ratio = objective.linear_damping(start).value_or(s.modal_ratio_start);
    return start;
  }
  // The start is a candidate too when it lies in the search box (held parameters at their
  // values): never hand back parameters that fit worse, nor any outside the given ranges.
  const Box box = initial_box(options);
  const double Ks = objective.reference_stiffness();
  const Vec4 start_v(start.Fs, start.Kt / Ks, start.chi, start.beta);
  bool start_inside = true;
  for (int k = 0; k < 4; ++k) {
    const double slack = 1e-12 * std::max(std::abs(box.lo(k)), std::abs(box.hi(k)));
    start_inside =
        start_inside && start_v(k) >= box.lo(k) - slack && start_v(k) <= box.hi(k) + slack;
  }
  const double start_cost = !start_inside ? INFINITY
                            : start.Kt == s.start.Kt && start.beta == s.start.beta
                                ? s.initial_cost
                                : objective.try_cost(start).value_or(INFINITY);
  Vec4 best_v;
  if (start_cost <= tr.best) {
    s.improved = false;
    best_v = start_v;
    s.best = start;
    s.final_cost = start_cost;
  } else {
    // Inside the box also after the round trip through the search coordinates (exp(log(60))
    // is 59.99999999999999).
    best_v = tr.best_v.cwiseMax(box.lo).cwiseMin(box.hi);
    s.best = to_params(best_v, Ks);
    s.final_cost = tr.best;
  }
  s.modal_ratio = objective.linear_damping(s.best).value_or(s.modal_ratio_start);
  s.at_bounds = bounds_reached(
      options, best_v, s.modal_ratio_fitted ? std::optional<double>(s.modal_ratio) : std::nullopt,
      s.bound_side);
  if (!s.improved) s.at_bounds.clear(), s.bound_side.fill(0);  // the start: not a fit's end
  s.linear_error = objective.linear_error(s.best);
  set_slips(objective, s);
  if (const auto e = objective.rms_errors(s.best, s.modal_ratio)) s.rms_errors = *e;
  s.constant_rms_errors = objective.constant_rms_errors();
  std::vector<int> free;
  for (int k = 0; k < 4; ++k)
    if (!s.held[k]) free.push_back(k);
  if (s.modal_ratio_fitted) free.push_back(4);
  SerialNoise noise;
  Eigen::MatrixXd cov =
      covariance(objective, free, best_v, s.modal_ratio, &s.reduced_chi2, &noise, &s.fixed_at_kink);
  // Too few effective points is no flat direction: holding beta would not make it a sigma.
  const auto too_few = [&] {
    return noise.effective_points > 0 &&
           !(t_degrees_of_freedom(noise.effective_points, static_cast<int>(free.size())) > 2);
  };
  // Microslip data fix R, not F_S and beta apart (a flat direction: H singular or nearly so):
  // the covariance of the others with beta held (F_S then stands for R), beta's sigma unknown.
  const auto beta = std::find(free.begin(), free.end(), 3);
  if (beta != free.end() && ((cov.size() == 0 && !too_few()) || s.microslip_only())) {
    free.erase(beta);
    cov = covariance(objective, free, best_v, s.modal_ratio, &s.reduced_chi2, &noise,
                     &s.fixed_at_kink);
  }
  s.effective_points = noise.effective_points;
  s.sigma_degrees_of_freedom =
      t_degrees_of_freedom(noise.effective_points, static_cast<int>(free.size()));
  s.noise_correlation = noise.rho;
  s.amplitude_share = noise.amplitude_share;
  // Only a misfit has a cause to name (an eigensolution of the model as given, so not always).
  if (s.misfit()) s.evidence = objective.misfit_evidence(s.best, s.modal_ratio);
  // Where scatter between the curves explains the misfit the sigmas rest on the cluster
  // covariance, whose variance has the curves less 1 degrees of freedom: Student's t with the
  // fewer of those and the points' (the seven curves of the two joint sets: 6 against 160).
  if (s.scatter_explains_misfit() && cov.size() > 0) {
    const double nu = static_cast<double>(s.evidence->curves - 1);
    const std::optional<double> wide = student_t_variance(nu),
                                narrow = student_t_variance(s.sigma_degrees_of_freedom);
    if (wide && narrow && nu < s.sigma_degrees_of_freedom) cov *= *wide / *narrow;
  }
  if (cov.size() > 0) {
    for (size_t i = 0; i < free.size(); ++i) {
      for (size_t j = 0; j < free.size(); ++j) {
        if (free[i] < 4 && free[j] < 4) s.covariance(free[i], free[j]) = cov(i, j);
      }
      if (free[i] == 4) s.modal_ratio_std = std::sqrt(std::max(cov(i, i), 0.0));
    }
  }
  for (int k = 0; k < 4; ++k) {
    const double sd = std::sqrt(std::max(s.covariance(k, k), 0.0));
    s.relative_std(k) = k != 2 ? sd : std::abs(s.best.chi) > 0 ? sd / std::abs(s.best.chi) : 0.0;
  }
  // With beta free and the data in microslip, F_S's sigma above is that at beta held: F_S then
  // stands for R, not for itself, and is not known (40 microslip fits of 3 hits: F_S 35 % off
  // with a stated 0.7 %, z 33). With beta held, by the user or the run, it is F_S given beta.
  if (!s.held[3] && s.microslip_only()) s.relative_std(0) = 0;
  // Not converged: the point is where the search stopped, not a minimum, and a covariance there
  // describes the slope it was still descending, not the data (7 of 12 one-curve fits at the
  // default budget stated chi 4.6 sigma off before the polish).
  if (s.status == IwanUpdateStatus::kBudget) {
    s.relative_std.setZero();
    s.covariance.setZero();
    s.modal_ratio_std = 0;
  }
  // How far an error of the rest of the model moves the parameters, which no residual shows
  // where K_T takes it up (a converged fit's minimum only: elsewhere the gradient is not 0).
  if (s.status == IwanUpdateStatus::kConverged && s.improved)
    linear_part_sensitivity(objective, free, best_v, s.modal_ratio, s);
  s.linear_part_updated = options.linear_part_updated;
  // Every other parameter whose words state no sigma (the start, data without slip) has no
  // number either: parameters.csv and Python read relative_std, the report sigma_reason(), and a
  // start that no candidate improved on stated its sigma in Python where the report said
  // "(sigma unknown)" and parameters.csv left it empty.
  s.clear_unstated_sigmas();
  return s.best;
}

double slip_force_at_beta(const model::IwanParameters& p, double beta) {
  // R = F_S (chi+1) / (phi_max^(chi+2) (beta + c)) with phi_max = F_S (1+beta) / (K_T (beta + c))
  // is F_S^-(chi+1) (chi+1) K_T^(chi+2) (beta + c)^(chi+1) / (1+beta)^(chi+2): solved for F_S at
  // the same R and K_T.
  const double e = p.chi + 1, c = e / (p.chi + 2);
  const double r = model::Iwan(p).R();
  return std::pow(
      e * std::pow(p.Kt, p.chi + 2) * std::pow(beta + c, e) / (r * std::pow(1 + beta, p.chi + 2)),
      1 / e);
}

void IwanUpdateSummary::set_beta_held_by_fit(IwanBetaHold why, double free_cost) {
  beta_hold = why;
  free_fit_cost = free_cost;
  clear_unstated_sigmas();
}

IwanSigmaReason IwanUpdateSummary::sigma_reason(int k) const {
  const bool z = k == 4;
  if (z ? !modal_ratio_fitted : held[k]) {
    if (k == 3 && beta_hold == IwanBetaHold::kMicroslip) return IwanSigmaReason::kBetaHeldMicroslip;
    if (k == 3 && beta_hold == IwanBetaHold::kFreeFitNoBetter)
      return IwanSigmaReason::kBetaHeldFreeNoBetter;
    return IwanSigmaReason::kHeldAsAsked;
  }
  // K_T and Z are the result of data without slip; F_S, chi and beta are not identified.
  if (k != 1 && !z && no_slip_seen()) return IwanSigmaReason::kNoSlip;
  if (!improved || status == IwanUpdateStatus::kNoValidPoint) return IwanSigmaReason::kStart;
  // Microslip data fix F_S and beta only together: with beta free neither is a result; with beta
  // held by the fit F_S is the slip force at that beta (before, "Fs 0.5 -> 0.564 N +/- 2.3 %" at
  // beta held 1 read like a result: the truth was 0.7 N at beta 0.6, z -2 to -13 over 10 seeds).
  const bool micro = microslip_only();
  if (micro && (k == 0 || k == 3) && !held[3]) return IwanSigmaReason::kMicroslipFamily;
  if (status == IwanUpdateStatus::kBudget) return IwanSigmaReason::kNotConverged;
  if (micro && k == 0 && !beta_held_as_asked()) return IwanSigmaReason::kGivenBeta;
  if (misfit_sets_the_error()) return IwanSigmaReason::kModelMisfit;
  if (!z && fixed_at_kink[k] && effective_points > 0 && sigma_degrees_of_freedom > 2)
    return IwanSigmaReason::kAtKink;
  if ((z ? modal_ratio_std : relative_std(k)) > 0)
    return micro && k == 0 ? IwanSigmaReason::kGivenBetaAsHeld : IwanSigmaReason::kStated;
  if (effective_points > 0 && !(sigma_degrees_of_freedom > 2))
    return IwanSigmaReason::kTooFewPoints;
  return IwanSigmaReason::kUnknown;
}

void IwanUpdateSummary::clear_unstated_sigmas() {
  const auto stated = [&](int k) {
    const IwanSigmaReason r = sigma_reason(k);
    return r == IwanSigmaReason::kStated || r == IwanSigmaReason::kGivenBetaAsHeld;
  };
  for (int k = 0; k < 4; ++k)
    if (!stated(k)) relative_std(k) = 0;
  if (!stated(4)) modal_ratio_std = 0;
}

std::string IwanUpdateSummary::parameter_note(int k) const {
  switch (sigma_reason(k)) {
    case IwanSigmaReason::kStated:
      // A relative sigma of Z at 0 is no number: its absolute one is in the report.
      return k == 4 && !(modal_ratio > 0) ? "at 0: its sigma is absolute (report)" : "";
    case IwanSigmaReason::kGivenBetaAsHeld:
      return fmt::format("given beta = {:.4g} as held (microslip only)", best.beta);
    case IwanSigmaReason::kHeldAsAsked:
      return k == 4 ? "the model's held" : "held as asked";
    case IwanSigmaReason::kBetaHeldMicroslip:
      return "held at its start by the fit: microslip only so not identified";
    case IwanSigmaReason::kBetaHeldFreeNoBetter:
      return "held at its start by the fit: the fit with beta free did no better";
    case IwanSigmaReason::kStart:
      return "the start: no candidate improved on it";
    case IwanSigmaReason::kNoSlip:
      return "not identified: no slip in the data";
    case IwanSigmaReason::kMicroslipFamily:
      return k == 0 ? "not identified apart from beta: microslip only"
                    : "not identified apart from Fs: microslip only";
    case IwanSigmaReason::kNotConverged:
      return "no sigma: not converged";
    case IwanSigmaReason::kGivenBeta:
      return fmt::format(
          "given beta = {:.4g}: not identified (microslip only: the data fix only the combination "
          "of Fs and beta)",
          best.beta);
    case IwanSigmaReason::kTooFewPoints:
      return fmt::format("sigma unknown: too few independent points ({:.2g})", effective_points);
    case IwanSigmaReason::kAtKink:
      return "sigma unknown: fixed only by points at phi_max, from one side";
    case IwanSigmaReason::kModelMisfit:
      return "no sigma: the model does not describe the data";
    case IwanSigmaReason::kUnknown:
      return "sigma unknown: no covariance at the result (a direction the data do not fix)";
  }
  return "";
}

namespace {

// The measured low-amplitude frequency lies nearer another mode of the model as given than mode R.
std::string wrong_mode(const MisfitEvidence& e) {
  return fmt::format(
      "the measured low-amplitude frequency {:.6g} Hz is {:+.3g} % off the model's mode {} "
      "({:.6g} Hz, linear, as given) but {:+.3g} % off its mode {} ({:.6g} Hz): the backbone "
      "looks like mode {}'s; check --mode",
      e.low_frequency_hz, 100 * (e.low_frequency_hz / e.mode_hz - 1), e.mode, e.mode_hz,
      100 * (e.low_frequency_hz / e.nearer_mode_hz - 1), e.nearer_mode, e.nearer_mode_hz,
      e.nearer_mode);
}

// The share of a curve's softening at its low end (MisfitEvidence::low_softening_share) below
// which its frequency is flat there: a joint's power law gives 0.040-0.053 on the one-mode truth
// (chi -0.5, hits from 5e-4 to 1.5-2.5 phi_max), a joint held slipping by another mode -0.002 to
// 0.017.
constexpr double kLowSofteningShare = 0.025;

// Damping at the low end beyond the fitted one-mode joint's: the structure's own damping, which
// the model lacks, or another mode slipping the same joint in the hits, which keeps it slipping
// there. The measured frequency's low end (low_softening_share) only leans between the two: a
// joint softens from zero amplitude on, but one nearly linear in amplitude (chi near 0) hardly
// does, and data that start near the other mode's slip soften there. On the one-mode truth (three
// hits, 1e-4 / 2 % noise) the own damping 5e-4 of a chi -0.05 joint over 3.5 decades reads 0.5 %
// (flat) and of a chi -0.2 joint with 10 points a curve over 2.5 decades 2.2 %, while another
// mode adding 0.1 phi_max to a chi -0.5 or -0.9 joint over 2.5 decades reads 3.5 % and 5.0 %
// (softening): each was named the other cause, alone. What decides is the refit with Z free: the
// own damping then fits within the noise (reduced chi-square 1.09, chi -0.05 and -0.5), the
// other mode's slip does not (7.6 and 9.0 for 0.1 and 0.3 phi_max on chi -0.5), except for a joint
// nearly linear in amplitude, whose slip at a constant offset only shifts the frequency and adds
// a nearly constant damping, as own damping does (1.3 for chi -0.05). With Z fitted already the
// own damping is not what is missing.
std::string own_damping_or_other_slip(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  const std::string strike =
      "strike so that the fitted mode dominates, or screen the hits with the other modes' "
      "backbones";
  // A mode that hardly moves the joint: no slip of it, by this mode or another, shows in this
  // mode's damping.
  if (s.joint_hardly_moved() && !s.modal_ratio_fitted) {
    return fmt::format(
        "That is the structure's own damping, which the model lacks (modal_ratio {:.3g}, held): "
        "this mode hardly moves the joint, so no slip of the joint, by this mode or another, "
        "damps it; fit it with --linear-damping fit (or set [damping] modal_ratio in the model)",
        s.modal_ratio);
  }
  if (s.modal_ratio_fitted) {
    return fmt::format(
        "That is not the structure's own damping, which is fitted (modal_ratio {:.3g}): another "
        "mode slipping the same joint in these hits keeps it slipping at the low end; {}",
        s.modal_ratio, strike);
  }
  const double share = e.low_softening_share;
  const std::string lean =
      !std::isfinite(share)
          ? std::string(
                "The measured frequency's low end leans neither way here (fewer than 10 points a "
                "curve, or no softening over it)")
      : share >= kLowSofteningShare
          ? fmt::format(
                "The measured frequency still softens there as a joint's does ({:.1f} % of the "
                "curve's softening lies between its lowest and second fifth of amplitudes), which "
                "leans toward the structure's own damping, but does not decide",
                100 * share)
          : fmt::format(
                "The measured frequency hardly changes there ({:.1f} % of the curve's softening "
                "lies between its lowest and second fifth of amplitudes; a joint's power law "
                "softens from zero amplitude on), which leans toward another mode's slip, but "
                "does not decide",
                100 * share);
  return fmt::format(
      "That is the structure's own damping (roughly constant in amplitude), which the model lacks "
      "(modal_ratio {:.3g}, held), or another mode slipping the same joint in these hits, which "
      "keeps it slipping at the low end. {}: a joint nearly linear in amplitude (chi near 0) "
      "hardly softens there, and data that start near the other mode's slip do. Refit with "
      "--linear-damping fit (or set [damping] modal_ratio in the model): the structure's own "
      "damping then fits within the noise, and a misfit that stays is the other mode's slip ({})",
      s.modal_ratio, lean, strike);
}

// What the residuals at s.best point at (IwanUpdateSummary::misfit_cause()), read as if s.best
// were the best fit.
std::string residual_cause(const IwanUpdateSummary& s) {
  // A start no candidate improved on is read too where the joint hardly moves over the data:
  // no Iwan parameters then change the curve, so the start is as good a fit as any.
  if ((!s.improved && !s.joint_hardly_moved()) || !s.misfit() || !s.evidence) return "";
  const MisfitEvidence& e = *s.evidence;
  const auto& held = s.held;
  const auto& bound_side = s.bound_side;
  // The linear limit: at the lowest amplitudes the model's frequency is K_T's and the linear
  // part's. Off by far more than the noise there (and than 0.1 %, a frequency resolution), no
  // Iwan parameter set bends the curve onto the data: the trial's wrong --mode ran into every
  // bound, and a backbone 5 % below the model with K_T held into chi's.
  const bool linear_off = linear_limit_off(e);
  if (linear_off && e.nearer_mode > 0) return wrong_mode(e);
  // Curves that disagree with one another: offsets of each curve from the others explain most
  // of the chi-square. Scatter between hits (the trial's three curves, each with its own 0.2 %
  // frequency and 5 % damping offset: reduced chi-square 9.6, and the report asked for 4 times
  // the evaluations while the sigmas, one cluster per curve, were right); no search cures it.
  if (e.curves >= 2 && e.between_curves_share >= 0.5) {
    return fmt::format(
        "the {} curves disagree with one another by more than their stated noise: an offset of "
        "each from the others (frequency {:+.2g} to {:+.2g} %, damping {:+.2g} to {:+.2g} % "
        "about the fitted curve) explains {:.0f} % of the chi-square. {}. To weigh the points by "
        "it, state it in each point's uncertainty (frequency_std_hz, damping_std)",
        e.curves, 100 * e.frequency_offsets(0), 100 * e.frequency_offsets(1),
        100 * e.damping_offsets(0), 100 * e.damping_offsets(1), 100 * e.between_curves_share,
        !e.apart_curve.empty()
            ? fmt::format(
                  "But {} ({} points, amplitude {:.3g} to {:.3g}) lies apart from the others "
                  "({} {:+.2g} % against their {:+.2g} to {:+.2g} %, {:.2g} times their spread: "
                  "random scatter between hits puts a curve there less than 1 time in 100): its "
                  "offset follows that hit (another strike point, another mode slipping the "
                  "joint), no random scatter, so no sigma is stated (one cluster per curve would "
                  "read it as scatter and understate the error); fit that curve apart, or leave "
                  "it out",
                  e.apart_curve, e.apart_points, e.apart_amplitude(0), e.apart_amplitude(1),
                  e.apart_in_damping ? "damping" : "frequency",
                  100 * e.apart_offset(e.apart_in_damping ? 1 : 0), 100 * e.apart_others(0),
                  100 * e.apart_others(1), e.apart_t)
            : fmt::format(
                  "That is scatter between the hits (each hit's joint a little different), which "
                  "neither a longer search nor a wider range cures; {}",
                  e.curves >= 4
                      ? fmt::format("the sigmas allow for it (one cluster per curve, Student's t "
                                    "with {} degrees of freedom)",
                                    e.curves - 1)
                      : fmt::format("with {} curves the sigmas do not allow for it (one cluster "
                                    "per curve leaves {} degree{} of freedom; four or more "
                                    "curves would give a sigma)",
                                    e.curves, e.curves - 1, e.curves - 1 == 1 ? "" : "s")));
  }
  // K_T held, so the curve's linear limit is mode R's linear frequency at the held K_T. Off the
  // measured low-amplitude frequency by more than three times its noise (and 0.1 %), that is the
  // linear part's error where the joint does not take it up: chi ran to its bound, where the
  // microslip softening is nearly even in amplitude and shifts the whole curve onto the low data
  // (data 0.5 % below the model with --gamma 1: the report said "widen it" and "--evaluations"),
  // or the fitted curve still misses the low data on the side of the offset by more than three
  // times their noise (the same data with chi inside its range: the curve 0.497 % above them, 9.9
  // times the 5e-4 noise, under linear_limit_off()'s ten, and no cause named at a reduced
  // chi-square of 52). A joint can only soften: data above the linear frequency are never its.
  // Where the fitted curve meets the low data with chi inside its range, the joint's softening at
  // the lowest amplitudes may be real, and the misfit has another cause.
  if (held[1] && e.linear_hz > 0 && e.low_frequency_hz > 0) {
    const double off = e.linear_hz / e.low_frequency_hz - 1;
    const double tolerance = std::max(3 * e.low_frequency_noise, 1e-3);
    const bool bent = bound_side[2] != 0 && off > 0;
    const bool missed =
        e.low_frequency_error * off > 0 && std::abs(e.low_frequency_error) > tolerance;
    // Data of a joint kept slipping at the low end (another mode adding 0.1 or 0.3 phi_max to
    // its slip, K_T held at the truth's): the measured frequency flat there (a softening share
    // of -0.002 to 0.009) 0.29-0.50 % below the linear limit, the measured damping there 3.2-3.9
    // times the fitted model's; a linear part 0.4 % or 1 % too stiff leaves the joint's
    // softening (0.045-0.053) and damping (0.42-0.88 times). Before, the first was told "an
    // error of the linear part".
    if (std::abs(off) > tolerance && off > 0 && e.low_softening_share < kLowSofteningShare &&
        e.low_model_damping > 0 && e.low_damping >= 2 * e.low_model_damping) {
      return fmt::format(
          "with Kt held, the measured low-amplitude frequency {:.6g} Hz lies {:.3g} % below mode "
          "{}'s linear frequency {:.6g} Hz (the curve's zero-amplitude limit) and hardly changes "
          "there ({:.1f} % of the curve's softening lies between its lowest and second fifth of "
          "amplitudes; a joint's power law softens from zero amplitude on), while the measured "
          "damping there, {:.3g}, lies {:.3g} times the fitted model's ({:.3g}): the joint "
          "slips at the low end as no one-mode Iwan curve does, lowering the frequency and "
          "adding damping there, as where another mode slipping the same joint in these hits "
          "keeps it slipping, rather than an error of the linear part. Strike so that the fitted "
          "mode dominates, or screen the hits with the other modes' backbones",
          e.low_frequency_hz, 100 * off / (1 + off), e.mode, e.linear_hz,
          100 * e.low_softening_share, e.low_damping, e.low_damping / e.low_model_damping,
          e.low_model_damping);
    }
    if (std::abs(off) > tolerance && (bent || missed)) {
      const std::string how =
          bent ? fmt::format(
                     "chi ran to its {} bound for the joint's microslip to soften the whole "
                     "curve by that much",
                     bound_side[2] > 0 ? "upper" : "lower")
          : off > 0
              ? fmt::format(
                    "the fitted curve still misses the low-amplitude data by {:+.3g} % ({:.0f} "
                    "times its noise), which the joint's microslip could not take up",
                    100 * e.low_frequency_error,
                    std::abs(e.low_frequency_error) / e.low_frequency_noise)
              : fmt::format(
                    "the fitted curve still misses the low-amplitude data by {:+.3g} % ({:.0f} "
                    "times its noise): a joint only softens, so no joint parameters reach a "
                    "frequency above the linear one",
                    100 * e.low_frequency_error,
                    std::abs(e.low_frequency_error) / e.low_frequency_noise);
      return fmt::format(
          "with Kt held, mode {}'s linear frequency {:.6g} Hz (the curve's zero-amplitude limit) "
          "lies {:+.3g} % off the measured low-amplitude frequency {:.6g} Hz ({:.0f} times its "
          "noise), and {}: the model's linear frequency disagrees with the data's low-amplitude "
          "one, an error of the linear part that no wider range and no longer search cures; "
          "update-linear first (or free Kt)",
          e.mode, e.linear_hz, 100 * off, e.low_frequency_hz, std::abs(off) / e.low_frequency_noise,
          how);
    }
  }
  // K_T free and not stopped short by its range, one target: K_T alone sets the curve's linear
  // limit, and a linear part 0.4 % or 1 % too stiff is taken up by it (the one-mode truth's
  // three hits: the fitted curve meets the low data within 3e-5). A linear limit left off the
  // low data there was bent for the rest of the data: where the fitted curve lies above them
  // with the measured damping there above the model's, K_T rose to steepen the joint's curve
  // onto that damping. Which damping, the structure's own or another mode's slip, the frequency's
  // low end only leans between (own_damping_or_other_slip()). Before, both were told "the model's
  // linear part does not match the measured mode; update-linear first", and still were with
  // fewer than 10 points a curve (8: every one of chi -0.05 to -0.9 over 3.5 decades), or over
  // 1.5-2.5 decades, where the joint's damping at the low end hides the own damping's excess
  // (chi -0.05 over 1.5 decades: the limit +0.109 %, 11 times the noise; chi -0.5 with 8 points
  // over 2.5 decades: +0.102 %, 10 times).
  if (linear_off && !held[1] && e.targets == 1 && !kt_stopped_short(s)) {
    if (e.low_frequency_error > 0 && e.low_model_damping > 0 &&
        e.low_damping > 1.1 * e.low_model_damping) {
      return fmt::format(
          "the measured damping at the lowest amplitudes, {:.3g}, lies {:.0f} % above the fitted "
          "model's there ({:.3g}); the fit raised Kt to steepen the joint's curve toward that "
          "damping, so its linear limit misses the measured low-amplitude frequency {:.6g} Hz by "
          "{:+.3g} % ({:.0f} times its noise), which is no error of the linear part (Kt free takes "
          "that up). {}",
          e.low_damping, 100 * (e.low_damping / e.low_model_damping - 1), e.low_model_damping,
          e.low_frequency_hz, 100 * e.low_frequency_error,
          std::abs(e.low_frequency_error) / e.low_frequency_noise, own_damping_or_other_slip(s));
    }
    return fmt::format(
        "the fitted curve's linear limit misses the measured low-amplitude frequency {:.6g} Hz by "
        "{:+.3g} % ({:.0f} times its noise) though Kt, free inside its range, sets that limit "
        "alone and would meet it: no error of the linear part (Kt takes that up), but the fit "
        "bending the curve for the rest of the data, as damping the one-mode joint lacks does. {}",
        e.low_frequency_hz, 100 * e.low_frequency_error,
        std::abs(e.low_frequency_error) / e.low_frequency_noise, own_damping_or_other_slip(s));
  }
  // Damping far above anything the joint gives alongside the measured frequencies: per cent
  // read as a fraction is 100 times (a trial's 0.005-0.035 % table without a unit ran chi into
  // its bound); a loss factor eta = 2 zeta read as zeta is twice. Values of 1 or more cannot be
  // per cent of a plausible damping ratio read right, so they say nothing of it.
  // Damping the joint cannot give where its microslip adds little: at the lowest amplitudes
  // the model's damping is the structure's own (Z, held). Measured damping that stays at least
  // half its median there (flat, not a joint's rise with amplitude) is that missing damping: a
  // flat 0.3 % backbone against a model without [damping] was told "a damping column in per
  // cent read as a fraction gives 100 times" at a factor of 3.2 (a per-cent column keeps the
  // joint's rise, and its lowest values lie well below its median).
  // A mode that leaves the joint still has no model damping at all (no ratio to take): that
  // is the same missing damping.
  // The measured frequency softening at the low end as a joint's does (low_softening_share)
  // says so too where the median factor stays under 1.7 (K_T held at the truth's on data with
  // the structure's own damping 5e-4: 1.64-1.65, the low damping 3.9 times the model's, and no
  // cause named before). Another mode slipping the joint gives the same low end (K_T held 10 %
  // low on data of another mode adding 0.1 phi_max, 8 points a curve: named own damping alone),
  // so both are named, with the refit that tells them apart (own_damping_or_other_slip()).
  if (!s.modal_ratio_fitted &&
      (e.damping_factor >= 1.7 || !(e.low_model_damping > 0) ||
       e.low_softening_share >= kLowSofteningShare) &&
      !(e.low_softening_share < kLowSofteningShare) && e.low_damping > 0 &&
      e.low_damping >= 3 * e.low_model_damping && e.low_damping >= 0.5 * e.median_damping) {
    return fmt::format(
        "the measured damping stays near {:.3g} down to the lowest amplitudes (its median over "
        "every point {:.3g}), where a joint's microslip adds little, while the model's damping "
        "there is {:.3g} (its own damping, modal_ratio {:.3g}, held): not the joint's. {}",
        e.low_damping, e.median_damping, e.low_model_damping, s.modal_ratio,
        own_damping_or_other_slip(s));
  }
  // Wherever else the measured frequency is flat at the low end (low_softening_share) with the
  // measured damping there twice the fitted model's or more, the joint slips there as no one-mode
  // Iwan curve does (another mode adding 0.1 phi_max, K_T held 10 % low: low damping 5.6 times the
  // model's, share 0.003-0.009; before, "a loss factor ... halve it" at a median factor of 1.73,
  // and before that "the structure's own damping"). A loss factor or a per-cent column keeps the
  // joint's softening there; the structure's own damping with a joint nearly linear in amplitude
  // does not (own_damping_or_other_slip()).
  if (e.low_softening_share < kLowSofteningShare && e.low_model_damping > 0 &&
      e.low_damping >= 2 * e.low_model_damping) {
    return fmt::format(
        "the measured damping at the lowest amplitudes, {:.3g}, lies {:.3g} times the fitted "
        "model's there ({:.3g}): more dissipation at low amplitude than the joint's power law "
        "allows. {}",
        e.low_damping, e.low_damping / e.low_model_damping, e.low_model_damping,
        own_damping_or_other_slip(s));
  }
  if (e.damping_factor >= 3 && e.damping_max < 1) {
    return fmt::format(
        "the measured damping lies a median {:.3g} times above the fitted model's, more than the "
        "joint gives alongside the measured frequencies; a damping column in per cent read as a "
        "fraction gives 100 times: if it is per cent, name the unit in its header "
        "(damping_ratio [%])",
        e.damping_factor);
  }
  if (e.damping_factor >= 1.7 && e.damping_factor <= 2.4 && !linear_off) {
    return fmt::format(
        "the measured damping lies a median {:.3g} times above the fitted model's; a loss factor "
        "(eta = 2 zeta) given as the damping ratio would do that: if so, halve it",
        e.damping_factor);
  }
  if (linear_off) {
    // K_T stopped by its range short of a frequency the model as given (gamma 1) has: the range
    // kept the fit from it, not the linear part (a gamma range of 0.05-0.9 on a model whose K_s
    // fits the data); the bound's own line says to widen it.
    const bool stopped = kt_stopped_short(s);
    if (stopped && model_as_given_matches(e)) return "";
    const std::string kt =
        held[1]   ? std::string(" with Kt held")
        : stopped ? fmt::format(
                        " with Kt at its {} bound, and mode {} of the model as given (Kt = Ks, "
                        "{:.6g} Hz) by {:+.3g} %",
                        bound_side[1] > 0 ? "upper" : "lower", e.mode, e.mode_hz,
                        100 * (e.mode_hz / e.low_frequency_hz - 1))
                  : std::string(", Kt alone cannot bring it there");
    return fmt::format(
        "the fitted curve's linear limit misses the measured low-amplitude frequency {:.6g} Hz "
        "by {:+.3g} % ({:.0f} times its noise){}: the model's linear part does not match the "
        "measured mode; update-linear first",
        e.low_frequency_hz, 100 * e.low_frequency_error,
        std::abs(e.low_frequency_error) / e.low_frequency_noise, kt);
  }
  return "";
}

}  // namespace

std::string IwanUpdateSummary::misfit_cause() const {
  if (status != IwanUpdateStatus::kBudget) return residual_cause(*this);
  // A fit that did not converge stopped where its evaluations ran out: its residuals are those
  // of that point, not of a best fit, so what they suggest (scatter between hits, a loss
  // factor, missing damping, the linear limit) is no finding (an unconverged fit was told "a
  // loss factor (eta = 2 zeta) given as the damping ratio" at a damping factor of 1.85);
  // tentative_cause() gives it, to be said as such. What rests on the model as given alone
  // stands: a measured low-amplitude frequency off mode R and nearer another mode.
  if ((!improved && !joint_hardly_moved()) || !misfit() || !evidence) return "";
  if (evidence->nearer_mode > 0 && !model_as_given_matches(*evidence)) return wrong_mode(*evidence);
  return "";
}

std::string IwanUpdateSummary::tentative_cause() const {
  if (status != IwanUpdateStatus::kBudget || !misfit_cause().empty()) return "";
  return residual_cause(*this);
}

namespace {

// The (F_S, beta) pairs that fit microslip data alike (slip_force_at_beta() of the result at a few
// betas, those whose phi_max stays above the largest measured slip), as the end of the report's
// slip line.
std::string microslip_family(const IwanUpdateSummary& s) {
  std::vector<std::string> pairs;
  for (const double b : {0.25, 0.5, 1.0, 2.0, 4.0}) {
    model::IwanParameters p = s.best;
    p.Fs = slip_force_at_beta(s.best, b);
    p.beta = b;
    if (!(p.Fs > 0) || !(model::Iwan(p).phi_max() > s.top_slip)) continue;
    pairs.push_back(fmt::format("{:.3g} N at beta {:g}", p.Fs, b));
  }
  if (pairs.empty()) return "";
  return fmt::format(
      ": every (Fs, beta) with the fitted Kt and chi and the same microslip dissipation fits "
      "these data alike ({}){}",
      fmt::join(pairs, ", "),
      s.beta_held_as_asked() ? std::string()
                             : std::string("; data past phi_max separate them, or hold beta at a "
                                           "known value with --beta"));
}

}  // namespace

std::string IwanUpdateSummary::report() const {
  const bool monte_carlo = optimizer != IwanOptimizer::kGlobalLocal;
  const std::string outcome = status == IwanUpdateStatus::kNoValidPoint ? "no valid sample"
                              : !improved          ? "no candidate improved on the start"
                              : !at_bounds.empty() ? "stopped at a bound of the search range"
                              : status == IwanUpdateStatus::kBudget
                                  ? (monte_carlo ? "not converged (the evaluation budget ran out "
                                                   "with the Monte Carlo still improving)"
                                                 : "not converged (the local solve from the best "
                                                   "point was still descending when its "
                                                   "evaluations ran out)")
                              : monte_carlo ? "converged (a Monte Carlo round brought no gain)"
                                            : "converged (the local solve from the best point met "
                                              "its tolerance)";
  // A cost the model could not evaluate is said so, never printed as a number.
  const auto cost_text = [](double c) {
    return std::isfinite(c) ? fmt::format("{:.4g}", c) : std::string("(not evaluable)");
  };
  // The polish may pass the budget: say by how much, so the count is not read as a bug.
  const std::string past =
      polish_evaluations > 0
          ? fmt::format(
                " ({} of them past the budget, carrying the local solve from the best "
                "point on toward its tolerance)",
                polish_evaluations)
          : std::string();
  std::string out = fmt::format(
      "Iwan update: {}, {} QSMA evaluations{}, {} {}, cost {} -> {}, {}\n", outcome, evaluations,
      past, rounds, monte_carlo ? "Monte Carlo rounds" : "local refinements",
      cost_text(initial_cost), cost_text(final_cost),
      linear_known ? fmt::format("linear frequency error {:.3g} %", 100 * linear_error)
                   : std::string("no measured linear frequency to compare"));
  // Each parameter with its one-sigma relative uncertainty where known; held ones say so.
  const bool no_slip = no_slip_seen();
  // The words of sigma_reason(), as parameters.csv's and Python's notes say them.
  auto sigma = [&](int k) -> std::string {
    switch (sigma_reason(k)) {
      case IwanSigmaReason::kStated:
        return fmt::format(" +/- {:.2g} %", 100 * relative_std(k));
      case IwanSigmaReason::kGivenBetaAsHeld:
        return fmt::format(" +/- {:.2g} % given beta = {:.4g} as held (microslip only)",
                           100 * relative_std(k), best.beta);
      case IwanSigmaReason::kHeldAsAsked:
        return " (held)";
      case IwanSigmaReason::kBetaHeldMicroslip:
        return " (held at its start by the fit, not fitted: microslip only)";
      case IwanSigmaReason::kBetaHeldFreeNoBetter:
        return " (held at its start by the fit, not fitted: the fit with it free did no better, "
               "below)";
      case IwanSigmaReason::kStart:
        return " (the start: no candidate improved on it)";
      case IwanSigmaReason::kNoSlip:
        return " (not identified: no slip in the data, below)";
      case IwanSigmaReason::kMicroslipFamily:
        return k == 0 ? " (not identified apart from beta: microslip only)"
                      : " (not identified apart from Fs: microslip only)";
      case IwanSigmaReason::kNotConverged:
        return " (no sigma: not converged)";
      case IwanSigmaReason::kGivenBeta: {
        const double conditional = std::sqrt(std::max(covariance(0, 0), 0.0));
        return fmt::format(
            " given beta = {:.4g} (not identified, microslip only: the data fix only the "
            "combination of Fs and beta, below{})",
            best.beta,
            conditional > 0 && !misfit_sets_the_error()
                ? fmt::format("; +/- {:.2g} % at that beta", 100 * conditional)
                : "");
      }
      case IwanSigmaReason::kTooFewPoints:
        return " (sigma unknown: too few independent points, below)";
      case IwanSigmaReason::kAtKink:
        return " (sigma unknown: fixed only by points at phi_max, from one side, below)";
      case IwanSigmaReason::kModelMisfit:
        return " (no sigma: the model does not describe the data, below)";
      case IwanSigmaReason::kUnknown:
        return " (sigma unknown: no covariance at the result)";
    }
    return "";
  };
  out += fmt::format(
      "  Fs {:.6g} -> {:.6g} N{}, Kt {:.6g} -> {:.6g} N/m{}, chi {:.4g} -> {:.4g}{}, beta {:.4g} "
      "-> {:.4g}{}\n",
      start.Fs, best.Fs, sigma(0), start.Kt, best.Kt, sigma(1), start.chi, best.chi, sigma(2),
      start.beta, best.beta, sigma(3));
  if (modal_ratio_fitted) {
    out += fmt::format(
        "  modal_ratio (the structure's own damping) {:.6g} -> {:.6g}{}; the best constant "
        "backbone (joint barely slipping) costs {:.4g}\n",
        modal_ratio_start, modal_ratio,
        sigma_reason(4) == IwanSigmaReason::kStated ? fmt::format(" +/- {:.2g}", modal_ratio_std)
                                                    : sigma(4),
        constant_cost);
  } else if (modal_ratio_start > 0) {
    out += fmt::format("  modal_ratio {:.4g} held (the model's own damping, in every damping)\n",
                       modal_ratio_start);
  }
  // The linear part's systematic effect (linear_part_sensitivity): an error of the rest of the
  // model that K_T takes up leaves white residuals and moves the parameters by many of their
  // sigmas (the one-mode truth with K 0.1 % stiffer: K_T -2.4 % +/- 0.07-0.09 %, F_S -5 % +/-
  // 0.3-0.4 %, reduced chi-square 1.14-1.31, and nothing said), so the rates are stated, and the
  // accuracy of the linear frequency each stated sigma needs.
  if (linear_part_sensitivity.cwiseAbs().maxCoeff() > 0 && frequency_per_stiffness != 0) {
    static const char* names[] = {"Fs", "Kt", "chi", "beta"};
    std::vector<std::string> moves, holds;
    for (const int k : {1, 0, 2, 3}) {
      if (linear_part_sensitivity(k) == 0) continue;
      // A rate below 0.001 % per 0.1 % is no move worth its digits (chi of a one-mode fit:
      // -1.2e-08 %), and a sigma that holds to a 10 % error of the linear frequency is not
      // limited by the linear part (that chi: "4e+06 %").
      const double move = 100 * 1e-3 * linear_part_sensitivity(k);
      moves.push_back(std::abs(move) < 1e-3 ? fmt::format("{} by less than 0.001 %", names[k])
                                            : fmt::format("{} by {:+.2g} %", names[k], move));
      if (const double t = linear_part_tolerance(k); t > 0 && t <= 0.1)
        holds.push_back(fmt::format("{:.2g} % ({})", 100 * t, names[k]));
    }
    out += fmt::format(
        "  linear part: a 0.1 % error in mode {}'s linear frequency from the rest of the model "
        "(its stiffness without the joints {:.3g} % off) moves {}{}{}; {}\n",
        sensitivity_mode, 0.1 / std::abs(frequency_per_stiffness), fmt::join(moves, ", "),
        held[1] ? std::string()
                : std::string(", and leaves no trace in the residuals: Kt takes the frequency up"),
        holds.empty() ? std::string()
                      : fmt::format("; the sigmas hold only where that frequency is right to {}",
                                    fmt::join(holds, ", ")),
        linear_part_updated
            ? "the model's linear frequencies match the measured ones (a linear update's "
              "result): the error left in its linear part carries into the parameters at these "
              "rates"
            : "fit the model's linear part to measured linear frequencies (update-linear) before "
              "reading the parameters closer than that");
  }
  if (no_slip) {
    out += fmt::format(
        "  WARNING: no slip in these data: the best constant backbone (the joint stuck, Kt and "
        "the structure's own damping fitted) fits them as well as any Iwan joint (cost {:.4g} "
        "against {:.4g}, a gain below what {} more parameters give by chance 1 time in 20). "
        "The measured frequency and damping do not change with amplitude beyond their noise: "
        "Fs, chi and beta are not identified, whatever the search, and Kt and modal_ratio are "
        "the result; {}\n",
        final_cost, constant_cost, held[3] ? "two" : "three",
        // A mode that hardly moves the joint: larger amplitudes of it are out of reach.
        joint_hardly_moved()
            ? fmt::format(
                  "this mode hardly moves the joint ({}), so larger amplitudes of it would not "
                  "reach phi_max: a mode whose shape slips the joint would identify it",
                  hardly_moved_words(*this))
            : std::string(
                  "larger amplitudes, where the frequency falls, would identify the joint"));
  }
  if (!improved || status == IwanUpdateStatus::kNoValidPoint) {
    out += fmt::format(
        "  the result is the start{}.{}\n",
        status == IwanUpdateStatus::kNoValidPoint ? " (no sample could be evaluated)" : "",
        no_slip ? " No slip in the data (above): no start would do better."
        : joint_hardly_moved()
            ? fmt::format(
                  " The measured modes hardly move the joint here ({}): the joint barely shapes "
                  "these backbones, so neither wider bounds nor another start would change "
                  "them; a mode whose shape slips the joint would identify it",
                  hardly_moved_words(*this))
        : optimizer == IwanOptimizer::kGlobalLocal
            ? " Widen the bounds or give a better start."
            : " The Monte Carlo's uniform samples rarely land near the optimum in wide bounds: "
              "use the global-local optimiser (--optimizer global-local).");
  }
  // Fs and beta drift together along the microslip family: a bound there is no better fit
  // beyond it, and widening the range only moves them along (Fs 38 % when it was tried).
  const bool family = !held[3] && microslip_only();
  const std::string cause = misfit_cause();
  // K_T sets the linear limit: at a bound short of the measured low-amplitude frequency, that
  // frequency pressed it there. Where the model as given (gamma 1) matches it, the range stopped
  // the fit (widen it); else a wider range would let K_T take up the linear part's error or
  // another mode's frequency, as a curve 1.5 % above the model ran K_T to gamma 2 (the plain
  // "would not cure that" was wrong there: a wider range does move it onto the data).
  const bool kt_short = kt_stopped_short(*this);
  const bool kt_range = kt_short && model_as_given_matches(*evidence) && evidence->nearer_mode == 0;
  // The relative sigma stated for the parameter a bound line names (0: none stated).
  const auto stated_at_bound = [&](const std::string& b) {
    static const char* prefixes[] = {"Fs", "gamma", "chi", "beta"};
    for (int k = 0; k < 4; ++k)
      if (b.rfind(prefixes[k], 0) == 0)
        return sigma_reason(k) == IwanSigmaReason::kStated ? relative_std(k) : 0.0;
    return 0.0;
  };
  for (const std::string& b : at_bounds) {
    const bool along = family && (b.rfind("Fs", 0) == 0 || b.rfind("beta", 0) == 0);
    const bool kt = b.rfind("gamma", 0) == 0 && kt_short;
    // Past phi_max throughout, K_T, chi and beta show only weakly: their bound is where the search
    // drifted along what the data leave free (a table from 2.7 to 27 phi_max ran K_T to gamma 2
    // with a sigma of 2.8e4 %, and was told to widen it and update-linear first).
    const bool weak = macroslip_only() && cause.empty() && b.rfind("Fs", 0) != 0;
    if (no_slip && b.rfind("gamma", 0) != 0) {
      out += fmt::format(
          "  WARNING: {}: the data show no slip (above), so nothing holds it; a wider range "
          "moves it, not the fit\n",
          b);
    } else if (weak) {
      out += fmt::format(
          "  WARNING: {}: the data lie past phi_max at every amplitude (below), where Kt, chi and "
          "beta show only weakly, so it ended there along what the data leave free; a wider range "
          "moves it, not the fit\n",
          b);
    } else if (along) {
      out += fmt::format(
          "  WARNING: {}: the microslip data fix Fs and beta only together, so it ended there "
          "along that family; a wider range moves it, not the fit\n",
          b);
    } else if (kt && !kt_range && !cause.empty()) {
      out += fmt::format(
          "  WARNING: {}: the measured low-amplitude frequency pressed it there, beyond the "
          "linear limit Kt reaches in its range (below); a wider range would let Kt take up {} "
          "rather than fit the joint\n",
          b, evidence->nearer_mode > 0 ? "another mode's frequency" : "the linear part's error");
    } else if (!cause.empty() && !kt) {
      out += fmt::format(
          "  WARNING: {}: the misfit below pressed it there; a wider range would not cure that\n",
          b);
    } else if (const double sd = stated_at_bound(b); sd > 0.5) {
      // A parameter the data hardly fix (not identifiable, its sigma over half its value) ends
      // at a bound along what they leave free: the lap joint's mode 2, whose joint barely moves,
      // put gamma at 2 +/- 78 % (the truth 1.6) and was told to widen the range.
      out += fmt::format(
          "  WARNING: {}: the data hardly fix it (+/- {:.2g} %), so it ended there along what "
          "they leave free; a wider range moves it, not the fit\n",
          b, 100 * sd);
    } else {
      out += fmt::format("  WARNING: {}: the best fit may lie outside the range, widen it\n", b);
    }
  }
  if (!cause.empty()) {
    out += fmt::format(
        "  WARNING: the model does not describe the data, and the residuals point at the data "
        "or the model rather than the search: {}\n",
        cause);
  }
  // The fit with beta freed lost to the one with it held at its start: beta is then no result
  // of the data, which reach macroslip where it is identified (before: "beta ... (held)", as if
  // asked, and held 1 in parameters.csv).
  if (held[3] && beta_hold == IwanBetaHold::kFreeFitNoBetter) {
    out += fmt::format(
        "  WARNING: the data reach macroslip, where beta is identified, but the fit with beta "
        "free ended at cost {:.4g}, above this fit's {:.4g} with beta held at its start {:.4g}: "
        "beta is not fitted and has no sigma, and the other parameters{} hold at that beta; run "
        "again with a larger --evaluations (e.g. {}), or hold beta at a known value with "
        "--beta\n",
        free_fit_cost, final_cost, best.beta,
        (relative_std.array() > 0).any() ? " and their sigmas" : "",
        4 * std::max(evaluations, 1500));
  }
  // K_T sets the stuck joint's linear frequencies, which update-linear fits to the measured
  // ones first. Where the fit moves it far, it likely takes up the linear model's error: a
  // backbone 5 % below an un-updated model moved K_T by -49 % and beta by +82 %, chi 8.6 sigma
  // off, all within the noise and without a word.
  // Where the residuals name a likelier cause (misfit_cause()), that is said instead.
  if (improved && !held[1] && start.Kt > 0 && std::abs(best.Kt / start.Kt - 1) > 0.25 &&
      cause.empty() && !macroslip_only()) {
    // After the linear update (linear_part_updated, as the "linear part:" line reads it) the
    // start is that update's K_T: sending the user to update-linear again sent them in a circle.
    out += fmt::format(
        "  note: Kt moved from {:.6g} to {:.6g} N/m ({:+.0f} %): {}\n", start.Kt, best.Kt,
        100 * (best.Kt / start.Kt - 1),
        linear_part_updated
            ? "away from the model's, whose linear frequencies match the measured ones (a "
              "linear update's result): the backbones' low-amplitude limit disagrees with those "
              "frequencies, or Kt takes up what beta and chi do not describe; hold Kt at the "
              "model's (--gamma 1) and see whether the fit still holds"
            : "where the model's linear frequencies were not fitted to the measured ones first "
              "(update-linear), the fit takes their error up into Kt, beta and chi; update them "
              "first, or hold Kt (--gamma, Kt / Ks) and see whether the fit still holds");
  }
  // A fit that did not converge stopped where its evaluations ran out, not at a minimum: said
  // whatever the chi-square (a fit at cost 1.31 where the minimum costs 0.73 looked fine at a
  // reduced chi-square of 0.68 and stated chi 4.6 sigma off), with no sigma.
  if (improved && status == IwanUpdateStatus::kBudget) {
    // Where the misfit has a named cause, or K_T's range stopped it, that comes first: a longer
    // search cures neither.
    const std::string advice =
        no_slip
            ? std::string("the data show no slip (above), which a longer search does not change")
        : !cause.empty() ? std::string(
                               "mend the cause named above first (a longer search cures a misfit "
                               "only where the search is at fault)")
        : kt_range ? std::string("widen the range named above first")
        // A longer search of data past phi_max throughout ended at the same cost, chi at its
        // bound and no sigma: the data, not the search, leave K_T, chi and beta free.
        : macroslip_only()
            ? std::string(
                  "the data lie past phi_max at every amplitude (below), where Kt, chi and beta "
                  "show only weakly, so a longer search may not fix them: data at amplitudes "
                  "below phi_max would")
            : fmt::format("run again with a larger --evaluations (e.g. {})",
                          4 * std::max(evaluations, 1500));
    // What the residuals where it stopped would suggest is said as that, not as a finding.
    const std::string tentative = tentative_cause();
    out += fmt::format(
        "  WARNING: the fit did not converge: {}; the parameters are where it stopped, not a "
        "best fit, and no sigma is stated; {}{}\n",
        monte_carlo ? "the Monte Carlo was still improving when its evaluation budget ran out"
                    : "the local solve from the best point was still descending when its "
                      "evaluations (its share of the budget and as many again) ran out",
        advice,
        tentative.empty()
            ? std::string()
            : fmt::format(". Where it stopped, the residuals alone would suggest the "
                          "following, no finding while the fit has not converged (a converged "
                          "fit may describe the data): {}",
                          tentative));
  }
  // A search that stopped at a bound with a misfit may have missed the best fit: 12 of 20
  // three-hit fits at the default 1500 ended at chi-square 9.7 with the truth costing 1.8
  // there, all 40 converged with 6000.
  // (Not where K_T's range alone kept it from the measured frequency: its bound's line says so.)
  if (improved && misfit() && cause.empty() && !kt_range && status != IwanUpdateStatus::kBudget &&
      !at_bounds.empty()) {
    out += fmt::format(
        "  WARNING: the search stopped at a bound with the model not describing the data: it "
        "may have missed the best fit rather than the model being wrong; run again with a "
        "larger --evaluations (e.g. {}) before judging the model\n",
        4 * std::max(evaluations, 1500));
  }
  if (rms_errors.any()) {
    out += fmt::format(
        "  relative RMS error: frequency {:.3g}, damping {:.3g} (the best constants: {:.3g}, "
        "{:.3g})\n",
        rms_errors(0), rms_errors(1), constant_rms_errors(0), constant_rms_errors(1));
  }
  // Residuals that run in waves along a curve leave few independent points: too few, and no
  // sigma is stated rather than a wrong one (a 200-point curve with AR(1) noise of rho 0.98 has
  // about 2 per sequence); few, and the sigmas allow for it but rest on them.
  // Too few points even if every residual were independent: said as such, not as waves (a
  // correlation read off 3 points sent the user after waves).
  const double fitted = std::round(effective_points - sigma_degrees_of_freedom);
  if (improved && effective_points > 0 && !(sigma_degrees_of_freedom > 2) &&
      static_cast<double>(residuals) - fitted <= 2) {
    out += fmt::format(
        "  WARNING: {} points ({} residuals) leave {:.0f} beyond the {:.0f} parameters fitted even "
        "if independent: too few to state a sigma (more than 2 needed); more points, or more "
        "curves, would give one\n",
        residuals / 2, residuals, std::max(0.0, static_cast<double>(residuals) - fitted), fitted);
  } else if (improved && effective_points > 0 && !(sigma_degrees_of_freedom > 2)) {
    out += fmt::format(
        "  WARNING: the residuals run in long waves along the curves (serial correlation {:.3g} "
        "from one point to the next, corrected for what the fit absorbs): the {} residuals amount "
        "to {:.2g} independent points, too few to state a sigma (more than {:.0f}, 2 beyond the "
        "parameters fitted, needed); {}\n",
        noise_correlation, residuals, effective_points,
        effective_points - sigma_degrees_of_freedom + 2,
        misfit() ? "with the model not describing the data (below), the waves are its misfit"
                 : "more curves (hits), or longer ones, would give one");
  } else if (improved && effective_points > 0 && effective_points < 30) {
    out += fmt::format(
        "  note: the residuals are serially correlated along the curves ({:.3g} from one point "
        "to the next, corrected for what the fit absorbs): the {} residuals amount to {:.3g} "
        "independent points; the sigmas allow for it (Student's t, {:.3g} degrees of freedom) "
        "but rest on these few\n",
        noise_correlation, residuals, effective_points, sigma_degrees_of_freedom);
  }
  if (improved && reduced_chi2 > 0) {
    out += fmt::format("  reduced chi-square {:.3g}", reduced_chi2);
    // With no sigma stated (too few effective points) there is no bound to speak of.
    const bool any_sigma = (relative_std.array() > 0).any();
    // Scatter between curves (the cause above) is in the sigmas with three or more curves.
    const bool scatter = evidence && evidence->curves >= 3 &&
                         cause.find("curves disagree with one another") != std::string::npos;
    out += misfit() ? std::string(
                          ": WARNING the model does not describe the data within their "
                          "stated noise") +
                          (scatter     ? " (the scatter between the curves, above)\n"
                           : any_sigma ? "; the uncertainties (scaled by it) are a lower bound\n"
                                       : "\n")
                    : " (the model describes the data within their stated noise)\n";
    // No sigma where the misfit, not the noise, sets the error (misfit_sets_the_error()): say
    // why, with the numbers that decided it.
    if (misfit_sets_the_error()) {
      const double k = static_cast<double>(residuals) / 6;
      const bool waves = !(noise_correlation < 0.3);
      const bool gathered = !(amplitude_share < 1.0 / 3 + 3 * std::sqrt((2.0 / 9) / (1.5 * k + 1)));
      out += fmt::format(
          "  WARNING: no sigma is stated: the model does not describe the data (reduced "
          "chi-square {:.3g}, beyond the {:.3g} the noise reaches over the {:.3g} independent "
          "points) and the residuals are no noise ({}): what the misfit pulls the parameters to, "
          "not the noise, sets their error, which no sigma from the residuals measures. {}\n",
          reduced_chi2, 1 + 3 * std::sqrt(2.0 / effective_points), effective_points,
          waves && gathered
              ? fmt::format("they run in waves, serial correlation {:.2g} from one point to the "
                            "next, and one third of the amplitudes holds {:.0f} % of the "
                            "chi-square",
                            noise_correlation, 100 * amplitude_share)
          : waves ? fmt::format("they run in waves, serial correlation {:.2g} from one point to "
                                "the next",
                                noise_correlation)
                  : fmt::format("one third of the amplitudes holds {:.0f} % of the chi-square",
                                100 * amplitude_share),
          cause.empty()
              ? "Find what the model lacks (another mode slipping the joint in the same hit, the "
                "linear part, the structure's own damping, a held parameter) before reading the "
                "parameters"
              : "Mend the cause named above first");
    }
    // A misfit whose residuals look like noise: uncorrelated from point to point (the AR(1)
    // coefficient, corrected for what the fit absorbs, below 0.3) and spread evenly over the
    // amplitudes (no third of the points, by amplitude, holds more than 1/3 of the chi-square by
    // 3 of its standard deviations under noise: a share of chi-square(k) in a sum of three is
    // Beta(k/2, k), of variance (2/9) / (3k/2 + 1), k a third of the points, not of the
    // residuals, as frequency or damping alone may carry the chi-square). A model's misfit runs
    // in waves instead: 60-point backbones of the one-mode truth with 1.5e-3 frequency noise
    // stated as 1.5e-4 fitted at reduced chi-square 33 to 71 over 16 seeds, serial correlation 0
    // to 0.25, largest third's share 0.39 to 0.52 (the note in all 16); the same data of a
    // chi -0.2 joint with chi held near -0.6 at 264 to 322, serial correlation 0.94 to 0.99 (no
    // note; its thirds, 0.42 to 0.49, were no less even: the correlation tells the two apart, the
    // thirds a misfit gathered at some amplitudes). A note, not a cause: a misfit can look white,
    // so the stated noise is only what to check first.
    if (misfit() && residuals_look_like_noise()) {
      out += fmt::format(
          "  note: the residuals are uncorrelated from point to point (serial correlation {:.2g}) "
          "and spread evenly over the amplitudes, as noise is, where a wrong model's run in "
          "waves: the stated uncertainties may be about sqrt(reduced chi-square) = {:.2g} times "
          "too small\n",
          noise_correlation, std::sqrt(reduced_chi2));
    }
    // Far below 1 (by more than 3 of its standard deviations): the stated noise is larger than
    // the residuals' scatter, and the sigmas, which never shrink the stated noise, are that much
    // too wide (one table's uncertainties stated 10 times too large: reduced chi-square 0.0074,
    // every z-score within 0.15 over 6 seeds, and nothing said). Not where floors raised them
    // (their note, below). Its standard deviation is sqrt(2 / n) over the residuals' effective
    // number n of independent points, not over their count: the example campaign's 978
    // residuals amount to 18.3 points, and its 0.669 (0.82 of the stated scatter, common over
    // 18 points) was called far below 1 against a limit of 0.86 from the count.
    const double independent =
        effective_points > 0 ? effective_points : static_cast<double>(residuals);
    if (!misfit() && residuals > 0 && floored(1) == 0 && floored(2) == 0 &&
        reduced_chi2 < 1 - 3 * std::sqrt(2.0 / independent)) {
      out += fmt::format(
          "  note: the reduced chi-square lies far below 1: the residuals scatter about {:.2g} "
          "times the stated uncertainties, which overstate the noise; the sigmas rest on them "
          "(never shrunk below them) and are as much too wide. State each point's one-sigma "
          "uncertainty (an expanded one, k sigma, with a coverage_factor column giving k)\n",
          std::sqrt(reduced_chi2));
    }
  }
  // A stated uncertainty below a floor is raised to it, and the sigmas and the chi-square then
  // rest on the floor (40 fits of data with 1e-5 noise stated as such: sigmas about 10 times the
  // actual errors, reduced chi-square 0.008, and nothing said).
  if (improved && (floored(1) > 0 || floored(2) > 0)) {
    out += fmt::format(
        "  note: the stated uncertainties of {} of {} frequencies and {} of {} dampings lie below "
        "the floors ({:.3g} f, {:.3g} zeta) and were raised to them: the uncertainties and the "
        "chi-square above rest on the floors there\n",
        floored(1), floored(0), floored(2), floored(0), frequency_floor, damping_floor);
  }
  if (top_slip > 0 && phi_max > 0) {
    out += fmt::format(
        "  largest joint slip {:.3g} to {:.3g} m over the measured amplitudes, phi_max {:.3g} m: "
        "{}\n",
        bottom_slip, top_slip, phi_max,
        microslip_only()
            ? "microslip only, Fs and beta are not identified separately" + microslip_family(*this)
        : macroslip_only()
            ? std::string(
                  "macroslip only: every measured amplitude lies past phi_max, which fixes Fs (the "
                  "plateau) while Kt, chi and beta, which shape the joint below phi_max, show "
                  "only weakly (their sigmas say how weakly); data at amplitudes below phi_max "
                  "would identify them")
            : std::string("the data reach macroslip"));
  }
  std::vector<std::string> at_kink;
  static const char* names[] = {"Fs", "Kt", "chi", "beta"};
  for (int k = 0; k < 4; ++k)
    if (sigma_reason(k) == IwanSigmaReason::kAtKink) at_kink.push_back(names[k]);
  if (!at_kink.empty()) {
    out += fmt::format(
        "  note: {} {} fixed only by the slopes of points at phi_max (an element's onset of "
        "macroslip between two sigmas each way), which hold on one side of it only: no sigma is "
        "stated; more points past phi_max would fix {}\n",
        fmt::join(at_kink, " and "), at_kink.size() > 1 ? "are" : "is",
        at_kink.size() > 1 ? "them" : "it");
  }
  return out;
}

std::vector<ParetoPoint> pareto_front(const IwanObjective& objective,
                                      const std::vector<double>& gammas,
                                      const IwanUpdateOptions& options) {
  std::vector<ParetoPoint> out;
  for (double g : gammas) {
    if (!(g > 0)) throw InputError(fmt::format("Pareto front: gamma {} must be > 0", g));
    IwanUpdateOptions o = options;
    o.fixed_gamma = g;
    IwanUpdateSummary s;
    ParetoPoint p;
    p.gamma = g;
    p.params = update_iwan(objective, o, &s);
    if (s.status == IwanUpdateStatus::kNoValidPoint) {
      throw InputError(fmt::format(
          "Pareto front: at gamma {} (K_T = {:.6g} N/m) no parameter set in the bounds gives a "
          "QSMA curve over the measured amplitudes",
          g, g * objective.reference_stiffness()));
    }
    p.linear_error = s.linear_error;
    p.backbone_cost = s.final_cost;
    out.push_back(p);
  }
  // Every measured linear mode's error, its pair followed by shape along the gammas; the
  // linear error of a point is the largest of them when there are any.
  const std::vector<std::vector<std::optional<double>>> along =
      objective.linear_errors_along(gammas);
  for (size_t i = 0; i < out.size(); ++i) {
    out[i].mode_errors = along[i];
    double largest = -1;
    for (const std::optional<double>& e : along[i])
      if (e) largest = std::max(largest, std::abs(*e));
    if (largest >= 0) out[i].linear_error = largest;
  }
  for (ParetoPoint& a : out) {
    for (const ParetoPoint& b : out) {
      if (&a != &b && b.linear_error <= a.linear_error && b.backbone_cost <= a.backbone_cost &&
          (b.linear_error < a.linear_error || b.backbone_cost < a.backbone_cost)) {
        a.dominated = true;
      }
    }
  }
  return out;
}

}  // namespace jointlab::correlate
