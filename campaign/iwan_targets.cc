#include "jointlab/campaign/iwan_targets.h"

#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "jointlab/campaign/steps/numeric_table.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/mode_interference.h"
#include "jointlab/model/joint_condensation.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;
using correlate::IwanTarget;
using correlate::MeasuredBackbone;
using correlate::ModeSlip;

namespace {

// Each mode's joint-slip pattern seen at a sensor, computed once per (mode, sensor).
class SlipPatterns {
 public:
  SlipPatterns(const model::Model& m, const std::vector<correlate::Sensor>& sensors,
               const std::vector<ModeBackbones>& modes, int power)
      : model_(m), jc_(m), sensors_(sensors), modes_(modes), power_(power) {}
  const ModeSlip& at(size_t mode, int sensor) {
    const auto key = std::make_pair(mode, sensor);
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    ModeSlip s;
    const int mm = modes_[mode].model_mode;
    if (mm > 0 && mm <= jc_.elastic_count())
      s = correlate::mode_slip(model_, jc_.modes(), mm, sensors_[static_cast<size_t>(sensor)].dof,
                               power_);
    return cache_.emplace(key, std::move(s)).first->second;
  }

 private:
  const model::Model& model_;
  const model::JointCondensation jc_;
  const std::vector<correlate::Sensor>& sensors_;
  const std::vector<ModeBackbones>& modes_;
  int power_;
  std::map<std::pair<size_t, int>, ModeSlip> cache_;
};

// Curves a bin needs for its standard deviation to weigh the points in it.
constexpr int kSpreadCurves = 3;

// sigma of frequency or damping in the scatter bin holding amplitude a (bins of at least
// kSpreadCurves curves), else -1: not known there.
double bin_std(const ScatterSummary& s, double a, bool frequency) {
  for (const ScatterBin& b : s.bins) {
    if (a >= b.amplitude_low && a < b.amplitude_high && b.curves >= kSpreadCurves)
      return frequency ? b.frequency_hz.std : b.damping.std;
  }
  return -1.0;
}

// Point i's own uncertainty on curve c, one sigma (k sigma as written over the curve's k), or 0
// where not known. (Read as one sigma, process's k = 3 weighed these points a third as much as
// the bins' one-sigma scatter beside them.)
double own_std(const ModeBackbones& mode, bool frequency, size_t c, Eigen::Index i) {
  const std::vector<Eigen::VectorXd>& stds = frequency ? mode.frequency_std_hz : mode.damping_std;
  if (c >= stds.size() || i >= stds[c].size()) return 0.0;
  const double k = c < mode.coverage.size() ? mode.coverage[c] : 1.0;
  return stds[c](i) / k;
}

bool flagged(const ScatterSummary& s, const std::string& id) {
  return std::any_of(s.hits.begin(), s.hits.end(),
                     [&](const HitDeviation& d) { return d.outlier && d.id == id; });
}

// Other modes' share of the joint slip at each point of curve c of mode k.
Eigen::VectorXd share_of_others(const std::vector<ModeBackbones>& modes, size_t k, size_t c,
                                SlipPatterns& slips) {
  const Curve& own = modes[k].curves[c];
  std::vector<ModeSlip> pattern(modes.size());
  std::vector<const Curve*> same_hit(modes.size(), nullptr);
  for (size_t j = 0; j < modes.size(); ++j) {
    if (j == k) {
      same_hit[j] = &own;
      pattern[j] = slips.at(k, modes[k].sensors[c]);
      continue;
    }
    for (size_t i = 0; i < modes[j].curves.size(); ++i) {
      const Curve& o = modes[j].curves[i];
      if (o.id != own.id || o.time_s.size() == 0) continue;
      same_hit[j] = &o;
      pattern[j] = slips.at(j, modes[j].sensors[i]);
      break;
    }
  }
  return correlate::slip_share(pattern, same_hit, k);
}

}  // namespace

std::string IwanTargets::screen_report(const std::vector<ModeBackbones>& modes) const {
  std::string out;
  for (size_t k = 0; k < modes.size() && k < points_screened.size(); ++k) {
    if (!modes[k].fitted || modes[k].model_mode <= 0) continue;
    const auto [points, left_out] = points_screened[k];
    out += fmt::format("  {}: {} of {} points left out where other modes carry the joint slip{}\n",
                       modes[k].name, left_out, points, hits_screened_out_text(k));
  }
  return out;
}

