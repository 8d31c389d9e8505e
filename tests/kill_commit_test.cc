// Issue 25's acceptance of outputs as a set: `process` and `run` killed (SIGKILL) at the first
// change of their output folder, 16 times each, leave a folder that holds exactly the old or
// exactly the new results, or that the next reader refuses with exit status 2 and a line saying
// to re-run; a re-run then gives the new results.
//
// The first change is watched with inotify over the folder's whole tree, two ways (8 kills each
// per command): the first change of anything (the staging folder appearing: the run is killed
// long before its commit) and the first change of a result itself (a visible output removed,
// replaced or moved in: the run is killed inside its commit, the hardest moment).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/inotify.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/tests/cli.h"
#include "jointlab/tests/small_campaign.h"
#include "jointlab/tests/test_util.h"

namespace jointlab {
namespace {

namespace fs = std::filesystem;

// The results in `dir`: every file and folder below it by relative path (files with their
// content), except the bookkeeping whose first component is hidden (.<command>.outputs, a
// staging or commit folder, temporaries).
using Tree = std::map<std::string, std::string>;

bool hidden(const fs::path& rel) { return !rel.empty() && rel.begin()->string().starts_with('.'); }

Tree results(const fs::path& dir) {
  Tree t;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator();
       ++it) {
    const fs::path rel = it->path().lexically_relative(dir);
    if (hidden(rel)) {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    t[rel.string()] = it->is_directory() ? "<dir>" : testing::read_file(it->path());
  }
  // A run's report says how many hits it processed and how many it reused from the run before:
  // a fact about the run, not about its results.
  for (const char* report : {"report.md", "report.html"}) {
    if (!t.count(report)) continue;
    t[report] =
        std::regex_replace(t[report], std::regex(R"(This run: \d+ hit\(s\) processed, \d+ reused)"),
                           "This run: (hits processed and reused)");
  }
  return t;
}

// Copies `from`'s whole content (hidden entries too) into a fresh `to`.
void restore(const fs::path& from, const fs::path& to) {
  fs::remove_all(to);
  fs::copy(from, to, fs::copy_options::recursive);
}

enum class Trigger { kAnyChange, kResults };

// Runs `jointlab args...` and kills it with SIGKILL at the first change in `dir`'s tree that
// `trigger` accepts. Returns true if it was killed (false: it ended first).
bool run_killed(const std::vector<std::string>& args, const fs::path& dir, Trigger trigger) {
  const int fd = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  EXPECT_GE(fd, 0);
  std::map<int, fs::path> watched;  // watch descriptor -> folder relative to dir
  const uint32_t mask = IN_CREATE | IN_DELETE | IN_MODIFY | IN_MOVED_FROM | IN_MOVED_TO |
                        IN_CLOSE_WRITE | IN_ATTRIB | IN_DELETE_SELF | IN_MOVE_SELF;
  watched[inotify_add_watch(fd, dir.c_str(), mask)] = "";
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_directory())
      watched[inotify_add_watch(fd, e.path().c_str(), mask)] = e.path().lexically_relative(dir);

