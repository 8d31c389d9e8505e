// The Iwan update's cause line: where the model does not describe the data, what the residuals
// at the result point at (a wrong mode, scatter between hits, the linear part, missing damping,
// the damping column's units), in one sentence (IwanUpdateSummary::misfit_cause()).
#include "jointlab/correlate/iwan_cause_detail.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/iwan_cycle.h"

namespace jointlab::correlate {
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

}  // namespace

bool iwan_detail::model_as_given_matches(const MisfitEvidence& e) {
  return e.mode_hz > 0 && e.low_frequency_hz > 0 &&
         std::abs(e.mode_hz / e.low_frequency_hz - 1) <= low_frequency_tolerance(e);
}

bool iwan_detail::kt_stopped_short(const IwanUpdateSummary& s) {
  if (!s.evidence || s.held[1] || s.bound_side[1] == 0) return false;
  return linear_limit_off(*s.evidence) && -s.evidence->low_frequency_error * s.bound_side[1] > 0;
}

// A factor on the amplitudes is the same factor on F_S: the joint's force is homogeneous in its
// slip and slip force (phi_max = F_S (1 + beta) / (K_T (beta + c))), and the rest of the model is
// linear, so the curve at a q with F_S is the curve at s q with s F_S. Amplitudes read larger than
// they are (a velocity or acceleration read as the modal amplitude or a displacement, mm read as
// m) call for F_S larger by that factor; where F_S's range stops it, the fitted joint still slips
// at the lowest measured amplitudes, its frequency there below its own linear limit, while the
// data lie above it. Velocity tables of the riveted beam (truth F_S 30 N) read as the modal
// amplitude: F_S at its upper bound 1500 N, the joint at 0.21 phi_max at the lowest amplitude
// and 37 at the highest, the fitted curve there 8.8 % below its linear limit and 15.3 % below the
// data (1532 times their noise); before, "the structure's own damping" was named, and with it
// fitted "no slip in these data". Both frequency offsets beyond linear_limit_off()'s tolerance.
bool iwan_detail::amplitudes_read_too_large(const IwanUpdateSummary& s) {
  if (!s.evidence || s.held[0] || s.bound_side[0] <= 0) return false;
  const MisfitEvidence& e = *s.evidence;
  if (!(e.linear_hz > 0) || !(e.low_frequency_hz > 0)) return false;
  const double tolerance = low_frequency_tolerance(e);
  const double model_low = e.low_frequency_hz * (1 + e.low_frequency_error);
  return e.low_frequency_error < -tolerance && model_low / e.linear_hz - 1 < -tolerance;
}

// The other direction: amplitudes read smaller than they are call for F_S smaller by their
// factor, and where F_S's range stops it at its lower bound, the fitted joint slips too little at
// the highest measured amplitudes. A smaller F_S softens the joint at every amplitude (its secant
// stiffness is K_T times a function falling in slip / phi_max, and phi_max is proportional to
// F_S), so the fitted curve lies above the data there while the measured frequency falls more
// from the lowest amplitudes to the highest than the fitted curve does: no joint with F_S in its
// range falls that far over these amplitudes. A linear part too stiff with K_T held lies above the
// data at both ends instead, and damping the joint cannot give pulls F_S down with the curve below
// the data. Displacement tables of the riveted beam (truth F_S 30 N) 1000 times too small: F_S at
// its lower bound 1.67 N, the fitted joint at 0.018 phi_max at the highest amplitude, the fitted
// curve there 4.15 % above the data (415 times their noise) and 0.88 % below them at the lowest;
// before, "the structure's own damping" or another mode's slip was named, and "a wider range would
// not cure that" (--fs-range 1e-4:100 gives F_S 0.02999 N, chi -0.3008, reduced chi-square 1.11).
bool iwan_detail::amplitudes_read_too_small(const IwanUpdateSummary& s) {
  if (!s.evidence || s.held[0] || s.bound_side[0] >= 0) return false;
  const MisfitEvidence& e = *s.evidence;
  if (!(e.high_frequency_hz > 0) || !(e.low_frequency_hz > 0)) return false;
  const double tolerance = std::max(10 * e.high_frequency_noise, 1e-3);
  return e.high_frequency_error > tolerance &&
         e.high_frequency_error - e.low_frequency_error > tolerance;
}

