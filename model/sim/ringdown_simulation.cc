#include "jointlab/model/sim/ringdown_simulation.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include <fmt/format.h>
#include <Eigen/Cholesky>

#include "jointlab/core/error.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/sim/iwan_history.h"

namespace jointlab::model {

double HalfSinePulse::operator()(double t) const {
  if (t <= start || t >= start + duration) return 0.0;
  return force * std::sin(M_PI * (t - start) / duration);
}

double HalfSinePulse::impulse() const { return 2 * force * duration / M_PI; }

std::string SimulationOptions::error(Eigen::Index size) const {
  auto dof_ok = [&](Eigen::Index d) { return d >= 0 && d < size; };
  if (!dof_ok(pulse.dof)) {
    return fmt::format("impact DOF {} is outside the model's 0..{}", pulse.dof, size - 1);
  }
  if (!(std::isfinite(pulse.force) && pulse.force != 0)) return "force must be finite and nonzero";
  // Energies are squares of the response: beyond 1e100 N (or below 1e-100 N) they leave double
  // precision (--force 1e300 once wrote accelerations of 3.6e301 with an energy closure of NaN).
  if (!(std::abs(pulse.force) <= 1e100 && std::abs(pulse.force) >= 1e-100)) {
    return fmt::format(
        "force {:g} N is outside the magnitudes 1e-100 to 1e100 N a record can hold "
        "(its energies are squares of the response)",
        pulse.force);
  }
  if (!(pulse.duration > 0 && std::isfinite(pulse.duration))) return "pulse length must be > 0";
  if (!(pulse.start >= 0 && std::isfinite(pulse.start))) return "pulse start must be >= 0";
  if (sensors.empty()) return "no sensor DOF given";
  for (Eigen::Index s : sensors) {
    if (!dof_ok(s)) return fmt::format("sensor DOF {} is outside the model's 0..{}", s, size - 1);
  }
  if (!(fs > 0 && std::isfinite(fs))) return "sample rate must be > 0";
  if (!(duration > 0 && std::isfinite(duration))) return "duration must be > 0";
  if (duration * fs < 16) return "the record must hold at least 16 samples";
  // Three response arrays (and the written record) hold samples x sensors numbers each:
  // 5e7 values are 1.2 GB in memory, beyond any ring-down test's need.
  if (const double values = std::floor(duration * fs) * static_cast<double>(sensors.size());
      values > 5e7) {
    return fmt::format(
        "the record would hold {:.3g} samples x {} sensor(s) = {:.3g} values; the limit is 5e7 "
        "(lower --fs or --duration)",
        std::floor(duration * fs), sensors.size(), values);
  }
  if (pulse.start + pulse.duration >= duration) return "the pulse must end inside the record";
  if (substeps < 0 || substeps > 100000) return "substeps must be in 0..100000 (0: automatic)";
  if (!(frequency_error > 0 && frequency_error < 0.1)) return "frequency error must be in (0, 0.1)";
  if (!(modal_damping >= 0 && modal_damping < 1)) return "modal damping must be in [0, 1)";
  if (!(rayleigh_mass >= 0 && std::isfinite(rayleigh_mass))) return "Rayleigh alpha must be >= 0";
  if (!(rayleigh_stiffness >= 0 && std::isfinite(rayleigh_stiffness))) {
    return "Rayleigh beta must be >= 0";
  }
  if (!(output_cutoff_hz >= 0 && std::isfinite(output_cutoff_hz))) {
    return "output cutoff must be >= 0";
  }
  if (!(newton_tolerance > 0 && newton_tolerance < 1e-3))
    return "Newton tolerance must be in (0, 1e-3)";
  if (max_newton_iterations < 1) return "max Newton iterations must be >= 1";
  return "";
}

double EnergyBalance::closure() const {
  return input - kinetic - strain - joint_dissipated - damping_dissipated;
}

double EnergyBalance::relative_closure() const {
  return input != 0 ? std::abs(closure()) / std::abs(input) : 0.0;
}

std::string EnergyBalance::report() const {
  return fmt::format(
      "input {:.6e} J = kinetic {:.6e} + strain {:.6e} (joints {:.3e}) + joint dissipation "
      "{:.6e} + damping {:.6e} + closure error {:.3e} J ({:.2e} of input)",
      input, kinetic, strain, joint_stored, joint_dissipated, damping_dissipated, closure(),
      relative_closure());
}

std::string SimulationSummary::report() const {
  std::string s = status == SimulationStatus::kOk ? "Simulation finished" : "Simulation cut short";
  s += fmt::format(
      ": {}\n  {} modes ({} rigid, {} in the sensor signals), {} joint coordinates; "
      "lowest elastic mode {:.4g} Hz\n  dt = {:.4g} s ({} substeps per sample), {} steps, "
      "{} Newton iterations (at most {} in a step)\n  largest joint displacement {:.4g} m "
      "({:.3g} of phi_max)\n  energy: {}",
      message, modes, rigid_modes, output_modes, joint_coordinates, lowest_elastic_hz, dt, substeps,
      steps, newton_iterations, max_step_iterations, max_joint_displacement, max_phi_ratio,
      energy.report());
  return s;
}

namespace {

// One Iwan coordinate r = u_a - u_b and the histories of the elements on it.
struct Coordinate {
  Eigen::Index a = 0, b = kGround;
  std::vector<IwanHistory> elements;
  double kt = 0;       // sum of K_T
  double phi_max = 0;  // largest phi_max
};

std::vector<Coordinate> iwan_coordinates(const Model& model) {
  std::vector<Coordinate> coords;
  std::map<std::pair<Eigen::Index, Eigen::Index>, size_t> index;
  for (const Joint& j : model.joints) {
    if (!j.iwan) continue;
    const auto key = std::make_pair(j.a, j.b);
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, coords.size()).first;
      coords.push_back({j.a, j.b, {}, 0, 0});
    }
    Coordinate& c = coords[it->second];
    c.elements.emplace_back(*j.iwan);
    c.kt += j.iwan->stiffness();
    c.phi_max = std::max(c.phi_max, j.iwan->phi_max());
  }
  return coords;
}