  const std::string program = testing::binary_dir() + "/bin/jointlab";
  std::vector<char*> argv{const_cast<char*>(program.c_str())};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t child = fork();
  if (child == 0) {
    const int null = ::open("/dev/null", O_RDWR);
    dup2(null, 0);
    dup2(null, 1);
    dup2(null, 2);
    execv(program.c_str(), argv.data());
    _exit(127);
  }
  EXPECT_GT(child, 0);
  bool killed = false;
  int status = 0;
  alignas(inotify_event) char buf[64 * 1024];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!killed) {
    pollfd p{fd, POLLIN, 0};
    ::poll(&p, 1, 5);
    for (ssize_t n; !killed && (n = ::read(fd, buf, sizeof buf)) > 0;) {
      for (char* at = buf; at < buf + n;) {
        const auto* ev = reinterpret_cast<const inotify_event*>(at);
        at += sizeof(inotify_event) + ev->len;
        if (ev->mask & IN_IGNORED || !watched.count(ev->wd)) continue;
        const fs::path rel = ev->len ? watched[ev->wd] / ev->name : watched[ev->wd];
        if (trigger == Trigger::kAnyChange || (!rel.empty() && !hidden(rel))) {
          ::kill(child, SIGKILL);
          killed = true;
          break;
        }
      }
    }
    if (killed) break;
    if (waitpid(child, &status, WNOHANG) == child) {
      ::close(fd);
      return false;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "no change in " << dir << " within 60 s";
      ::kill(child, SIGKILL);
      break;
    }
  }
  waitpid(child, &status, 0);
  ::close(fd);
  return killed && WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

std::vector<std::string> words(const std::string& line) {
  std::vector<std::string> w;
  for (size_t at = 0; at < line.size();) {
    const size_t end = std::min(line.find(' ', at), line.size());
    if (end > at) w.push_back(line.substr(at, end - at));
    at = end + 1;
  }
  return w;
}

// The paths where two trees differ, for messages.
std::string differences(const Tree& a, const Tree& b) {
  std::string d;
  for (const auto& [path, text] : a)
    if (!b.count(path) || b.at(path) != text) d += " " + path;
  for (const auto& [path, text] : b)
    if (!a.count(path)) d += " +" + path;
  return d;
}

struct Outcomes {
  int old = 0, fresh = 0, refused = 0;
  int unkilled = 0;  // runs that ended before their kill landed (tried again)
};

// 16 kills of `command` (whose complete results are `old_results` in `start`, copied to `dir`
// before each), half at the first change of anything in `dir`, half at the first change of a
// result; `reader` is the next reader's command line.
Outcomes kill_loop(const std::string& command, const fs::path& start, const fs::path& dir,
                   const Tree& old_results, const Tree& new_results, const std::string& reader) {
  Outcomes o;
  for (int k = 0; k < 16; ++k) {
    const Trigger trigger = k % 2 == 0 ? Trigger::kAnyChange : Trigger::kResults;
    SCOPED_TRACE(fmt::format("kill {} ({})", k + 1,
                             trigger == Trigger::kAnyChange ? "first change" : "first result"));
    // On a busy machine the command may end before the kill lands: tried again (up to 10
    // times), so that every outcome counted is that of a kill.
    bool killed = false;
    for (int attempt = 0; attempt < 10 && !killed; ++attempt) {
      restore(start, dir);
      killed = run_killed(words(command), dir, trigger);
      if (!killed) ++o.unkilled;
    }
    if (!killed) {
      ADD_FAILURE() << "ended before the kill 10 times";
      continue;
    }
    const Tree after = results(dir);
    if (after == old_results) {
      ++o.old;
    } else if (after == new_results) {
      ++o.fresh;
    } else {
      const testing::CommandResult r = testing::run_jointlab(reader);
      EXPECT_EQ(r.status, 2) << r.err;
      EXPECT_NE(r.err.find("killed while putting its results in place"), std::string::npos)
          << r.err;
      EXPECT_NE(r.err.find("re-run "), std::string::npos) << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      ++o.refused;
    }
    const testing::CommandResult again = testing::run_jointlab(command);
    EXPECT_EQ(again.status, 0) << again.err;
    const Tree rerun = results(dir);
    EXPECT_TRUE(rerun == new_results)
        << "the re-run does not give the new results:" << differences(rerun, new_results);
  }
  return o;
}

class KilledCommit : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::scratch_dir("kill_commit");
    campaign_ = new testing::SmallCampaign(testing::make_small_campaign(dir_ / "campaign", ""));
  }
  static void TearDownTestSuite() {
    delete campaign_;
    fs::remove_all(dir_);
  }
  static inline fs::path dir_;
  static inline testing::SmallCampaign* campaign_ = nullptr;
};

