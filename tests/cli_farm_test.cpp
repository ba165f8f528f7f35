// `ssgi run` on a render farm: threads from the scheduler, signals and kills mid-write,
// resuming with --skip-existing, --no-clobber, and progress for job managers and terminals.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <spawn.h>
#include <sys/wait.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

TEST_F(Cli, ThreadsComeFromTheOptionElseTheSchedulersAllocation) {
  // A farm task gets its allocation, not the node's cores: --threads, else Slurm's
  // SLURM_CPUS_PER_TASK, else OpenCue's CUE_THREADS (then the cgroup quota, the CPUs allowed).
  const std::string in = testdata("sample/sample.0001.exr");
  auto threads_of = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"info", in, "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = run_ssgi(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false)["threads"];
  };
  ::setenv("SLURM_CPUS_PER_TASK", "3", 1);
  nlohmann::json t = threads_of({});
  EXPECT_EQ(t["count"], 3);
  EXPECT_EQ(t["from"], "SLURM_CPUS_PER_TASK");
  t = threads_of({"--threads", "5"});
  EXPECT_EQ(t["count"], 5);
  EXPECT_EQ(t["from"], "--threads");
  ::setenv("SLURM_CPUS_PER_TASK", "none", 1);  // not a count: the next source
  ::setenv("CUE_THREADS", "2", 1);
  t = threads_of({});
  EXPECT_EQ(t["count"], 2);
  EXPECT_EQ(t["from"], "CUE_THREADS");
  ::unsetenv("SLURM_CPUS_PER_TASK");
  ::unsetenv("CUE_THREADS");
  t = threads_of({});
  EXPECT_GE(t["count"].get<int>(), 1);
  EXPECT_NE(t["from"], "--threads");
}

// The channels and header of two EXRs that must be the same frame: every channel's values
// equal, bit for bit.
void expect_same_pixels(const std::string& a, const std::string& b) {
  const ExrImage x = read_exr(a), y = read_exr(b);
  ASSERT_EQ(x.channel_names(), y.channel_names()) << a << " vs " << b;
  for (const auto& [name, plane] : x.planes) EXPECT_EQ(plane, y.planes.at(name)) << name;
}

// Starts `ssgi run IN -o DIR/o.####.exr -q --preset final --stats DIR/stats.json` (stderr to
// /dev/null), watches DIR and sends `signal` at the first sight of a hidden temporary file
// (`mid_write`) or `after_ms` after frame 1 is there, unless the run ends first. Returns the
// wait status; *seen_temporary says whether a temporary file was there when it was sent.
int signal_run(const std::string& in, const std::string& dir, int signal, bool mid_write,
               int after_ms, bool* seen_temporary) {
  std::vector<std::string> args = {
      SSGI_BINARY, "run",      in,      "-o",      dir + "/o.####.exr",
      "-q",        "--preset", "final", "--stats", dir + "/stats.json"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  int status = 0;
  bool ended = false;
  *seen_temporary = false;
  for (int waited = 0; waited < 60000 && !ended; ++waited) {
    bool temporary = false, first_frame = false;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      const std::string name = entry.path().filename().string();
      temporary |= name[0] == '.';
      first_frame |= name == "o.0001.exr";
    }
    if (mid_write ? temporary : first_frame) {
      *seen_temporary = temporary;
      ::usleep(static_cast<useconds_t>(after_ms) * 1000);
      break;
    }
    ended = ::waitpid(pid, &status, WNOHANG) == pid;
    ::usleep(500);
  }
  if (!ended) {
    ::kill(pid, signal);
    if (::waitpid(pid, &status, 0) != pid) return -1;
  }
  return status;
}

// Every file of `dir` under a final name (not hidden) is whole: it opens and all its pixels
// read. Hidden ones are allowed only when `hidden_allowed`.
void expect_only_whole_frames(const std::string& dir, bool hidden_allowed,
                              const std::string& what) {
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name[0] == '.') {
      EXPECT_TRUE(hidden_allowed) << name << " left, " << what;
      continue;
    }
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    if (name == "stats.json") continue;
    auto image = OIIO::ImageInput::open(entry.path().string());
    ASSERT_TRUE(image) << name << ", " << what;
    std::vector<float> pixels(image->spec().image_pixels() * image->spec().nchannels);
    EXPECT_TRUE(
        image->read_image(0, 0, 0, image->spec().nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        << name << ": " << image->geterror() << ", " << what;
  }
}

