// libFuzzer target: the model file reader on arbitrary TOML, beside valid 3 x 3 matrices and
// DOF labels so that the fuzzer reaches the Iwan sets, springs and joints.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "jointlab/core/error.h"
#include "jointlab/model/model_file.h"

namespace {

void write_text(const std::filesystem::path& p, const std::string& text) {
  jointlab::fuzz::write_bytes(p, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto& dir = jointlab::fuzz::scratch();
  static const bool matrices = [&] {
    write_text(dir / "M.mtx",
               "%%MatrixMarket matrix coordinate real symmetric\n3 3 3\n1 1 1\n2 2 1\n3 3 1\n");
    write_text(dir / "K.mtx",
               "%%MatrixMarket matrix coordinate real symmetric\n3 3 5\n1 1 2e4\n2 1 -1e4\n"
               "2 2 2e4\n3 2 -1e4\n3 3 1e4\n");
    write_text(dir / "dofs.csv", "node,component\n1,3\n2,3\n3,3\n");
    return true;
  }();
  (void)matrices;
  jointlab::fuzz::write_bytes(dir / "model.toml", data, size);
  try {
    const jointlab::model::Model m = jointlab::model::read_model(dir / "model.toml");
    (void)m.linear_stiffness();
  } catch (const jointlab::InputError&) {
  }
  return 0;
}