namespace {

using iwan_detail::amplitudes_read_too_large;
using iwan_detail::amplitudes_read_too_small;
using iwan_detail::kt_stopped_short;

// The cause where amplitudes_read_too_small(): the amplitudes' quantity or unit.
std::string small_amplitude_cause(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  return fmt::format(
      "Fs ran to its lower bound {:.4g} N and still the fitted curve at the highest measured "
      "amplitudes lies {:+.3g} % off the measured frequency {:.6g} Hz there ({:.0f} times its "
      "noise), while at the lowest it lies {:+.3g} % off: the measured frequency falls more over "
      "these amplitudes than any joint with Fs in its range does (the fitted one reaches {:.2g} "
      "phi_max at the highest). A factor on the amplitudes is the same factor on Fs (the joint's "
      "force is homogeneous in its slip and slip force), so these amplitudes are smaller than the "
      "quantity they are read as: a displacement read as a velocity or acceleration (divided by "
      "omega or omega^2), an acceleration in g read as m/s^2, or m given the unit mm. Check "
      "--amplitude, --dof and the amplitude column's unit (the amplitude line below says how "
      "they were read); only where those are right does Fs lie below its range (--fs-range)",
      s.best.Fs, 100 * e.high_frequency_error, e.high_frequency_hz,
      e.high_frequency_error / std::max(e.high_frequency_noise, 1e-12), 100 * e.low_frequency_error,
      s.phi_max > 0 ? s.top_slip / s.phi_max : 0.0);
}

// The cause where amplitudes_read_too_large() or amplitudes_read_too_small(): the amplitudes'
// quantity or unit.
std::string amplitude_scale_cause(const IwanUpdateSummary& s) {
  if (amplitudes_read_too_small(s)) return small_amplitude_cause(s);
  if (!amplitudes_read_too_large(s)) return "";
  const MisfitEvidence& e = *s.evidence;
  const double model_low = e.low_frequency_hz * (1 + e.low_frequency_error);
  return fmt::format(
      "Fs ran to its upper bound {:.4g} N and still the fitted joint slips at the lowest measured "
      "amplitudes ({:.2g} phi_max there, {:.2g} phi_max at the highest): the fitted curve there "
      "lies {:+.3g} % off its own linear limit {:.6g} Hz and {:+.3g} % off the measured "
      "low-amplitude frequency {:.6g} Hz ({:.0f} times its noise). A factor on the amplitudes is "
      "the same factor on Fs (the joint's force is homogeneous in its slip and slip force), so "
      "these amplitudes are larger than the quantity they are read as: a velocity or "
      "acceleration read as a displacement or as the modal amplitude, or mm read as m. Check "
      "--amplitude, --dof and the amplitude column's unit (the amplitude line below says how "
      "they were read); only where those are right does Fs lie above its range (--fs-range)",
      s.best.Fs, s.phi_max > 0 ? s.bottom_slip / s.phi_max : 0.0,
      s.phi_max > 0 ? s.top_slip / s.phi_max : 0.0, 100 * (model_low / e.linear_hz - 1),
      e.linear_hz, 100 * e.low_frequency_error, e.low_frequency_hz,
      std::abs(e.low_frequency_error) / e.low_frequency_noise);
}
using iwan_detail::model_as_given_matches;

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
// joint softens from zero amplitude on, but one nearly linear in amplitude or steeper (chi near or
// above 0: 1.1 % at chi 0.3 and 1, 5.8 % at -0.5, the one-mode truth's three 40-point hits from
// 1e-8 read at the truth) hardly does, and data that start near the other mode's slip soften there.
// On the one-mode truth (three hits, 1e-4 / 2 % noise) the own damping 5e-4 of a chi -0.05 joint
// over 3.5 decades reads 0.5 % (flat) and of a chi -0.2 joint with 10 points a curve over 2.5
// decades 2.2 %, while another mode adding 0.1 phi_max to a chi -0.5 or -0.9 joint over 2.5 decades
// reads 3.5 % and 5.0 % (softening): each was named the other cause, alone. What decides is the
// refit with Z free: the own damping then fits within the noise (reduced chi-square 1.09, chi -0.05
// and -0.5), the other mode's slip does not (7.6 and 9.0 for 0.1 and 0.3 phi_max on chi -0.5),
// except for a joint nearly linear in amplitude, whose slip at a constant offset only shifts the
// frequency and adds a nearly constant damping, as own damping does (1.3 for chi -0.05). With Z
// fitted already the own damping is not what is missing.
std::string own_damping_or_other_slip(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  const std::string strike =
      "strike so that the fitted mode dominates, or screen the hits with the other modes' "
      "backbones";
  // A mode that hardly moves the joint: no slip of it, by this mode or another, shows in this
  // mode's damping.
  // Not where F_S ran to its upper bound: the fitted joint then hardly slips because the fit set
  // it aside, which says nothing of how far this mode moves it (a per-cent damping column on
  // microslip tables, F_S 1500 N, the joint at 8e-4 phi_max, was told "this mode hardly moves the
  // joint").
  if (s.joint_hardly_moved() && !s.modal_ratio_fitted && (s.held[0] || s.bound_side[0] <= 0)) {
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
      "keeps it slipping at the low end. {}: a joint nearly linear in amplitude or steeper (chi "
      "near or above 0) hardly softens there, and data that start near the other mode's slip do. "
      "Refit with "
      "--linear-damping fit (or set [damping] modal_ratio in the model): the structure's own "
      "damping then fits within the noise, and a misfit that stays is the other mode's slip ({})",
      s.modal_ratio, lean, strike);
}

// The offsets' evidence of scatter between curves (MisfitEvidence::between_curves_share).
std::string offset_evidence(const MisfitEvidence& e) {
  return fmt::format(
      "an offset of each from the others (frequency {:+.2g} to {:+.2g} %, damping {:+.2g} to "
      "{:+.2g} % about the fitted curve) explains {:.0f} % of the chi-square",
      100 * e.frequency_offsets(0), 100 * e.frequency_offsets(1), 100 * e.damping_offsets(0),
      100 * e.damping_offsets(1), 100 * e.between_curves_share);
}

// The shapes' evidence (MisfitEvidence::hits_differ_in_shape()): scatter that reshapes the
// curves (F_S and K_T off in opposite senses in a hit) offsets them little. Three hits of the
// one-mode truth, F_S and K_T scattered 5 % and 2 % between them (40 seeds each): over one
// range 10 fits ended "the model does not describe the data" with no cause named and no sigma,
// at rising levels from one floor 2 (opposite senses: 5), each with offsets explaining 0.27-0.49
// of the chi-square; their curves' own offsets and slopes explained 0.33-0.67, the common curve
// gained 10-34 over 22 degrees of freedom. Models wrong with the hits alike (chi held at -0.6 on
// chi -0.2 data, the linear part 0.4 % stiff, another mode's slip, the structure's own damping
// missing; 40 seeds each, both shapes): shares at most 0.05, each fit saying what it said before.
std::string shape_evidence(const MisfitEvidence& e) {
  return fmt::format(
      "where their amplitudes overlap they differ in shape, the offsets alone explaining {:.0f} "
      "% of the chi-square: each curve's own offset and slope about a common curve explain "
      "{:.0f} % (a chi-square of {:.0f} where the stated noise gives about {}), while that "
      "common curve, the misfit the hits share at each amplitude, gains no more than the noise "
      "gives ({:.0f} over {} degrees of freedom). A model error gives every hit the same "
      "residual at the same amplitude; these hits' residuals are their own",
      100 * e.between_curves_share, 100 * e.between_hits_share, e.between_hits_chi2,
      e.between_hits_dof, e.common_chi2, e.common_dof);
}

// Scatter between hits that does not explain the misfit alone (MisfitEvidence::
// model_misses_each_hit()): each curve fitted alone still misses, and alike at the same
// amplitude. Three hits scattered 5 % / 2 % with the linear part 0.4 % stiff: the offsets were
// named scatter and the cluster sigmas stated, F_S and K_T up to 5.5 (one range) and 8.5 (rising
// levels) of them off the nominal joint.
std::string model_beside_scatter(const MisfitEvidence& e) {
  // The parameters each curve's own fit freed, and those it held as the fit did.
  static const char* const names[] = {"F_S", "K_T", "chi", "beta"};
  std::vector<std::string> own, held;
  for (size_t k = 0; k < 4; ++k) (e.each_hit_held[k] ? held : own).push_back(names[k]);
  if (e.each_hit_own_damping) own.push_back("modal_ratio");
  const auto join = [](const std::vector<std::string>& v) {
    std::string out;
    for (size_t i = 0; i < v.size(); ++i)
      out += (i == 0 ? "" : i + 1 == v.size() ? " and " : ", ") + v[i];
    return out;
  };
  const std::string freed =
      fmt::format("its own {}{}", join(own),
                  held.empty() ? "" : fmt::format(", {} held as in the fit", join(held)));
  return fmt::format(
      "That is scatter between the hits, but not all of the misfit: each curve fitted alone "
      "(linearised about this result, {}) still keeps a chi-square of {:.0f} where the stated "
      "noise gives about {}, and what it keeps is shared: a common curve of the frequency "
      "residuals in amplitude gains {:.3g} times the rest's own scatter per degree of freedom "
      "({} and {}; under 1 time in 100 by chance). A model error the hits share (the linear "
      "part, chi, K_T or beta held off the joint's, the structure's own damping, another mode "
      "slipping the joint) pulls every parameter further than the scatter between hits shows, "
      "so no sigma is stated (one cluster per hit would read the scatter alone: three hits "
      "scattered 5 % / 2 % with the linear part 0.4 % stiff stated F_S and K_T up to 8.5 of "
      "those sigmas off)",
      freed, e.each_hit_chi2, e.each_hit_dof, e.shared_frequency_f, e.shared_frequency_dof,
      e.shared_frequency_rest_dof);
}

// Curves that disagree with one another: offsets of each curve from the others explain most
// of the chi-square, or, where the curves overlap in amplitude, their own shapes do. Scatter
// between hits (the trial's three curves, each with its own 0.2 % frequency and 5 % damping offset:
// reduced chi-square 9.6, and the report asked for 4 times the evaluations while the sigmas, one
// cluster per hit, were right); no search cures it.
std::string scatter_cause(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  // The clusters of the sigmas are the hits: curves of one hit (its channels or modes) share
  // its joint (s.hits; 0 where not set: one hit per curve).
  const int hits = s.hits > 0 ? std::min(e.curves, s.hits) : e.curves;
  const bool offsets = e.between_curves_share >= 0.5;
  if (e.curves >= 2 && (offsets || e.hits_differ_in_shape())) {
    return fmt::format(
        "the {} curves disagree with one another by more than their stated noise: {}. {}. {}",
        e.curves, offsets ? offset_evidence(e) : shape_evidence(e),
        !e.apart_curve.empty()
            ? fmt::format(
                  "But {} ({} points, amplitude {:.3g} to {:.3g}) lies apart from the others "
                  "({} {:+.2g} % against their {:+.2g} to {:+.2g} %, {:.2g} times their spread: "
                  "random scatter between hits puts a curve there less than 1 time in 100): its "
                  "offset follows that hit (another strike point, another mode slipping the "
                  "joint), no random scatter, so no sigma is stated (one cluster per hit would "
                  "read it as scatter and understate the error); fit that curve apart, or leave "
                  "it out",
                  e.apart_curve, e.apart_points, e.apart_amplitude(0), e.apart_amplitude(1),
                  e.apart_in_damping ? "damping" : "frequency",
                  100 * e.apart_offset(e.apart_in_damping ? 1 : 0), 100 * e.apart_others(0),
                  100 * e.apart_others(1), e.apart_t)
        : e.model_misses_each_hit()
            ? model_beside_scatter(e)
            : fmt::format(
                  "That is scatter between the hits (each hit's joint a little different), which "
                  "neither a longer search nor a wider range cures; {}",
                  hits >= 4
                      ? fmt::format("the sigmas allow for it (one cluster per hit, Student's t "
                                    "with {} degrees of freedom)",
                                    hits - 1)
                  : hits == 3
                      ? fmt::format(
                            "the sigmas allow for it (one cluster per hit, Student's t with 2 "
                            "degrees of freedom, whose variance is infinite: each sigma is its "
                            "95 % interval over 1.96, 2.2 times the scatter's standard error), "
                            "taking the three {} for random scatter of one joint, which "
                            "three hits cannot tell from one hit unlike the others (four or "
                            "more can)",
                            offsets ? "offsets" : "hits' differences")
                      : fmt::format("with {} {} the sigmas do not allow for it (one cluster "
                                    "per hit leaves {} degree of freedom; three or more "
                                    "hits would give a sigma)",
                                    hits, hits == 1 ? "hit" : "hits", hits - 1)),
        e.model_misses_each_hit()
            ? std::string("Mend the model first (update-linear for the linear part), then refit; "
                          "each hit fitted alone (its backbone as the only curve) shows the "
                          "misfit a model error leaves in every one")
        : offsets
            ? std::string("To weigh the points by it, state it in each point's uncertainty "
                          "(frequency_std_hz, damping_std)")
            : std::string("Fit each hit alone (its backbone as the only curve: each should fit "
                          "within its noise), compare the hits in the scatter summary, or strike "
                          "each level two or more times to measure how far the joint changes"));
  }
  return "";
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
std::string held_kt_cause(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  const auto& held = s.held;
  const auto& bound_side = s.bound_side;
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
  return "";
}

// A damping column in per cent read as a fraction, beside the cause named, where it could be:
// every measured damping below 1 (a per-cent value of 1 or more read right is no plausible
// damping ratio either) and the measured damping at the lowest amplitudes at least 10 times the
// model's there. Per cent is 100 times; the fit takes up part of it (microslip tables of the
// riveted beam in per cent without a unit: 0.0636 against the model's 0.00143 there, 44 times),
// while the structure's own damping missing, which no number here tells from it, read 3.7-3.9
// times in the trials. Only the user knows the column's unit, so it is named as a possibility:
// before, the per-cent table was told "the structure's own damping" alone.
std::string per_cent_possibility(const MisfitEvidence& e) {
  if (!(e.damping_max < 1) || !(e.low_model_damping > 0) ||
      !(e.low_damping >= 10 * e.low_model_damping))
    return "";
  return fmt::format(
      ". Or, every measured damping lying below 1 and {:.3g} times the model's at the lowest "
      "amplitudes, a damping column in per cent read as a fraction (100 times the damping "
      "ratio): if it is per cent, name the unit in its header (damping_ratio [%])",
      e.low_damping / e.low_model_damping);
}

// A loss factor (eta = 2 zeta) given as the damping ratio, beside the cause named, where the fit
// bent the curve toward damping above the model's: the loss factor doubles every measured
// damping, and the fit takes up part of it, so the median measured over model damping lies
// between 1.5 and damping_units_cause()'s 2.4 (the riveted beam's loss factor over 2.5 decades:
// 1.69, the fit raising K_T 1.8 % and the linear limit 0.139 % off; before, "the structure's own
// damping" alone). The structure's own damping and another mode's slip give such factors too
// (1.64 and 1.73-1.74 in the trials), so it is a possibility, not the cause.
std::string loss_factor_possibility(const MisfitEvidence& e) {
  if (!(e.damping_factor >= 1.5 && e.damping_factor <= 2.4)) return "";
  return fmt::format(
      ". Or, the measured damping lying a median {:.3g} times the fitted model's, a loss factor "
      "(eta = 2 zeta) given as the damping ratio, which doubles every damping: if so, halve it",
      e.damping_factor);
}

// A damping column in another unit, from the low end's damping rise against its frequency drop
// (MisfitEvidence::low_rise_ratio), where the loss-factor rule's median factor does not show it:
// no Iwan joint of chi at or below chi_ref adds more damping per relative frequency drop in
// microslip than iwan_rise_limit(chi_ref) (kIwanRiseLimit at chi_ref 0; chi_ref the fitted chi, 0
// below it), the structure's own damping, constant, adds none to the rise, and a unit factor
// multiplies it. Checked where the fit puts the joint in microslip over those two fifths (its
// slip at the lowest amplitude times their amplitude span below half phi_max: just past phi_max
// the macroslip delta's dissipation rises ahead of its stiffness loss).
// The riveted beam's loss factor on 14-point microslip tables: the fit took the doubling up
// almost whole (a median factor of 1.08, K_T raised, the linear limit +0.104 % off), and "the
// structure's own damping" alone was named, where the rise reads 4.3 standard deviations above
// the limit; its true tables (40 points) read 0.32-0.35 per curve, 12.5 below, and none of the
// probe's 30 other cases reached 1.5.
// A joint of chi above 0 rises more steeply (0.510 at chi 0.3): judged at the fitted chi, and
// where chi ran to its upper bound (the default range stops at 0) a joint of chi above it is
// named beside the unit, with the chi whose limit reaches the measured rise. FloorTruth's joint
// at chi 0.3 on three 40-point microslip hits (1e-5 frequency and 0.5 % damping noise) read
// 0.511, 5.9 standard deviations above 0.424, 0.03 above 0.510: a fit with chi stopped at 0 was
// told "a damping column in another unit" alone.
std::string damping_rise_possibility(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  const double chi_ref = std::max(0.0, s.best.chi);
  if (!(chi_ref <= model::kIwanCycleChiMax)) return "";
  const double limit = iwan_rise_limit(chi_ref);
  // Evidence without the rise's pieces (built by hand) states its excess at kIwanRiseLimit alone.
  const double excess = std::isfinite(e.low_rise) ? e.low_rise_excess_at(limit)
                        : chi_ref == 0            ? e.low_rise_excess
                                                  : NAN;
  if (!(excess > 3) || !(e.low_rise_ratio > 0) || !(s.phi_max > 0) || !(s.bottom_slip > 0) ||
      !(s.bottom_slip * e.low_rise_span < 0.5 * s.phi_max))
    return "";
  // chi at its upper bound: the data may call for a larger chi, whose joint rises more steeply.
  std::string larger_chi, larger_chi_why;
  if (!s.held[2] && s.bound_side[2] > 0) {
    larger_chi = fmt::format("{} {:g}", iwan_detail::kLargerChiWords, s.best.chi);
    double lo = chi_ref, hi = model::kIwanCycleChiMax;
    if (iwan_rise_limit(hi) < e.low_rise_ratio) {
      larger_chi_why = fmt::format(
          "chi ran to its upper bound {:g}, but no joint of chi up to {:g} rises that steeply; ",
          s.best.chi, hi);
    } else {
      for (int i = 0; i < 60 && hi - lo > 1e-3 * (1 + lo); ++i) {
        const double mid = 0.5 * (lo + hi);
        (iwan_rise_limit(mid) < e.low_rise_ratio ? lo : hi) = mid;
      }
      larger_chi_why = fmt::format(
          "chi ran to its upper bound {:g}, and a joint of chi {:.2g} or more rises that steeply "
          "(widen --chi-range and see whether the fit takes such a chi); ",
          s.best.chi, hi);
    }
  }
  return fmt::format(
      ". Or a damping column in another unit{}: from the lowest to the second fifth of amplitudes "
      "the measured damping rises {:.2g} times the measured frequency's relative drop, {:.1f} "
      "standard deviations above the {:.2f} that no Iwan joint with chi at or below {:g} exceeds "
      "in microslip (where the fitted joint is there, below {:.2g} phi_max), and the structure's "
      "own damping, constant, adds nothing to that rise: {}a loss factor (eta = 2 zeta) given as "
      "the damping ratio doubles it (if so, halve it), per cent read as a fraction is 100 times "
      "(if so, name the unit in its header, damping_ratio [%])",
      larger_chi, e.low_rise_ratio, excess, limit, chi_ref,
      s.bottom_slip * e.low_rise_span / s.phi_max, larger_chi_why);
}

// A damping column in another unit beside the cause named: the loss-factor rule's median factor,
// else the low end's damping rise.
std::string damping_unit_possibility(const IwanUpdateSummary& s) {
  const std::string loss = loss_factor_possibility(*s.evidence);
  return loss.empty() ? damping_rise_possibility(s) : loss;
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
std::string free_kt_cause(const IwanUpdateSummary& s, bool linear_off) {
  const MisfitEvidence& e = *s.evidence;
  const auto& held = s.held;
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
          std::abs(e.low_frequency_error) / e.low_frequency_noise,
          own_damping_or_other_slip(s) + damping_unit_possibility(s));
    }
    return fmt::format(
        "the fitted curve's linear limit misses the measured low-amplitude frequency {:.6g} Hz by "
        "{:+.3g} % ({:.0f} times its noise) though Kt, free inside its range, sets that limit "
        "alone and would meet it: no error of the linear part (Kt takes that up), but the fit "
        "bending the curve for the rest of the data, as damping the one-mode joint lacks does. {}",
        e.low_frequency_hz, 100 * e.low_frequency_error,
        std::abs(e.low_frequency_error) / e.low_frequency_noise,
        own_damping_or_other_slip(s) + damping_unit_possibility(s));
  }
  return "";
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
std::string flat_damping_cause(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
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
        own_damping_or_other_slip(s) + per_cent_possibility(e));
  }
  return "";
}

