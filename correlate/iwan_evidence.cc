// What the Iwan objective's misfit at a result shows of its likelier causes
// (IwanObjective::misfit_evidence()): the linear-limit offset and the nearer mode, the low end's
// damping and softening, and the scatter between curves with a curve lying apart.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>

#include <Eigen/QR>

#include <fmt/format.h>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/core/error.h"
#include "jointlab/core/median.h"
#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_objective.h"
#include "jointlab/correlate/iwan_objective_detail.h"
#include "jointlab/model/iwan_cycle.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate {

using iwan_detail::stated_sigma;

namespace {

// The median of x (the upper middle one of an even count); 0 for none.
double upper_median(std::vector<double> x) {
  if (x.empty()) return 0.0;
  const auto mid = x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2);
  std::nth_element(x.begin(), mid, x.end());
  return *mid;
}

// The scatter between the curves of every target with two or more, gathered target by target:
// each curve's mean normalised residual (frequency and damping apart) against its target's mean,
// each one's mean relative offset, and the curve lying farthest apart (MisfitEvidence).
struct CurveScatter {
  double total = 0, between = 0;
  int between_curves = 0;
  double apart_t = 0;
  std::string apart_name;
  Eigen::Vector2d apart_offset = Eigen::Vector2d::Zero(), apart_others = Eigen::Vector2d::Zero();
  bool apart_damping = false;
  int apart_points = 0;
  Eigen::Vector2d apart_amplitude = Eigen::Vector2d::Zero();
  Eigen::Vector2d f_range = Eigen::Vector2d(INFINITY, -INFINITY);
  Eigen::Vector2d z_range = Eigen::Vector2d(INFINITY, -INFINITY);
  // The chi-square the curves' own shapes gain beyond the common curve and the rank they add,
  // and the common curve's own (add_hit_shapes()).
  double hits_gain = 0, common_gain = 0;
  int hits_dof = 0, common_dof = 0;
  // What each curve keeps fitted alone, linearised, and what a common frequency curve then gains
  // and leaves (add_group_shapes()).
  double each_chi2 = 0, shared_gain = 0, shared_rest = 0;
  int each_dof = 0, shared_dof = 0, shared_rest_dof = 0;
  // Columns of the slopes (at most F_S, K_T, chi, beta and Z) freed in each curve's own fit
  // although held (add_each_curve_alone()).
  std::array<bool, 5> freed{};
};

// One target's curves: each one's point count, mean normalised residual, mean relative offset
// from the model and relative noise of that mean, and the target's means over every point.
struct CurveMeans {
  std::vector<Eigen::Vector2d> mean_r, mean_rel, noise_rel;
  std::vector<double> count;
  Eigen::Vector2d mr, mrel;
};

// CurveMeans of target t, whose residuals r and model values v start at index k.
CurveMeans curve_means(const IwanTarget& t, const std::vector<double>& r,
                       const std::vector<double>& v, int k, double f_floor, double z_floor) {
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
      const double sf = std::max(stated(0), f_floor * b.frequency_hz(j));
      const double sz = std::max(stated(1), z_floor * std::abs(b.damping_ratio(j)));
      var += Eigen::Vector2d(fm > 0 ? std::pow(sf / fm, 2) : 0, zm > 0 ? std::pow(sz / zm, 2) : 0);
    }
    count[c] = static_cast<double>(n);
    mean_r[c] = rr / std::max(1.0, count[c]);
    mean_rel[c] = rel / std::max(1.0, count[c]);
    noise_rel[c] = var.cwiseSqrt() / std::max(1.0, count[c]);
    sum_r += rr, sum_rel += rel, n_all += count[c];
  }
  const Eigen::Vector2d mr = sum_r / n_all, mrel = sum_rel / n_all;
  return {mean_r, mean_rel, noise_rel, count, mr, mrel};
}

// Adds a target's curves to the scatter between curves: their share of the squared residuals
// and the range of their offsets.
void add_between(const CurveMeans& means, CurveScatter& scatter) {
  const size_t nc = means.count.size();
  for (size_t c = 0; c < nc; ++c) {
    scatter.between += means.count[c] * (means.mean_r[c] - means.mr).squaredNorm();
    const Eigen::Vector2d d = means.mean_rel[c] - means.mrel;
    scatter.f_range =
        Eigen::Vector2d(std::min(scatter.f_range(0), d(0)), std::max(scatter.f_range(1), d(0)));
    scatter.z_range =
        Eigen::Vector2d(std::min(scatter.z_range(0), d(1)), std::max(scatter.z_range(1), d(1)));
  }
  scatter.between_curves += static_cast<int>(nc);
}