std::string IwanTargets::screened_out(const std::vector<ModeBackbones>& modes,
                                      double max_slip_share) const {
  if (!fitted.empty() || screened == 0) return "";
  std::string per_mode;
  for (size_t k = 0; k < modes.size() && k < points_screened.size(); ++k) {
    per_mode += fmt::format("{}{}: {} of {}", per_mode.empty() ? "" : ", ", modes[k].name,
                            points_screened[k].second, points_screened[k].first);
  }
  // Not "fit the modes one at a time", as this said before: a mode's backbone whose joint slip
  // comes from other modes is not described by its one-mode QSMA curve, and a fit of it alone
  // takes that slip as its own (a lap joint struck at the rivets: F_S 21 % off, z -13).
  return fmt::format(
      "the slip screen leaves no backbone of at least two points: every point where other "
      "modes carry over {:g} % of the joint slip is left out ({}); in these hits the joints "
      "slip mostly through other modes, which no one-mode QSMA curve describes (fitting the "
      "modes one at a time would take that slip as theirs): strike where the fitted modes "
      "dominate the joint slip",
      100 * max_slip_share, per_mode);
}

std::string IwanTargets::hits_screened_out_text(size_t k) const {
  if (k >= hits_screened_out.size() || hits_screened_out[k].empty()) return "";
  const std::vector<std::string>& hits = hits_screened_out[k];
  std::string names;
  for (size_t i = 0; i < hits.size(); ++i)
    names += (i == 0 ? "" : i + 1 == hits.size() ? " and " : ", ") + hits[i];
  return fmt::format("; every point but at most one of {}, so {} left out of the fit", names,
                     hits.size() == 1 ? "that hit is" : "those hits are");
}

size_t IwanTargets::curves() const {
  size_t n = 0;
  for (const IwanTarget& t : fitted) n += t.curves.size();
  return n;
}

IwanTargets iwan_targets(const model::Model& m, const std::vector<correlate::Sensor>& sensors,
                         const std::vector<ModeBackbones>& modes, const IwanTargetOptions& o) {
  for (const ModeBackbones& mb : modes) {
    if (mb.sensors.size() != mb.curves.size())
      throw InputError(fmt::format("{}: one sensor per backbone expected", mb.name));
    for (const int s : mb.sensors)
      if (s < 0 || s >= static_cast<int>(sensors.size()))
        throw InputError(fmt::format("{}: sensor index {} out of range", mb.name, s));
  }
  SlipPatterns slips(m, sensors, modes, correlate::amplitude_power(o.amplitude));
  IwanTargets out;
  out.points_screened.assign(modes.size(), {0, 0});
  out.hits_screened_out.assign(modes.size(), {});
  for (size_t k = 0; k < modes.size(); ++k) {
    const ModeBackbones& mode = modes[k];
    if (mode.model_mode <= 0) continue;
    IwanTarget t;
    t.mode = mode.model_mode;
    t.linear_frequency_hz = mode.linear_frequency_hz;
    for (size_t c = 0; c < mode.curves.size(); ++c) {
      const Curve& cv = mode.curves[c];
      if (mode.scatter.options.exclude_outliers && flagged(mode.scatter, cv.id)) continue;
      const correlate::BackboneKind kind =
          c < mode.kinds.size() ? mode.kinds[c] : correlate::BackboneKind::kRingdown;
      const Eigen::VectorXd share = kind == correlate::BackboneKind::kSteppedSine
                                        ? Eigen::VectorXd::Zero(cv.amplitude.size())
                                        : share_of_others(modes, k, c, slips);
      std::vector<Eigen::Index> keep;
      for (Eigen::Index j = 0; j < cv.amplitude.size(); ++j)
        if (!mode.fitted || share(j) <= o.max_slip_share) keep.push_back(j);
      const Eigen::Index left_out = cv.amplitude.size() - static_cast<Eigen::Index>(keep.size());
      out.screened += left_out;
      out.points_screened[k].first += cv.amplitude.size();
      out.points_screened[k].second += left_out;
      if (keep.size() < 2) {
        // A backbone the screen emptied is named, not only counted in "6 curves": the 0.4 m
        // beam's mode 1 lost 3 of its 9 hits to the screen without a word.
        if (left_out > 0 && cv.amplitude.size() >= 2) out.hits_screened_out[k].push_back(cv.id);
        continue;
      }
      const Eigen::Index n = static_cast<Eigen::Index>(keep.size());
      MeasuredBackbone mb = correlate::sized_backbone(kind, mode.sensors[c], n);
      mb.source = cv.id;  // the hit, as the report names a curve apart ("curve 7" before)
      for (Eigen::Index j = 0; j < n; ++j) {
        const Eigen::Index i = keep[static_cast<size_t>(j)];
        mb.amplitude(j) = cv.amplitude(i);
        mb.frequency_hz(j) = cv.frequency_hz(i);
        mb.damping_ratio(j) = cv.damping(i);
        const double bf = bin_std(mode.scatter, cv.amplitude(i), true);
        const double bz = bin_std(mode.scatter, cv.amplitude(i), false);
        mb.frequency_std_hz(j) = bf >= 0 ? bf : own_std(mode, true, c, i);
        mb.damping_std(j) = bz >= 0 ? bz : own_std(mode, false, c, i);
      }
      t.curves.push_back(std::move(mb));
    }
    if (t.curves.empty()) continue;
    out.every.emplace_back(k, t);
    if (mode.fitted) out.fitted.push_back(std::move(t));
  }
  return out;
}

