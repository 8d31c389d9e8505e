// Running a test campaign end to end (docs/run.md): the model, every hit, the scatter
// summaries, QSMA of the model's modes, the updates, the figures and the report.
//
// Output directory OUT:
//   model/                       the reduced model (when the campaign gives a description)
//   hits/<group>/                each hit's backbones <stem>.<channel>.band<k>.csv and its
//                                linear data <stem>.linear.csv (band, channel index, linear
//                                frequency [Hz] and damping, complex amplitude [m])
//   scatter/mode<k>.{bins.csv,hits.csv,json}   scatter summaries (scatter.h)
//   qsma/mode<k>.start.csv, mode<k>.updated.csv  model curves in the measured amplitude
//   figures/*.png                spectrum, backbones per mode, MAC, frequency errors
//   report.html, report.md       the report (report.h)
// Restart: the model and each hit are recomputed only when missing or older than their
// inputs (the description or test file, and the campaign file); everything after them is
// cheap and always rewritten. QSMA amplitudes are converted to the measured quantity at the
// reference channel: displacement x = |phi_r[d]| q, velocity omega x, acceleration omega^2 x,
// omega = 2 pi f(q) along the curve.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "jointlab/campaign/campaign.h"

namespace jointlab::campaign {

/// Settings of run_campaign().
struct RunOptions {
  std::filesystem::path out;                         ///< output directory (created)
  bool force = false;                                ///< recompute even up-to-date outputs
  unsigned threads = 0;                              ///< workers for the hits; 0: every core
  std::function<void(const std::string&)> progress;  ///< one line per step (may be empty)
};

/// What run_campaign() did.
struct RunSummary {
  int hits = 0;                           ///< hits in the campaign
  int hits_processed = 0;                 ///< hits processed in this run
  int hits_reused = 0;                    ///< hits whose outputs were up to date
  bool model_built = false;               ///< the model was built in this run
  bool model_reused = false;              ///< the built model was up to date
  int flagged_hits = 0;                   ///< hits flagged in any mode
  std::vector<std::string> notes;         ///< skipped steps and other remarks
  std::filesystem::path report_html;      ///< the HTML report
  std::filesystem::path report_markdown;  ///< the Markdown report
  /// A few lines for a person.
  std::string report() const;
};

/// True when `output` exists and is newer than every input (missing inputs are ignored).
bool up_to_date(const std::filesystem::path& output,
                const std::vector<std::filesystem::path>& inputs);

/// Runs the whole campaign into options.out; InputError for bad input (files, DOFs, bands).
RunSummary run_campaign(const Campaign& campaign, const RunOptions& options);

}  // namespace jointlab::campaign
