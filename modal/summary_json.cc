#include "jointlab/modal/summary_json.h"

#include "jointlab/data/atomic_file.h"

namespace jointlab::modal {

void write_amplitude_keys(data::JsonWriter& j, Quantity amplitude, double coverage_factor) {
  j.key("amplitude_quantity").value(quantity_name(amplitude));
  j.key("amplitude_unit").value(si_unit(amplitude));
  // The *_std columns and values are expanded uncertainties: coverage_factor times sigma.
  j.key("coverage_factor").value(coverage_factor);
}

void write_summary_json(const std::filesystem::path& dir,
                        const std::function<void(data::JsonWriter&)>& header, std::size_t files,
                        const std::function<void(data::JsonWriter&, std::size_t)>& file) {
  data::JsonWriter j;
  j.begin_object();
  header(j);
  j.key("files").begin_array();
  for (std::size_t i = 0; i < files; ++i) {
    j.begin_object();
    file(j, i);
    j.end_object();
  }
  j.end_array();
  j.end_object();
  data::write_file_atomically(dir / "summary.json", j.str());
}

}  // namespace jointlab::modal