ModeBackbones process_run_backbones(const data::ProcessRun& run,
                                    const std::vector<correlate::Sensor>& sensors, int band,
                                    const std::vector<std::string>& channels,
                                    const ScatterOptions& scatter) {
  ModeBackbones mb;
  mb.name = fmt::format("band {}", band);
  // Without a chosen channel, one for every hit (band_channel): the scatter summary below
  // compares the hits' curves point by point, which curves read at two channels (one amplitude
  // the mode shape's ratio times the other's) cannot be. The example campaign's low_hit1, its
  // band 1 read at acc_9001_z where the other 8 hits named acc_9003_z, was flagged an outlier of
  // them and left out of the fit without a word.
  for (const correlate::BandOutput& b :
       correlate::band_outputs(run, sensors, band, channels, &mb.channel_note)) {
    BackboneFile bf = read_backbone_file(run.dir / b.output->file,
                                         fs::path(b.output->source).stem().string(), "");
    mb.curves.push_back(std::move(bf.curve));
    mb.frequency_std_hz.push_back(std::move(bf.frequency_std_hz));
    mb.damping_std.push_back(std::move(bf.damping_std));
    mb.coverage.push_back(bf.coverage_factor);
    mb.sensors.push_back(b.sensor);
  }
  mb.scatter = summarize_scatter(mb.curves, scatter);
  return mb;
}

ModeBackbones stepped_sine_run_backbones(const data::SteppedSineRun& run, int sensor,
                                         const ScatterOptions& scatter) {
  ModeBackbones mb;
  mb.name = "stepped sine";
  for (const data::SteppedSineOutput& o : run.outputs) {
    if (o.file.empty()) continue;
    const data::BackboneTable b = data::read_process_backbone(run.dir / o.file);
    if (b.size() == 0) throw InputError(where(b.source, 0, "no backbone point"));
    Curve cv;
    cv.id = fs::path(o.source).stem().string();
    cv.amplitude = b.amplitude;
    cv.frequency_hz = b.frequency_hz;
    cv.damping = b.damping_ratio;
    mb.curves.push_back(std::move(cv));
    mb.frequency_std_hz.push_back(b.frequency_std_hz);
    mb.damping_std.push_back(b.damping_std);
    mb.coverage.push_back(run.coverage_factor);  // the run's k (its summary.json)
    mb.sensors.push_back(sensor);
    mb.kinds.push_back(correlate::BackboneKind::kSteppedSine);
  }
  if (mb.curves.empty()) {
    throw InputError(fmt::format("{}: no file gave a stepped-sine backbone",
                                 (run.dir / "summary.json").string()));
  }
  mb.scatter = summarize_scatter(mb.curves, scatter);
  return mb;
}

}  // namespace jointlab::campaign
