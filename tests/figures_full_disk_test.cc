// A figure written onto a full disk: the cairo drivers report no write error, so the file
// is checked for its format's end; nothing truncated may be moved into place. The disk is
// a 8 kB tmpfs mounted in a private mount namespace of a child process (skipped where the
// test may not mount).
#include <sched.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "jointlab/campaign/figures.h"
#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::campaign {
namespace {

namespace fs = std::filesystem;

constexpr int kCannotMount = 77;

// In a child: mounts an 8 kB tmpfs on `dir` and draws `file_name` there. Exit 0 when the
// figure is refused with an InputError and `dir` stays empty.
int draw_on_full_disk(const fs::path& dir, const std::string& file_name) {
  if (unshare(CLONE_NEWNS) != 0) return kCannotMount;
  if (mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) return kCannotMount;
  if (mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=8k") != 0) return kCannotMount;
  SpectrumFigure s;
  s.title = "spectrum";
  s.amplitude_label = "acceleration [m/s^2]";
  s.frequency_hz = Eigen::VectorXd::LinSpaced(2000, 0, 1000);
  s.channel_names = {"a", "b"};
  s.spectra.push_back((1.0 / (1.0 + (s.frequency_hz.array() - 120).square())).matrix());
  s.spectra.push_back((0.5 / (1.0 + (s.frequency_hz.array() - 290).square())).matrix());
  try {
    plot_spectrum(s, dir / file_name);
  } catch (const InputError& e) {
    const std::string m = e.what();
    if (m.find(file_name) == std::string::npos) return 3;
    return fs::is_empty(dir) ? 0 : 4;
  }
  return 2;  // no error: a truncated figure would have been moved into place
}

TEST(Figures, AFullDiskLeavesNoFigure) {
  for (const char* name : {"spectrum.png", "spectrum.svg", "spectrum.pdf"}) {
    const fs::path dir = testing::scratch_path("jointlab-full-disk-test", "disk");
    fs::create_directories(dir);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) _exit(draw_on_full_disk(dir, name));
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(WIFEXITED(status)) << name;
    if (WEXITSTATUS(status) == kCannotMount) GTEST_SKIP() << "cannot mount a tmpfs here";
    EXPECT_EQ(WEXITSTATUS(status), 0) << name << " (2: no error, 3: message, 4: files left)";
    EXPECT_TRUE(fs::is_empty(dir)) << name;  // the mount was the child's only
  }
}

}  // namespace
}  // namespace jointlab::campaign