// The residual sum of squares of u after least squares on the columns of a, and a's rank.
std::pair<double, int> least_squares_rest(const Eigen::MatrixXd& a, const Eigen::VectorXd& u) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  qr.setThreshold(1e-10);
  const Eigen::VectorXd rest = u - a * qr.solve(u);
  return {rest.squaredNorm(), static_cast<int>(qr.rank())};
}

// Curve g's rows of the slopes (du/dx, every column) and its normalised residuals u = r sqrt(N)
// (curve, index: as add_group_shapes()), frequency and damping together.
void curve_system(const Eigen::MatrixXd& slopes, const std::vector<int>& curve,
                  const std::vector<int>& index, const std::vector<double>& r, double n_points,
                  int g, Eigen::MatrixXd& a, Eigen::VectorXd& u) {
  std::vector<int> at;
  for (size_t i = 0; i < curve.size(); ++i)
    if (curve[i] == g) at.push_back(index[i]);
  const auto k = static_cast<Eigen::Index>(at.size());
  a.resize(2 * k, slopes.cols());
  u.resize(2 * k);
  for (Eigen::Index j = 0; j < k; ++j) {
    for (int q = 0; q < 2; ++q) {
      a.row(2 * j + q) = slopes.row(at[static_cast<size_t>(j)] + q);
      u(2 * j + q) = r[static_cast<size_t>(at[static_cast<size_t>(j)] + q)] * std::sqrt(n_points);
    }
  }
}

// Whether the curves' own values of held column c scatter about the held value: each curve's
// linearised step in c with the columns `free` free beside it (Frisch-Waugh: c's slopes and the
// residuals less their projections on the others'), taken over the curves whose points fix c
// apart from those (3 or more needed); the mean of those steps has a Student's t, over their
// count less 1 degrees of freedom, that chance reaches 5 times in 100 or more. A value held off
// the joint's moves every curve alike (beta held at 0.35 on a joint of 0.5: t 18.9; gamma held
// 2 % off with no scatter between hits: held in 60 of 60); hits whose joints scatter about the
// value held move each its own way.
bool held_value_scatters(const Eigen::MatrixXd& slopes, const std::vector<int>& free, int c,
                         const std::vector<int>& curve, const std::vector<int>& index,
                         const std::vector<double>& r, double n_points, int nc) {
  std::vector<double> own;
  for (int g = 0; g < nc; ++g) {
    Eigen::MatrixXd a;
    Eigen::VectorXd u;
    curve_system(slopes, curve, index, r, n_points, g, a, u);
    Eigen::MatrixXd others(a.rows(), static_cast<Eigen::Index>(free.size()));
    for (size_t j = 0; j < free.size(); ++j)
      others.col(static_cast<Eigen::Index>(j)) = a.col(free[j]);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(others);
    qr.setThreshold(1e-10);
    const Eigen::VectorXd ac = a.col(c) - others * qr.solve(a.col(c));
    const Eigen::VectorXd uc = u - others * qr.solve(u);
    if (ac.squaredNorm() > 1e-6 * a.col(c).squaredNorm())
      own.push_back(ac.dot(uc) / ac.squaredNorm());
  }
  const auto m = static_cast<double>(own.size());
  if (own.size() < 3) return false;
  double mean = 0, ss = 0;
  for (const double x : own) mean += x / m;
  for (const double x : own) ss += (x - mean) * (x - mean);
  const double se = std::sqrt(ss / (m - 1) / m);
  if (!(se > 0)) return false;
  const double t = std::abs(mean) / se;
  return 2 * boost::math::cdf(boost::math::complement(boost::math::students_t(m - 1), t)) >= 0.05;
}