// The modes with the joints at linear stiffness (rigid-body modes included), their damping
// and how many are kept in the output.
struct ModalBasis {
  int n = 0;
  int rigid_count = 0;
  int n_out = 0;             // modes below the output cutoff
  Eigen::MatrixXd phi;       // mode shapes, mass-normalised
  Eigen::VectorXd w2, w, c;  // omega^2 (0 for rigid), omega, modal damping 2 zeta omega + ...
};

ModalBasis modal_basis(const Model& model, const SimulationOptions& options,
                       SimulationSummary& sum) {
  LinearModes modes = linear_modes(model.mass, model.linear_stiffness());
  ModalBasis b;
  b.n = modes.size();
  b.rigid_count = modes.rigid_count;
  b.w2 = modes.omega2;
  for (int i = 0; i < modes.rigid_count; ++i) b.w2(i) = 0;
  b.w = b.w2.cwiseSqrt();
  sum.modes = b.n;
  sum.rigid_modes = modes.rigid_count;
  sum.lowest_elastic_hz = modes.rigid_count < b.n ? b.w(modes.rigid_count) / (2 * M_PI) : 0.0;
  b.c.resize(b.n);
  for (int i = 0; i < b.n; ++i) {
    b.c(i) = options.rayleigh_mass + options.rayleigh_stiffness * b.w2(i) +
             (modes.rigid(i) ? 0.0 : 2 * options.modal_damping * b.w(i));
  }
  const double cutoff = options.output_cutoff_hz > 0 ? options.output_cutoff_hz : 0.45 * options.fs;
  while (b.n_out < b.n && b.w(b.n_out) <= 2 * M_PI * cutoff) ++b.n_out;
  sum.output_modes = b.n_out;
  b.phi = std::move(modes.shapes);
  return b;
}

