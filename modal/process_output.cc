#include "jointlab/modal/process_output.h"

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/json_writer.h"
#include "jointlab/data/names.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/modal/summary_json.h"

namespace jointlab::modal {

std::string backbone_file_name(const std::string& source, const std::string& channel, int band) {
  return data::file_name_part(std::filesystem::path(source).stem().string()) + "." +
         data::file_name_part(channel) + ".band" + std::to_string(band) + ".csv";
}

data::Table backbone_table(const Backbone& b, const RingdownOptions& options) {
  data::Table t;
  t.add_exact("time_s", b.time_s);  // full precision: a Unix-time record keeps its steps
  t.add("amplitude", b.amplitude);
  t.add("frequency_hz", b.frequency_hz);
  t.add("damping_ratio", b.damping);
  t.add("frequency_std_hz", b.frequency_std_hz);
  t.add("damping_std", b.damping_std);
  t.add("damped_frequency_hz", b.damped_frequency_hz);
  t.add("decay_rate_1_per_s", b.decay_rate);
  t.add("displacement_m", b.displacement);
  t.add("snr", b.snr);
  t.add("window_s", b.window_s);
  t.add("harmonic", b.harmonic.cast<double>());
  t.add("exchange", b.exchange.cast<double>());
  // The k of the *_std columns, named in the header row itself: a comment line above it
  // would become the header of readers that take the first line (numpy, pandas).
  t.add("coverage_factor", Eigen::VectorXd::Constant(b.size(), options.coverage_factor));
  return t;
}

void write_backbones(const std::filesystem::path& dir, const RecordResult& result,
                     const RingdownOptions& options) {
  for (const ChannelBand& r : result.results) {
    if (r.ringdown.summary.status != RingdownStatus::kOk) continue;
    const data::Table t = backbone_table(r.ringdown.backbone, options);
    const std::string name = backbone_file_name(result.source, r.channel, r.band_index);
    if (name.size() > data::kMaxFileNameBytes) {
      throw InputError(fmt::format(
          "{}: channel '{}' band {}: its output file name would be {} bytes ('{}...'), more "
          "than the {} a file name may have; shorten the file's or the channel's name",
          result.source, printable(r.channel), r.band_index, name.size(), printable(name),
          data::kMaxFileNameBytes));
    }
    data::write_table(dir / name, t);
  }
}

namespace {

// The linear values: a straight-line fit of the backbone's lower half evaluated at its
// lowest amplitude (linear_reference_amplitude), its expanded uncertainty and the amplitudes
// the fit spans.
void write_linear(data::JsonWriter& j, const RingdownSummary& s) {
  if (!s.linear_reason.empty()) {  // absent with its reason, never 0 standing in for "none"
    j.key("linear_reason").value(s.linear_reason);
    return;
  }
  j.numbers({{"linear_frequency_hz", s.linear_frequency_hz},
             {"linear_frequency_std_hz", s.linear_frequency_std_hz},
             {"linear_damping_ratio", s.linear_damping},
             {"linear_damping_std", s.linear_damping_std},
             {"linear_reference_amplitude", s.linear_fit_min},
             {"linear_fit_amplitude_min", s.linear_fit_min},
             {"linear_fit_amplitude_max", s.linear_fit_max}});
}

// One record's entry of "files": its bands (with linear values and operating shape) and outputs.
void write_record(data::JsonWriter& j, const RecordResult& rec) {
  j.key("file").value(rec.source);
  j.key("bands").begin_array();
  for (size_t b = 0; b < rec.bands.size(); ++b) {
    j.begin_object();
    j.key("band").value(static_cast<int>(b) + 1);
    j.key("low_hz").value(rec.bands[b].lo);
    j.key("high_hz").value(rec.bands[b].hi);
    j.key("reference_channel").value(rec.reference[b]);
    // The reference channel's low-amplitude values are the band's linear modal data.
    for (const ChannelBand& r : rec.results) {
      if (r.band_index != static_cast<int>(b) + 1 || r.channel != rec.reference[b]) continue;
      const RingdownSummary& s = r.ringdown.summary;
      if (s.status == RingdownStatus::kOk) write_linear(j, s);
    }
    // A band with a backbone at no channel says why (its reference channel's reason), and has
    // no shape: its entries are absent, never 0 standing in for "none".
    const std::string why = band_without_backbone(rec, static_cast<int>(b) + 1);
    if (!why.empty()) j.key("reason").value(why);
    j.key("operating_shape").begin_array();
    for (const ChannelBand& r : rec.results) {
      if (r.band_index != static_cast<int>(b) + 1 || !why.empty()) continue;
      j.begin_object();
      j.key("channel").value(r.channel);
      j.key("real_m").value(r.complex_amplitude.real());
      j.key("imag_m").value(r.complex_amplitude.imag());
      j.end_object();
    }
    j.end_array();
    j.end_object();
  }
  j.end_array();
  // --modes: the spectral peaks left out, and why (only where some were).
  if (!rec.left_out.empty()) {
    j.key("left_out_peaks").begin_array();
    for (const LeftOutPeak& p : rec.left_out) {
      j.begin_object();
      j.key("frequency_hz").value(p.frequency_hz);
      j.key("low_hz").value(p.band.lo);
      j.key("high_hz").value(p.band.hi);
      j.key("reason").value(p.reason);
      j.end_object();
    }
    j.end_array();
  }
  j.key("outputs").begin_array();
  for (const ChannelBand& r : rec.results) {
    const RingdownSummary& s = r.ringdown.summary;
    j.begin_object();
    j.key("channel").value(r.channel);
    j.key("measured_quantity").value(quantity_name(r.measured));
    j.key("band").value(r.band_index);
    j.key("noise_floor_m").value(s.noise_floor_m);
    if (s.status == RingdownStatus::kOk) {
      j.key("file").value(backbone_file_name(rec.source, r.channel, r.band_index));
      j.key("points").value(static_cast<long>(r.ringdown.backbone.size()));
      j.key("span_start_s").value(s.span_start_s);
      j.key("span_end_s").value(s.span_end_s);
      j.key("amplitude_decades").value(s.amplitude_decades);
      write_linear(j, s);
      j.key("superharmonic_points").value(s.superharmonic_points);
      // Only where a mode exchanges energy (a rare record): the summaries of others stay as
      // they were.
      if (s.exchange_points > 0) j.key("exchange_points").value(s.exchange_points);
      if (!s.message.empty()) j.key("note").value(s.message);
    } else {
      j.key("file").null();
      j.key("reason").value(s.message);
    }
    j.end_object();
  }
  j.end_array();
}

}  // namespace

void write_summary(const std::filesystem::path& dir, const std::vector<RecordResult>& results,
                   const ProcessOptions& options) {
  const RingdownOptions& o = options.ringdown;
  write_summary_json(
      dir,
      [&](data::JsonWriter& j) {
        j.key("program").value("jointlab process");
        j.key("method").value(o.method == Method::kHilbert ? "hilbert" : "pff");
        write_amplitude_keys(j, o.amplitude, o.coverage_factor);
      },
      results.size(), [&](data::JsonWriter& j, size_t i) { write_record(j, results[i]); });
}

}  // namespace jointlab::modal