// Each curve of a group fitted alone, linearised (MisfitEvidence::model_misses_each_hit()): the
// normalised residuals u = r sqrt(N) of curve g's points (curve, index: as add_group_shapes())
// less their projection on that curve's own rows of `slopes` (du/dx, x those of (ln F_S, ln K_T,
// chi, ln beta) and Z the fit frees, then those it held at a value the options state, columns
// marked `stated`), frequency and damping together; then the frequency's alone with the common
// curve's hat functions `hats` added: the chi-square they gain, over what they leave. Where the
// hits differ only in their joints' parameters each curve's own fit leaves the noise, and a
// common curve gains no more than that noise's share; a model error leaves the same shape in every
// hit at the same amplitude. The damping is left out of the common curve: the model's damping
// differs from the data's own at a few tenths of a percent even where it is their truth (the
// one-mode truth's common damping curve gains F 11-41 beyond each hit's fit, scatter or none),
// which the 2 % noise hides in any one curve but not in a curve fitted to all of them.
// A stated column is freed there too where the curves' own values of it scatter about the value
// held (held_value_scatters(); `freed` marks it): K_T held by --gamma at the joint's mean while it
// scatters between hits is no error the hits share, and held, each curve kept its own K_T's
// offset, the model was said to miss every hit (gamma held, three hits at rising levels, F_S and
// K_T scattered 5 % and 2 %: 31 of 60 fits without a sigma for it).
void add_each_curve_alone(const Eigen::MatrixXd& slopes, const std::vector<bool>& stated,
                          const Eigen::MatrixXd& hats, const std::vector<int>& curve,
                          const std::vector<int>& index, const std::vector<double>& r,
                          double n_points, int nc, CurveScatter& scatter) {
  std::vector<int> cols, held;
  for (int c = 0; c < static_cast<int>(slopes.cols()); ++c)
    (stated[static_cast<size_t>(c)] ? held : cols).push_back(c);
  if (!held.empty() && std::all_of(held.begin(), held.end(), [&](int c) {
        return held_value_scatters(slopes, cols, c, curve, index, r, n_points, nc);
      })) {
    for (const int c : held) scatter.freed[static_cast<size_t>(c)] = true;
    cols.insert(cols.end(), held.begin(), held.end());
  }
  const int n = static_cast<int>(curve.size()), np = static_cast<int>(cols.size());
  const int knots = static_cast<int>(hats.cols());
  // Frequency rows: each curve's own slopes (block diagonal), then the hats.
  Eigen::MatrixXd own_f = Eigen::MatrixXd::Zero(n, nc * np + knots);
  Eigen::VectorXd u_f(n);
  for (int i = 0; i < n; ++i) {
    const int at = index[static_cast<size_t>(i)], g = curve[static_cast<size_t>(i)];
    for (int c = 0; c < np; ++c) own_f(i, g * np + c) = slopes(at, cols[static_cast<size_t>(c)]);
    u_f(i) = r[static_cast<size_t>(at)] * std::sqrt(n_points);
  }
  for (int g = 0; g < nc; ++g) {
    Eigen::MatrixXd a_all;
    Eigen::VectorXd u;
    curve_system(slopes, curve, index, r, n_points, g, a_all, u);
    Eigen::MatrixXd a(a_all.rows(), np);
    for (int c = 0; c < np; ++c) a.col(c) = a_all.col(cols[static_cast<size_t>(c)]);
    const auto [rest, rank] = least_squares_rest(a, u);
    scatter.each_chi2 += rest;
    scatter.each_dof += static_cast<int>(a.rows()) - rank;
  }
  own_f.rightCols(knots) = hats;
  const auto [rest_own, rank_own] = least_squares_rest(own_f.leftCols(nc * np), u_f);
  const auto [rest_all, rank_all] = least_squares_rest(own_f, u_f);
  scatter.shared_gain += std::max(0.0, rest_own - rest_all);
  scatter.shared_dof += rank_all - rank_own;
  scatter.shared_rest += rest_all;
  scatter.shared_rest_dof += n - rank_all;
}

