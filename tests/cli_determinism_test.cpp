// The same bits whatever the run: any thread count, chunking of the frames (temporal window,
// multiframe) or SIMD target, and `ssgi reference` against `ssgi run`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

TEST_F(Cli, OutputBitsDoNotDependOnThreadCountOrRun) {
  // Default settings (the full pipeline); one thread, two threads, and two threads again.
  const std::string in = testdata("sample/sample.####.exr");
  for (const std::string run : {"t1", "t2", "t2again"}) {
    const CliResult r = run_ssgi(
        {"run", in, "-o", path(run + ".####.exr"), "--threads", run == "t1" ? "1" : "2", "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  for (int f = 1; f <= 6; ++f) {
    const std::string frame = ".000" + std::to_string(f) + ".exr";
    const ExrImage t1 = read_exr(path("t1" + frame));
    const ExrImage t2 = read_exr(path("t2" + frame));
    const ExrImage again = read_exr(path("t2again" + frame));
    for (const std::string& c : kOurChannels) {
      const std::vector<float>& a = t1.planes.at(c);
      ASSERT_EQ(t2.planes.at(c).size(), a.size());
      // Bit for bit (memcmp, not ==): also the same signed zeros.
      EXPECT_EQ(std::memcmp(a.data(), t2.planes.at(c).data(), a.size() * sizeof(float)), 0)
          << "1 vs 2 threads, frame " << f << " " << c;
      EXPECT_EQ(
          std::memcmp(t2.planes.at(c).data(), again.planes.at(c).data(), a.size() * sizeof(float)),
          0)
          << "run to run, frame " << f << " " << c;
    }
  }
}

TEST_F(Cli, TemporalWindowGivesTheSameBitsInAnyChunking) {
  // Chunking: the 10-frame static/ shot (and the panning pan/ shot) as one
  // run, as chunks of 3 and frame by frame: the window reads the frames on disk around each
  // output frame whatever --frames selects, so every frame has the same bits.
  for (const auto& [name, last] :
       std::vector<std::pair<std::string, int>>{{"static", 10}, {"pan", 6}}) {
    const std::string in = testdata(name + "/" + name + ".####.exr");
    ASSERT_EQ(
        run_ssgi({"run", in, "-o", path(name + "_whole.####.exr"), "--rays", "2", "-q"}).exit_code,
        0);
    for (int first = 1; first <= last; first += 3) {
      const std::string frames =
          std::to_string(first) + "-" + std::to_string(std::min(first + 2, last));
      ASSERT_EQ(run_ssgi({"run", in, "--frames", frames, "-o", path(name + "_chunk.####.exr"),
                          "--rays", "2", "-q"})
                    .exit_code,
                0);
    }
    // Frame by frame, naming each file of the shot (as a farm task of one frame would).
    for (int f = 1; f <= last; ++f) {
      char file[32];
      std::snprintf(file, sizeof file, ".%04d.exr", f);
      ASSERT_EQ(run_ssgi({"run", testdata(name + "/" + name + file), "-o",
                          path(name + "_single" + file), "--rays", "2", "-q"})
                    .exit_code,
                0);
    }
    for (int f = 1; f <= last; ++f) {
      char frame[16];
      std::snprintf(frame, sizeof frame, ".%04d.exr", f);
      const ExrImage whole = read_exr(path(name + "_whole" + frame));
      for (const std::string run : {"_chunk", "_single"}) {
        const ExrImage other = read_exr(path(name + run + frame));
        for (const std::string& c : kOurChannels) {
          const std::vector<float>& a = whole.planes.at(c);
          ASSERT_EQ(other.planes.at(c).size(), a.size());
          EXPECT_EQ(std::memcmp(a.data(), other.planes.at(c).data(), a.size() * sizeof(float)), 0)
              << name << run << " frame " << f << " " << c;
        }
      }
    }
  }
}

TEST_F(Cli, MultiframeGivesTheSameBitsInAnyChunkingAndSaysWhatItFound) {
  // The panning shot with its missed rays continued in the window's frames: -v counts rays
  // continued and found per frame, the light differs from a run without, and a chunked and a
  // frame-by-frame run give the whole run's bits (the continuation reads the window's frames
  // alone).
  const std::string in = testdata("pan/pan.####.exr");
  auto run = [&](std::vector<std::string> args, const std::string& multiframe = "on") {
    for (const std::string& a :
         {std::string("--preset"), std::string("draft"), std::string("--multiframe"), multiframe})
      args.push_back(a);
    return run_ssgi(args);
  };
  CliResult r = run({"run", in, "-o", path("mf_whole.####.exr"), "-v"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("plan: multiframe: missed rays continued in the depth buffers of up to 2 "
                       "frames each side"),
            std::string::npos)
      << r.err;
  std::size_t found_total = 0, frames_reported = 0;
  const std::string per_frame = "missed rays continued in frames";
  for (std::size_t at = r.err.find(per_frame); at != std::string::npos;
       at = r.err.find(per_frame, at + 1)) {
    const std::size_t start = r.err.rfind("multiframe: ", at);
    const std::string line = r.err.substr(start, r.err.find('\n', at) - start);
    unsigned long rays = 0, found = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "multiframe: %lu missed rays", &rays), 1) << line;
    const std::size_t semi = line.find("; ");
    ASSERT_NE(semi, std::string::npos) << line;
    ASSERT_EQ(std::sscanf(line.c_str() + semi, "; %lu met a surface", &found), 1) << line;
    EXPECT_GT(rays, 0u) << line;
    EXPECT_LE(found, rays) << line;
    found_total += found;
    ++frames_reported;
  }
  EXPECT_EQ(frames_reported, 6u) << r.err;
  EXPECT_GT(found_total, 0u) << r.err;
  ASSERT_EQ(run({"run", in, "-o", path("mf_off.####.exr")}, "off").exit_code, 0);
  ASSERT_EQ(run({"run", in, "--frames", "1-2", "-o", path("mf_chunk.####.exr")}).exit_code, 0);
  ASSERT_EQ(run({"run", in, "--frames", "3-6", "-o", path("mf_chunk.####.exr")}).exit_code, 0);
  ASSERT_EQ(run({"run", testdata("pan/pan.0004.exr"), "-o", path("mf_single.0004.exr")}).exit_code,
            0);
  bool differs = false;
  for (int f = 1; f <= 6; ++f) {
    char frame[16];
    std::snprintf(frame, sizeof frame, ".%04d.exr", f);
    const ExrImage whole = read_exr(path(std::string("mf_whole") + frame));
    const ExrImage chunk = read_exr(path(std::string("mf_chunk") + frame));
    for (const std::string& c : kOurChannels) {
      const std::vector<float>& a = whole.planes.at(c);
      EXPECT_EQ(std::memcmp(a.data(), chunk.planes.at(c).data(), a.size() * sizeof(float)), 0)
          << "frame " << f << " " << c;
    }
    differs |= whole.planes.at("indirect.R") !=
               read_exr(path(std::string("mf_off") + frame)).planes.at("indirect.R");
  }
  EXPECT_TRUE(differs);
  const ExrImage whole = read_exr(path("mf_whole.0004.exr"));
  const ExrImage single = read_exr(path("mf_single.0004.exr"));
  for (const std::string& c : kOurChannels) EXPECT_EQ(whole.planes.at(c), single.planes.at(c)) << c;
  // Without the window there is nothing to continue in, and the plan says so.
  r = run({"info", in, "--temporal", "none"});
  EXPECT_NE(r.out.find("multiframe: off (it continues rays in the temporal window's frames: "
                       "needs --temporal window)"),
            std::string::npos)
      << r.out;
  expect_usage_error(run_ssgi({"run", in, "-o", path("x.####.exr"), "--multiframe", "maybe"}),
                     "run", "--multiframe must be off, on or on:K");
}

TEST_F(Cli, ReferenceWritesWhatRunWritesAndComparesWithIt) {
  // The lone plane sees only the environment: the reference's indirect light is exactly the
  // environment colour, and `compare` against the same file from `run` passes a loose threshold
  // (both see only the environment) and exits 0; the reference's own flags are checked.
  const std::string in = testdata("plane/plane.0001.exr");
  CliResult r = run_ssgi({"reference", in, "-o", path("ref.exr"), "--spp", "16", "--miss", "env",
                          "--env-color", "0.25", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ExrImage ref = read_exr(path("ref.exr"));
  for (const std::string& c : kOurChannels) EXPECT_EQ(ref.planes.count(c), 1u) << c;
  const std::vector<float>& depth = ref.planes.at("ViewLayer.Depth.Z");
  for (std::size_t p = 0; p < depth.size(); ++p) {
    if (depth[p] < 1e9f) {
      ASSERT_FLOAT_EQ(ref.planes.at("indirect.G")[p], 0.25f) << p;
    }
  }
  r = run_ssgi({"run", in, "-o", path("run.exr"), "--rays", "4", "--miss", "env", "--env-color",
                "0.25", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_ssgi(
      {"compare", "--channels", "indirect", "--fail", "1e-4", path("run.exr"), path("ref.exr")});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  expect_usage_error(run_ssgi({"reference", in, "-o", path("x.exr"), "--rays", "4"}), "reference",
                     "'--rays' is not an option of ssgi reference (it is of ssgi run or ssgi info "
                     "or ssgi preview)");
  expect_usage_error(run_ssgi({"run", in, "-o", path("x.exr"), "--spp", "4"}), "run",
                     "'--spp' is not an option of ssgi run (it is of ssgi reference)");
}

TEST_F(Cli, EverySimdTargetGivesTheSameBits) {
  // Every target this CPU and build have (ssgi info lists them), Highway's portable ones and
  // the scalar twins (--simd scalar, or SSGI_SIMD=scalar): the kernels do each value's
  // arithmetic in the twin's order, so the frames are the same bits (what makes a mixed farm
  // safe).
  const std::string in = testdata("sample/sample.1-2#.exr");
  const CliResult info = run_ssgi({"info", in, "--json"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const nlohmann::json report = nlohmann::json::parse(info.out);
  std::vector<std::string> targets = report["simd"]["available"];
  ASSERT_GE(targets.size(), 3u);  // auto, at least one target, scalar
  EXPECT_EQ(targets.front(), "auto");
  EXPECT_EQ(targets.back(), "scalar");
  EXPECT_EQ(report["simd"]["target"], targets[1]);  // auto is the best
  ASSERT_EQ(run_ssgi({"run", in, "-o", path("auto.####.exr"), "-q"}).exit_code, 0);
  targets.erase(targets.begin());
  for (const std::string& target : targets) {
    const CliResult r =
        run_ssgi({"run", in, "-o", path(target + ".####.exr"), "-q", "--simd", target});
    ASSERT_EQ(r.exit_code, 0) << target << ": " << r.err;
  }
  ::setenv("SSGI_SIMD", "scalar", 1);
  const CliResult env = run_ssgi({"run", in, "-o", path("env.####.exr"), "-q"});
  const CliResult env_info = run_ssgi({"info", in});
  ::setenv("SSGI_SIMD", "avx9", 1);
  const CliResult bad_env = run_ssgi({"info", in});
  ::unsetenv("SSGI_SIMD");
  ASSERT_EQ(env.exit_code, 0) << env.err;
  EXPECT_NE(env_info.out.find("simd:          scalar ("), std::string::npos) << env_info.out;
  targets.push_back("env");
  for (const char* f : {"0001", "0002"}) {
    const ExrImage a = read_exr(path(std::string("auto.") + f + ".exr"));
    const std::vector<float>& ind = a.planes.at("indirect.R");
    EXPECT_GT(*std::max_element(ind.begin(), ind.end()), 0.0f);
    for (const std::string& target : targets) {
      const ExrImage b = read_exr(path(target + "." + f + ".exr"));
      for (const std::string& c : kOurChannels)
        EXPECT_EQ(a.planes.at(c), b.planes.at(c)) << target << " " << c;
    }
  }
  std::string list;
  for (const auto& t : report["simd"]["available"])
    list += (list.empty() ? "" : ", ") + t.get<std::string>();
  expect_usage_error(
      bad_env, "info",
      "SSGI_SIMD: SIMD target 'avx9' is not one this CPU and build have (" + list + ")");
  const CliResult bad = run_ssgi({"run", in, "-o", path("x.####.exr"), "--simd", "avx9"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err.rfind("ssgi: error: --simd: SIMD target 'avx9' is not one", 0), 0u) << bad.err;
}

}  // namespace
}  // namespace cli_test