TEST_F(Cli, SignalsStopTheRunRemoveTemporaryFilesAndLeaveFinishedFramesWhole) {
  // SIGINT and SIGTERM while a frame is being written (its hidden temporary file is on disk)
  // and at moments after the first frame is done: exit 130 or 143, nothing hidden or temporary
  // left, every frame on disk a whole, readable EXR.
  const std::string in = testdata("sample/sample.####.exr");
  struct Case {
    int signal;
    bool mid_write;  // at the first sight of a temporary file, else `after_ms` after frame 1
    int after_ms;
  };
  const Case cases[] = {{SIGINT, true, 0},   {SIGTERM, true, 0},  {SIGINT, true, 0},
                        {SIGTERM, false, 0}, {SIGINT, false, 40}, {SIGTERM, false, 120}};
  int interrupted = 0, mid_write = 0;
  for (std::size_t k = 0; k < std::size(cases); ++k) {
    const Case& c = cases[k];
    const std::string dir = path("run" + std::to_string(k));
    std::filesystem::create_directory(dir);
    bool seen_temporary = false;
    const int status = signal_run(in, dir, c.signal, c.mid_write, c.after_ms, &seen_temporary);
    ASSERT_TRUE(WIFEXITED(status)) << "case " << k;
    const int code = WEXITSTATUS(status);
    if (code != 0) {
      EXPECT_EQ(code, 128 + c.signal) << "case " << k;
      ++interrupted;
      mid_write += seen_temporary;
    }
    expect_only_whole_frames(dir, /*hidden_allowed=*/false, "case " + std::to_string(k));
  }
  // The signals came during the runs, and some while a frame was being written.
  EXPECT_GE(interrupted, 5);
  EXPECT_GE(mid_write, 2);
}

TEST_F(Cli, KillMidWriteLeavesNoPartialFrameAndAResumeFinishesTheShot) {
  // SIGKILL cannot be caught: the frame being written stays a hidden temporary file, never a
  // partial file under its final name. The farm's retry with --skip-existing keeps the frames
  // the killed run finished and makes the others: the same frames as a run never killed.
  const std::string in = testdata("sample/sample.####.exr");
  const std::string dir = path("killed");
  std::filesystem::create_directory(dir);
  bool seen_temporary = false;
  const int status = signal_run(in, dir, SIGKILL, /*mid_write=*/false, 0, &seen_temporary);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the run ended first";
  expect_only_whole_frames(dir, /*hidden_allowed=*/true, "after SIGKILL");
  const std::vector<std::string> args = {"run", in, "-q", "--preset", "final", "-o"};
  std::vector<std::string> resume = args;
  resume.push_back(dir + "/o.####.exr");
  resume.push_back("--skip-existing");
  resume.push_back("--stats");
  resume.push_back(path("resume.json"));
  ASSERT_EQ(run_ssgi(resume).exit_code, 0);
  std::ifstream file(path("resume.json"));
  const nlohmann::json stats = nlohmann::json::parse(file, nullptr, false);
  ASSERT_FALSE(stats.is_discarded());
  EXPECT_GE(stats["summary"]["skipped"].get<int>(), 1);  // frame 1 was there
  EXPECT_GE(stats["summary"]["written"].get<int>(), 1);
  std::vector<std::string> whole = args;
  whole.push_back(path("whole.####.exr"));
  ASSERT_EQ(run_ssgi(whole).exit_code, 0);
  for (int f = 1; f <= 6; ++f) {
    const std::string name = "o.000" + std::to_string(f) + ".exr";
    expect_same_pixels(dir + "/" + name, path("whole.000" + std::to_string(f) + ".exr"));
  }
}