// Adds the own shapes of target t's curves `group` (each starting at residual start[c]) to the
// scatter between curves (MisfitEvidence::between_hits_share), N = n_points: the normalised
// residuals u = r sqrt(N) (unit variance under the stated noise) of each quantity against
// x = ln amplitude, fitted first by a common piecewise-linear curve (hat functions on knots
// spread evenly over the group's x, one per three points a curve, 2 to 30), then with each
// curve's offset and slope (x less its mean) added; the chi-square that gains and the rank it
// adds, and the common curve's own. Where two curves overlap in amplitude their own terms fit
// what the common curve cannot: the data of one against the other's.
void add_group_shapes(const IwanTarget& t, const std::vector<int>& group,
                      const std::vector<int>& start, const std::vector<double>& r, double n_points,
                      const Eigen::MatrixXd* slopes, const std::vector<bool>& stated,
                      CurveScatter& scatter) {
  const int nc = static_cast<int>(group.size());
  int n = 0;
  for (const int c : group)
    n += static_cast<int>(t.curves[static_cast<size_t>(c)].amplitude.size());
  Eigen::VectorXd x(n);
  std::vector<int> curve(static_cast<size_t>(n)), index(static_cast<size_t>(n));
  for (int g = 0, i = 0; g < nc; ++g) {
    const int c = group[static_cast<size_t>(g)];
    const MeasuredBackbone& b = t.curves[static_cast<size_t>(c)];
    for (Eigen::Index j = 0; j < b.amplitude.size(); ++j, ++i) {
      x(i) = std::log(b.amplitude(j));
      curve[static_cast<size_t>(i)] = g;
      index[static_cast<size_t>(i)] = start[static_cast<size_t>(c)] + 2 * static_cast<int>(j);
    }
  }
  const double lo = x.minCoeff(), hi = x.maxCoeff();
  if (!(hi > lo)) return;
  const int knots = std::clamp(n / nc / 3 + 1, 2, 30);  // 30: a QR of n rows stays cheap
  const double step = (hi - lo) / (knots - 1);
  Eigen::MatrixXd both = Eigen::MatrixXd::Zero(n, knots + 2 * nc);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(nc), count = Eigen::VectorXd::Zero(nc);
  for (int i = 0; i < n; ++i) {
    const double at = std::clamp((x(i) - lo) / step, 0.0, knots - 1.0);
    const int left = std::min(static_cast<int>(at), knots - 2);
    both(i, left) = 1 - (at - left);
    both(i, left + 1) = at - left;
    mean(curve[static_cast<size_t>(i)]) += x(i);
    count(curve[static_cast<size_t>(i)]) += 1;
  }
  for (int i = 0; i < n; ++i) {
    const int g = curve[static_cast<size_t>(i)];
    both(i, knots + 2 * g) = 1;
    both(i, knots + 2 * g + 1) = x(i) - mean(g) / count(g);
  }
  for (int q = 0; q < 2; ++q) {
    Eigen::VectorXd u(n);
    for (int i = 0; i < n; ++i)
      u(i) = r[static_cast<size_t>(index[static_cast<size_t>(i)] + q)] * std::sqrt(n_points);
    const auto [rest_common, rank_common] = least_squares_rest(both.leftCols(knots), u);
    const auto [rest_both, rank_both] = least_squares_rest(both, u);
    scatter.hits_gain += std::max(0.0, rest_common - rest_both);
    scatter.hits_dof += rank_both - rank_common;
    scatter.common_gain += std::max(0.0, u.squaredNorm() - rest_common);  // >= 0 to rounding
    scatter.common_dof += rank_common;
  }
  if (slopes)
    add_each_curve_alone(*slopes, stated, both.leftCols(knots), curve, index, r, n_points, nc,
                         scatter);
}

