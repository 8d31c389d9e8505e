// QSMA on a riveted-beam-sized reduced model: the joint-condensed solver of
// model/qsma.h against a straightforward Newton on all DOFs.
//
// Run: build/bin/jointlab_bench_qsma
//
// Model (built here): two stacked free-free steel beams, 24 Euler-Bernoulli elements each,
// six DOFs per node (u, v, w, theta_x, theta_y, theta_z; u and v at the contact face through
// a rigid offset from the centroid): 2 x 25 x 6 = 300 DOFs. 24 rivets join the faces, each
// with Iwan elements on the relative u and v (48 Iwan coordinates) and linear springs on
// w and the three rotations. Six rigid-body modes.
// Condensed: one-time set-up (all modes, C = B G B^T), then one 100-point curve of mode 1
// with the default range (microslip start, end at full macroslip or the limit load,
// bracketed to 1e-4), every search and bracketing solve included.
// All DOFs: the same 100 load levels (given to it: no range search), each solved by Newton
// on K_lin u - B^T h(B u) = alpha M phi with Phi_rb^T M u = 0 (Lagrange multipliers), a
// sparse LU of the bordered tangent (pattern analysed once), a proportional predictor and a
// line search on the potential energy.
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>
#include <Eigen/SparseLU>

#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/qsma.h"

namespace {

using jointlab::model::Iwan;
using jointlab::model::IwanParameters;
using jointlab::model::Joint;
using jointlab::model::JointCondensation;
using jointlab::model::Model;

constexpr int kElements = 24;
constexpr int kNodes = kElements + 1;
constexpr int kDofs = 2 * 6 * kNodes;  // 300
const IwanParameters kRivet{100.0, 1.0e7, -0.5, 0.5};

// 4x4 Hermite bending matrices on (displacement, slope) pairs.
void hermite(double ei, double area_mass, double l, Eigen::Matrix4d& k, Eigen::Matrix4d& m) {
  k << 12, 6 * l, -12, 6 * l, 6 * l, 4 * l * l, -6 * l, 2 * l * l, -12, -6 * l, 12, -6 * l, 6 * l,
      2 * l * l, -6 * l, 4 * l * l;
  k *= ei / (l * l * l);
  m << 156, 22 * l, 54, -13 * l, 22 * l, 4 * l * l, 13 * l, -3 * l * l, 54, 13 * l, 156, -22 * l,
      -13 * l, -3 * l * l, -22 * l, 4 * l * l;
  m *= area_mass * l / 420;
}

Model riveted_beams() {
  const double L = 0.5, E = 2.1e11, G = 8.1e10, rho = 7850, b = 0.03, h = 0.003;
  const double A = b * h, Iy = b * h * h * h / 12, Iz = h * b * b * b / 12;
  const double J = b * h * h * h / 3 * (1 - 0.63 * h / b), le = L / kElements;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(kDofs, kDofs), M = K;
  Eigen::Matrix4d kb, mb;
  for (int beam = 0; beam < 2; ++beam) {
    const double e = beam == 0 ? h / 2 : -h / 2;
    for (int el = 0; el < kElements; ++el) {
      Eigen::Matrix<double, 12, 12> kc = Eigen::Matrix<double, 12, 12>::Zero(), mc = kc;
      auto put = [&](const int(&d)[2], double kk, double mm) {
        kc(d[0], d[0]) += kk, kc(d[1], d[1]) += kk, kc(d[0], d[1]) -= kk, kc(d[1], d[0]) -= kk;
        mc(d[0], d[0]) += mm / 3, mc(d[1], d[1]) += mm / 3;
        mc(d[0], d[1]) += mm / 6, mc(d[1], d[0]) += mm / 6;
      };
      put({0, 6}, E * A / le, rho * A * le);          // axial
      put({3, 9}, G * J / le, rho * (Iy + Iz) * le);  // torsion
      hermite(E * Iz, rho * A, le, kb, mb);           // v, theta_z
      const int xy[4] = {1, 5, 7, 11};
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) kc(xy[i], xy[j]) += kb(i, j), mc(xy[i], xy[j]) += mb(i, j);
      hermite(E * Iy, rho * A, le, kb, mb);  // w, -theta_y
      const int xz[4] = {2, 4, 8, 10};
      const double s[4] = {1, -1, 1, -1};
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          kc(xz[i], xz[j]) += s[i] * s[j] * kb(i, j);
          mc(xz[i], xz[j]) += s[i] * s[j] * mb(i, j);
        }
      // Face DOFs: u_c = u - e theta_y, v_c = v + e theta_x (rigid offset e).
      Eigen::Matrix<double, 12, 12> T = Eigen::Matrix<double, 12, 12>::Identity();
      for (int n = 0; n < 2; ++n) T(6 * n, 6 * n + 4) = -e, T(6 * n + 1, 6 * n + 3) = e;
      const int o = beam * 6 * kNodes + 6 * el;
      K.block(o, o, 12, 12) += T.transpose() * kc * T;
      M.block(o, o, 12, 12) += T.transpose() * mc * T;
    }
  }
  Model model;
  model.mass = M.sparseView();
  model.stiffness = K.sparseView();
  const double springs[6] = {0, 0, 1e9, 1e4, 1e4, 1e4};
  for (int node = 0; node < kNodes; ++node) {
    if (node == kNodes / 2) continue;  // 24 rivets
    const Eigen::Index bot = 6 * node, top = 6 * kNodes + 6 * node;
    for (int c = 0; c < 6; ++c) {
      if (c < 2) {
        model.joints.push_back({top + c, bot + c, "iwan.rivet", kRivet.Kt, Iwan(kRivet)});
      } else {
        model.joints.push_back({top + c, bot + c, "spring", springs[c], std::nullopt});
      }
    }
  }
  return model;
}

