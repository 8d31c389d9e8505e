#include "jointlab/tests/cli.h"

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "jointlab/tests/test_util.h"

namespace jointlab::testing {

namespace {
std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

std::string scratch_dir(const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path dir = scratch_root() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

CommandResult run_jointlab(const std::string& args) {
  const std::string dir = scratch_dir("cli_capture");
  const std::string out = dir + "/out.txt", err = dir + "/err.txt";
  const std::string cmd =
      binary_dir() + "/bin/jointlab " + args + " > " + out + " 2> " + err + " < /dev/null";
  const int raw = std::system(cmd.c_str());
  CommandResult r;
  r.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove_all(dir);
  return r;
}

}  // namespace jointlab::testing