// add_group_shapes() over target t's curves (residuals from index k) of one amplitude scale
// each: the same sensor, kind and modal flag. Curves read at another sensor or as another
// quantity put the same modal amplitude elsewhere in x, where a model error would read as
// their own shape.
void add_hit_shapes(const IwanTarget& t, const std::vector<double>& r, int k, double n_points,
                    const Eigen::MatrixXd* slopes, const std::vector<bool>& stated,
                    CurveScatter& scatter) {
  std::vector<int> start;
  for (const MeasuredBackbone& c : t.curves) {
    start.push_back(k);
    k += 2 * static_cast<int>(c.amplitude.size());
  }
  std::map<std::tuple<int, int, bool>, std::vector<int>> groups;
  for (size_t c = 0; c < t.curves.size(); ++c) {
    const MeasuredBackbone& b = t.curves[c];
    groups[{static_cast<int>(b.kind), b.modal ? -1 : b.sensor, b.modal}].push_back(
        static_cast<int>(c));
  }
  for (const auto& [key, group] : groups)
    if (group.size() >= 2) add_group_shapes(t, group, start, r, n_points, slopes, stated, scatter);
}

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
void find_apart_curve(const IwanTarget& t, const CurveMeans& means, CurveScatter& scatter) {
  const size_t nc = t.curves.size();
  const boost::math::students_t dist(static_cast<double>(nc) - 2);
  for (size_t c = 0; c < nc; ++c) {
    for (int q = 0; q < 2; ++q) {
      double m = 0, ss = 0;
      for (size_t o = 0; o < nc; ++o)
        if (o != c) m += means.mean_rel[o](q);
      m /= static_cast<double>(nc - 1);
      Eigen::Vector2d others(INFINITY, -INFINITY);
      for (size_t o = 0; o < nc; ++o) {
        if (o == c) continue;
        ss += std::pow(means.mean_rel[o](q) - m, 2);
        others = Eigen::Vector2d(std::min(others(0), means.mean_rel[o](q)),
                                 std::max(others(1), means.mean_rel[o](q)));
      }
      const double sd = std::sqrt(ss / static_cast<double>(nc - 2));
      const double scale = std::sqrt(sd * sd * (1 + 1.0 / static_cast<double>(nc - 1)) +
                                     std::pow(means.noise_rel[c](q), 2));
      if (!(scale > 0)) continue;
      const double tc = std::abs(means.mean_rel[c](q) - m) / scale;
      const double chance = 2 * boost::math::cdf(boost::math::complement(dist, tc));
      if (chance * 2 * static_cast<double>(nc) < 0.01 && tc > scatter.apart_t) {
        const MeasuredBackbone& b = t.curves[c];
        scatter.apart_t = tc;
        scatter.apart_name = !b.source.empty() ? b.source : fmt::format("curve {}", c + 1);
        scatter.apart_offset = means.mean_rel[c] - means.mrel;
        scatter.apart_others = others - Eigen::Vector2d::Constant(means.mrel(q));
        scatter.apart_damping = q == 1;
        scatter.apart_points = static_cast<int>(b.amplitude.size());
        scatter.apart_amplitude = Eigen::Vector2d(b.amplitude.minCoeff(), b.amplitude.maxCoeff());
      }
    }
  }
}

// The low end's damping rise against its frequency drop (MisfitEvidence::low_rise_ratio) over
// target t's curves, gathered into (rise, drop, their variances, span). In
// microslip an Iwan joint's first-harmonic stiffness loss is R A^(chi+1) G(chi) and its damping
// 2 R A^(chi+1) / (pi (chi + 2) (chi + 3) K) (method.md), both of the slip amplitude A to the
// same power, and at every joint of a mode alike: their increments between two amplitudes keep
// the ratio 4 / (pi (chi + 2) (chi + 3) G(chi)), at most kIwanRiseLimit for chi <= 0 and
// iwan_rise_limit(chi) above, whatever F_S, K_T, beta and the mode shape. The structure's own
// damping, constant, drops out of the rise, and another mode's slip added to the joint's shifts A
// alike in both.
struct LowRise {
  double rise = 0, drop = 0, rise_variance = 0, drop_variance = 0, span = 0;
  int curves = 0;
};

