// What the reader gives the pipeline: colour transforms on the light and albedo passes only, and
// normals derived from depth; the composite of those passes, written beside them or over them;
// and the same frame given as buffers instead.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <tuple>

#include "gi/composite.h"
#include "gtest/gtest.h"
#include "io/color.h"
#include "io/input_frame.h"
#include "io/pass_agreement.h"
#include "pipeline_support.h"
#include "plan.h"

namespace ssgi::pipeline_test {
namespace {

// Read through an ACEScg -> lin_rec709 transform, the colour passes change and the data passes
// (depth, normals, motion) keep every bit.
TEST(Pipeline, ColourTransformsTouchLightAndAlbedoOnly) {
  InputOptions in;
  in.pattern = std::string(SSGI_TESTDATA_DIR) + "/moving/moving.0002.exr";
  const SequenceInfo seq = open_sequence(in);
  GiSettings s;
  const RoleMask roles = make_plan(seq, s).roles;
  ASSERT_TRUE(roles & role_bit(Role::kMotion));
  ColorSettings c;
  c.config = std::string(SSGI_TESTDATA_DIR) + "/ocio/config.ocio";
  c.input = "ACEScg";
  const ColorManagement color(c);
  EXPECT_EQ(color.working_space(), "lin_rec709");
  const GBuffer plain = read_gbuffer(seq, 2, roles, in);
  const GBuffer converted = read_gbuffer(seq, 2, roles, in, &color);
  for (const auto& [name, a, b] :
       {std::tuple{"depth", &plain.depth, &converted.depth},
        std::tuple{"normal", &plain.normal, &converted.normal},
        std::tuple{"motion_prev", &plain.motion_prev, &converted.motion_prev}}) {
    ASSERT_FALSE(a->empty()) << name;
    ASSERT_EQ(a->data().size(), b->data().size()) << name;
    EXPECT_EQ(std::memcmp(a->data().data(), b->data().data(), a->bytes()), 0) << name;
  }
  // ACEScg (1, 0, 0) is lin_rec709 (1.705, -0.130, -0.024): red albedo gets redder.
  double changed = 0;
  for (std::size_t i = 0; i < plain.albedo.data().size(); ++i)
    changed =
        std::max(changed, double(std::abs(plain.albedo.data()[i] - converted.albedo.data()[i])));
  EXPECT_GT(changed, 0.01);
}

// --normals depth: on the ground plane and on the sample room the normals the reader derives
// from depth are the file's wherever the pixel and its neighbours lie on one flat surface
// (within 1 degree on every pixel of the plane; on 85% of the room's, measured 90%: its boxes and
// walls are flat),
// and the plan says where they come from.
TEST(Pipeline, NormalsFromDepthMatchTheFlatSurfacesOfThePass) {
  for (const auto& [pattern, share] :
       {std::pair{"plane/plane.0001.exr", 0.99}, std::pair{"sample/sample.0001.exr", 0.85}}) {
    SCOPED_TRACE(pattern);
    InputOptions in;
    in.pattern = std::string(SSGI_TESTDATA_DIR) + "/" + pattern;
    in.normals = "pass";
    const SequenceInfo pass_seq = open_sequence(in);
    in.normals = "depth";
    const SequenceInfo depth_seq = open_sequence(in);
    ASSERT_FALSE(pass_seq.normals_from_depth);
    ASSERT_TRUE(depth_seq.normals_from_depth);
    const GiSettings s;
    const Plan plan = make_plan(depth_seq, s);
    bool said = false;
    for (const std::string& r : plan.reasons)
      said |= r.find("depth buffer's pixel") != std::string::npos;
    EXPECT_TRUE(said);
    const GBuffer a = read_gbuffer(pass_seq, pass_seq.frames.front(), plan.roles, in);
    const GBuffer b = read_gbuffer(depth_seq, depth_seq.frames.front(), plan.roles, in);
    std::size_t surfaces = 0, agree = 0;
    for (int y = 0; y < a.height(); ++y)
      for (int x = 0; x < a.width(); ++x) {
        if (!a.is_surface(x, y)) continue;
        ++surfaces;
        double dot = 0;
        for (int c = 0; c < 3; ++c) dot += a.normal.at(c, x, y) * b.normal.at(c, x, y);
        agree += dot > std::cos(M_PI / 180) ? 1 : 0;
      }
    std::printf("%s: %zu of %zu normals within 1 degree\n", pattern, agree, surfaces);
    ASSERT_GT(surfaces, 100u);
    EXPECT_GE(static_cast<double>(agree), share * surfaces);
  }
}

// --normals depth on features one pixel across: a wall facing the camera with a pole (a column,
// 0.3 nearer) and a rod (a row, 0.1 nearer) before it. Either one-sided difference across the
// pole or the rod runs to the wall and would turn its normal sideways; a pixel both of whose
// neighbours lie nearer or both farther faces the camera along that axis, so every pixel here
// gets the wall's normal, the camera's -z.
TEST(Pipeline, NormalsFromDepthTurnFeaturesOnePixelAcrossToTheCamera) {
  const Box2i window{0, 0, 64, 48};
  const Camera cam = camera_from_fov(60.0, window);
  Image depth(64, 48, 1, 10.0f);
  for (int y = 0; y < 48; ++y) depth.at(0, 20, y) = 9.7f;  // the pole
  for (int x = 0; x < 64; ++x) depth.at(0, x, 30) = 9.9f;  // the rod
  const Image n = detail::normals_from_depth(depth, cam, window, window);
  for (const auto& [x, y] : {std::pair{20, 10}, std::pair{40, 30}, std::pair{20, 30},
                             std::pair{19, 10}, std::pair{21, 10}, std::pair{40, 29}}) {
    SCOPED_TRACE(std::to_string(x) + "," + std::to_string(y));
    EXPECT_NEAR(n.at(0, x, y), 0.0f, 1e-4f);
    EXPECT_NEAR(n.at(1, x, y), 0.0f, 1e-4f);
    EXPECT_NEAR(n.at(2, x, y), -1.0f, 1e-6f);
  }
}

bool same_bits(const Image& a, const Image& b) {
  return a.channels() == b.channels() && a.width() == b.width() && a.height() == b.height() &&
         std::memcmp(a.data().data(), b.data().data(), a.bytes()) == 0;
}

// The composite written over the frame's albedo and beauty has the bits of the one written beside
// them, on a frame with background, surfaces without albedo and non-finite light; with a beauty
// (written over), without one, and without emission.
TEST(Pipeline, CompositeInPlaceGivesTheBitsOfTheCompositeBeside) {
  GiSettings s;
  const Frame f = load("sample/sample.0001.exr", s);
  const Pipeline pipeline(f.seq, s);
  Image coverage;
  const Image indirect = pipeline.indirect_light(f.g, &coverage);
  GBuffer base = f.g;
  ASSERT_EQ(base.beauty.channels(), 4);
  ASSERT_FALSE(base.emission.empty());
  const int w = base.width();
  for (int x = 0; x < w; ++x) {
    for (int c = 0; c < 3; ++c) base.albedo.at(c, x, 1) = 0.0f;       // row 1: no albedo
    base.depth.at(0, x, 2) = std::numeric_limits<float>::infinity();  // row 2: background
  }
  base.direct.at(0, 3, 3) = std::numeric_limits<float>::quiet_NaN();
  base.direct.at(1, 4, 3) = 3e38f;
  base.emission.at(2, 4, 3) = 3e38f;
  int cases = 0;
  for (const int variant : {0, 1, 2}) {
    GBuffer g = base;
    if (variant == 1) g.beauty = Image();
    if (variant == 2) g.emission = Image();
    const FrameResult beside = detail::composite_frame(g, indirect, coverage);
    const FrameResult over = detail::composite_frame_in_place(&g, indirect, coverage);
    EXPECT_TRUE(same_bits(beside.indirect, over.indirect)) << variant;
    EXPECT_TRUE(same_bits(beside.gi, over.gi)) << variant;
    EXPECT_TRUE(same_bits(beside.composite, over.composite)) << variant;
    EXPECT_TRUE(same_bits(beside.coverage, over.coverage)) << variant;
    EXPECT_TRUE(g.albedo.empty() && g.beauty.empty()) << variant;
    // Not a composite of nothing: surfaces got light, the background the beauty.
    double gi = 0;
    for (float v : over.gi.data()) gi += v;
    EXPECT_GT(gi, 0) << variant;
    if (variant != 1) EXPECT_EQ(over.composite.at(0, 5, 2), base.beauty.at(0, 5, 2)) << variant;
    ++cases;
  }
  EXPECT_EQ(cases, 3);
}

// A frame given as buffers (still_sequence) is lit as its file is: the same bits, with the same
// coverage; and a pass with the wrong channels or size is a usage error that names it.
TEST(Pipeline, AStillSequenceLightsBuffersAsTheirFileIs) {
  GiSettings s;
  const Frame f = load("sample/sample.0001.exr", s);
  Image file_coverage, buffers_coverage;
  const Image file = Pipeline(f.seq, s).indirect_light(f.g, &file_coverage);
  const Image buffers = Pipeline(*still_sequence(f.g), s).indirect_light(f.g, &buffers_coverage);
  EXPECT_TRUE(same_bits(file, buffers));
  EXPECT_TRUE(same_bits(file_coverage, buffers_coverage));
  for (const bool wrong_size : {false, true}) {
    GBuffer g = f.g;
    g.normal = Image(g.width() - (wrong_size ? 1 : 0), g.height(), wrong_size ? 3 : 1);
    try {
      still_sequence(g);
      ADD_FAILURE() << "accepted a normal pass it cannot use";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kUsage);
      EXPECT_NE(std::string(e.what()).find("normal"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace ssgi::pipeline_test
