// run(): a whole campaign, as `jointlab run` (docs/python.md).
#include "binding.h"

#include <fmt/format.h>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"

namespace jointlab::python {
namespace {

// run: a whole campaign into `out`, as `jointlab run`; the summary as a dict. Hits that could
// not be processed and modes without a backbone are listed, not raised (everything else is
// written), as the library reports them.
py::dict run(const PathArg& campaign_arg, const PathArg& out_arg, bool force,
             const Integer& threads_arg, const py::object& progress) {
  check_progress(progress);
  const std::string campaign_file = text(campaign_arg), out = text(out_arg);
  const unsigned threads = threads_option(threads_arg);
  campaign::RunSummary s;
  InterruptCheck interrupted;  // made on the calling thread, the one that checks
  {
    py::gil_scoped_release release;
    const campaign::Campaign c = campaign::read_campaign(campaign_file);
    campaign::RunOptions o;
    o.out = out;
    o.force = force;
    o.threads = threads;
    o.progress = [&progress](const std::string& line) { report(progress, line); };
    o.interrupt = [&interrupted] { interrupted(); };
    s = campaign::run_campaign(c, o);
  }
  py::dict d;
  d["hits"] = s.hits;
  d["hits_processed"] = s.hits_processed;
  d["hits_reused"] = s.hits_reused;
  py::list failed;
  for (const campaign::FailedHit& f : s.failed_hits) failed.append(f.text());
  d["failed_hits"] = failed;
  d["flagged_hits"] = s.flagged_hits;
  // As the report's "model built" / "model up to date": built in this run, or reused.
  d["model_built"] = s.model_built;
  d["model_reused"] = s.model_reused;
  d["notes"] = s.notes;
  d["no_backbone"] = s.no_backbone;
  d["refused"] = s.refused;
  d["stopped"] = s.stopped;
  d["report_html"] = s.report_html.string();
  d["report_markdown"] = s.report_markdown.string();
  d["report"] = s.report();
  return d;
}

}  // namespace

void bind_run(py::module_& m) {
  m.def("run", &run, py::arg("campaign"), py::arg("out"), py::arg("force") = false,
        py::arg("threads") = 0, py::arg("progress") = py::none(),
        R"(Runs a test campaign (TOML, docs/campaign-file.md) into `out`, as `jointlab run`.

force     recompute even outputs that are up to date
threads   workers for the hits (0: every core)
progress  callable taking one line per step, or None (Ctrl-C: at the next step; building the
          model, at the next step of its eigen-solve)

Returns a dict: 'hits', 'hits_processed', 'hits_reused', 'failed_hits' (one line each),
'flagged_hits', 'model_built' (built in this run), 'model_reused' (the built
model up to date), 'notes', 'no_backbone' (modes no hit gave a backbone for), 'refused' (updates
that refused their data), 'stopped' (why a step was not run: the Iwan update after a linear
update whose pairs the shapes do not confirm), 'report_html', 'report_markdown', 'report'. Bad input (the campaign, its model, DOFs, bands) raises InputError.

    s = jointlab.run("campaign.toml", "out")
    print(s["report_html"])
)");
}

}  // namespace jointlab::python