void add_low_rise(const MeasuredBackbone& c, const std::vector<Eigen::Index>& by_amplitude,
                  double f_floor, double z_floor, LowRise& out) {
  const Eigen::Index n = c.amplitude.size(), fifth = n / 5;
  if (fifth < 2) return;
  // The median of a band's frequencies or dampings and its variance (the mean's for 2 points; for
  // more, pi / 2 times the mean's, the large-sample variance of a median, which over-covers few).
  const auto band = [&](Eigen::Index from, int q) {
    std::vector<double> x;
    double var = 0;
    for (Eigen::Index i = from; i < from + fifth; ++i) {
      const Eigen::Index j = by_amplitude[static_cast<size_t>(i)];
      const double value = q == 0 ? c.frequency_hz(j) : c.damping_ratio(j);
      x.push_back(value);
      const double sigma =
          std::max(stated_sigma(c, j)(q), (q == 0 ? f_floor : z_floor) * std::abs(value));
      var += sigma * sigma;
    }
    // The middle value, or the mean of the middle two: the upper middle one (upper_median()) is
    // a point further up for the rising damping than for the falling frequency, and on 40-point
    // curves (1.23 times in amplitude from one point to the next) read chi 0's 0.424 as 0.521.
    const double k = static_cast<double>(fifth);
    return std::pair(median(x), (fifth == 2 ? 1.0 : M_PI / 2) * var / (k * k));
  };
  const auto [f1, vf1] = band(0, 0);
  const auto [f2, vf2] = band(fifth, 0);
  const auto [z1, vz1] = band(0, 1);
  const auto [z2, vz2] = band(fifth, 1);
  if (!(f1 > 0)) return;
  out.rise += z2 - z1;
  out.drop += (f1 - f2) / f1;
  out.rise_variance += vz1 + vz2;
  out.drop_variance += (vf1 + vf2) / (f1 * f1);
  out.span = std::max(out.span, c.amplitude(by_amplitude[static_cast<size_t>(2 * fifth - 1)]) /
                                    c.amplitude(by_amplitude[0]));
  ++out.curves;
}

// The low-amplitude end of target t, whose model values v start at index k (advanced past its
// points): each curve's lowest tenth of its points by amplitude (at least 3, at most all), where
// the model is at its linear limit, K_T and the linear part, and its softening share; its
// highest tenth, where the joint slips most; every
// point's measured over model damping and the largest measured damping are gathered.
MisfitEvidence low_end(const IwanTarget& t, const std::vector<double>& v, double f_floor,
                       double z_floor, int& k, std::vector<double>& damping_ratios,
                       double& damping_max) {
  LowRise rise;
  std::vector<double> f_lo, error, noise, z_lo, z_model_lo, all_z, f_share, f_hi, error_hi,
      noise_hi;
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
      noise.push_back(std::max(stated_sigma(c, j)(0), f_floor * f) / f);
      z_lo.push_back(c.damping_ratio(j));
      z_model_lo.push_back(v[static_cast<size_t>(k + 2 * j + 1)]);
    }
    add_low_rise(c, by_amplitude, f_floor, z_floor, rise);
    // The highest amplitudes alike: where the joint slips most.
    for (Eigen::Index i = n - low; i < n; ++i) {
      const Eigen::Index j = by_amplitude[static_cast<size_t>(i)];
      const double f = c.frequency_hz(j);
      f_hi.push_back(f);
      error_hi.push_back(v[static_cast<size_t>(k + 2 * j)] / f - 1);
      noise_hi.push_back(std::max(stated_sigma(c, j)(0), f_floor * f) / f);
    }
    // The measured frequency's drop from the lowest fifth of the points by amplitude to the
    // second fifth, over its drop from the lowest fifth to the highest (medians of each): the
    // share of the curve's softening that happens at its low end.
    if (const Eigen::Index fifth = n / 5; fifth >= 2) {
      const auto band = [&](Eigen::Index from) {
        std::vector<double> f;
        for (Eigen::Index i = from; i < from + fifth; ++i)
          f.push_back(c.frequency_hz(by_amplitude[static_cast<size_t>(i)]));
        return upper_median(f);
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
  e.low_frequency_hz = upper_median(f_lo);
  e.low_frequency_error = upper_median(error);
  e.low_frequency_noise = upper_median(noise);
  e.low_damping = upper_median(z_lo);
  e.low_model_damping = upper_median(z_model_lo);
  e.median_damping = upper_median(all_z);
  e.low_softening_share = f_share.empty() ? NAN : upper_median(f_share);
  e.high_frequency_hz = upper_median(f_hi);
  e.high_frequency_error = upper_median(error_hi);
  e.high_frequency_noise = upper_median(noise_hi);
  if (rise.curves > 0 && rise.rise_variance + rise.drop_variance > 0) {
    e.low_rise_ratio = rise.drop > 0 ? rise.rise / rise.drop : NAN;
    e.low_rise = rise.rise;
    e.low_drop = rise.drop;
    e.low_rise_variance = rise.rise_variance;
    e.low_drop_variance = rise.drop_variance;
    e.low_rise_excess = e.low_rise_excess_at(kIwanRiseLimit);
    e.low_rise_span = rise.span;
  }
  return e;
}

// Mode R's linear frequency in the model as given (`modes`), and another elastic mode whose
// linear frequency lies within a third of mode R's distance from the measured one: the backbone
// may be that mode's.
void set_nearer_mode(const model::LinearModes& modes, int mode, MisfitEvidence& e) {
  const int col = modes.rigid_count + mode - 1;
  if (col < modes.size()) e.mode_hz = modes.frequency_hz(col);
  double best = std::abs(e.mode_hz / e.low_frequency_hz - 1) / 3;
  for (int i = modes.rigid_count; i < modes.size() && e.mode_hz > 0; ++i) {
    const double d = std::abs(modes.frequency_hz(i) / e.low_frequency_hz - 1);
    if (i != col && d < best) {
      best = d;
      e.nearer_mode = i - modes.rigid_count + 1;
      e.nearer_mode_hz = modes.frequency_hz(i);
    }
  }
}

// The scatter between curves in the evidence.
void set_scatter(const CurveScatter& scatter, double n_points, MisfitEvidence& out) {
  out.between_curves_share = scatter.between / scatter.total;
  out.between_hits_chi2 = scatter.hits_gain;
  out.between_hits_dof = scatter.hits_dof;
  out.common_chi2 = scatter.common_gain;
  out.common_dof = scatter.common_dof;
  out.each_hit_chi2 = scatter.each_chi2;
  out.each_hit_dof = scatter.each_dof;
  out.shared_frequency_f = scatter.shared_dof > 0 && scatter.shared_rest_dof > 0
                               ? (scatter.shared_gain / scatter.shared_dof) /
                                     (scatter.shared_rest / scatter.shared_rest_dof)
                               : 0.0;
  out.shared_frequency_dof = scatter.shared_dof;
  out.shared_frequency_rest_dof = scatter.shared_rest_dof;
  out.between_hits_share = scatter.hits_gain / (scatter.total * n_points);
  out.curves = scatter.between_curves;
  out.frequency_offsets = scatter.f_range;
  out.damping_offsets = scatter.z_range;
  out.apart_curve = scatter.apart_name;
  out.apart_t = scatter.apart_t;
  out.apart_offset = scatter.apart_offset;
  out.apart_others = scatter.apart_others;
  out.apart_in_damping = scatter.apart_damping;
  out.apart_points = scatter.apart_points;
  out.apart_amplitude = scatter.apart_amplitude;
}

}  // namespace

