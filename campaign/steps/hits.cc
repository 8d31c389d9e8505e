#include "jointlab/campaign/steps/hits.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <new>
#include <optional>

#include <fmt/format.h>

#include "jointlab/campaign/steps/numeric_table.h"
#include "jointlab/campaign/steps/stamp.h"
#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/read_record.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/modal/process.h"
#include "jointlab/modal/process_output.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

fs::path hit_dir(const fs::path& out, const std::string& group) { return out / "hits" / group; }

namespace {

// The campaign's processing settings; a setting `process` refuses is the campaign's error.
modal::ProcessOptions process_options(const Campaign& c) {
  modal::ProcessOptions opt;
  for (const CampaignMode& m : c.modes) opt.bands.push_back(m.band);
  for (const CampaignChannel& ch : c.channels) opt.channels.push_back(ch.name);
  opt.quantity = c.quantity;
  opt.ringdown.amplitude = c.amplitude;
  if (const std::string why = opt.check(); !why.empty())
    throw InputError(fmt::format("{}: {}", c.file.string(), why));
  return opt;
}

// A band and channel of a hit without a backbone, for `why` (their cache row says so).
modal::ChannelBand without_backbone(int band, const std::string& channel, const std::string& why) {
  modal::ChannelBand cb;
  cb.channel = channel;
  cb.band_index = band;
  cb.ringdown.summary.message = why;
  cb.complex_amplitude = {std::numeric_limits<double>::quiet_NaN(), 0.0};
  return cb;
}

// Reads and processes one test file; InputError for whatever is wrong with it as a whole.
// A channel the file lacks (or that has no unit where the campaign gives no quantity), or a
// band past its Nyquist frequency, is left out of this hit alone with its reason: one bad
// mode or channel once dropped every hit for every mode. The rest is processed as it would
// be with the campaign's settings alone (bands one at a time only when together they fail).
modal::RecordResult analyse_hit(const Campaign& c, const modal::ProcessOptions& opt,
                                const fs::path& file, signal::FftCache& cache) {
  const data::Record rec = data::read_record(file);
  std::vector<std::pair<std::string, std::string>> lacking;  // channel, why
  modal::ProcessOptions kept = opt;
  kept.channels.clear();
  for (const CampaignChannel& ch : c.channels) {
    if (std::string why = modal::not_a_response(rec, ch.name); !why.empty()) {
      lacking.emplace_back(ch.name, std::move(why));
    } else if (!rec.find(ch.name)->quantity && !c.quantity) {
      // The rule of `process`: a channel without a unit measures what the campaign says, or
      // nothing can be assumed.
      lacking.emplace_back(
          ch.name,
          fmt::format("channel '{}' has no unit and the campaign gives no quantity: give its "
                      "unit in the header (e.g. '{} [m/s^2]', '{} [m/s]') or quantity = "
                      "\"acceleration\"|\"velocity\"|\"displacement\" in [campaign] of {}",
                      ch.name, ch.name, ch.name, c.file.string()));
    } else {
      kept.channels.push_back(ch.name);
    }
  }
  if (kept.channels.empty())
    throw InputError(fmt::format("{}: {}", file.string(), lacking.front().second));
  modal::RecordResult r;
  try {
    r = modal::process_record(rec, kept, cache);
  } catch (const InputError&) {
    if (kept.bands.size() < 2) throw;
    r = {};
    r.source = rec.source;
    r.bands = kept.bands;
    r.reference.assign(kept.bands.size(), "");
    std::string first;
    bool any = false;
    for (size_t b = 0; b < kept.bands.size(); ++b) {
      modal::ProcessOptions one = kept;
      one.bands = {kept.bands[b]};
      const int index = static_cast<int>(b) + 1;
      try {
        modal::RecordResult part = modal::process_record(rec, one, cache);
        any = true;
        r.reference[b] = part.reference.front();
        for (modal::ChannelBand& cb : part.results) {
          cb.band_index = index;
          r.results.push_back(std::move(cb));
        }
      } catch (const InputError& e) {
        if (first.empty()) first = e.what();
        // The hit's rows name the file: its reason without it.
        std::string why = e.what();
        if (const std::string name = file.string() + ": "; why.rfind(name, 0) == 0)
          why.erase(0, name.size());
        for (const std::string& ch : kept.channels)
          r.results.push_back(without_backbone(index, ch, why));
      }
    }
    if (!any) throw InputError(first);  // no band could be processed
  }
  for (const auto& [channel, why] : lacking)
    for (size_t b = 0; b < kept.bands.size(); ++b)
      r.results.push_back(without_backbone(static_cast<int>(b) + 1, channel, why));
  return r;
}

// `text` on one line.
std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\r', ' ');
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

// The linear data of a hit's cache, `n` rows to fill (columns: hits.h; the measured values
// start absent, the indices and shape at 0), and its reasons, one line
// "<band> <channel index> <why>" per band and channel without a backbone.
struct LinearColumns {
  explicit LinearColumns(Eigen::Index n)
      : band(Eigen::VectorXd::Zero(n)),
        chan(band),
        ok(band),
        f(Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN())),
        z(f),
        re(f),
        im(f),
        t0(f),
        t1(f),
        dec(f) {}
  Eigen::VectorXd band, chan, ok, f, z, re, im, t0, t1, dec;
  std::string reasons;

