// A small jointed structure with known parameters, for tests, benchmarks and examples.
//
// Two grounded spring-mass chains of n masses each (n >= 6): chain A (indices 0..n-1,
// 0.5 kg each) and chain B (indices n..2n-1, 0.3 kg each). Every chain is grounded at its
// first mass by 2e6 N/m; consecutive masses are joined by 1e6 N/m except
//   A1-A2: a structural 2e5 N/m in parallel with the joint element "spring.ka"
//          (or, with iwan, "iwan.rivet": an Iwan element with K_T = ka),
//   A3-A4: only the joint element "spring.kflat" (very stiff: frequencies barely see it),
//   B1-B2: only the joint element "spring.kb".
// With ka = 5e5, kb = 3e5 the first mode of chain A (57.9 Hz) lies just below the first mode
// of chain B (59.9 Hz); raising ka past about 6e5 swaps them (a "torsion" mode crossing a
// "bending" mode). Stiffness in N/m, mass in kg.
#pragma once

#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/iwan.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// Parameters of two_chain_structure().
struct TwoChainParameters {
  int n = 6;            ///< masses per chain (>= 6)
  double ka = 5e5;      ///< "spring.ka" (or the Iwan K_T) [N/m]
  double kb = 3e5;      ///< "spring.kb" [N/m]
  double kflat = 1e10;  ///< "spring.kflat" [N/m]
  bool iwan = false;    ///< A1-A2 is "iwan.rivet" instead of "spring.ka"
  double Fs = 20;       ///< Iwan slip force [N]
  double chi = -0.5;    ///< Iwan exponent
  double beta = 1.0;    ///< Iwan macroslip weight
};

/// Builds the two-chain model (validated).
model::Model two_chain_structure(const TwoChainParameters& p = {});

/// Twin cantilevers: two chains of three masses (1 and 1.05 kg, inner springs 1e4 N/m), each
/// grounded at its first mass by "spring.kg" = kg and coupled at their tips (DOFs 2 and 5) by
/// "spring.kc" = kc [N/m]; their lowest two modes are the chains in phase and in opposition.
model::Model twin_chains_structure(double kg, double kc);

/// A one-mode model: unit modal mass, a spring k0 [N/m] in parallel with one Iwan element
/// "iwan.j" (parameters p) to ground, and the structure's own damping ratio z (modal_ratio).
model::Model one_mode_structure(double k0, const model::IwanParameters& p, double z = 0);

/// A backbone of elastic mode `mode` of `model` as `process` would report it at sensor
/// `sensor`: `points` points log-spaced in modal amplitude over the two decades below `top` times
/// the end of the automatic QSMA range (a ring-down's span), the amplitude the sensor DOF's QSMA
/// deflection (model::QsmaDof, not |phi| q) converted to `quantity`,
/// frequency and damping perturbed by Gaussian relative noise (frequency_noise, damping_noise;
/// seeded) and their std columns set to those noise levels. The columns are those a test of
/// `kind` shows (QSMA's ring-down or first-harmonic pair, the amplitude at the first-harmonic
/// frequency), or with IwanComparison::kSecant QSMA's secant pair.
MeasuredBackbone synthetic_backbone(const model::Model& model, int mode,
                                    const std::vector<Sensor>& sensors, int sensor,
                                    AmplitudeQuantity quantity, int points, double top,
                                    double frequency_noise, double damping_noise, unsigned seed,
                                    BackboneKind kind = BackboneKind::kRingdown,
                                    IwanComparison columns = IwanComparison::kMatched);

}  // namespace jointlab::correlate
