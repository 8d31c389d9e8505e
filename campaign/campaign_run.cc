#include "jointlab/campaign/campaign_run.h"

#include <set>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/campaign/option_keys.h"
#include "jointlab/campaign/steps/campaign_figures.h"
#include "jointlab/campaign/steps/campaign_report.h"
#include "jointlab/campaign/steps/hits.h"
#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/campaign/steps/linear_step.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_results.h"
#include "jointlab/campaign/steps/model_side.h"
#include "jointlab/campaign/steps/validate.h"
#include "jointlab/core/error.h"
#include "jointlab/data/output_stage.h"
#include "jointlab/model/model_file_writer.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

std::string FailedHit::text() const { return fmt::format("{}: {}", file.string(), why); }

std::string RunSummary::report() const {
  std::string s =
      fmt::format("{} hit(s): {} processed, {} up to date", hits, hits_processed, hits_reused);
  if (!failed_hits.empty()) s += fmt::format(", {} left out", failed_hits.size());
  s += fmt::format("; {} flagged", flagged_hits);
  if (model_built) s += "; model built";
  if (model_reused) s += "; model up to date";
  for (const FailedHit& f : failed_hits) s += fmt::format("\n  left out: {}", f.text());
  for (const std::string& m : no_backbone) s += fmt::format("\n  {}: no backbone", m);
  // As the report says them: a campaign's settings by their keys, not the commands' options.
  for (const std::string& n : notes) s += "\n  note: " + with_campaign_keys(n);
  s +=
      fmt::format("\n  report: {}\n  markdown: {}", report_html.string(), report_markdown.string());
  return s;
}

