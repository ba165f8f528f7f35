// The `ssgi` command line's usage: --version and --help, usage errors (exit 2, nothing
// written), each subcommand's help and the presets' settings.
#include <Imath/half.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

TEST_F(Cli, VersionAndHelpExitZero) {
  // --version prints one line on stdout.
  CliResult r = run_ssgi({"--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out.rfind("ssgi ", 0), 0u);
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1);
  EXPECT_EQ(r.err, "");
  // Help goes to stdout (it was asked for), for the tool and each subcommand.
  const std::vector<std::pair<std::vector<std::string>, std::string>> helps = {
      {{"--help"}, "usage: ssgi <subcommand>"},
      {{"run", "--help"}, "usage: ssgi run INPUT -o OUTPUT"},
      {{"info", "--help"}, "usage: ssgi info INPUT"},
  };
  for (const auto& [args, head] : helps) {
    r = run_ssgi(args);
    EXPECT_EQ(r.exit_code, 0) << args.back();
    EXPECT_EQ(r.out.rfind(head, 0), 0u) << r.out;
    EXPECT_EQ(r.err, "");
  }
}

TEST_F(Cli, UsageErrorsExitTwoAndWriteNothing) {
  const std::string in = testdata("sample/sample.####.exr");
  const std::string out = path("out.####.exr");
  // No arguments at all: usage on stderr.
  CliResult r = run_ssgi({});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err.rfind("usage: ssgi", 0), 0u);
  // An unknown subcommand is named, then the usage.
  r = run_ssgi({"render", in});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("ssgi: error: unknown subcommand 'render'\nusage: ssgi", 0), 0u);
  expect_usage_error(run_ssgi({"run", in, "-o", out, "--bogus"}), "run",
                     "unknown option '--bogus' for ssgi run");
  // The option table: an ambiguous prefix names its candidates, an option of another
  // subcommand says whose it is, and -v with -q contradict.
  expect_usage_error(run_ssgi({"run", in, "-o", out, "--lay", "x"}), "run",
                     "ambiguous option '--lay' for ssgi run: --layout, --layer-prefix");
  expect_usage_error(run_ssgi({"run", in, "-o", out, "-v", "-q"}), "run",
                     "-v (--verbose) and -q (--quiet) contradict each other");
  expect_usage_error(run_ssgi({"run", in, "-o", out, "-x"}), "run",
                     "unknown option '-x' for ssgi run");
  expect_usage_error(run_ssgi({"run", in}), "run", "no output given (-o PATTERN)");
  expect_usage_error(run_ssgi({"run", "-o", out}), "run", "no input sequence given");
  expect_usage_error(run_ssgi({"run", in, "-o", out, "--rays"}), "run",
                     "option '--rays' needs a value");
  expect_usage_error(run_ssgi({"run", in, "-o", out, "--rays", "0"}), "run",
                     "--rays: '0' is not an integer in [1, 4096]");
  expect_usage_error(run_ssgi({"info", in, "--datatype", "double"}), "info",
                     "--datatype must be half or float");
  // Conflicting sources and bad values are caught before any frame is read or anything printed.
  expect_usage_error(run_ssgi({"run", in, "-o", out, "--fov", "40", "--camera", "c.json"}), "run",
                     "--camera and --fov both give the camera: use one");
  expect_usage_error(run_ssgi({"run", in, "-o", out, "--env", "e.exr", "--env-color", "1"}), "run",
                     "--env and --env-color both give the environment: use one");
  expect_usage_error(run_ssgi({"info", in, "--depth-kind", "ndc"}), "info",
                     "unknown --depth-kind 'ndc' (planar, radial, inverse, negative)");
  r = run_ssgi({"info", in, "--denoise-sigma-spatial", "0"});
  EXPECT_EQ(r.out, "");
  expect_usage_error(r, "info", "--denoise-sigma-spatial must be positive (got 0)");
  // ssgi writes OpenEXR only, whatever the output's extension would make OIIO write.
  expect_usage_error(run_ssgi({"run", in, "-o", path("out.####.tif")}), "run",
                     "output '" + path("out.####.tif") + "' must end in .exr: ssgi writes OpenEXR");
  // Several frames cannot go to one file name.
  expect_usage_error(run_ssgi({"run", in, "-o", path("out.exr")}), "run",
                     "output '" + path("out.exr") +
                         "' has no frame field (e.g. ####) but 6 frames are to be written");
  EXPECT_TRUE(entries().empty());
}

TEST_F(Cli, BadCompressionIsAUsageError) {
  const std::string in = testdata("sample/sample.0001.exr");
  expect_usage_error(run_ssgi({"run", in, "-o", path("o.exr"), "--compression", "lzma"}), "run",
                     "unknown --compression 'lzma' (none, rle, zips, zip, piz, pxr24, b44, b44a, "
                     "dwaa[:level], dwab[:level])");
  expect_usage_error(run_ssgi({"run", in, "-o", path("o.exr"), "--compression", "zip:3"}), "run",
                     "--compression 'zip:3': only dwaa and dwab take a level");
  expect_usage_error(run_ssgi({"run", in, "-o", path("o.exr"), "--compression", "dwaa:x"}), "run",
                     "--compression 'dwaa:x': the level must be a positive number");
  EXPECT_TRUE(entries().empty());
}