// Wherever else the measured frequency is flat at the low end (low_softening_share) with the
// measured damping there twice the fitted model's or more, the joint slips there as no one-mode
// Iwan curve does (another mode adding 0.1 phi_max, K_T held 10 % low: low damping 5.6 times the
// model's, share 0.003-0.009; before, "a loss factor ... halve it" at a median factor of 1.73,
// and before that "the structure's own damping"). A loss factor or a per-cent column keeps the
// joint's softening there; the structure's own damping with a joint nearly linear in amplitude
// does not (own_damping_or_other_slip()).
std::string low_end_slip_cause(const IwanUpdateSummary& s) {
  const MisfitEvidence& e = *s.evidence;
  if (e.low_softening_share < kLowSofteningShare && e.low_model_damping > 0 &&
      e.low_damping >= 2 * e.low_model_damping) {
    return fmt::format(
        "the measured damping at the lowest amplitudes, {:.3g}, lies {:.3g} times the fitted "
        "model's there ({:.3g}): more dissipation at low amplitude than the joint's power law "
        "allows. {}",
        e.low_damping, e.low_damping / e.low_model_damping, e.low_model_damping,
        own_damping_or_other_slip(s));
  }
  return "";
}

// A damping column in per cent read as a fraction (100 times), or a loss factor read as the
// damping ratio (twice).
std::string damping_units_cause(const IwanUpdateSummary& s, bool linear_off) {
  const MisfitEvidence& e = *s.evidence;
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
  return "";
}

