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
// Outputs appear as a set (data/output_stage.h): everything is written into a staging folder
// in OUT and committed at the end, so a run that fails or is killed leaves OUT's previous
// results as they were; a run that ends with hits left out (a test file that cannot be read
// or processed) or modes without a backbone still commits.
// Restart: the model and each hit are recomputed only when missing or when their stamp (the
// content of their input file, every setting they depend on and the program's version,
// steps/stamp.h) differs; everything after them is cheap and always rewritten. Before any hit
// is processed the whole campaign is checked (update settings, model, DOFs, model modes,
// element sets). QSMA amplitudes are converted to the measured quantity at the
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
  /// Called often during the model's build (each step of its fixed-interface eigen-solve) and
  /// the linear and Iwan updates, also from worker threads (so thread-safe); it may throw to stop
  /// the run (the Python module's Ctrl-C). May be empty.
  std::function<void()> interrupt;
};

/// A hit that could not be read or processed: left out of the run and named in its report.
struct FailedHit {
  std::filesystem::path file;  ///< the test file
  std::string group;           ///< its group's name
  std::string why;             ///< what is wrong with it (one line)
  /// "<file>: <why>".
  std::string text() const;
};

/// What run_campaign() did.
struct RunSummary {
  int hits = 0;                           ///< hits in the campaign
  int hits_processed = 0;                 ///< hits processed in this run
  int hits_reused = 0;                    ///< hits whose outputs were up to date
  std::vector<FailedHit> failed_hits;     ///< hits left out: unreadable or unprocessable
  bool model_built = false;               ///< the model was built in this run
  bool model_reused = false;              ///< the built model was up to date
  int flagged_hits = 0;                   ///< hits flagged in any mode
  std::vector<std::string> notes;         ///< skipped steps and other remarks
  std::vector<std::string> refused;       ///< updates that refused their data (also in notes)
  std::vector<std::string> stopped;       ///< steps not run after a result unfit for them: why
  std::vector<std::string> no_backbone;   ///< modes no hit gave a backbone for (report: why)
  std::filesystem::path report_html;      ///< the HTML report
  std::filesystem::path report_markdown;  ///< the Markdown report
  /// A few lines for a person.
  std::string report() const;
};

/// Runs the whole campaign into options.out; InputError for bad input (the campaign, its
/// model, DOFs, bands), and then the previous results stay as they were. A hit that cannot be
/// read or processed and a mode no hit gives a backbone for are no error here: everything
/// else is written, the report says so at its top and RunSummary::failed_hits and
/// RunSummary::no_backbone list them.
RunSummary run_campaign(const Campaign& campaign, const RunOptions& options);

}  // namespace jointlab::campaign
