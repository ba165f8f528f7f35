// Colour management through OpenColorIO (checked against its own ocioconvert): input, working
// and output spaces, environment maps, and `ssgi preview` through the config's display and view.
#include <OpenImageIO/imagebufalgo.h>
#include <fcntl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "cli_support.h"

namespace cli_test {
namespace {

TEST_F(Cli, AnEightBitEnvironmentMapIsDecodedFromSrgb) {
  // The lone plane sees only the environment. A PNG of sRGB 128 everywhere is light 0.2158605
  // (the sRGB decoding of 128/255), not 0.502: it must light the plane as an EXR holding that
  // linear value does.
  const float linear = std::pow((128.0f / 255.0f + 0.055f) / 1.055f, 2.4f);
  OIIO::ImageBuf png(OIIO::ImageSpec(64, 32, 3, OIIO::TypeDesc::UINT8));
  OIIO::ImageBufAlgo::fill(png, {128 / 255.0f, 128 / 255.0f, 128 / 255.0f});
  ASSERT_TRUE(png.write(path("env.png"))) << png.geterror();
  OIIO::ImageBuf exr(OIIO::ImageSpec(64, 32, 3, OIIO::TypeDesc::FLOAT));
  OIIO::ImageBufAlgo::fill(exr, {linear, linear, linear});
  ASSERT_TRUE(exr.write(path("env.exr"))) << exr.geterror();
  std::map<std::string, float> mean;
  for (const char* env : {"env.png", "env.exr"}) {
    const std::string out = path(std::string("o_") + env + ".0001.exr");
    const CliResult r = run_ssgi({"run", testdata("plane/plane.0001.exr"), "-o", out, "-q", "--env",
                                  path(env), "--miss", "env"});
    ASSERT_EQ(r.exit_code, 0) << env << ": " << r.err;
    const ExrImage image = read_exr(out);
    const std::vector<float>& ind = image.planes.at("indirect.G");
    double sum = 0;
    for (float v : ind) sum += v;
    mean[env] = static_cast<float>(sum / static_cast<double>(ind.size()));
  }
  EXPECT_GT(mean["env.exr"], 0.05f);
  EXPECT_NEAR(mean["env.png"], mean["env.exr"], 1e-4f * mean["env.exr"]);
}

const std::string kOcioConfig = testdata("ocio/config.ocio");

// Runs OpenColorIO's own ocioconvert (Debian's opencolorio-tools) on `in` with the test config.
int ocioconvert(const std::string& in, const std::string& from, const std::string& out,
                const std::string& to) {
  const std::string command = "OCIO='" + kOcioConfig + "' " + SSGI_OCIOCONVERT + " '" + in + "' '" +
                              from + "' '" + out + "' '" + to + "' > /dev/null 2>&1";
  return std::system(command.c_str());
}

// The channels `names` of `image` as an RGB float EXR of their own.
void write_rgb_exr(const std::string& path, const ExrImage& image,
                   const std::vector<std::string>& names) {
  ExrImage rgb;
  rgb.spec = OIIO::ImageSpec(image.spec.width, image.spec.height, 3, OIIO::TypeDesc::FLOAT);
  for (int c = 0; c < 3; ++c) rgb.planes["RGB"[c] + std::string()] = image.planes.at(names[c]);
  write_exr(path, rgb);
}

// The largest |a - b| / max(|b|, floor) over the planes `a_names` of a and `b_names` of b.
double max_relative_error(const ExrImage& a, const std::vector<std::string>& a_names,
                          const ExrImage& b, const std::vector<std::string>& b_names,
                          double floor = 1e-6) {
  double worst = 0;
  for (std::size_t c = 0; c < a_names.size(); ++c) {
    const std::vector<float>& x = a.planes.at(a_names[c]);
    const std::vector<float>& y = b.planes.at(b_names[c]);
    for (std::size_t p = 0; p < x.size(); ++p)
      worst =
          std::max(worst, std::abs(double(x[p]) - y[p]) / std::max(std::abs(double(y[p])), floor));
  }
  return worst;
}

TEST_F(Cli, OutputInAcescgMatchesOcioconvertAndRoundTripsTheInput) {
  const std::string in = testdata("sample/sample.0001.exr");
  const std::vector<std::string> base = {"run",           in,         "-q", "--temporal", "none",
                                         "--colorconfig", kOcioConfig};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  const CliResult linear = run_ssgi(with({"-o", path("linear.0001.exr")}));
  ASSERT_EQ(linear.exit_code, 0) << linear.err;
  const CliResult ap1 =
      run_ssgi(with({"-o", path("ap1.0001.exr"), "--output-colorspace", "ACEScg"}));
  ASSERT_EQ(ap1.exit_code, 0) << ap1.err;
  const ExrImage a = read_exr(path("linear.0001.exr")), b = read_exr(path("ap1.0001.exr"));
  EXPECT_EQ(a.spec.get_string_attribute("ssgi:colorspace"), "lin_rec709");
  EXPECT_EQ(b.spec.get_string_attribute("ssgi:colorspace"), "ACEScg");
  const std::vector<std::string> ind = {"indirect.R", "indirect.G", "indirect.B"};
  const std::vector<std::string> rgb = {"R", "G", "B"};
  // ocioconvert of the working-space run's layers is the ACEScg run's, to 1e-5 relative (float
  // matrices in a different order of operations; values below 1e-4 compared absolutely).
  for (const auto& layer : {ind, std::vector<std::string>{"R", "G", "B"}}) {
    write_rgb_exr(path("layer.exr"), a, layer);
    ASSERT_EQ(ocioconvert(path("layer.exr"), "lin_rec709", path("layer_ap1.exr"), "ACEScg"), 0);
    const ExrImage converted = read_exr(path("layer_ap1.exr"));
    EXPECT_LT(max_relative_error(b, layer, converted, rgb, 1e-4), 1e-5) << layer[0];
    // The transform is not the identity: the layers differ by more than rounding.
    EXPECT_GT(max_relative_error(b, layer, a, layer, 1e-4), 1e-2) << layer[0];
  }
  double lit = 0;
  for (float v : a.planes.at("indirect.G")) lit += v;
  EXPECT_GT(lit, 0);
  // In and out through ACEScg: the composite's background (the input beauty) comes back.
  const CliResult round = run_ssgi(with({"-o", path("round.0001.exr"), "--input-colorspace",
                                         "ACEScg", "--output-colorspace", "ACEScg"}));
  ASSERT_EQ(round.exit_code, 0) << round.err;
  const ExrImage r = read_exr(path("round.0001.exr"));
  const std::vector<float>& depth = r.planes.at("ViewLayer.Depth.Z");
  std::size_t background = 0;
  double worst = 0;
  for (std::size_t p = 0; p < depth.size(); ++p) {
    if (depth[p] < 1e9f) continue;
    ++background;
    for (const char* c : {"R", "G", "B"}) {
      const float want = r.planes.at(std::string("ViewLayer.Combined.") + c)[p];
      worst = std::max(worst, std::abs(double(r.planes.at(c)[p]) - want) /
                                  std::max(std::abs(double(want)), 1e-4));
    }
  }
  EXPECT_GT(background, 0u);
  EXPECT_LT(worst, 1e-5);
  // Read as ACEScg, the same passes give other light: the input transform ran.
  EXPECT_GT(max_relative_error(r, ind, b, ind, 1e-4), 1e-2);
}

TEST_F(Cli, ColourTransformsLeaveDataAndPassedThroughChannelsBitForBit) {
  const std::string in = testdata("sample/sample.0001.exr");
  const CliResult r =
      run_ssgi({"run", in, "-o", path("o.0001.exr"), "-q", "--colorconfig", kOcioConfig,
                "--input-colorspace", "ACEScg", "--output-colorspace", "ACES2065-1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ExrImage input = read_exr(in), output = read_exr(path("o.0001.exr"));
  for (const std::string& name : input.spec.channelnames) {
    const std::vector<float>& x = input.planes.at(name);
    const std::vector<float>& y = output.planes.at(name);
    ASSERT_EQ(x.size(), y.size()) << name;
    EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(float)), 0) << name;
  }
}

TEST_F(Cli, ColourOptionsAreCheckedAndDecideWhatSkipExistingKeeps) {
  const std::string in = testdata("sample/sample.0001.exr");
  const std::string out = path("o.0001.exr");
  expect_usage_error(
      run_ssgi({"run", in, "-o", out, "--input-colorspace", "ACEScg"}), "run",
      "--input-colorspace needs an OCIO config: give --colorconfig FILE or set OCIO");
  const CliResult unknown =
      run_ssgi({"run", in, "-o", out, "--colorconfig", kOcioConfig, "--output-colorspace", "nope"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("has no colour space 'nope' (it has lin_rec709, ACEScg"),
            std::string::npos)
      << unknown.err;
  const CliResult missing = run_ssgi({"run", in, "-o", out, "--colorconfig", path("none.ocio")});
  EXPECT_EQ(missing.exit_code, 4);
  expect_one_error(missing, path("none.ocio"), "cannot read the OCIO config: no such file");
  EXPECT_FALSE(fs::exists(out));
  // --skip-existing keeps a frame made with the same colour settings, remakes one made with
  // others.
  const std::vector<std::string> run = {
      "run",           in,         "-o", out, "-v", "--skip-existing", "--temporal", "none",
      "--colorconfig", kOcioConfig};
  ASSERT_EQ(run_ssgi(run).exit_code, 0);
  const CliResult again = run_ssgi(run);
  EXPECT_EQ(again.err.find("made again"), std::string::npos) << again.err;
  std::vector<std::string> other = run;
  other.insert(other.end(), {"--output-colorspace", "ACEScg"});
  const CliResult remade = run_ssgi(other);
  EXPECT_NE(remade.err.find("exists but is made again: ssgi:settings"), std::string::npos)
      << remade.err;
  EXPECT_NE(remade.err.find("ssgi's layers written as ACEScg (--output-colorspace)"),
            std::string::npos)
      << remade.err;
  EXPECT_EQ(read_exr(out).spec.get_string_attribute("ssgi:colorspace"), "ACEScg");
  // OIIO calls every EXR "Linear": said under -v, taken as scene-linear, not an error.
  EXPECT_NE(remade.err.find("the input says 'Linear', which the config does not know: taken as "
                            "scene-linear"),
            std::string::npos)
      << remade.err;
  // $OCIO stands for --colorconfig.
  ::setenv("OCIO", kOcioConfig.c_str(), 1);
  const CliResult from_env = run_ssgi({"run", in, "-o", path("env.0001.exr"), "-q",
                                       "--output-colorspace", "ACEScg", "--temporal", "none"});
  ::unsetenv("OCIO");
  ASSERT_EQ(from_env.exit_code, 0) << from_env.err;
  const ExrImage env = read_exr(path("env.0001.exr"));
  EXPECT_EQ(env.spec.get_string_attribute("ssgi:colorspace"), "ACEScg");
  EXPECT_EQ(env.planes.at("indirect.R"), read_exr(out).planes.at("indirect.R"));
}

TEST_F(Cli, AnEnvironmentMapGoesThroughTheConfigsSpaces) {
  // The lone plane sees only the environment, a constant map. Through the config, an 8-bit
  // map is decoded from its sRGB space (the same curve as without one); --env-colorspace raw
  // takes its values as they are; an ACEScg EXR map converts to lin_rec709 by the matrix.
  OIIO::ImageBuf png(OIIO::ImageSpec(64, 32, 3, OIIO::TypeDesc::UINT8));
  OIIO::ImageBufAlgo::fill(png, {128 / 255.0f, 128 / 255.0f, 128 / 255.0f});
  ASSERT_TRUE(png.write(path("env.png"))) << png.geterror();
  OIIO::ImageBuf exr(OIIO::ImageSpec(64, 32, 3, OIIO::TypeDesc::FLOAT));
  const float color[3] = {0.2f, 0.1f, 0.05f};
  OIIO::ImageBufAlgo::fill(exr, color);
  ASSERT_TRUE(exr.write(path("env.exr"))) << exr.geterror();
  const auto mean_indirect = [&](const std::string& env, std::vector<std::string> extra) {
    const std::string out = path("o.0001.exr");
    std::vector<std::string> args = {"run",      testdata("plane/plane.0001.exr"),
                                     "-o",       out,
                                     "-q",       "--env",
                                     path(env),  "--miss",
                                     "env",      "--colorconfig",
                                     kOcioConfig};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = run_ssgi(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::array<double, 3> mean{};
    const ExrImage image = read_exr(out);
    for (int c = 0; c < 3; ++c) {
      for (float v : image.planes.at(std::string("indirect.") + "RGB"[c])) mean[c] += v;
      mean[c] /= image.planes.at("indirect.R").size();
    }
    return mean;
  };
  const std::array<double, 3> srgb = mean_indirect("env.png", {});
  const std::array<double, 3> raw = mean_indirect("env.png", {"--env-colorspace", "raw"});
  const std::array<double, 3> linear = mean_indirect("env.exr", {});
  const std::array<double, 3> ap1 = mean_indirect("env.exr", {"--env-colorspace", "ACEScg"});
  // sRGB 128 is light 0.2158605; 0.502 as data; the EXR's green 0.1 as it is. The light is
  // proportional to the map's value in each channel.
  const double decoded = std::pow((128.0 / 255 + 0.055) / 1.055, 2.4);
  EXPECT_GT(linear[1], 0.005);
  EXPECT_NEAR(srgb[1] / linear[1], decoded / color[1], 1e-3);
  EXPECT_NEAR(raw[1] / linear[1], (128.0 / 255) / color[1], 1e-3);
  // Read as ACEScg, each channel scales as ocioconvert converts the map's colour.
  ASSERT_EQ(ocioconvert(path("env.exr"), "ACEScg", path("env_rec709.exr"), "lin_rec709"), 0);
  const ExrImage converted = read_exr(path("env_rec709.exr"));
  for (int c = 0; c < 3; ++c) {
    const double want = converted.planes.at(std::string(1, "RGB"[c]))[0] / color[c];
    EXPECT_NEAR(ap1[c] / linear[c], want, 1e-3 * want) << c;
  }
  EXPECT_GT(ap1[0] / linear[0], 1.2);  // AP1 red is redder than Rec.709's
}

TEST_F(Cli, PreviewIsTheCompositeThroughTheDisplayPerFrame) {
  const std::string in = testdata("sample/sample.####.exr");
  const std::vector<std::string> run = {"run",       in,
                                        "--frames",  "1-2",
                                        "-o",        path("o.####.exr"),
                                        "--preview", path("p.####.png"),
                                        "-q",        "--skip-existing"};
  ASSERT_EQ(run_ssgi(run).exit_code, 0);
  const ExrImage exr = read_exr(path("o.0001.exr"));
  auto png = OIIO::ImageInput::open(path("p.0001.png"));
  ASSERT_TRUE(png);
  const OIIO::ImageSpec spec = png->spec();
  EXPECT_EQ(spec.width, exr.spec.full_width);
  EXPECT_EQ(spec.height, exr.spec.full_height);
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT8);
  std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * 3);
  ASSERT_TRUE(png->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()));
  // Without a config: the sRGB encoding of the composite, to the 8-bit step.
  double sum = 0, worst = 0;
  for (std::size_t p = 0; p < pixels.size() / 3; ++p)
    for (int c = 0; c < 3; ++c) {
      const float v = std::clamp(exr.planes.at("RGB"[c] + std::string())[p], 0.0f, 1.0f);
      const float want = v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
      worst = std::max(worst, std::abs(double(pixels[p * 3 + c]) - want));
      sum += pixels[p * 3 + c];
    }
  EXPECT_LE(worst, 0.5 / 255 + 1e-6);
  EXPECT_GT(sum / pixels.size(), 0.02);
  // A rerun keeps both frames; a missing preview makes its frame again.
  const std::string before = file_bytes(path("o.0002.exr"));
  fs::remove(path("p.0001.png"));
  const CliResult again = run_ssgi(run);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(fs::exists(path("p.0001.png")));
  EXPECT_EQ(file_bytes(path("o.0002.exr")), before);
  std::vector<std::string> refuse = run;
  refuse.back() = "--no-clobber";
  const CliResult refused = run_ssgi(refuse);
  EXPECT_EQ(refused.exit_code, 2);
  expect_usage_error(run_ssgi({"run", in, "-o", path("o.####.exr"), "--preview", path("p.tif")}),
                     "run",
                     "--preview '" + path("p.tif") +
                         "' has no frame field (e.g. ####) but 6 frames are to be written");
}

TEST_F(Cli, PreviewSheetShowsEachFramesPassesAndTheDifference) {
  const std::string in = testdata("sample/sample.####.exr");
  // The reference: a run with other settings, so that the difference is not zero.
  ASSERT_EQ(run_ssgi({"run", in, "-o", path("ref.####.exr"), "-q", "--bounces", "1"}).exit_code, 0);
  const CliResult r = run_ssgi({"preview", in, "--frames", "2,5", "--reference",
                                path("ref.####.exr"), "-o", path("sheet.png")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  OIIO::ImageBuf sheet(path("sheet.png"));
  ASSERT_TRUE(sheet.read()) << sheet.geterror();
  // Two rows of five 96x64 panels with the labels around them.
  EXPECT_EQ(sheet.spec().width, 84 + 5 * (96 + 8) + 8);
  EXPECT_EQ(sheet.spec().height, 50 + 28 + 2 * (64 + 22 + 8) + 8);
  // The composite panel of the first row is lit; the difference panel is not all black.
  const auto mean_of = [&](int column) {
    const OIIO::ROI roi(84 + column * 104, 84 + column * 104 + 96, 78, 78 + 64);
    const auto stats = OIIO::ImageBufAlgo::computePixelStats(sheet, roi);
    return (stats.avg[0] + stats.avg[1] + stats.avg[2]) / 3;
  };
  EXPECT_GT(mean_of(3), 0.05);
  EXPECT_GT(mean_of(4), 0.01);
  expect_usage_error(run_ssgi({"preview", in, "-o", path("sheet.jpg")}), "preview",
                     "output '" + path("sheet.jpg") + "' must end in .png: the sheet is a PNG");
  EXPECT_FALSE(fs::exists(path("sheet.jpg")));
}

TEST_F(Cli, PreviewGoesThroughTheConfigsDisplayAndView) {
  const std::string in = testdata("sample/sample.0001.exr");
  const auto preview = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "run", in, "-o", path(name + ".0001.exr"), "-q", "--preview", path(name + ".0001.png")};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = run_ssgi(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    OIIO::ImageBuf png(path(name + ".0001.png"));
    EXPECT_TRUE(png.read()) << png.geterror();
    return png;
  };
  const OIIO::ImageBuf plain = preview("plain", {});
  const OIIO::ImageBuf standard = preview("standard", {"--colorconfig", kOcioConfig});
  const OIIO::ImageBuf raw =
      preview("raw", {"--colorconfig", kOcioConfig, "--display-view", "Raw"});
  // The config's sRGB / Standard view is the sRGB curve: the built-in one's picture, to the
  // 8-bit step where float rounding crosses one.
  const auto standard_diff = OIIO::ImageBufAlgo::compare(standard, plain, 1.01 / 255, 0);
  EXPECT_LE(standard_diff.maxerror, 1.01 / 255);
  // The Raw view shows the composite's values clamped to [0, 1], not encoded: darker.
  const ExrImage exr = read_exr(path("raw.0001.exr"));
  double worst = 0;
  for (int y = 0; y < exr.spec.height; ++y)
    for (int x = 0; x < exr.spec.width; ++x) {
      float p[3];
      raw.getpixel(x, y, p, 3);
      for (int c = 0; c < 3; ++c) {
        const float v = exr.planes.at(std::string(1, "RGB"[c]))[y * exr.spec.width + x];
        worst = std::max(worst, std::abs(double(p[c]) - std::clamp(v, 0.0f, 1.0f)));
      }
    }
  EXPECT_LE(worst, 0.5 / 255 + 1e-6);
  const auto stats_raw = OIIO::ImageBufAlgo::computePixelStats(raw);
  const auto stats_plain = OIIO::ImageBufAlgo::computePixelStats(plain);
  EXPECT_LT(stats_raw.avg[1], 0.8 * stats_plain.avg[1]);
  const CliResult bad =
      run_ssgi({"run", in, "-o", path("x.0001.exr"), "--preview", path("x.0001.png"),
                "--colorconfig", kOcioConfig, "--display-view", "Filmic"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("has no view 'Filmic'"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("x.0001.exr")));
}

}  // namespace
}  // namespace cli_test
