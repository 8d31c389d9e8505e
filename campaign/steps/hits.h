// Step "process hits" of a campaign run (method.md Figure 1, test side): every test file of
// every group is processed with the library of `jointlab process` (the campaign's bands and
// channels) into OUT/hits/<group>/, then read back. A hit is recomputed only when its cache
// is missing or its stamp (<stem>.stamp, stamp.h: the test file's content, hit_settings()
// and the program's version) differs. A test file that cannot be read or processed (an
// InputError about that file) does not stop the run: its hit is left out, with the error as
// the reason of its every band and channel, and is tried again by the next run.
//
// Cache of one hit: the backbones <stem>.<channel>.band<k>.csv (modal/process_output.h),
// <stem>.reasons.txt (one line "<band> <channel index> <why there is no backbone>" per band
// and channel without one) and <stem>.linear.csv (band, channel index, ok, linear frequency
// [Hz] and damping, complex amplitude [m], kept span start and end [s] and its decades).
#pragma once

#include <complex>
#include <filesystem>
#include <string>
#include <vector>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/correlate/curve.h"
#include "jointlab/signal/band_analytic.h"

namespace jointlab::campaign {

/// One hit's linear data of one band at one channel.
struct LinearEntry {
  bool ok = false;                 ///< the band gave a backbone at this channel
  double frequency_hz = 0;         ///< linear frequency [Hz]
  double damping = 0;              ///< linear damping ratio
  std::complex<double> amplitude;  ///< complex amplitude (operating shape entry) [m]
  double span_start_s = 0;         ///< first kept point [s] (when ok)
  double span_end_s = 0;           ///< last kept point [s] (when ok)
  double decades = 0;              ///< decades of amplitude kept (when ok)
  std::string reason;              ///< why there is no backbone (when not ok)
  bool has_linear = false;         ///< frequency_hz and damping were measured (else absent)
};

/// Each point's own uncertainty as `process` reports it (empty: unknown).
struct PointStd {
  Eigen::VectorXd frequency_hz;  ///< k sigma [Hz], as process writes it
  Eigen::VectorXd damping;       ///< k sigma of the damping ratio
  double coverage = 1.0;         ///< k (the backbone file's coverage_factor)
};

/// Everything a run knows about one hit.
struct HitData {
  std::string group;                                  ///< its group's name
  std::string stem;                                   ///< the test file's stem (the hit's id)
  std::filesystem::path file;                         ///< the test file
  std::vector<std::vector<LinearEntry>> linear;       ///< [band][channel]
  std::vector<std::vector<correlate::Curve>> curves;  ///< [band][channel]; empty: none
  std::vector<std::vector<PointStd>> point_std;       ///< [band][channel]: each point's own
};

/// The folder of a group's hits under the run's output folder.
std::filesystem::path hit_dir(const std::filesystem::path& out, const std::string& group);

/// Processes one test file with the campaign's settings and writes its cache into `dir`.
/// Returns "" or, when the file cannot be read or processed, why (one line, naming the file),
/// its cache then that of a hit without a backbone at any band and channel for that reason,
/// without its earlier backbones and stamp. InputError for the campaign's settings or a cache
/// that cannot be written. `at_once`: how many hits are processed at the same time (said when
/// one runs out of memory).
std::string process_hit(const Campaign& campaign, const std::filesystem::path& file,
                        const std::filesystem::path& dir, signal::FftCache& cache,
                        size_t at_once = 1);

/// Reads one hit's cache from `dir`.
HitData load_hit(const Campaign& campaign, const CampaignGroup& group,
                 const std::filesystem::path& file, const std::filesystem::path& dir);

/// Every setting a hit's cache depends on, as text for its stamp (stamp.h): the bands, the
/// channels, what unit-less channels measure and the backbones' amplitude quantity.
std::string hit_settings(const Campaign& campaign);

/// The step: processes the hits whose cache is stale (in parallel), reads every hit back in
/// campaign order, counts processed and reused hits in `summary` and lists there the hits
/// that could not be read or processed (left out: no backbone, no stamp, tried again next run).
std::vector<HitData> process_hits(const Campaign& campaign, const std::filesystem::path& out,
                                  const RunOptions& options, RunSummary& summary);

}  // namespace jointlab::campaign