TEST_F(Cli, SkipExistingKeepsWholeMatchingOutputsAndMakesTheRest) {
  // A whole run, then a resume over its outputs: frame 1 kept as it is, frame 2 truncated (a
  // half-copied file), frame 3 made with another seed. The resume keeps 1 and makes 2 and 3
  // again, the same bits as the whole run.
  const std::string in = testdata("sample/sample.1-3#.exr");
  const std::vector<std::string> base = {"run", in, "--preset", "draft", "--no-passthrough"};
  std::vector<std::string> whole = base;
  for (const char* a : {"-q", "-o"}) whole.push_back(a);
  whole.push_back(path("whole.####.exr"));
  ASSERT_EQ(run_ssgi(whole).exit_code, 0);
  for (const char* f : {"0001", "0002"})
    fs::copy_file(path(std::string("whole.") + f + ".exr"), path(std::string("o.") + f + ".exr"));
  {
    const std::string bytes = file_bytes(path("o.0002.exr"));
    std::ofstream(path("o.0002.exr"), std::ios::binary | std::ios::trunc)
        << bytes.substr(0, bytes.size() * 2 / 3);
  }
  std::vector<std::string> other = base;
  for (const char* a : {"--frames", "3", "--seed", "7", "-q", "-o"}) other.push_back(a);
  other.push_back(path("o.####.exr"));
  ASSERT_EQ(run_ssgi(other).exit_code, 0);
  const std::string kept = file_bytes(path("o.0001.exr"));

  std::vector<std::string> resume = base;
  for (const char* a : {"--skip-existing", "-v", "--stats"}) resume.push_back(a);
  resume.push_back(path("stats.json"));
  resume.push_back("-o");
  resume.push_back(path("o.####.exr"));
  const CliResult r = run_ssgi(resume);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Frame 1 untouched (a rewrite would differ: the command line is in the header).
  EXPECT_EQ(file_bytes(path("o.0001.exr")), kept);
  for (const char* f : {"0002", "0003"})
    expect_same_pixels(path(std::string("o.") + f + ".exr"),
                       path(std::string("whole.") + f + ".exr"));
  const std::string& err = r.err;
  EXPECT_NE(err.find(path("o.0002.exr") + ": exists but is made again: incomplete or damaged"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find(path("o.0003.exr") + ": exists but is made again: ssgi:settings is '"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("ssgi: frame 1 (1/3): " + path("o.0001.exr") + " is there already, skipped"),
            std::string::npos)
      << err;
  EXPECT_EQ(r.err_lines().back(), "ssgi: 2 of 3 frames written, 1 skipped (already written)");
  std::ifstream file(path("stats.json"));
  const nlohmann::json stats = nlohmann::json::parse(file, nullptr, false);
  ASSERT_FALSE(stats.is_discarded());
  EXPECT_EQ(stats["summary"]["frames"], 3);
  EXPECT_EQ(stats["summary"]["written"], 2);
  EXPECT_EQ(stats["summary"]["skipped"], 1);
  EXPECT_EQ(stats["summary"]["failed"], 0);
  EXPECT_EQ(stats["frames"][0]["skipped"], true);
  EXPECT_GT(stats["summary"]["total"]["gi_ms"].get<double>(), 0.0);

  // Now everything is there and matches: nothing is made.
  const CliResult again = run_ssgi(resume);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.err_lines().back(), "ssgi: 0 of 3 frames written, 3 skipped (already written)");
  EXPECT_EQ(file_bytes(path("o.0001.exr")), kept);
}

TEST_F(Cli, NoClobberRefusesBeforeComputingAnything) {
  const std::string in = testdata("sample/sample.1-3#.exr");
  const std::vector<std::string> args = {"run",          in,   "--preset",        "draft", "-q",
                                         "--no-clobber", "-o", path("o.####.exr")};
  ASSERT_EQ(run_ssgi(args).exit_code, 0);  // nothing in the way
  const std::string first = file_bytes(path("o.0001.exr"));
  fs::remove(path("o.0003.exr"));
  const CliResult r = run_ssgi(args);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err_lines().front(), "ssgi: error: " + path("o.0001.exr") +
                                       ": exists (as do 1 more outputs) and --no-clobber does "
                                       "not overwrite");
  EXPECT_EQ(file_bytes(path("o.0001.exr")), first);
  EXPECT_FALSE(fs::exists(path("o.0003.exr")));  // refused before any frame was computed
  EXPECT_EQ(entries(), (std::set<std::string>{"o.0001.exr", "o.0002.exr"}));
  // With --skip-existing the two reusable outputs are no obstacle: frame 3 is made.
  std::vector<std::string> resume = args;
  resume.push_back("--skip-existing");
  const CliResult ok = run_ssgi(resume);
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(path("o.0003.exr")));
  EXPECT_EQ(file_bytes(path("o.0001.exr")), first);
}