// The old command's results, then the new command's from the same start; then the new
// command killed 16 times at the first change of `out`: each time the folder holds the old or
// the new results, or `reader` refuses it (kill_loop).
void expect_old_new_or_refused(const char* name, const std::string& old_command,
                               const std::string& new_command, const fs::path& out,
                               const fs::path& start, const std::string& reader) {
  ASSERT_EQ(testing::run_jointlab(old_command).status, 0);
  const Tree old_results = results(out);
  restore(out, start);
  ASSERT_EQ(testing::run_jointlab(new_command).status, 0);
  const Tree new_results = results(out);
  ASSERT_NE(old_results, new_results);
  const Outcomes o = kill_loop(new_command, start, out, old_results, new_results, reader);
  ::testing::Test::RecordProperty(
      "outcomes", fmt::format("old {}, new {}, refused {}", o.old, o.fresh, o.refused));
  std::printf("%s: 16 kills: %d old, %d new, %d refused by the next reader (%d tried again)\n",
              name, o.old, o.fresh, o.refused, o.unkilled);
  EXPECT_EQ(o.old + o.fresh + o.refused, 16);
  // Half the kills land inside the commit: some must find the new results or be refused,
  // or the loop never tested the switch from old to new.
  EXPECT_GT(o.fresh + o.refused, 0);
}

TEST_F(KilledCommit, ProcessFolderIsOldNewOrRefused) {
  const testing::SmallCampaign& s = *campaign_;
  const fs::path out = dir_ / "process", start = dir_ / "process.start";
  std::string files;
  for (const fs::path& h : s.hits) {
    files += ' ';
    files += h.string();
  }
  const double f = s.frequency_hz;
  // The old run: one band; the new one: that band moved and a second band, so that the new set
  // replaces every old file and adds others (the audit's mix of k = 2 and k = 3).
  const std::string old_command = fmt::format("process{} --band {:.3f}:{:.3f} --out {}", files,
                                              0.85 * f, 1.15 * f, out.string());
  const std::string new_command =
      fmt::format("process{} --band {:.3f}:{:.3f} --band {:.3f}:{:.3f} --out {}", files, 0.8 * f,
                  1.2 * f, 0.9 * f, 1.1 * f, out.string());
  const std::string reader = fmt::format(
      "update-iwan {} --measured {} --sensors {} --set iwan.rivet --mode {}:1 --channel acc_5 "
      "--evaluations 10 --out {}",
      s.model.string(), out.string(), s.sensors.string(), s.model_mode, (dir_ / "iwan").string());
  expect_old_new_or_refused("process", old_command, new_command, out, start, reader);
}

TEST_F(KilledCommit, RunFolderIsOldNewOrRefused) {
  const testing::SmallCampaign& s = *campaign_;
  const fs::path out = dir_ / "run", start = dir_ / "run.start";
  // The old campaign; the new one has another band, so that every hit, summary and figure
  // changes.
  const std::string text = testing::read_file(s.campaign);
  const std::string old_band = fmt::format("band = [{:.3f}, {:.3f}]", s.band[0], s.band[1]);
  ASSERT_NE(text.find(old_band), std::string::npos);
  std::string changed = text;
  changed.replace(
      text.find(old_band), old_band.size(),
      fmt::format("band = [{:.3f}, {:.3f}]", 0.8 * s.frequency_hz, 1.2 * s.frequency_hz));
  const fs::path new_campaign = s.campaign.parent_path() / "campaign_new.toml";
  testing::write_text(new_campaign.string(), changed);
  const std::string old_command =
      fmt::format("run {} --out {} --quiet", s.campaign.string(), out.string());
  const std::string new_command =
      fmt::format("run {} --out {} --quiet", new_campaign.string(), out.string());
  // A reader of a run's backbone (update-iwan --backbone, as compare and the Python module).
  const std::string reader = fmt::format(
      "update-iwan {} --set iwan.rivet --mode {} --backbone {} --evaluations 10 --out {}",
      s.model.string(), s.model_mode, (out / "hits/all/hit1.acc_5.band1.csv").string(),
      (dir_ / "iwan").string());
  expect_old_new_or_refused("run", old_command, new_command, out, start, reader);
}

}  // namespace
}  // namespace jointlab
