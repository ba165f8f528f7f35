// `ssgi compare` from the command line: the note when A and B name their channels differently
// (idiff pairs them by index) and the --channels argument it suggests.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

// A 2x2 EXR of constant channels, `values` by name.
void write_constant_exr(const std::string& path, const std::map<std::string, float>& values) {
  ExrImage image;
  image.spec = OIIO::ImageSpec(2, 2, static_cast<int>(values.size()), OIIO::TypeDesc::FLOAT);
  image.spec.channelnames.clear();
  for (const auto& [name, value] : values) {
    image.spec.channelnames.push_back(name);
    image.planes[name] = std::vector<float>(4, value);
  }
  write_exr(path, image);
}

// An ssgi output against a renderer's frame: the same light and positions under other names.
// By index (in the order OIIO reads them) P.X meets ViewLayer.DiffInd.R: a failure, as idiff's,
// with a note that names the pairs and the --channels argument that pairs the layers by their
// suffixes; with that argument the files are equal.
TEST_F(Cli, CompareSaysWhenChannelNamesDifferAndHowToPairThem) {
  const std::string a = path("ssgi.exr"), b = path("render.exr");
  write_constant_exr(a, {{"indirect.R", 0.25f},
                         {"indirect.G", 0.5f},
                         {"indirect.B", 0.75f},
                         {"P.X", 1.0f},
                         {"P.Y", 2.0f},
                         {"P.Z", 3.0f}});
  write_constant_exr(b, {{"ViewLayer.DiffInd.R", 0.25f},
                         {"ViewLayer.DiffInd.G", 0.5f},
                         {"ViewLayer.DiffInd.B", 0.75f},
                         {"ViewLayer.Position.X", 1.0f},
                         {"ViewLayer.Position.Y", 2.0f},
                         {"ViewLayer.Position.Z", 3.0f}});
  const CliResult by_index = run_ssgi({"compare", a, b});
  EXPECT_EQ(by_index.exit_code, 2) << by_index.err;
  EXPECT_NE(by_index.out.find("FAILURE"), std::string::npos) << by_index.out;
  const std::string argument =
      "P.X=ViewLayer.Position.X,P.Y=ViewLayer.Position.Y,P.Z=ViewLayer.Position.Z,"
      "indirect=ViewLayer.DiffInd";
  EXPECT_EQ(by_index.err,
            "ssgi: warning: A and B name their channels differently; compared by index: "
            "P.X with ViewLayer.DiffInd.R, P.Y with ViewLayer.DiffInd.G, P.Z with "
            "ViewLayer.DiffInd.B (6 pairs in all)\n"
            "ssgi: hint: to pair them by name: --channels " +
                argument + "\n");

  const CliResult by_name = run_ssgi({"compare", "--channels", argument, a, b});
  EXPECT_EQ(by_name.exit_code, 0) << by_name.err;
  EXPECT_EQ(by_name.err, "");
  EXPECT_NE(by_name.out.find("PASS"), std::string::npos) << by_name.out;

  // Names that agree get no note; -q keeps it quiet.
  EXPECT_EQ(run_ssgi({"compare", a, a}).err, "");
  EXPECT_EQ(run_ssgi({"compare", "-q", a, b}).err, "FAILURE\n");
}

// When the layers cannot be matched one to one (two of A's R,G,B layers, one of B's), the
// note says how to pair them without guessing.
TEST_F(Cli, CompareSuggestsNoPairingItCannotDerive) {
  const std::string a = path("ssgi.exr"), b = path("render.exr");
  write_constant_exr(a, {{"gi.R", 1.0f},
                         {"gi.G", 1.0f},
                         {"gi.B", 1.0f},
                         {"indirect.R", 1.0f},
                         {"indirect.G", 1.0f},
                         {"indirect.B", 1.0f}});
  write_constant_exr(b, {{"X.R", 1.0f}, {"X.G", 1.0f}, {"X.B", 1.0f}});
  const CliResult r = run_ssgi({"compare", a, b});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::vector<std::string> lines = r.err_lines();
  ASSERT_EQ(lines.size(), 2u) << r.err;
  EXPECT_EQ(lines[1],
            "ssgi: hint: to pair them by name: --channels A_NAME=B_NAME[,...] (a channel or an "
            "R,G,B layer)");
}

}  // namespace
}  // namespace cli_test