  // Writes <stem>.reasons.txt, then <stem>.linear.csv: its presence marks the hit as complete.
  void write(const fs::path& dir, const fs::path& file) const {
    data::write_file_atomically(dir / (file.stem().string() + ".reasons.txt"), reasons);
    data::Table t;
    // Values a channel did not measure are absent (empty cells), never 0 for "none".
    t.add({{"band", band}, {"channel", chan}, {"ok", ok}});
    t.add_optional("linear_frequency_hz", f);
    t.add_optional("linear_damping", z);
    t.add_optional("amplitude_re_m", re);
    t.add_optional("amplitude_im_m", im);
    t.add_optional("span_start_s", t0);
    t.add_optional("span_end_s", t1);
    t.add_optional("decades", dec);
    data::write_table(dir / (file.stem().string() + ".linear.csv"), t);
  }
};

// The cache of a processed hit.
void write_hit(const Campaign& c, const fs::path& file, const fs::path& dir,
               const modal::RecordResult& r, const modal::ProcessOptions& opt) {
  modal::write_backbones(dir, r, opt.ringdown);
  LinearColumns l(static_cast<Eigen::Index>(r.results.size()));
  for (Eigen::Index i = 0; i < l.band.size(); ++i) {
    const modal::ChannelBand& cb = r.results[i];
    l.band(i) = cb.band_index;
    for (size_t k = 0; k < c.channels.size(); ++k)
      if (c.channels[k].name == cb.channel) l.chan(i) = static_cast<double>(k);
    const modal::RingdownSummary& rs = cb.ringdown.summary;
    const bool good = rs.status == modal::RingdownStatus::kOk;
    constexpr double kAbsent = std::numeric_limits<double>::quiet_NaN();
    l.ok(i) = good;
    l.f(i) = rs.has_linear() ? rs.linear_frequency_hz : kAbsent;
    l.z(i) = rs.has_linear() ? rs.linear_damping : kAbsent;
    // A band with a backbone at no channel has no reference, so no shape: absent, not 0.
    const bool shape = std::isfinite(cb.complex_amplitude.real()) &&
                       std::isfinite(cb.complex_amplitude.imag()) &&
                       modal::band_without_backbone(r, cb.band_index).empty();
    l.re(i) = shape ? cb.complex_amplitude.real() : kAbsent;
    l.im(i) = shape ? cb.complex_amplitude.imag() : kAbsent;
    l.t0(i) = good ? rs.span_start_s : kAbsent;
    l.t1(i) = good ? rs.span_end_s : kAbsent;
    l.dec(i) = good ? rs.amplitude_decades : kAbsent;
    if (!good) {
      const std::string why = one_line(rs.message.empty() ? "no span kept" : rs.message);
      l.reasons += fmt::format("{} {} {}\n", cb.band_index, static_cast<int>(l.chan(i)), why);
    }
  }
  l.write(dir, file);
}

// The cache of a hit that could not be read or processed: no backbone at any band and
// channel, each for `why`; its earlier backbones and stamp go, so that nothing of an earlier
// run is read as this hit's and the hit is tried again by the next run.
void write_failed_hit(const Campaign& c, const fs::path& file, const fs::path& dir,
                      const std::string& why) {
  const size_t nb = c.modes.size(), nc = c.channels.size();
  std::vector<fs::path> stale{dir / (file.stem().string() + ".stamp")};
  for (size_t b = 0; b < nb; ++b)
    for (const CampaignChannel& ch : c.channels)
      stale.push_back(dir /
                      modal::backbone_file_name(file.string(), ch.name, static_cast<int>(b) + 1));
  for (const fs::path& p : stale) {
    std::error_code ec;
    fs::remove(p, ec);
    if (ec)
      throw InputError(where(p.string(), 0, "cannot remove an earlier result: " + ec.message()));
  }
  LinearColumns l(static_cast<Eigen::Index>(nb * nc));
  for (size_t b = 0; b < nb; ++b) {
    for (size_t ch = 0; ch < nc; ++ch) {
      const Eigen::Index i = static_cast<Eigen::Index>(b * nc + ch);
      l.band(i) = static_cast<double>(b + 1);
      l.chan(i) = static_cast<double>(ch);
      l.reasons += fmt::format("{} {} {}\n", b + 1, ch, why);
    }
  }
  l.write(dir, file);
}

