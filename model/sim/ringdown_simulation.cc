#include "jointlab/model/sim/ringdown_simulation.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
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

}  // namespace

SimulatedResponse simulate_ringdown(const Model& model, const SimulationOptions& options,
                                    SimulationSummary* summary) {
  assert(summary != nullptr);
  if (const std::string e = options.error(model.size()); !e.empty()) {
    throw InputError(fmt::format("simulate: {}", e));
  }
  SimulationSummary& sum = *summary;
  sum = SimulationSummary{};

  // Linear modes with the joints at linear stiffness, rigid-body modes included.
  const LinearModes modes = linear_modes(model.mass, model.linear_stiffness());
  const int n = modes.size();
  const Eigen::MatrixXd& phi = modes.shapes;
  Eigen::VectorXd w2 = modes.omega2;
  for (int i = 0; i < modes.rigid_count; ++i) w2(i) = 0;
  const Eigen::VectorXd w = w2.cwiseSqrt();
  sum.modes = n;
  sum.rigid_modes = modes.rigid_count;
  sum.lowest_elastic_hz = modes.rigid_count < n ? w(modes.rigid_count) / (2 * M_PI) : 0.0;

  // Damping per mode and the output filter.
  Eigen::VectorXd c(n);
  for (int i = 0; i < n; ++i) {
    c(i) = options.rayleigh_mass + options.rayleigh_stiffness * w2(i) +
           (modes.rigid(i) ? 0.0 : 2 * options.modal_damping * w(i));
  }
  const double cutoff = options.output_cutoff_hz > 0 ? options.output_cutoff_hz : 0.45 * options.fs;
  int n_out = 0;
  while (n_out < n && w(n_out) <= 2 * M_PI * cutoff) ++n_out;
  sum.output_modes = n_out;

  // Step: substeps per sample from the period error of the lowest elastic mode.
  int sub = options.substeps;
  if (sub == 0) {
    const double w1 = modes.rigid_count < n ? w(modes.rigid_count) : 0.0;
    const double wdt_max = std::sqrt(12 * options.frequency_error);
    sub = std::max(4, static_cast<int>(std::ceil(w1 / (options.fs * wdt_max))));
  }
  const double dt = 1.0 / (options.fs * sub);
  sum.dt = dt;
  sum.substeps = sub;

  // Joint coordinates, Psi = B Phi and the condensed step operator S^{-1}.
  std::vector<Coordinate> coords = iwan_coordinates(model);
  const int nj = static_cast<int>(coords.size());
  sum.joint_coordinates = nj;
  Eigen::MatrixXd psi(nj, n);
  for (int j = 0; j < nj; ++j) {
    psi.row(j) = phi.row(coords[j].a);
    if (coords[j].b != kGround) psi.row(j) -= phi.row(coords[j].b);
  }
  const Eigen::VectorXd khat = (w2.array() + 2 * c.array() / dt + 4 / (dt * dt)).matrix();
  const Eigen::VectorXd kinv = khat.cwiseInverse();
  Eigen::MatrixXd s(nj, nj), s_inv(nj, nj);
  Eigen::VectorXd kt(nj), phi_max(nj);
  for (int j = 0; j < nj; ++j) kt(j) = coords[j].kt, phi_max(j) = coords[j].phi_max;
  if (nj > 0) {
    s = psi * kinv.asDiagonal() * psi.transpose();
    Eigen::LDLT<Eigen::MatrixXd> ldlt(s);
    const double dmax = ldlt.vectorD().cwiseAbs().maxCoeff();
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * dmax)) {
      throw InputError(
          "simulate: the model's Iwan joint coordinates are linearly dependent (a closed loop "
          "of Iwan joints); the joint problem has no unique solution");
    }
    s_inv = ldlt.solve(Eigen::MatrixXd::Identity(nj, nj));
    s_inv = 0.5 * (s_inv + s_inv.transpose()).eval();
  }

  // Sensor and impact rows of Phi.
  const auto n_sens = static_cast<Eigen::Index>(options.sensors.size());
  Eigen::MatrixXd phi_s(n_sens, n_out);
  for (Eigen::Index k = 0; k < n_sens; ++k) phi_s.row(k) = phi.row(options.sensors[k]).head(n_out);
  const Eigen::VectorXd phi_d = phi.row(options.pulse.dof).transpose();

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
  Eigen::VectorXd r = Eigen::VectorXd::Zero(nj), r_p(nj), h = r, dh(nj), grad(nj), step(nj),
                  r_try(nj), h_try(nj), dh_try(nj), trial_h(nj), res(nj), res_try(nj);
  double p_prev = options.pulse(0.0), u_d_prev = 0;
  EnergyBalance& en = sum.energy;
  auto record = [&](Eigen::Index k) {
    out.acceleration.row(k) = (phi_s * acc.head(n_out)).transpose();
    out.velocity.row(k) = (phi_s * vel.head(n_out)).transpose();
    out.displacement.row(k) = (phi_s * eta.head(n_out)).transpose();
    out.force(k) = options.pulse(static_cast<double>(k) / options.fs);
  };
  // h, h' and the incremental potential sum_j H_j(r_j) of a trial r.
  auto evaluate = [&](const Eigen::VectorXd& rt, Eigen::VectorXd& ht, Eigen::VectorXd& dht) {
    double pot = 0;
    for (int j = 0; j < nj; ++j) {
      double f = 0, df = 0, work = 0;
      for (const IwanHistory& e : coords[j].elements) {
        const IwanMove m = e.trial(rt(j));
        f += m.force, df += m.tangent, work += m.work;
      }
      const double rc = r(j);
      ht(j) = kt(j) * rt(j) - f;
      dht(j) = kt(j) - df;
      pot += 0.5 * kt(j) * (rt(j) * rt(j) - rc * rc) - work;
    }
    return pot;
  };
  // The step's potential Pi(r) = 1/2 (r - r_p)^T S^{-1} (r - r_p) - sum H_j(r_j).
  auto potential = [&](const Eigen::VectorXd& rt, double pot_h) {
    const Eigen::VectorXd d = rt - r_p;
    return 0.5 * d.dot(s_inv * d) - pot_h;
  };

  record(0);
  const long total_steps = static_cast<long>(n_samples - 1) * sub;
  const long progress_every = std::max<long>(1, total_steps / 10);
  Eigen::LLT<Eigen::MatrixXd> llt(nj);
  Eigen::MatrixXd jac(nj, nj);
  for (long m = 1; m <= total_steps; ++m) {
    const double t = static_cast<double>(m) * dt;
    const double p = options.pulse(t);
    // Newmark predictor without the joint softening of the new step.
    hist = (4 / (dt * dt)) * eta + (4 / dt) * vel + acc;
    hist += c.cwiseProduct((2 / dt) * eta + vel);
    eta_p = (phi_d * p + hist).cwiseProduct(kinv);
    if (nj > 0) {
      r_p = psi * eta_p;
      // Newton on S^{-1} (r - r_p) - h(r) = 0, started from the committed softening. The
      // residual is formed as r - r_p - S h (no large cancelling terms) and mapped by S^{-1}
      // to the gradient of the step's convex potential Pi.
      Eigen::VectorXd r_new = r_p + s * h;
      double pot_h = evaluate(r_new, trial_h, dh);
      double pi = potential(r_new, pot_h);
      res = r_new - r_p - s * trial_h;
      bool converged = false;
      int it = 0;
      while (it < options.max_newton_iterations) {
        ++it;
        grad = s_inv * res;
        jac = s_inv;
        jac.diagonal() -= dh;
        llt.compute(jac);
        step = -llt.solve(grad);
        if (!step.allFinite()) break;
        const double step_max = step.cwiseAbs().maxCoeff();
        if (step_max <= options.newton_tolerance * r_new.cwiseAbs().maxCoeff()) {
          r_new += step;  // below the tolerance: the commit evaluates the forces there
          converged = true;
          break;
        }
        // Full step when the residual falls, else backtracking on Pi (Armijo).
        const double res_max = res.cwiseAbs().maxCoeff();
        double lambda = 1;
        for (int ls = 0;; ++ls) {
          r_try = r_new + lambda * step;
          const double pot_try = evaluate(r_try, h_try, dh_try);
          const double pi_try = potential(r_try, pot_try);
          res_try = r_try - r_p - s * h_try;
          if (res_try.cwiseAbs().maxCoeff() < res_max ||
              pi_try <= pi + 1e-4 * lambda * grad.dot(step) || ls == 40) {
            r_new = r_try, trial_h = h_try, dh = dh_try, pi = pi_try, res = res_try;
            break;
          }
          lambda *= 0.5;
        }
      }
      sum.newton_iterations += it;
      sum.max_step_iterations = std::max(sum.max_step_iterations, it);
      if (!converged || !r_new.allFinite()) {
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
      // Commit the joints.
      for (int j = 0; j < nj; ++j) {
        double f = 0;
        for (IwanHistory& e : coords[j].elements) {
          const IwanMove mv = e.commit(r_new(j));
          f += mv.force;
          en.joint_dissipated += mv.dissipation;
        }
        h(j) = kt(j) * r_new(j) - f;
        sum.max_joint_displacement = std::max(sum.max_joint_displacement, std::abs(r_new(j)));
        sum.max_phi_ratio = std::max(sum.max_phi_ratio, std::abs(r_new(j)) / phi_max(j));
      }
      r = r_new;
      eta_p += kinv.cwiseProduct(psi.transpose() * h);
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
    if (options.progress && m % progress_every == 0) {
      options.progress(fmt::format(
          "t = {:.3f} s of {:.3f} s ({:.0f} %), joint dissipation {:.4e} J", t,
          (n_samples - 1) / options.fs,
          100.0 * static_cast<double>(m) / static_cast<double>(total_steps), en.joint_dissipated));
    }
  }

  // Energies at the end.
  en.kinetic = 0.5 * vel.squaredNorm();
  double stored = 0;
  for (const Coordinate& co : coords) {
    for (const IwanHistory& e : co.elements) stored += e.stored_energy();
  }
  en.joint_stored = stored;
  en.strain = 0.5 * (w2.array() * eta.array().square()).sum() -
              0.5 * (kt.array() * r.array().square()).sum() + stored;
  if (sum.status == SimulationStatus::kOk) {
    sum.message = fmt::format("{} samples at {} Hz ({} s)", n_samples, options.fs,
                              (n_samples - 1) / options.fs);
  }
  return out;
}

}  // namespace jointlab::model