TEST_F(Cli, SilentWrongResultsAreRefused) {
  const std::string in = testdata("sample/sample.0001.exr");
  // An empty --frames (a variable that expanded to nothing) is not "every frame".
  expect_usage_error(run_ssgi({"run", testdata("sample/sample.####.exr"), "-o", path("o.####.exr"),
                               "--frames", ""}),
                     "run", "--frames: empty frame list");
  // A frame range in the output name would be ignored.
  CliResult r = run_ssgi({"run", testdata("sample/sample.####.exr"), "-o", path("o.1-3#.exr")});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("names frames"), std::string::npos) << r.err;
  // Layer prefixes that are not layer names.
  for (const std::string bad : {".", "..", "a..b", ".a", "a b", ""}) {
    r = run_ssgi({"run", in, "-o", path("o.exr"), "--layer-prefix", bad});
    EXPECT_EQ(r.exit_code, 2) << "'" << bad << "': " << r.err;
    EXPECT_NE(r.err.find("is not a layer name"), std::string::npos) << r.err;
  }
  EXPECT_TRUE(entries().empty());
}

TEST_F(Cli, PresetsSetTheirSettingsAndGivenOptionsOverrideThem) {
  // info shows the resolved settings: each preset's row, and an option given wins wherever it
  // stands on the command line.
  const std::string in = testdata("sample/sample.0001.exr");
  auto settings_of = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"info", in, "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = run_ssgi(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false);
  };
  const nlohmann::json plain = settings_of({});
  EXPECT_EQ(plain["preset"], "default");
  EXPECT_EQ(plain["settings"]["slices"], "2");
  EXPECT_EQ(plain["settings"]["trace-scale"], "auto (480 across)");
  const nlohmann::json draft = settings_of({"--preset", "draft"});
  EXPECT_EQ(draft["settings"]["slices"], "1");
  EXPECT_EQ(draft["settings"]["trace-scale"], "auto (240 across)");
  EXPECT_EQ(draft["settings"]["bounces"], "4");
  const nlohmann::json fin = settings_of({"--slices", "3", "--preset=final"});
  EXPECT_EQ(fin["preset"], "final");
  EXPECT_EQ(fin["settings"]["slices"], "3");  // given, so not the preset's 4
  EXPECT_EQ(fin["settings"]["trace-scale"], "auto (480 across)");
  EXPECT_EQ(fin["settings"]["max-steps"], "28");
  EXPECT_EQ(fin["settings"]["multiframe"], "on");
  EXPECT_EQ(plain["settings"].count("multiframe"), 0u);  // off: not in the provenance
  // An abbreviation getopt_long accepts is the preset too.
  const nlohmann::json abbreviated = settings_of({"--pre", "draft"});
  EXPECT_EQ(abbreviated["preset"], "draft");
  EXPECT_EQ(abbreviated["settings"]["slices"], "1");
  expect_usage_error(run_ssgi({"info", in, "--preset", "best"}), "info",
                     "unknown --preset 'best' (draft, default, final)");
}

TEST_F(Cli, HelpListsEachSubcommandsOwnOptionsWithTheDefaultsTheyRunWith) {
  // One option table: each --help lists the options its subcommand takes, with the defaults
  // that subcommand starts from.
  auto help = [&](const std::string& sub) {
    const CliResult r = run_ssgi({sub, "--help"});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.out;
  };
  auto lists = [](const std::string& text, const std::string& option) {
    return text.find("  " + option + " ") != std::string::npos ||
           text.find("  " + option + "\n") != std::string::npos;
  };
  const std::string run_text = help("run"), info_text = help("info"),
                    reference_text = help("reference");
  // Each option's help as one line (its wrapped continuation lines joined).
  auto joined = [](std::string text) {
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n' && text.compare(i + 1, 24, std::string(24, ' ')) == 0) {
        out += ' ';
        i += 24;
      } else {
        out += text[i];
      }
    }
    return out;
  };
  const std::string run = joined(run_text), info = joined(info_text),
                    reference = joined(reference_text);
  EXPECT_TRUE(lists(run, "--max-steps N"));
  EXPECT_NE(run.find("samples per slice side or per march ray (default: 28)"), std::string::npos);
  EXPECT_NE(run.find("(default: window:2)"), std::string::npos);
  EXPECT_TRUE(lists(run, "--stats FILE.json"));
  EXPECT_FALSE(lists(run, "--spp N"));
  EXPECT_FALSE(lists(run, "--json"));
  EXPECT_TRUE(lists(info, "--json"));
  EXPECT_FALSE(lists(info, "--stats FILE.json"));
  EXPECT_TRUE(lists(reference, "--spp N"));
  EXPECT_NE(reference.find("rays per pixel and bounce, 1 to 4096 (default: 256)"),
            std::string::npos);
  EXPECT_FALSE(lists(reference, "--rays N"));
  EXPECT_FALSE(lists(reference, "--max-steps N"));
  // The reference's own defaults: no denoiser, no temporal stage.
  EXPECT_NE(reference.find("pyramid or none (default: none)"), std::string::npos);
  EXPECT_NE(reference.find("or none (default: none)"), std::string::npos);
  EXPECT_NE(run.find("pyramid or none (default: pyramid)"), std::string::npos);
  // Every line fits a terminal of 80 columns.
  for (const std::string* text : {&run_text, &info_text, &reference_text}) {
    std::size_t start = 0;
    while (start < text->size()) {
      const std::size_t end = std::min(text->find('\n', start), text->size());
      EXPECT_LE(end - start, 79u) << text->substr(start, end - start);
      start = end + 1;
    }
  }
}

}  // namespace
}  // namespace cli_test