// A hit left out for `message` (an InputError's, which names the file: "FILE:LINE: what" or
// "FILE: what"), its reason without the file's name.
FailedHit left_out(const fs::path& file, const std::string& group, const std::string& message) {
  FailedHit f{file, group, message};
  const std::string name = file.string() + ":";
  if (message.rfind(name, 0) != 0) return f;
  std::string why = message.substr(name.size());
  size_t digits = 0;
  while (digits < why.size() && std::isdigit(static_cast<unsigned char>(why[digits]))) ++digits;
  if (digits > 0 && digits < why.size() && why[digits] == ':')
    why = "line " + why.substr(0, digits) + why.substr(digits);
  const size_t text = why.find_first_not_of(' ');
  if (text != std::string::npos) f.why = why.substr(text);
  return f;
}

}  // namespace

std::string process_hit(const Campaign& c, const fs::path& file, const fs::path& dir,
                        signal::FftCache& cache, size_t at_once) {
  const modal::ProcessOptions opt = process_options(c);
  std::optional<modal::RecordResult> r;
  std::string why;
  try {
    r = analyse_hit(c, opt, file, cache);
  } catch (const InputError& e) {
    why = one_line(e.what());
  } catch (const std::bad_alloc&) {
    // Named and left out like any hit that cannot be processed.
    why = data::out_of_memory_message(file, at_once);
  }
  fs::create_directories(dir);
  if (r) {
    write_hit(c, file, dir, *r, opt);
  } else {
    write_failed_hit(c, file, dir, why);
  }
  return why;
}

HitData load_hit(const Campaign& c, const CampaignGroup& g, const fs::path& file,
                 const fs::path& dir) {
  HitData h;
  h.group = g.name;
  h.stem = file.stem().string();
  h.file = file;
  const size_t nb = c.modes.size(), nc = c.channels.size();
  h.linear.assign(nb, std::vector<LinearEntry>(nc));
  h.curves.assign(nb, std::vector<correlate::Curve>(nc));
  h.point_std.assign(nb, std::vector<PointStd>(nc));
  const fs::path lin = dir / (h.stem + ".linear.csv");
  const NumericTable t = read_numeric_table(lin, /*allow_empty=*/true);
  const auto& band = t.column("band", lin);
  const auto& chan = t.column("channel", lin);
  const auto& ok = t.column("ok", lin);
  const auto& f = t.column("linear_frequency_hz", lin);
  const auto& z = t.column("linear_damping", lin);
  const auto& re = t.column("amplitude_re_m", lin);
  const auto& im = t.column("amplitude_im_m", lin);
  const auto& t0 = t.column("span_start_s", lin);
  const auto& t1 = t.column("span_end_s", lin);
  const auto& dec = t.column("decades", lin);
  // Absent cells (NaN) stay out of every number: has_linear says whether f and z exist, and
  // an absent shape entry is 0 in memory (linear_modes() skips a zero reference).
  const auto or0 = [](double v) { return std::isnan(v) ? 0.0 : v; };
  for (size_t i = 0; i < band.size(); ++i) {
    if (!std::isfinite(band[i]) || !std::isfinite(chan[i]) || !std::isfinite(ok[i]))
      throw InputError(where(lin.string(), static_cast<long>(i) + 2,
                             "a required cell is empty (delete the file to recompute it)"));
    const int b = static_cast<int>(band[i]) - 1, ch = static_cast<int>(chan[i]);
    if (b < 0 || b >= static_cast<int>(nb) || ch < 0 || ch >= static_cast<int>(nc)) continue;
    LinearEntry& le = h.linear[b][ch];
    le = {ok[i] > 0.5, or0(f[i]),  or0(z[i]),   {or0(re[i]), or0(im[i])},
          or0(t0[i]),  or0(t1[i]), or0(dec[i]), ""};
    le.has_linear = ok[i] > 0.5 && std::isfinite(f[i]) && std::isfinite(z[i]);
  }
  std::ifstream reasons(dir / (h.stem + ".reasons.txt"));
  int rb = 0, rc = 0;
  std::string why;
  while (reasons >> rb >> rc && std::getline(reasons, why)) {
    if (rb < 1 || rb > static_cast<int>(nb) || rc < 0 || rc >= static_cast<int>(nc)) continue;
    h.linear[rb - 1][rc].reason = why.empty() ? why : why.substr(1);
  }
  for (size_t b = 0; b < nb; ++b) {
    for (size_t ch = 0; ch < nc; ++ch) {
      const LinearEntry& le = h.linear[b][ch];
      const fs::path p = dir / modal::backbone_file_name(file.string(), c.channels[ch].name,
                                                         static_cast<int>(b) + 1);
      correlate::Curve& cv = h.curves[b][ch];
      if (le.ok && fs::exists(p)) {
        BackboneFile bf = read_backbone_file(p, h.stem, g.name);
        cv = std::move(bf.curve);
        h.point_std[b][ch] = {std::move(bf.frequency_std_hz), std::move(bf.damping_std),
                              bf.coverage_factor};
      }
      cv.id = h.stem;
      cv.group = g.name;
      cv.has_linear = le.has_linear;
      cv.linear_frequency_hz = le.frequency_hz;
      cv.linear_damping = le.damping;
    }
  }
  return h;
}