TEST_F(Cli, ProgressForOpenJobDescriptionAndDeadlineGoesToStdout) {
  // Frame 2 of 3 is broken: the lines say so, and openjd hears why the run failed.
  write_frames_with_a_broken_one(3, 2);
  const std::vector<std::string> args = {
      "run", path("in.####.exr"), "--preset", "draft", "--temporal", "none", "-q", "--progress"};
  std::vector<std::string> openjd = args;
  for (const char* a : {"openjd", "-o"}) openjd.push_back(a);
  openjd.push_back(path("a.####.exr"));
  const CliResult j = run_ssgi(openjd);
  EXPECT_EQ(j.exit_code, 1);
  EXPECT_EQ(j.out,
            "openjd_status: ssgi: 3 frames to write\n"
            "openjd_progress: 0\n"
            "openjd_progress: 33.3\n"
            "openjd_status: frame 1 written (1/3)\n"
            "openjd_progress: 66.7\n"
            "openjd_status: frame 2 failed (2/3)\n"
            "openjd_progress: 100.0\n"
            "openjd_status: frame 3 written (3/3)\n"
            "openjd_fail: ssgi: 2 of 3 frames written, 1 failed (2)\n");
  expect_one_error(j, path("in.0002.exr"), "");  // -q: only the error on stderr

  std::vector<std::string> deadline = args;
  for (const char* a : {"deadline", "-o"}) deadline.push_back(a);
  deadline.push_back(path("b.####.exr"));
  const CliResult d = run_ssgi(deadline);
  EXPECT_EQ(d.exit_code, 1);
  EXPECT_EQ(d.out, "Progress: 0%\nProgress: 33%\nProgress: 66%\nProgress: 100%\n");

  // An error that stops the whole run before any frame.
  const CliResult none =
      run_ssgi({"run", path("nothing.####.exr"), "-o", path("c.####.exr"), "--progress", "openjd"});
  EXPECT_EQ(none.exit_code, 4);
  EXPECT_EQ(none.out.rfind("openjd_fail: ", 0), 0u) << none.out;
  EXPECT_NE(none.out.find("nothing.####.exr"), std::string::npos) << none.out;
  expect_usage_error(run_ssgi({"run", "in.exr", "-o", "o.exr", "--progress", "bar"}), "run",
                     "--progress must be auto, lines, openjd or deadline");
}

TEST_F(Cli, OnATerminalAProgressBarShowsFramesRateAndEta) {
  // The child's stderr is a terminal (a pseudo-terminal this test reads).
  std::vector<std::string> args = {
      SSGI_BINARY, "run",  testdata("sample/sample.1-3#.exr"), "-o", path("o.####.exr"),
      "--preset",  "draft"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int master = -1;
  const pid_t pid = ::forkpty(&master, nullptr, nullptr, nullptr);
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  std::string screen;
  char buf[4096];
  for (ssize_t got; (got = ::read(master, buf, sizeof buf)) > 0;) screen.append(buf, got);
  ::close(master);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << screen;
  // From the start, before the first frame is done; then each frame, rate and ETA; the last
  // state stays, and the summary follows on its own line.
  const std::size_t start =
      screen.find("\r\033[K[------------------------] 0/3 frames  0:00 elapsed");
  const std::size_t one = screen.find("[########----------------] 1/3 frames  ");
  const std::size_t all = screen.find("[########################] 3/3 frames  ");
  ASSERT_NE(start, std::string::npos) << screen;
  ASSERT_NE(one, std::string::npos) << screen;
  ASSERT_NE(all, std::string::npos) << screen;
  EXPECT_LT(start, one);
  EXPECT_LT(one, all);
  EXPECT_NE(screen.find(" s/frame  ", one), std::string::npos) << screen;
  EXPECT_NE(screen.find(" elapsed, ETA 0:0", one), std::string::npos) << screen;
  EXPECT_NE(screen.find("\r\nssgi: 3 of 3 frames written\r\n", all), std::string::npos) << screen;
  EXPECT_EQ(screen.find("ssgi: frame "), std::string::npos) << screen;  // no per-frame lines
}

}  // namespace
}  // namespace cli_test