// The fitted curve's linear limit off the measured low-amplitude frequency, with K_T held, at a
// bound short of it, or unable to reach it alone: the linear part.
std::string linear_part_cause(const IwanUpdateSummary& s, bool linear_off) {
  const MisfitEvidence& e = *s.evidence;
  const auto& held = s.held;
  const auto& bound_side = s.bound_side;
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

// What the residuals at s.best point at, read as if s.best were the best fit (residual_cause()).
std::string named_cause(const IwanUpdateSummary& s) {
  // A start no candidate improved on is read too where the joint hardly moves over the data:
  // no Iwan parameters then change the curve, so the start is as good a fit as any.
  if ((!s.improved && !s.joint_hardly_moved()) || !s.misfit() || !s.evidence) return "";
  const MisfitEvidence& e = *s.evidence;
  // The linear limit: at the lowest amplitudes the model's frequency is K_T's and the linear
  // part's. Off by far more than the noise there (and than 0.1 %, a frequency resolution), no
  // Iwan parameter set bends the curve onto the data: the trial's wrong --mode ran into every
  // bound, and a backbone 5 % below the model with K_T held into chi's.
  const bool linear_off = linear_limit_off(e);
  if (linear_off && e.nearer_mode > 0) return wrong_mode(e);
  if (std::string c = amplitude_scale_cause(s); !c.empty()) return c;
  if (std::string c = scatter_cause(s); !c.empty()) return c;
  if (std::string c = held_kt_cause(s); !c.empty()) return c;
  if (std::string c = free_kt_cause(s, linear_off); !c.empty()) return c;
  if (std::string c = flat_damping_cause(s); !c.empty()) return c;
  if (std::string c = low_end_slip_cause(s); !c.empty()) return c;
  if (std::string c = damping_units_cause(s, linear_off); !c.empty()) return c;
  if (std::string c = linear_part_cause(s, linear_off); !c.empty()) return c;
  return "";
}

// chi free at its upper bound beside the cause named: a joint of larger chi is an Iwan element
// (any chi > -1) the range left out, and may be what the data ask for; only a wider range tells.
// An SDOF joint at chi 0.3 (three 40-point hits to 1.0-1.5 phi_max, 1e-4 / 2 % noise) fitted in
// the default range (chi at most 0) ended at chi 0, reduced chi-square 1720, with "the
// structure's own damping ... or another mode slipping the same joint" named alone and chi's
// bound line "a wider range would not cure that"; with --chi-range -0.9:0.9 it fits at reduced
// chi-square 1.08, chi 0.3018 +/- 0.23 %.
std::string larger_chi_possibility(const IwanUpdateSummary& s, const std::string& cause) {
  if (cause.empty() || s.held[2] || !(s.bound_side[2] > 0) ||
      cause.find(iwan_detail::kLargerChiWords) != std::string::npos)
    return "";
  return fmt::format(
      ". Or a joint of chi above its upper bound {:g}, which the range left out (any chi > -1 is "
      "an Iwan element; the default range stops at 0, a Coulomb interface's): refit with a wider "
      "--chi-range to tell",
      s.best.chi);
}

// What the residuals at s.best point at (IwanUpdateSummary::misfit_cause()), read as if s.best
// were the best fit, with a joint of larger chi beside where chi ran to its upper bound.
std::string residual_cause(const IwanUpdateSummary& s) {
  const std::string c = named_cause(s);
  return c + larger_chi_possibility(s, c);
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

}  // namespace jointlab::correlate