namespace {

// The updated model as a model file with its matrices (DIR/updated/model.toml): what a second
// run, `simulate`, `compare` or `qsma` starts from, headed by what updated it and where the
// report says how far the data fix each value.
void write_updated_model(const Campaign& c, const ModelResults& r, const fs::path& path) {
  model::ModelFileComments comments;
  comments.header.push_back(fmt::format("The model `jointlab run` updated for the campaign {}:",
                                        c.file.filename().string()));
  if (r.linear.ran)
    comments.header.push_back(fmt::format("- [update.linear] sets {}{}",
                                          fmt::join(c.linear_update.sets, ", "),
                                          r.linear.note.empty() ? "" : " (see its note)"));
  if (r.iwan.ran)
    comments.header.push_back(fmt::format("- [update.iwan] set {}", r.iwan.set));
  else if (!r.iwan.note.empty())
    comments.header.push_back("- not the Iwan joints: [update.iwan] did not run (see the report)");
  comments.header.push_back(
      "report.md says how far the data fix each value (sigmas, flat or unidentified sets) and");
  comments.header.push_back("what it warns of; read it before using these values.");
  model::write_model_file(path, r.updated, {}, comments);
}

// The model side (method.md Figure 1, right): evaluate the model, update its linear
// stiffness, then its Iwan joints, and evaluate the updated model.
ModelResults model_side(const Campaign& c, CampaignModelData data, const MeasuredSide& measured,
                        const fs::path& out, const RunOptions& o, RunSummary& summary) {
  ModelResults r;
  r.data = std::move(data);
  r.start = evaluate_model(c, r.data.model, r.data.dofs, "model, start", out / "qsma", "start");
  r.linear = linear_update_step(c, r.data, measured.modes, o.progress, &measured, o.interrupt);
  if (!r.linear.note.empty()) summary.notes.push_back(r.linear.note);
  if (r.linear.refused) summary.refused.push_back("update.linear");
  // Not from a linear result that cannot carry it (pairs the shapes do not confirm): stopped.
  r.iwan = iwan_update_after(c, r.data, r.linear, measured, o.progress, o.interrupt);
  if (!r.iwan.note.empty()) summary.notes.push_back(r.iwan.note);
  if (r.iwan.refused) summary.refused.push_back("update.iwan");
  if (r.iwan.stopped) summary.stopped.push_back(r.iwan.note);
  if (r.iwan.ran && r.linear.ran &&
      r.linear.summary.status == correlate::LinearUpdateStatus::kPairsUnconfirmed) {
    summary.notes.push_back(
        "update.iwan: run from a linear update whose pairs the shapes do not confirm at its "
        "result, as accept_unconfirmed_pairs = true in [update.iwan] asks: the joint rests on "
        "those pairs");
  }
  r.have_updated = r.linear.ran || r.iwan.ran;
  if (r.have_updated) {
    r.updated = r.iwan.ran ? r.iwan.updated : r.linear.updated;
    r.after = evaluate_model(c, r.updated, r.data.dofs, "model, updated", out / "qsma", "updated");
    fs::create_directories(out / "updated");
    write_updated_model(c, r, out / "updated" / "model.toml");
  }
  return r;
}

// What `run` writes into its output folder (the staging folder replaces these as a set).
bool is_run_output(const std::string& name) {
  static const std::set<std::string> names{"model",   "hits",    "scatter",     "qsma",
                                           "updated", "figures", "report.html", "report.md"};
  return names.count(name) > 0;
}

// The previous run's model and hits, copied into the staging folder so that those whose
// stamps still match are reused (steps/stamp.h) without touching the previous results.
void carry_over(const fs::path& from, const fs::path& to) {
  for (const char* name : {"model", "hits"}) {
    if (!fs::is_directory(from / name)) continue;
    std::error_code ec;
    fs::copy(from / name, to / name, fs::copy_options::recursive, ec);
    if (ec) {
      // A full disk shows as ENOSPC or, through some file systems, as EIO: say which folder
      // ran out and by how much rather than "Input/output error".
      std::uintmax_t needed = 0;
      std::error_code walk;
      for (fs::recursive_directory_iterator it(from / name, walk), end; !walk && it != end;
           it.increment(walk)) {
        std::error_code size_ec;
        if (it->is_regular_file(size_ec)) needed += it->file_size(size_ec);
      }
      std::error_code space_ec;
      const fs::space_info space = fs::space(to, space_ec);
      if (ec == std::errc::no_space_on_device || (!space_ec && space.available < needed)) {
        throw InputError(where(from.string(), 0,
                               fmt::format("cannot copy the previous results ({}) for reuse: no "
                                           "space left on device ({} bytes free, {} needed)",
                                           name, space.available, needed)));
      }
      throw InputError(where(
          from.string(), 0,
          fmt::format("cannot copy the previous results ({}) for reuse: {}", name, ec.message())));
    }
  }
}

// The whole run into the staging folder `out` (final_out: where its outputs will be).
RunSummary run_staged(const Campaign& c, const RunOptions& o, const fs::path& out,
                      const fs::path& final_out) {
  RunSummary summary;
  summary.hits = c.hit_count();
  validate_settings(c);
  if (!o.force) carry_over(final_out, out);
  const fs::path model_file = prepare_model(c, out, o, summary);
  CampaignModelData model_data;
  if (!model_file.empty()) {
    if (o.progress) o.progress(fmt::format("model: reading {}", model_file.string()));
    model_data = validate_model(c, model_file);
    // The report names the model file where it will be.
    const fs::path rel = model_file.lexically_relative(out);
    if (!rel.empty() && *rel.begin() != "..") model_data.file = final_out / rel;
  }
  const std::vector<HitData> hits = process_hits(c, out, o, summary);
  const MeasuredSide measured = summarise_measured(c, hits, out / "scatter", o.progress);
  summary.flagged_hits = measured.flagged_hits;
  for (size_t k = 0; k < c.modes.size(); ++k)
    if (measured.curves[k].empty()) {
      summary.no_backbone.push_back(c.modes[k].name);
      summary.notes.push_back(fmt::format(
          "{}: no backbone in any hit; its steps are left out (the report's top says why){}",
          c.modes[k].name,
          measured.reference_hint[k].empty() ? "" : "; " + measured.reference_hint[k]));
    }
  ModelResults model;
  if (!model_file.empty()) model = model_side(c, std::move(model_data), measured, out, o, summary);
  const ModelResults* with_model = model_file.empty() ? nullptr : &model;
  if (o.progress) o.progress("figures: drawing");
  const CampaignFigures figures =
      draw_figures(c, measured, with_model, out / "figures", summary.failed_hits);
  const Report report = campaign_report(c, summary, measured, with_model, figures);
  write_report_html(report, out / "report.html");
  write_report_markdown(report, out / "report.md");
  return summary;
}

}  // namespace

RunSummary run_campaign(const Campaign& c, const RunOptions& o) {
  const fs::path final_out = fs::absolute(o.out);
  // Every output is written into a staging folder and committed as a set at the end: a run
  // that fails or is killed leaves the previous results as they were.
  data::OutputStage stage(final_out, "run", is_run_output);
  // Messages name files where they will be, not where they are staged.
  const auto shown = [&](std::string text) {
    const std::string from = stage.path().string(), to = final_out.string();
    for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
      text.replace(at, from.size(), to);
    return text;
  };
  RunOptions staged = o;
  if (o.progress) staged.progress = [&](const std::string& line) { o.progress(shown(line)); };
  RunSummary summary;
  try {
    summary = run_staged(c, staged, stage.path(), final_out);
  } catch (const InputError& e) {
    throw InputError(shown(e.what()));
  }
  stage.commit();
  summary.report_html = final_out / "report.html";
  summary.report_markdown = final_out / "report.md";
  return summary;
}

}  // namespace jointlab::campaign