// Substeps per sample from the period error of the lowest elastic mode (unless given).
int substeps(const ModalBasis& b, const SimulationOptions& options) {
  if (options.substeps != 0) return options.substeps;
  const double w1 = b.rigid_count < b.n ? b.w(b.rigid_count) : 0.0;
  const double wdt_max = std::sqrt(12 * options.frequency_error);
  return std::max(4, static_cast<int>(std::ceil(w1 / (options.fs * wdt_max))));
}

// The joint coordinates r = Psi eta of one time step: the condensed step operator S (and
// S^{-1}), the Newton solve of S^{-1} (r - r_p) - h(r) = 0 and the commit of the joints.
class JointStep {
 public:
  JointStep(std::vector<Coordinate> coords, const ModalBasis& b, const Eigen::VectorXd& kinv)
      : coords_(std::move(coords)), nj_(static_cast<int>(coords_.size())) {
    psi_.resize(nj_, b.n);
    for (int j = 0; j < nj_; ++j) {
      psi_.row(j) = b.phi.row(coords_[j].a);
      if (coords_[j].b != kGround) psi_.row(j) -= b.phi.row(coords_[j].b);
    }
    s_.resize(nj_, nj_);
    s_inv_.resize(nj_, nj_);
    kt_.resize(nj_);
    phi_max_.resize(nj_);
    for (int j = 0; j < nj_; ++j) kt_(j) = coords_[j].kt, phi_max_(j) = coords_[j].phi_max;
    if (nj_ > 0) {
      s_ = psi_ * kinv.asDiagonal() * psi_.transpose();
      Eigen::LDLT<Eigen::MatrixXd> ldlt(s_);
      const double dmax = ldlt.vectorD().cwiseAbs().maxCoeff();
      if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * dmax)) {
        throw InputError(
            "simulate: the model's Iwan joint coordinates are linearly dependent (a closed loop "
            "of Iwan joints); the joint problem has no unique solution");
      }
      s_inv_ = ldlt.solve(Eigen::MatrixXd::Identity(nj_, nj_));
      s_inv_ = 0.5 * (s_inv_ + s_inv_.transpose()).eval();
    }
    r_ = Eigen::VectorXd::Zero(nj_);
    h_ = r_;
    for (Eigen::VectorXd* v : {&r_p_, &r_new_, &dh_, &grad_, &step_, &r_try_, &h_try_, &dh_try_,
                               &trial_h_, &res_, &res_try_}) {
      v->resize(nj_);
    }
    // Sized and in a defined state (a factorisation never computed has no valid info()).
    llt_.compute(Eigen::MatrixXd::Identity(nj_, nj_));
    jac_.resize(nj_, nj_);
  }

  int size() const { return nj_; }
  const Eigen::MatrixXd& psi() const { return psi_; }
  const Eigen::VectorXd& kt() const { return kt_; }
  const Eigen::VectorXd& r() const { return r_; }
  const Eigen::VectorXd& h() const { return h_; }
  const std::vector<Coordinate>& coordinates() const { return coords_; }

  // Newton on S^{-1} (r - r_p) - h(r) = 0 from the predicted r_p, started from the committed
  // softening. The residual is formed as r - r_p - S h (no large cancelling terms) and mapped
  // by S^{-1} to the gradient of the step's convex potential Pi. Returns the iterations taken;
  // `converged` says whether the step fell below the tolerance.
  int solve(const Eigen::VectorXd& r_p, const SimulationOptions& options, bool& converged) {
    r_p_ = r_p;
    r_new_ = r_p_ + s_ * h_;
    double pot_h = evaluate(r_new_, trial_h_, dh_);
    double pi = potential(r_new_, pot_h);
    res_ = r_new_ - r_p_ - s_ * trial_h_;
    converged = false;
    int it = 0;
    while (it < options.max_newton_iterations) {
      ++it;
      grad_ = s_inv_ * res_;
      jac_ = s_inv_;
      jac_.diagonal() -= dh_;
      llt_.compute(jac_);
      step_ = -llt_.solve(grad_);
      if (!step_.allFinite()) break;
      const double step_max = step_.cwiseAbs().maxCoeff();
      if (step_max <= options.newton_tolerance * r_new_.cwiseAbs().maxCoeff()) {
        r_new_ += step_;  // below the tolerance: the commit evaluates the forces there
        converged = true;
        break;
      }
      line_search(pi);
    }
    converged = converged && r_new_.allFinite();
    return it;
  }

  // Commits the joints at the solved r: new softening h, dissipation and extremes.
  void commit(EnergyBalance& en, SimulationSummary& sum) {
    for (int j = 0; j < nj_; ++j) {
      double f = 0;
      for (IwanHistory& e : coords_[j].elements) {
        const IwanMove mv = e.commit(r_new_(j));
        f += mv.force;
        en.joint_dissipated += mv.dissipation;
      }
      h_(j) = kt_(j) * r_new_(j) - f;
      sum.max_joint_displacement = std::max(sum.max_joint_displacement, std::abs(r_new_(j)));
      sum.max_phi_ratio = std::max(sum.max_phi_ratio, std::abs(r_new_(j)) / phi_max_(j));
    }
    r_ = r_new_;
  }

 private:
  // Full step when the residual falls, else backtracking on Pi (Armijo).
  void line_search(double& pi) {
    const double res_max = res_.cwiseAbs().maxCoeff();
    double lambda = 1;
    for (int ls = 0;; ++ls) {
      r_try_ = r_new_ + lambda * step_;
      const double pot_try = evaluate(r_try_, h_try_, dh_try_);
      const double pi_try = potential(r_try_, pot_try);
      res_try_ = r_try_ - r_p_ - s_ * h_try_;
      if (res_try_.cwiseAbs().maxCoeff() < res_max ||
          pi_try <= pi + 1e-4 * lambda * grad_.dot(step_) || ls == 40) {
        r_new_ = r_try_, trial_h_ = h_try_, dh_ = dh_try_, pi = pi_try, res_ = res_try_;
        return;
      }
      lambda *= 0.5;
    }
  }

  // h, h' and the incremental potential sum_j H_j(r_j) of a trial r.
  double evaluate(const Eigen::VectorXd& rt, Eigen::VectorXd& ht, Eigen::VectorXd& dht) const {
    double pot = 0;
    for (int j = 0; j < nj_; ++j) {
      double f = 0, df = 0, work = 0;
      for (const IwanHistory& e : coords_[j].elements) {
        const IwanMove m = e.trial(rt(j));
        f += m.force, df += m.tangent, work += m.work;
      }
      const double rc = r_(j);
      ht(j) = kt_(j) * rt(j) - f;
      dht(j) = kt_(j) - df;
      pot += 0.5 * kt_(j) * (rt(j) * rt(j) - rc * rc) - work;
    }
    return pot;
  }

  // The step's potential Pi(r) = 1/2 (r - r_p)^T S^{-1} (r - r_p) - sum H_j(r_j).
  double potential(const Eigen::VectorXd& rt, double pot_h) const {
    const Eigen::VectorXd d = rt - r_p_;
    return 0.5 * d.dot(s_inv_ * d) - pot_h;
  }

  std::vector<Coordinate> coords_;
  int nj_;
  Eigen::MatrixXd psi_, s_, s_inv_, jac_;
  Eigen::VectorXd kt_, phi_max_, r_, h_;
  Eigen::VectorXd r_p_, r_new_, dh_, grad_, step_, r_try_, h_try_, dh_try_, trial_h_, res_,
      res_try_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
};