// The all-DOF Newton at given load levels (continuation from the previous level).
class AllDofNewton {
 public:
  AllDofNewton(const Model& model, const jointlab::model::LinearModes& modes, int column)
      : k_(model.linear_stiffness()) {
    for (const Joint& j : model.joints) {
      if (j.iwan) joints_.push_back(j);
    }
    const Eigen::MatrixXd rb = model.mass * modes.shapes.leftCols(modes.rigid_count);
    load_ = model.mass * modes.shapes.col(column);
    n_ = k_.rows();
    nr_ = rb.cols();
    // Bordered pattern: K_lin (joint entries included) and the constraint blocks.
    std::vector<Eigen::Triplet<double>> t;
    for (int c = 0; c < k_.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(k_, c); it; ++it)
        t.emplace_back(it.row(), it.col(), it.value());
    for (Eigen::Index i = 0; i < n_; ++i)
      for (Eigen::Index r = 0; r < nr_; ++r) {
        t.emplace_back(i, n_ + r, rb(i, r));
        t.emplace_back(n_ + r, i, rb(i, r));
      }
    base_.resize(n_ + nr_, n_ + nr_);
    base_.setFromTriplets(t.begin(), t.end());
    base_.makeCompressed();
    lu_.analyzePattern(base_);
    rb_ = rb;
  }

  double run(const std::vector<double>& alphas) {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n_);
    double previous = 0, q_sum = 0;
    for (double alpha : alphas) {
      if (previous > 0) u *= alpha / previous;  // proportional predictor
      solve(alpha, u);
      previous = alpha;
      q_sum += u.dot(load_);
    }
    return q_sum;
  }

 private:
  double potential(const Eigen::VectorXd& u, double alpha) const {
    double pi = 0.5 * u.dot(k_ * u) - alpha * load_.dot(u);
    for (const Joint& j : joints_) pi -= j.iwan->softening_energy(u(j.a) - u(j.b));
    return pi;
  }

  void solve(double alpha, Eigen::VectorXd& u) {
    for (int it = 0; it < 200; ++it) {
      Eigen::SparseMatrix<double> a = base_;
      Eigen::VectorXd res(n_ + nr_);
      res.head(n_) = k_ * u - alpha * load_;
      res.tail(nr_) = rb_.transpose() * u;
      for (const Joint& j : joints_) {
        const double r = u(j.a) - u(j.b);
        const double h = j.iwan->softening(r), dh = j.iwan->softening_tangent(r);
        res(j.a) -= h, res(j.b) += h;
        a.coeffRef(j.a, j.a) -= dh, a.coeffRef(j.b, j.b) -= dh;
        a.coeffRef(j.a, j.b) += dh, a.coeffRef(j.b, j.a) += dh;
      }
      const double scale = alpha * load_.norm() + (k_ * u).norm();
      if (res.norm() <= 1e-12 * scale) return;
      lu_.factorize(a);
      const Eigen::VectorXd step = lu_.solve(-res).head(n_);
      const double len = step.lpNorm<Eigen::Infinity>(), size = u.lpNorm<Eigen::Infinity>();
      if (len <= 1e-13 * size) return;
      const double pi0 = potential(u, alpha), slope = res.head(n_).dot(step);
      double t = std::min(1.0, std::max(size, 1e-9) / len);
      Eigen::VectorXd trial;
      for (int k = 0; k < 100; ++k, t /= 2) {
        trial = u + t * step;
        if (potential(trial, alpha) <= pi0 + 1e-4 * t * slope || t * len <= 1e-6 * size) break;
      }
      u = trial;
    }
  }

  Eigen::SparseMatrix<double> k_, base_;
  Eigen::MatrixXd rb_;
  Eigen::VectorXd load_;
  Eigen::Index n_ = 0, nr_ = 0;
  std::vector<Joint> joints_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
};

const Model& model() {
  static const Model m = riveted_beams();
  return m;
}
const JointCondensation& condensed() {
  static const JointCondensation c(model());
  return c;
}
jointlab::model::QsmaOptions hundred_points() {
  jointlab::model::QsmaOptions o;
  o.points = 100;
  return o;
}

void BM_QsmaSetUp(benchmark::State& state) {
  for (auto _ : state) {
    JointCondensation c(model());
    benchmark::DoNotOptimize(c.flexibility().data());
  }
  state.counters["dofs"] = static_cast<double>(model().size());
  state.counters["joint_coordinates"] = condensed().size();
}
BENCHMARK(BM_QsmaSetUp)->Unit(benchmark::kMillisecond);

void BM_QsmaCondensedCurve(benchmark::State& state) {
  jointlab::model::QsmaSummary summary;
  for (auto _ : state) {
    const auto curve = jointlab::model::qsma(condensed(), 1, hundred_points(), &summary);
    benchmark::DoNotOptimize(curve.data());
  }
  state.counters["points"] = 100;
  state.counters["solves"] = summary.solves;
  state.counters["newton_iterations"] = summary.newton_iterations;
}
BENCHMARK(BM_QsmaCondensedCurve)->Unit(benchmark::kMillisecond);

void BM_QsmaAllDofCurve(benchmark::State& state) {
  jointlab::model::QsmaSummary summary;
  const auto curve = jointlab::model::qsma(condensed(), 1, hundred_points(), &summary);
  std::vector<double> alphas;
  for (const auto& p : curve) alphas.push_back(p.force_amplitude);
  AllDofNewton newton(model(), condensed().modes(), condensed().modes().rigid_count);
  for (auto _ : state) benchmark::DoNotOptimize(newton.run(alphas));
  state.counters["points"] = static_cast<double>(alphas.size());
}
BENCHMARK(BM_QsmaAllDofCurve)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