std::string hit_settings(const Campaign& c) {
  std::string s =
      fmt::format("quantity {} amplitude {};", c.quantity ? quantity_name(*c.quantity) : "none",
                  quantity_name(c.amplitude));
  for (const CampaignMode& m : c.modes)
    s += fmt::format(" band {:.17g}:{:.17g};", m.band.lo, m.band.hi);
  for (const CampaignChannel& ch : c.channels) s += fmt::format(" channel '{}';", ch.name);
  return s;
}

std::vector<HitData> process_hits(const Campaign& c, const fs::path& out, const RunOptions& o,
                                  RunSummary& summary) {
  struct Job {
    const CampaignGroup* group;
    fs::path file;
  };
  std::vector<Job> jobs;
  std::vector<size_t> todo;
  for (const CampaignGroup& g : c.groups)
    for (const fs::path& f : g.files) jobs.push_back({&g, f});
  const std::string settings = hit_settings(c);
  std::vector<std::string> stamps;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const Job& j = jobs[i];
    const fs::path marker = hit_dir(out, j.group->name) / (j.file.stem().string() + ".stamp");
    stamps.push_back(input_stamp({j.file}, settings));
    if (!o.force && stamp_matches(marker, stamps.back())) {
      ++summary.hits_reused;
    } else {
      todo.push_back(i);
    }
  }
  const auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  if (!todo.empty()) {
    process_options(c);  // the campaign's own settings are refused before any hit
    say(fmt::format("process: {} hit(s) to process, {} up to date", todo.size(),
                    summary.hits_reused));
    // Each job owns its entry: why its hit could not be read or processed (empty: it was).
    std::vector<std::string> failed(todo.size());
    const size_t at_once = std::min<size_t>(todo.size(), threads_or_cores(o.threads));
    parallel_for(
        todo.size(), o.threads, [] { return signal::FftCache{}; },
        [&](size_t i, signal::FftCache& cache) {
          const Job& j = jobs[todo[i]];
          const fs::path dir = hit_dir(out, j.group->name);
          failed[i] = process_hit(c, j.file, dir, cache, at_once);
          if (failed[i].empty())
            write_stamp(dir / (j.file.stem().string() + ".stamp"), stamps[todo[i]]);
        });
    for (size_t i = 0; i < todo.size(); ++i) {
      if (failed[i].empty()) {
        ++summary.hits_processed;
        continue;
      }
      const Job& j = jobs[todo[i]];
      summary.failed_hits.push_back(left_out(j.file, j.group->name, failed[i]));
      say(fmt::format("process: {}; the hit is left out", summary.failed_hits.back().text()));
    }
  } else {
    say(fmt::format("process: all {} hit(s) up to date", jobs.size()));
  }
  std::vector<HitData> hits;
  for (const Job& j : jobs)
    hits.push_back(load_hit(c, *j.group, j.file, hit_dir(out, j.group->name)));
  return hits;
}

}  // namespace jointlab::campaign