// Energies at the end of the simulation.
void final_energies(EnergyBalance& en, const ModalBasis& b, const JointStep& joints,
                    const Eigen::VectorXd& eta, const Eigen::VectorXd& vel) {
  en.kinetic = 0.5 * vel.squaredNorm();
  double stored = 0;
  for (const Coordinate& co : joints.coordinates()) {
    for (const IwanHistory& e : co.elements) stored += e.stored_energy();
  }
  en.joint_stored = stored;
  en.strain = 0.5 * (b.w2.array() * eta.array().square()).sum() -
              0.5 * (joints.kt().array() * joints.r().array().square()).sum() + stored;
}

}  // namespace

SimulatedResponse simulate_ringdown(const Model& model, const SimulationOptions& options,
                                    SimulationSummary* summary) {
  assert(summary != nullptr);
  if (const std::string e = options.error(model.size()); !e.empty()) {
    throw InputError(fmt::format("simulate: {}", e));
  }
  SimulationSummary& sum = *summary;
  sum = SimulationSummary{};

  const ModalBasis b = modal_basis(model, options, sum);
  const int n = b.n, n_out = b.n_out;
  const Eigen::VectorXd& c = b.c;
  const int sub = substeps(b, options);
  const double dt = 1.0 / (options.fs * sub);
  sum.dt = dt;
  sum.substeps = sub;
  // The Newmark update forms the acceleration from displacement increments: with w_1 dt
  // below 1e-6 its rounding, eps / (w_1 dt)^2 of it per step, reaches 1e-4 and the record
  // drifts (at w_1 dt = 2e-7 the energy balance closed only to 3e-3, at 5e-8 not at all).
  if (const double w1 = b.rigid_count < b.n ? b.w(b.rigid_count) : 0.0; w1 > 0 && w1 * dt < 1e-6) {
    throw InputError(fmt::format(
        "simulate: the time step {:.3g} s is under 1e-6 / omega_1 of the lowest elastic mode "
        "({:.4g} Hz): the Newmark update would lose the acceleration to rounding; lower "
        "--fs (at most {:.3g} Hz with {} substeps) or --substeps",
        dt, w1 / (2 * std::numbers::pi), w1 / (sub * 1e-6), sub));
  }

  // A pulse shorter than two steps falls between them: its samples are all zero (--pulse
  // 1e-300 once wrote an all-zero record whose header said 10 N).
  if (options.pulse.duration < 2 * dt) {
    throw InputError(fmt::format(
        "simulate: the pulse of {:.3g} s is shorter than two time steps ({:.3g} s each, {} "
        "substeps per sample): the impact would not reach the model; lengthen --pulse or raise "
        "--substeps",
        options.pulse.duration, dt, sub));
  }

  const Eigen::VectorXd khat = (b.w2.array() + 2 * c.array() / dt + 4 / (dt * dt)).matrix();
  const Eigen::VectorXd kinv = khat.cwiseInverse();
  JointStep joints(iwan_coordinates(model), b, kinv);
  sum.joint_coordinates = joints.size();

  // Sensor and impact rows of Phi.
  const auto n_sens = static_cast<Eigen::Index>(options.sensors.size());
  Eigen::MatrixXd phi_s(n_sens, n_out);
  for (Eigen::Index k = 0; k < n_sens; ++k)
    phi_s.row(k) = b.phi.row(options.sensors[k]).head(n_out);
  const Eigen::VectorXd phi_d = b.phi.row(options.pulse.dof).transpose();

  const auto n_samples =
      static_cast<Eigen::Index>(std::floor(options.duration * options.fs + 1e-9));
  SimulatedResponse out;
  out.fs = options.fs;
  out.acceleration.setZero(n_samples, n_sens);
  out.velocity.setZero(n_samples, n_sens);
  out.displacement.setZero(n_samples, n_sens);
  out.force.setZero(n_samples);

  // State.
  Eigen::VectorXd eta = Eigen::VectorXd::Zero(n), vel = eta, acc = eta, eta_p(n), hist(n);
  double p_prev = options.pulse(0.0), u_d_prev = 0;
  EnergyBalance& en = sum.energy;
  auto record = [&](Eigen::Index k) {
    out.acceleration.row(k) = (phi_s * acc.head(n_out)).transpose();
    out.velocity.row(k) = (phi_s * vel.head(n_out)).transpose();
    out.displacement.row(k) = (phi_s * eta.head(n_out)).transpose();
    out.force(k) = options.pulse(static_cast<double>(k) / options.fs);
  };

  record(0);
  const long total_steps = static_cast<long>(n_samples - 1) * sub;
  // Progress every tenth of the steps, and at least every 5 s of wall time with the time
  // still to go: a fine step (--substeps) may take hours, and its first tenth as long.
  const long progress_every = std::max<long>(1, total_steps / 10);
  const auto started = std::chrono::steady_clock::now();
  auto last_report = started;
  const auto seconds = [](auto from, auto to) {
    return std::chrono::duration<double>(to - from).count();
  };
  for (long m = 1; m <= total_steps; ++m) {
    const double t = static_cast<double>(m) * dt;
    const double p = options.pulse(t);
    // Newmark predictor without the joint softening of the new step.
    hist = (4 / (dt * dt)) * eta + (4 / dt) * vel + acc;
    hist += c.cwiseProduct((2 / dt) * eta + vel);
    eta_p = (phi_d * p + hist).cwiseProduct(kinv);
    if (joints.size() > 0) {
      bool converged = false;
      const int it = joints.solve(joints.psi() * eta_p, options, converged);
      sum.newton_iterations += it;
      sum.max_step_iterations = std::max(sum.max_step_iterations, it);
      if (!converged) {
        sum.status = SimulationStatus::kNewtonFailed;
        sum.message = fmt::format(
            "the joint problem did not converge at t = {:.6g} s after {} Newton iterations; "
            "the record ends at the last sample before it",
            t, it);
        const Eigen::Index kept = (m - 1) / sub + 1;
        out.acceleration.conservativeResize(kept, Eigen::NoChange);
        out.velocity.conservativeResize(kept, Eigen::NoChange);
        out.displacement.conservativeResize(kept, Eigen::NoChange);
        out.force.conservativeResize(kept);
        break;
      }
      joints.commit(en, sum);
      eta_p += kinv.cwiseProduct(joints.psi().transpose() * joints.h());
    }
    // Newmark update (eta_p now holds eta_{n+1}).
    const Eigen::VectorXd acc_new = (4 / (dt * dt)) * (eta_p - eta) - (4 / dt) * vel - acc;
    const Eigen::VectorXd vel_new = vel + (dt / 2) * (acc + acc_new);
    en.damping_dissipated += dt * (c.array() * (0.5 * (vel + vel_new)).array().square()).sum();
    const double u_d = phi_d.dot(eta_p);
    en.input += (u_d - u_d_prev) * 0.5 * (p + p_prev);
    u_d_prev = u_d, p_prev = p;
    eta = eta_p, vel = vel_new, acc = acc_new;
    ++sum.steps;
    if (m % sub == 0) record(m / sub);
    if (options.progress && (m % progress_every == 0 || m % 1024 == 0)) {
      const auto now = std::chrono::steady_clock::now();
      if (m % progress_every == 0 || seconds(last_report, now) >= 5.0) {
        last_report = now;
        const double done = static_cast<double>(m) / static_cast<double>(total_steps);
        options.progress(fmt::format(
            "t = {:.3f} s of {:.3f} s ({:.1f} %, about {:.0f} s to go), joint dissipation "
            "{:.4e} J",
            t, (n_samples - 1) / options.fs, 100.0 * done,
            seconds(started, now) * (1 - done) / done, en.joint_dissipated));
      }
    }
  }

  final_energies(en, b, joints, eta, vel);
  if (sum.status == SimulationStatus::kOk) {
    sum.message = fmt::format("{} samples at {} Hz ({} s)", n_samples, options.fs,
                              (n_samples - 1) / options.fs);
  }
  return out;
}

}  // namespace jointlab::model