double iwan_rise_limit(double chi) {
  const double j1 =
      model::IwanCycle(model::Iwan(model::IwanParameters{1, 1, chi, 0})).microslip_integral();
  const double secant = 4 * (chi + 1) / (M_PI * (chi + 3));
  const double first_harmonic = 4 / (M_PI * (chi + 2) * (chi + 3) * (1 / (chi + 1) - j1));
  return std::max(secant, first_harmonic);
}

namespace {

// How often noise of `dof` degrees of freedom reaches a chi-square of `chi2` or more.
double chi2_chance(int dof, double chi2) {
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), chi2));
}

}  // namespace

bool MisfitEvidence::hits_differ_in_shape() const {
  if (!(between_hits_dof > 0) || !(common_dof > 0) || !(between_hits_share >= 0.25)) return false;
  return chi2_chance(between_hits_dof, between_hits_chi2) < 1e-3 &&
         chi2_chance(common_dof, common_chi2) >= 1e-3;
}

bool MisfitEvidence::model_misses_each_hit() const {
  if (!(each_hit_dof > 0) || !(shared_frequency_dof > 0) || !(shared_frequency_rest_dof > 0))
    return false;
  const double each = chi2_chance(each_hit_dof, each_hit_chi2);
  const double shared = boost::math::cdf(boost::math::complement(
      boost::math::fisher_f(shared_frequency_dof, shared_frequency_rest_dof),
      std::max(0.0, shared_frequency_f)));
  return each < 1e-3 && shared < 1e-2;
}

std::optional<MisfitEvidence> IwanObjective::misfit_evidence(
    const model::IwanParameters& p, double z, const std::array<bool, 4>& held,
    const std::array<bool, 4>& stated) const {
  std::vector<double> r(residual_count_), v(residual_count_);
  if (!evaluate(p, r.data(), nullptr, false, &z, nullptr, v.data())) return std::nullopt;
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
  CurveScatter scatter;
  for (double x : r) scatter.total += x * x;
  // The residuals' slopes in the free ones of (ln F_S, ln K_T, chi, ln beta) and Z, in the units
  // of u = r sqrt(N), for each curve's own fit (add_each_curve_alone()); none where a step cannot
  // be evaluated. A held parameter stays held there: freed, each curve's own beta took up a held
  // beta's error, which every hit shares (beta held at 0.35 on a joint of 0.5, three hits
  // scattered 5 % / 2 %: the offsets named scatter and cluster sigmas stated in 35 of 100 fits
  // over one range and 65 at rising levels; now 0 and 17), unless held at a value the options
  // state (`stated`) about which the curves' own values scatter (held_value_scatters()). Z, where
  // fitted inside its range, is each curve's own too: held at the fit's, a structure's own damping
  // that scatters between hits (20 % about 5e-4) kept each curve's damping offset, and each curve
  // alone kept 4.5 times the chi-square its noise gives (median of 56 fits), leaving the frequency
  // F alone to keep the rule from saying the model misses every hit.
  std::vector<int> free;
  std::vector<bool> held_stated;
  for (int k = 0; k < 4; ++k) {
    const bool asserted = stated[static_cast<size_t>(k)] && held[static_cast<size_t>(k)];
    if (!held[static_cast<size_t>(k)] || asserted) {
      free.push_back(k);
      held_stated.push_back(asserted);
    }
  }
  if (fit_z_ && z > 1e-6 && z + 1e-6 < z_max_) {  // steps of 1e-6 (central_differences())
    free.push_back(4);
    held_stated.push_back(false);
  }
  std::optional<Eigen::MatrixXd> slopes;
  if (!free.empty() && std::any_of(targets_.begin(), targets_.end(),
                                   [](const IwanTarget& t) { return t.curves.size() >= 2; })) {
    Eigen::MatrixXd d(residual_count_, static_cast<Eigen::Index>(free.size()));
    const double root_n = std::sqrt(static_cast<double>(residual_count_) / 2);
    if (iwan_detail::central_differences(
            *this, free, iwan_detail::Vec4(p.Fs, p.Kt / Ks_, p.chi, p.beta), z,
            [&](int j, double h, const Eigen::VectorXd& rp, const Eigen::VectorXd& rm) {
              d.col(j) = (rp - rm) / (2 * h) * root_n;
            }))
      slopes = d;
  }
  int k = 0;
  for (const IwanTarget& t : targets_) {
    if (t.curves.size() >= 2) {
      const CurveMeans means = curve_means(t, r, v, k, f_floor_, z_floor_);
      add_between(means, scatter);
      add_hit_shapes(t, r, k, static_cast<double>(residual_count_) / 2, slopes ? &*slopes : nullptr,
                     held_stated, scatter);
      if (t.curves.size() >= 4) find_apart_curve(t, means, scatter);
    }
    MisfitEvidence e = low_end(t, v, f_floor_, z_floor_, k, damping_ratios, damping_max);
    e.targets = static_cast<int>(targets_.size());
    if (modes && e.low_frequency_hz > 0) set_nearer_mode(*modes, t.mode, e);
    if (fitted_modes) {
      const int col = fitted_modes->rigid_count + t.mode - 1;
      if (col < fitted_modes->size()) e.linear_hz = fitted_modes->frequency_hz(col);
    }
    if (!out || std::abs(e.low_frequency_error) > std::abs(out->low_frequency_error)) out = e;
  }
  if (out) {
    out->damping_factor = upper_median(damping_ratios);
    out->damping_max = damping_max;
    out->each_hit_held = held;
    out->each_hit_own_damping = slopes && !free.empty() && free.back() == 4;
    for (size_t j = 0; j < free.size(); ++j)
      if (free[j] < 4 && scatter.freed[j]) out->each_hit_held[static_cast<size_t>(free[j])] = false;
    if (scatter.between_curves > 0 && scatter.total > 0)
      set_scatter(scatter, static_cast<double>(residual_count_) / 2, *out);
  }
  return out;
}

}  // namespace jointlab::correlate
