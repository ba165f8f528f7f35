#include "io/layout.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ssgi/error.h"

namespace ssgi {
namespace {

using Names = std::vector<std::string>;

FileChannels one_part(Names channels, std::map<std::string, std::string> attributes = {}) {
  FileChannels f;
  f.subimage_names = {""};
  f.channels = {std::move(channels)};
  f.attributes = std::move(attributes);
  return f;
}

Names names(const Layout& layout, Role role) {
  Names out;
  for (const ChannelRef& c : layout.channels(role)) out.push_back(c.name);
  return out;
}

// The channel list of /work/shared/data/room/room.0001.exr as `oiiotool --info -v` prints it.
const Names kCyclesSampleChannels = {
    "ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B", "ViewLayer.Combined.A",
    "ViewLayer.Depth.Z",    "ViewLayer.DiffCol.R",  "ViewLayer.DiffCol.G",  "ViewLayer.DiffCol.B",
    "ViewLayer.DiffDir.R",  "ViewLayer.DiffDir.G",  "ViewLayer.DiffDir.B",  "ViewLayer.DiffInd.R",
    "ViewLayer.DiffInd.G",  "ViewLayer.DiffInd.B",  "ViewLayer.Emit.R",     "ViewLayer.Emit.G",
    "ViewLayer.Emit.B",     "ViewLayer.Env.R",      "ViewLayer.Env.G",      "ViewLayer.Env.B",
    "ViewLayer.Normal.X",   "ViewLayer.Normal.Y",   "ViewLayer.Normal.Z",   "ViewLayer.Position.X",
    "ViewLayer.Position.Y", "ViewLayer.Position.Z", "ViewLayer.Vector.X",   "ViewLayer.Vector.Y",
    "ViewLayer.Vector.Z",   "ViewLayer.Vector.W"};

const std::map<std::string, std::string> kCyclesSampleAttributes = {
    {"BlenderMultiChannel", "Blender V2.55.1 and newer"},
    {"cycles.ViewLayer.samples", "512"},
    {"compression", "zip"}};

// The sample's channels under the names Arnold gives the same passes.
Names arnold_names(const Names& blender) {
  const std::map<std::string, std::string> rename = {{"Combined.R", "R"},
                                                     {"Combined.G", "G"},
                                                     {"Combined.B", "B"},
                                                     {"Combined.A", "A"},
                                                     {"Depth.Z", "Z"},
                                                     {"DiffCol.R", "diffuse_albedo.R"},
                                                     {"DiffCol.G", "diffuse_albedo.G"},
                                                     {"DiffCol.B", "diffuse_albedo.B"},
                                                     {"DiffDir.R", "diffuse_direct.R"},
                                                     {"DiffDir.G", "diffuse_direct.G"},
                                                     {"DiffDir.B", "diffuse_direct.B"},
                                                     {"DiffInd.R", "diffuse_indirect.R"},
                                                     {"DiffInd.G", "diffuse_indirect.G"},
                                                     {"DiffInd.B", "diffuse_indirect.B"},
                                                     {"Emit.R", "emission.R"},
                                                     {"Emit.G", "emission.G"},
                                                     {"Emit.B", "emission.B"},
                                                     {"Env.R", "background.R"},
                                                     {"Env.G", "background.G"},
                                                     {"Env.B", "background.B"},
                                                     {"Normal.X", "N.X"},
                                                     {"Normal.Y", "N.Y"},
                                                     {"Normal.Z", "N.Z"},
                                                     {"Position.X", "P.X"},
                                                     {"Position.Y", "P.Y"},
                                                     {"Position.Z", "P.Z"},
                                                     {"Vector.X", "motionvector.X"},
                                                     {"Vector.Y", "motionvector.Y"}};
  Names out;
  for (const std::string& name : blender) {
    auto it = rename.find(name.substr(std::string("ViewLayer.").size()));
    if (it != rename.end()) out.push_back(it->second);
  }
  return out;
}

TEST(LayoutNames, RolesRoundTrip) {
  for (int i = 0; i < kRoleCount; ++i) {
    Role role;
    ASSERT_TRUE(parse_role(role_name(static_cast<Role>(i)), &role)) << i;
    EXPECT_EQ(static_cast<int>(role), i);
  }
  Role role;
  EXPECT_FALSE(parse_role("colour", &role));
  EXPECT_FALSE(parse_role("Depth", &role));
  EXPECT_EQ(role_min_components(Role::kDepth), 1);
  EXPECT_EQ(role_max_components(Role::kDepth), 1);
  EXPECT_EQ(role_min_components(Role::kMotion), 2);
  EXPECT_EQ(role_max_components(Role::kMotion), 4);
  EXPECT_EQ(role_min_components(Role::kBeauty), 3);
  EXPECT_EQ(role_max_components(Role::kBeauty), 4);
  EXPECT_EQ(role_max_components(Role::kAlbedo), 3);
}

TEST(LayoutNames, DepthKindsRoundTrip) {
  for (DepthKind k :
       {DepthKind::kPlanarZ, DepthKind::kRadial, DepthKind::kInverseZ, DepthKind::kNegativeZ}) {
    DepthKind parsed;
    ASSERT_TRUE(parse_depth_kind(depth_kind_name(k), &parsed)) << depth_kind_name(k);
    EXPECT_EQ(parsed, k);
  }
  DepthKind parsed;
  EXPECT_FALSE(parse_depth_kind("linear", &parsed));
  EXPECT_STREQ(normal_space_name(NormalSpace::kWorld), "world");
  EXPECT_STREQ(normal_space_name(NormalSpace::kCamera), "camera");
  for (NormalSpace s :
       {NormalSpace::kWorld, NormalSpace::kCamera, NormalSpace::kCameraGl, NormalSpace::kAuto}) {
    NormalSpace read;
    ASSERT_TRUE(parse_normal_space(normal_space_name(s), &read)) << normal_space_name(s);
    EXPECT_EQ(read, s);
  }
  NormalSpace read;
  EXPECT_FALSE(parse_normal_space("object", &read));
}

TEST(LayoutPresets, TableHasEveryRendererAndCitesIt) {
  Names got;
  for (const LayoutPreset& p : layout_presets()) {
    got.push_back(p.name);
    EXPECT_FALSE(p.renderer.empty()) << p.name;
    EXPECT_FALSE(p.reference.empty()) << p.name;
    EXPECT_EQ(p.candidates[0].empty(), p.name == "custom") << p.name;
  }
  EXPECT_EQ(got, (Names{"blender", "arnold", "vray", "renderman", "karma", "redshift", "unreal",
                        "nuke", "custom"}));
  ASSERT_NE(find_layout_preset("nuke"), nullptr);
  EXPECT_EQ(find_layout_preset("nuke")->depth_kind, DepthKind::kInverseZ);
  EXPECT_EQ(find_layout_preset("mantra"), nullptr);
}

TEST(LayoutDetect, CyclesSampleIsBlender) {
  const Layout l =
      resolve_layout(one_part(kCyclesSampleChannels, kCyclesSampleAttributes), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "blender");
  EXPECT_EQ(names(l, Role::kDepth), Names{"ViewLayer.Depth.Z"});
  EXPECT_EQ(names(l, Role::kNormal),
            (Names{"ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"}));
  EXPECT_EQ(names(l, Role::kAlbedo),
            (Names{"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B"}));
  EXPECT_EQ(names(l, Role::kDirect),
            (Names{"ViewLayer.DiffDir.R", "ViewLayer.DiffDir.G", "ViewLayer.DiffDir.B"}));
  EXPECT_EQ(names(l, Role::kEmission),
            (Names{"ViewLayer.Emit.R", "ViewLayer.Emit.G", "ViewLayer.Emit.B"}));
  EXPECT_EQ(names(l, Role::kMotion), (Names{"ViewLayer.Vector.X", "ViewLayer.Vector.Y",
                                            "ViewLayer.Vector.Z", "ViewLayer.Vector.W"}));
  EXPECT_EQ(names(l, Role::kPosition),
            (Names{"ViewLayer.Position.X", "ViewLayer.Position.Y", "ViewLayer.Position.Z"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"ViewLayer.Combined.R", "ViewLayer.Combined.G",
                                            "ViewLayer.Combined.B", "ViewLayer.Combined.A"}));
  for (int i = 0; i < kRoleCount; ++i)
    for (const ChannelRef& c : l.roles[i]) EXPECT_EQ(c.subimage, 0);
  EXPECT_EQ(l.preset.depth_kind, DepthKind::kPlanarZ);
  EXPECT_EQ(l.preset.normal_space, NormalSpace::kWorld);
  EXPECT_FALSE(l.preset.direct_includes_albedo);
  // Vector: XY = previous - current, ZW = current - next, y up (data README).
  EXPECT_TRUE(l.preset.motion.xy_to_previous);
  EXPECT_TRUE(l.preset.motion.y_up);
  EXPECT_TRUE(l.preset.motion.zw_current_minus_next);
  EXPECT_LT(l.preset.background_depth, 1e10);
  EXPECT_NE(l.detected_because.find("header attribute BlenderMultiChannel"), std::string::npos)
      << l.detected_because;
  EXPECT_NE(l.detected_because.find("depth ViewLayer.Depth.Z"), std::string::npos)
      << l.detected_because;
  EXPECT_NE(l.detected_because.find("normal ViewLayer.Normal.{X,Y,Z}"), std::string::npos)
      << l.detected_because;
}

TEST(LayoutDetect, BlenderWithoutAttributesStillDetectedByChannels) {
  const Layout l = resolve_layout(one_part(kCyclesSampleChannels), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "blender");
  EXPECT_EQ(l.detected_because.find("header attribute"), std::string::npos);
}

TEST(LayoutDetect, BlenderLongPassNamesAnyViewLayerAndReorderedChannels) {
  // Newer Blender pass names, a view layer not called ViewLayer, and components in the order
  // OIIO may report them (it moves channels inside a layer).
  const Names channels = {
      "Shot_A.Combined.A",       "Shot_A.Combined.B",       "Shot_A.Combined.G",
      "Shot_A.Combined.R",       "Shot_A.Depth.Z",          "Shot_A.Diffuse Color.B",
      "Shot_A.Diffuse Color.G",  "Shot_A.Diffuse Color.R",  "Shot_A.Diffuse Direct.R",
      "Shot_A.Diffuse Direct.G", "Shot_A.Diffuse Direct.B", "Shot_A.Emission.R",
      "Shot_A.Emission.G",       "Shot_A.Emission.B",       "Shot_A.Normal.Z",
      "Shot_A.Normal.X",         "Shot_A.Normal.Y"};
  const Layout l = resolve_layout(one_part(channels), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "blender");
  EXPECT_EQ(names(l, Role::kDepth), Names{"Shot_A.Depth.Z"});
  EXPECT_EQ(names(l, Role::kNormal),
            (Names{"Shot_A.Normal.X", "Shot_A.Normal.Y", "Shot_A.Normal.Z"}));
  EXPECT_EQ(names(l, Role::kAlbedo),
            (Names{"Shot_A.Diffuse Color.R", "Shot_A.Diffuse Color.G", "Shot_A.Diffuse Color.B"}));
  EXPECT_EQ(names(l, Role::kDirect), (Names{"Shot_A.Diffuse Direct.R", "Shot_A.Diffuse Direct.G",
                                            "Shot_A.Diffuse Direct.B"}));
  EXPECT_EQ(names(l, Role::kEmission),
            (Names{"Shot_A.Emission.R", "Shot_A.Emission.G", "Shot_A.Emission.B"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"Shot_A.Combined.R", "Shot_A.Combined.G",
                                            "Shot_A.Combined.B", "Shot_A.Combined.A"}));
  EXPECT_FALSE(l.has(Role::kMotion));
  EXPECT_FALSE(l.has(Role::kPosition));
}

TEST(LayoutDetect, BlenderTwoViewLayersReadEveryRoleFromTheDepthsLayer) {
  // "Fg" comes first in the list for albedo, but depth is found in "Bg" first: all roles must
  // come from one view layer.
  const Names channels = {"Bg.Depth.Z",  "Fg.DiffCol.R", "Fg.DiffCol.G", "Fg.DiffCol.B",
                          "Fg.Depth.Z",  "Bg.DiffCol.R", "Bg.DiffCol.G", "Bg.DiffCol.B",
                          "Fg.Normal.X", "Fg.Normal.Y",  "Fg.Normal.Z",  "Bg.Normal.X",
                          "Bg.Normal.Y", "Bg.Normal.Z"};
  const Layout l = resolve_layout(one_part(channels), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "blender");
  EXPECT_EQ(names(l, Role::kDepth), Names{"Bg.Depth.Z"});
  EXPECT_EQ(names(l, Role::kAlbedo), (Names{"Bg.DiffCol.R", "Bg.DiffCol.G", "Bg.DiffCol.B"}));
  EXPECT_EQ(names(l, Role::kNormal), (Names{"Bg.Normal.X", "Bg.Normal.Y", "Bg.Normal.Z"}));
}

TEST(LayoutDetect, SampleRenamedToArnoldIsArnold) {
  for (bool with_signature : {true, false}) {
    std::map<std::string, std::string> attrs;
    if (with_signature) attrs["arnold/version"] = "Arnold 7.2.5.0";
    const Layout l =
        resolve_layout(one_part(arnold_names(kCyclesSampleChannels), attrs), "", {}, "f.exr");
    EXPECT_EQ(l.preset.name, "arnold");
    EXPECT_EQ(names(l, Role::kDepth), Names{"Z"});
    EXPECT_EQ(names(l, Role::kNormal), (Names{"N.X", "N.Y", "N.Z"}));
    EXPECT_EQ(names(l, Role::kAlbedo),
              (Names{"diffuse_albedo.R", "diffuse_albedo.G", "diffuse_albedo.B"}));
    EXPECT_EQ(names(l, Role::kDirect),
              (Names{"diffuse_direct.R", "diffuse_direct.G", "diffuse_direct.B"}));
    EXPECT_EQ(names(l, Role::kEmission), (Names{"emission.R", "emission.G", "emission.B"}));
    EXPECT_EQ(names(l, Role::kMotion), (Names{"motionvector.X", "motionvector.Y"}));
    EXPECT_EQ(names(l, Role::kPosition), (Names{"P.X", "P.Y", "P.Z"}));
    EXPECT_EQ(names(l, Role::kBeauty), (Names{"R", "G", "B", "A"}));
    EXPECT_TRUE(l.preset.direct_includes_albedo);
    EXPECT_EQ(l.preset.normal_space, NormalSpace::kWorld);
    EXPECT_EQ(l.detected_because.find("header attribute arnold/version") != std::string::npos,
              with_signature)
        << l.detected_because;
  }
}

TEST(LayoutDetect, VRay) {
  const Names channels = {"R",
                          "G",
                          "B",
                          "A",
                          "VRayDiffuseFilter.R",
                          "VRayDiffuseFilter.G",
                          "VRayDiffuseFilter.B",
                          "VRayNormals.R",
                          "VRayNormals.G",
                          "VRayNormals.B",
                          "VRayRawLighting.R",
                          "VRayRawLighting.G",
                          "VRayRawLighting.B",
                          "VRaySelfIllumination.R",
                          "VRaySelfIllumination.G",
                          "VRaySelfIllumination.B",
                          "VRayVelocity.R",
                          "VRayVelocity.G",
                          "VRayVelocity.B",
                          "VRayZDepth.R",
                          "VRayZDepth.G",
                          "VRayZDepth.B"};
  const Layout l =
      resolve_layout(one_part(channels, {{"vrayInfo/vrayversion", "6.00.20"}}), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "vray");
  EXPECT_EQ(names(l, Role::kDepth), Names{"VRayZDepth.R"});
  EXPECT_EQ(names(l, Role::kNormal), (Names{"VRayNormals.R", "VRayNormals.G", "VRayNormals.B"}));
  EXPECT_EQ(names(l, Role::kAlbedo),
            (Names{"VRayDiffuseFilter.R", "VRayDiffuseFilter.G", "VRayDiffuseFilter.B"}));
  EXPECT_EQ(names(l, Role::kDirect),
            (Names{"VRayRawLighting.R", "VRayRawLighting.G", "VRayRawLighting.B"}));
  EXPECT_EQ(names(l, Role::kEmission),
            (Names{"VRaySelfIllumination.R", "VRaySelfIllumination.G", "VRaySelfIllumination.B"}));
  // R G B A would give four components; velocity has only R G B, so two.
  EXPECT_EQ(names(l, Role::kMotion), (Names{"VRayVelocity.R", "VRayVelocity.G"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"R", "G", "B", "A"}));
  EXPECT_FALSE(l.has(Role::kPosition));
  EXPECT_FALSE(l.preset.direct_includes_albedo);
  // Camera space, on axes V-Ray does not document: decided per frame.
  EXPECT_EQ(l.preset.normal_space, NormalSpace::kAuto);
  EXPECT_NE(l.detected_because.find("vrayInfo/vrayversion"), std::string::npos);
}

TEST(LayoutDetect, RenderMan) {
  const Names channels = {"R",
                          "G",
                          "B",
                          "A",
                          "Nn.x",
                          "Nn.y",
                          "Nn.z",
                          "P.x",
                          "P.y",
                          "P.z",
                          "albedo.r",
                          "albedo.g",
                          "albedo.b",
                          "backward.x",
                          "backward.y",
                          "directDiffuse.r",
                          "directDiffuse.g",
                          "directDiffuse.b",
                          "emissive.r",
                          "emissive.g",
                          "emissive.b",
                          "z"};
  const Layout l = resolve_layout(one_part(channels), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "renderman");
  EXPECT_EQ(names(l, Role::kDepth), Names{"z"});
  EXPECT_EQ(names(l, Role::kNormal), (Names{"Nn.x", "Nn.y", "Nn.z"}));
  EXPECT_EQ(names(l, Role::kAlbedo), (Names{"albedo.r", "albedo.g", "albedo.b"}));
  EXPECT_EQ(names(l, Role::kDirect),
            (Names{"directDiffuse.r", "directDiffuse.g", "directDiffuse.b"}));
  EXPECT_EQ(names(l, Role::kEmission), (Names{"emissive.r", "emissive.g", "emissive.b"}));
  EXPECT_EQ(names(l, Role::kMotion), (Names{"backward.x", "backward.y"}));
  EXPECT_EQ(names(l, Role::kPosition), (Names{"P.x", "P.y", "P.z"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"R", "G", "B", "A"}));
  EXPECT_TRUE(l.preset.direct_includes_albedo);
  EXPECT_EQ(l.preset.normal_space, NormalSpace::kCamera);
  EXPECT_TRUE(l.preset.motion.xy_to_previous);
}

FileChannels karma_file() {
  FileChannels f;
  f.subimage_names = {"C",      "depth",         "N",        "P",
                      "albedo", "directdiffuse", "emission", "motionvector"};
  f.channels = {{"R", "G", "B", "A"}, {"Z"},           {"R", "G", "B"}, {"R", "G", "B"},
                {"R", "G", "B"},      {"R", "G", "B"}, {"R", "G", "B"}, {"R", "G", "B"}};
  f.attributes = {{"Software", "Karma (cpu) 20.5.684"}};
  return f;
}

TEST(LayoutDetect, KarmaMultiPart) {
  const Layout l = resolve_layout(karma_file(), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "karma");
  auto expect_role = [&](Role role, int subimage, const Names& channels) {
    EXPECT_EQ(names(l, role), channels) << role_name(role);
    for (const ChannelRef& c : l.channels(role)) EXPECT_EQ(c.subimage, subimage) << role_name(role);
  };
  expect_role(Role::kBeauty, 0, {"R", "G", "B", "A"});
  expect_role(Role::kDepth, 1, {"Z"});
  expect_role(Role::kNormal, 2, {"R", "G", "B"});
  expect_role(Role::kPosition, 3, {"R", "G", "B"});
  expect_role(Role::kAlbedo, 4, {"R", "G", "B"});
  expect_role(Role::kDirect, 5, {"R", "G", "B"});
  expect_role(Role::kEmission, 6, {"R", "G", "B"});
  expect_role(Role::kMotion, 7, {"R", "G"});
  EXPECT_TRUE(l.preset.direct_includes_albedo);
  EXPECT_NE(l.detected_because.find("Software \"Karma (cpu) 20.5.684\""), std::string::npos)
      << l.detected_because;
  EXPECT_NE(l.detected_because.find("depth depth/Z"), std::string::npos) << l.detected_because;
}

TEST(LayoutDetect, KarmaSinglePartLayers) {
  const Names channels = {"C.R",
                          "C.G",
                          "C.B",
                          "C.A",
                          "N.X",
                          "N.Y",
                          "N.Z",
                          "albedo.R",
                          "albedo.G",
                          "albedo.B",
                          "Pz",
                          "directdiffuse.R",
                          "directdiffuse.G",
                          "directdiffuse.B"};
  const Layout l = resolve_layout(one_part(channels), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "karma");
  EXPECT_EQ(names(l, Role::kDepth), Names{"Pz"});
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"C.R", "C.G", "C.B", "C.A"}));
  EXPECT_EQ(names(l, Role::kDirect),
            (Names{"directdiffuse.R", "directdiffuse.G", "directdiffuse.B"}));
}

const Names kRedshiftChannels = {"R",
                                 "G",
                                 "B",
                                 "A",
                                 "DiffuseFilter.R",
                                 "DiffuseFilter.G",
                                 "DiffuseFilter.B",
                                 "DiffuseLightingRaw.R",
                                 "DiffuseLightingRaw.G",
                                 "DiffuseLightingRaw.B",
                                 "Emission.R",
                                 "Emission.G",
                                 "Emission.B",
                                 "MotionVectors.R",
                                 "MotionVectors.G",
                                 "MotionVectors.B",
                                 "N.X",
                                 "N.Y",
                                 "N.Z",
                                 "P.X",
                                 "P.Y",
                                 "P.Z",
                                 "Z"};

TEST(LayoutDetect, Redshift) {
  const Layout l = resolve_layout(one_part(kRedshiftChannels), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "redshift");
  EXPECT_EQ(names(l, Role::kDepth), Names{"Z"});
  EXPECT_EQ(names(l, Role::kNormal), (Names{"N.X", "N.Y", "N.Z"}));
  EXPECT_EQ(names(l, Role::kAlbedo),
            (Names{"DiffuseFilter.R", "DiffuseFilter.G", "DiffuseFilter.B"}));
  EXPECT_EQ(names(l, Role::kDirect),
            (Names{"DiffuseLightingRaw.R", "DiffuseLightingRaw.G", "DiffuseLightingRaw.B"}));
  EXPECT_EQ(names(l, Role::kEmission), (Names{"Emission.R", "Emission.G", "Emission.B"}));
  EXPECT_EQ(names(l, Role::kMotion), (Names{"MotionVectors.R", "MotionVectors.G"}));
  EXPECT_EQ(names(l, Role::kPosition), (Names{"P.X", "P.Y", "P.Z"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"R", "G", "B", "A"}));
  EXPECT_FALSE(l.preset.direct_includes_albedo);
}

TEST(LayoutDetect, SignatureDecidesBetweenPresetsSharingChannelNames) {
  // Z, N, P and R G B A resolve the same roles in the arnold and redshift presets.
  const Names shared = {"R", "G", "B", "A", "N.X", "N.Y", "N.Z", "P.X", "P.Y", "P.Z", "Z"};
  EXPECT_EQ(resolve_layout(one_part(shared), "", {}, "f.exr").preset.name, "arnold");
  EXPECT_EQ(
      resolve_layout(one_part(shared, {{"redshift/version", "3.5"}}), "", {}, "f.exr").preset.name,
      "redshift");
  EXPECT_EQ(
      resolve_layout(one_part(shared, {{"arnold/version", "7.2"}}), "", {}, "f.exr").preset.name,
      "arnold");
}

TEST(LayoutDetect, UnrealMovieRenderQueue) {
  Names channels;
  for (const char* layer :
       {"FinalImage", "FinalImageBaseColor", "FinalImageMovieRenderQueue_MotionVectors",
        "FinalImageMovieRenderQueue_WorldDepth", "FinalImageWorldNormal"})
    for (const char* c : {"A", "B", "G", "R"}) channels.push_back(std::string(layer) + "." + c);
  const Layout l = resolve_layout(
      one_part(channels, {{"unreal/camera/FinalImage/focalLength", "35"}}), "", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "unreal");
  EXPECT_EQ(names(l, Role::kDepth), Names{"FinalImageMovieRenderQueue_WorldDepth.R"});
  EXPECT_EQ(names(l, Role::kNormal), (Names{"FinalImageWorldNormal.R", "FinalImageWorldNormal.G",
                                            "FinalImageWorldNormal.B"}));
  EXPECT_EQ(names(l, Role::kAlbedo),
            (Names{"FinalImageBaseColor.R", "FinalImageBaseColor.G", "FinalImageBaseColor.B"}));
  // B and A of the motion layer are not a second vector: not read.
  EXPECT_EQ(names(l, Role::kMotion), (Names{"FinalImageMovieRenderQueue_MotionVectors.R",
                                            "FinalImageMovieRenderQueue_MotionVectors.G"}));
  EXPECT_EQ(names(l, Role::kBeauty),
            (Names{"FinalImage.R", "FinalImage.G", "FinalImage.B", "FinalImage.A"}));
  EXPECT_FALSE(l.has(Role::kDirect));
  // Motion "stored in the 0,1 coordinate space ... 0.5, 0.5 is no motion", screen-normalised.
  EXPECT_EQ(l.preset.motion.offset, -0.5);
  EXPECT_TRUE(l.preset.motion.in_ndc);
  EXPECT_FALSE(l.preset.motion.zw_current_minus_next);
}

TEST(LayoutDetect, NukeScanlineRender) {
  const Names channels = {"R",          "G",          "B",       "A",         "N.red",
                          "N.green",    "N.blue",     "P.red",   "P.green",   "P.blue",
                          "backward.u", "backward.v", "depth.Z", "forward.u", "forward.v"};
  const Layout l = resolve_layout(
      one_part(channels, {{"nuke/version", "15.0v4"}, {"nuke/full_layer_names", "0"}}), "", {},
      "f.exr");
  EXPECT_EQ(l.preset.name, "nuke");
  EXPECT_EQ(names(l, Role::kDepth), Names{"depth.Z"});
  EXPECT_EQ(names(l, Role::kNormal), (Names{"N.red", "N.green", "N.blue"}));
  EXPECT_EQ(names(l, Role::kPosition), (Names{"P.red", "P.green", "P.blue"}));
  EXPECT_EQ(names(l, Role::kMotion), (Names{"backward.u", "backward.v"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"R", "G", "B", "A"}));
  EXPECT_FALSE(l.has(Role::kAlbedo));
  EXPECT_EQ(l.preset.depth_kind, DepthKind::kInverseZ);
  EXPECT_TRUE(l.preset.motion.xy_to_previous);
  EXPECT_TRUE(l.preset.motion.y_up);
}

TEST(LayoutDetect, BareDepthNameNeverMatchesALayerSuffix) {
  // Arnold's bare "Z" must not take "Something.Z"; no preset knows this file.
  try {
    resolve_layout(one_part({"Something.Z", "R", "G", "B"}), "", {}, "shot.0001.exr");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInput);
    EXPECT_EQ(e.file(), "shot.0001.exr");
    EXPECT_NE(std::string(e.what()).find("no depth channel"), std::string::npos) << e.what();
  }
}

const Names kArbitraryChannels = {"R",       "G",      "B",     "A",       "base.r",
                                  "base.g",  "base.b", "dist",  "light.r", "light.g",
                                  "light.b", "nrm.x",  "nrm.y", "nrm.z"};

TEST(LayoutOverrides, ArbitraryNamesResolveToCustom) {
  const Layout l =
      resolve_layout(one_part(kArbitraryChannels), "",
                     {"depth=dist", "normal=nrm", "albedo=base", "direct=light"}, "f.exr");
  EXPECT_EQ(l.preset.name, "custom");
  EXPECT_EQ(names(l, Role::kDepth), Names{"dist"});
  EXPECT_EQ(names(l, Role::kNormal), (Names{"nrm.x", "nrm.y", "nrm.z"}));
  EXPECT_EQ(names(l, Role::kAlbedo), (Names{"base.r", "base.g", "base.b"}));
  EXPECT_EQ(names(l, Role::kDirect), (Names{"light.r", "light.g", "light.b"}));
  EXPECT_EQ(names(l, Role::kBeauty), (Names{"R", "G", "B", "A"}));
  EXPECT_FALSE(l.has(Role::kMotion));
  EXPECT_EQ(l.preset.depth_kind, DepthKind::kPlanarZ);
  EXPECT_EQ(l.preset.normal_space, NormalSpace::kAuto);
  EXPECT_FALSE(l.preset.direct_includes_albedo);
  EXPECT_NE(l.detected_because.find("no preset matched"), std::string::npos);
  EXPECT_NE(l.detected_because.find("--channel depth=dist"), std::string::npos);
}

TEST(LayoutOverrides, FullChannelListsInComponentOrder) {
  const Layout l = resolve_layout(one_part(kArbitraryChannels), "",
                                  {"depth=dist", "normal=nrm.z, nrm.y ,nrm.x"}, "f.exr");
  // The list is taken in the order given: the user's component order.
  EXPECT_EQ(names(l, Role::kNormal), (Names{"nrm.z", "nrm.y", "nrm.x"}));
}

TEST(LayoutOverrides, ReplaceOneRoleOfADetectedPreset) {
  const Layout l = resolve_layout(one_part(kCyclesSampleChannels, kCyclesSampleAttributes), "",
                                  {"direct=DiffInd"}, "f.exr");
  EXPECT_EQ(l.preset.name, "blender");
  EXPECT_EQ(names(l, Role::kDirect),
            (Names{"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B"}));
  EXPECT_EQ(names(l, Role::kAlbedo),
            (Names{"ViewLayer.DiffCol.R", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.B"}));
  EXPECT_NE(l.detected_because.find("; --channel direct=DiffInd"), std::string::npos);
}

TEST(LayoutOverrides, PartOverride) {
  const Layout l = resolve_layout(karma_file(), "", {"albedo=part:emission"}, "f.exr");
  EXPECT_EQ(names(l, Role::kAlbedo), (Names{"R", "G", "B"}));
  EXPECT_EQ(l.channels(Role::kAlbedo)[0].subimage, 6);
}

TEST(LayoutOverrides, SignatureWithOverriddenDepthKeepsThePreset) {
  // A Nuke-written file whose depth layer was renamed: the nuke/ attributes still choose the
  // preset (and its 1/z convention) once the depth is named.
  const Names channels = {"R", "G", "B", "A", "zinv.Z", "N.red", "N.green", "N.blue"};
  const FileChannels f = one_part(channels, {{"nuke/version", "15.0v4"}});
  const Layout l = resolve_layout(f, "", {"depth=zinv"}, "f.exr");
  EXPECT_EQ(l.preset.name, "nuke");
  EXPECT_EQ(names(l, Role::kDepth), Names{"zinv.Z"});
  EXPECT_EQ(l.preset.depth_kind, DepthKind::kInverseZ);
  EXPECT_THROW(resolve_layout(f, "", {}, "f.exr"), Error);
}

TEST(LayoutForced, ForcedPresetWinsOverDetection) {
  const Layout l =
      resolve_layout(one_part(arnold_names(kCyclesSampleChannels)), "redshift", {}, "f.exr");
  EXPECT_EQ(l.preset.name, "redshift");
  EXPECT_EQ(names(l, Role::kDepth), Names{"Z"});
  EXPECT_FALSE(l.has(Role::kAlbedo));  // redshift's DiffuseFilter is not there
  EXPECT_NE(l.detected_because.find("--layout redshift"), std::string::npos);
}

TEST(LayoutForced, CustomNeedsADepthOverride) {
  const Layout l = resolve_layout(one_part(kArbitraryChannels), "custom", {"depth=dist"}, "f.exr");
  EXPECT_EQ(l.preset.name, "custom");
  EXPECT_EQ(names(l, Role::kDepth), Names{"dist"});
  EXPECT_THROW(resolve_layout(one_part(kArbitraryChannels), "custom", {}, "f.exr"), Error);
}

// Runs resolve_layout and returns the error it throws.
Error error_of(const FileChannels& file, const std::string& forced, const Names& overrides) {
  try {
    resolve_layout(file, forced, overrides, "shot.0001.exr");
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return Error(ErrorKind::kInternal, {}, "no error");
}

TEST(LayoutErrors, UnknownPresetListsTheKnownOnes) {
  const Error e = error_of(one_part(kCyclesSampleChannels), "mantra", {});
  EXPECT_EQ(e.kind(), ErrorKind::kUsage);
  const std::string what = e.what();
  EXPECT_NE(what.find("mantra"), std::string::npos) << what;
  EXPECT_NE(what.find("blender, arnold, vray, renderman, karma, redshift, unreal, nuke, custom"),
            std::string::npos)
      << what;
}

TEST(LayoutErrors, MalformedOverridesAreUsageErrors) {
  const FileChannels f = one_part(kArbitraryChannels);
  for (const Names& overrides :
       {Names{"albedo"}, Names{"=base"}, Names{"albedo="}, Names{"colour=base"},
        Names{"normal=nrm.x,nrm.y"}, Names{"motion=a,b,c"}, Names{"normal=nrm.x,,nrm.z"},
        Names{"albedo=base", "albedo=light"}, Names{"albedo=part:"}}) {
    const Error e = error_of(f, "", overrides);
    EXPECT_EQ(e.kind(), ErrorKind::kUsage) << overrides.front() << ": " << e.what();
  }
  const std::string what = error_of(f, "", {"colour=base"}).what();
  EXPECT_NE(what.find("unknown role 'colour'"), std::string::npos) << what;
  EXPECT_NE(what.find("depth, normal, albedo"), std::string::npos) << what;
  const std::string count = error_of(f, "", {"normal=nrm.x,nrm.y"}).what();
  EXPECT_NE(count.find("takes 3 channels, got 2"), std::string::npos) << count;
}

TEST(LayoutErrors, OverrideNamingMissingChannelsIsAnInputErrorOnTheFile) {
  const Error e = error_of(one_part(kArbitraryChannels), "", {"depth=dist", "albedo=DiffCol"});
  EXPECT_EQ(e.kind(), ErrorKind::kInput);
  EXPECT_EQ(e.file(), "shot.0001.exr");
  const std::string what = e.what();
  EXPECT_NE(what.find("--channel albedo=DiffCol"), std::string::npos) << what;
  EXPECT_NE(what.find("DiffCol.{R,G,B}"), std::string::npos) << what;
  EXPECT_EQ(error_of(one_part(kArbitraryChannels), "", {"depth=dist", "normal=nx,ny,nz"}).kind(),
            ErrorKind::kInput);
  EXPECT_EQ(error_of(one_part(kArbitraryChannels), "", {"depth=part:depth"}).kind(),
            ErrorKind::kInput);
}

TEST(LayoutErrors, NoDepthAnywhereIsAnInputError) {
  const Error e = error_of(one_part({"R", "G", "B", "A", "base.r", "base.g", "base.b"}), "", {});
  EXPECT_EQ(e.kind(), ErrorKind::kInput);
  EXPECT_EQ(e.file(), "shot.0001.exr");
  EXPECT_NE(std::string(e.what()).find("--channel depth="), std::string::npos) << e.what();
  // A forced preset whose depth is missing says which names it looked for.
  const Error forced = error_of(one_part(kCyclesSampleChannels), "nuke", {});
  EXPECT_EQ(forced.kind(), ErrorKind::kInput);
  EXPECT_NE(std::string(forced.what()).find("looked for depth"), std::string::npos)
      << forced.what();
}

// What the frame reader gives resolve_layout, read here with OIIO directly.
FileChannels probe(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  EXPECT_TRUE(in) << path << ": " << OIIO::geterror();
  FileChannels f;
  if (!in) return f;
  for (int s = 0; in->seek_subimage(s, 0); ++s) {
    const OIIO::ImageSpec& spec = in->spec();
    f.subimage_names.push_back(spec.get_string_attribute("oiio:subimagename"));
    f.channels.push_back(spec.channelnames);
    if (s == 0)
      for (const OIIO::ParamValue& p : spec.extra_attribs)
        f.attributes[p.name().string()] = p.get_string();
  }
  return f;
}

// One channel of a subimage as floats.
std::vector<float> read_channel(const std::string& path, const ChannelRef& ref) {
  auto in = OIIO::ImageInput::open(path);
  if (!in || !in->seek_subimage(ref.subimage, 0)) return {};
  const OIIO::ImageSpec spec = in->spec();
  const int c = spec.channelindex(ref.name);
  if (c < 0) return {};
  std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height);
  if (!in->read_image(ref.subimage, 0, c, c + 1, OIIO::TypeDesc::FLOAT, pixels.data())) return {};
  return pixels;
}

TEST(LayoutOnDisk, EveryFixtureIsDetectedAsItsPreset) {
  // Roles each fixture provides (testdata/layouts, written by tests/fixtures/layout_fixtures.cpp).
  const std::map<std::string, int> expected_roles = {
      {"blender", 8}, {"arnold", 8},   {"vray", 7},   {"renderman", 8},
      {"karma", 8},   {"redshift", 8}, {"unreal", 5}, {"nuke", 5}};
  for (const auto& [name, role_count] : expected_roles) {
    const std::string path = std::string(SSGI_TESTDATA_DIR) + "/layouts/" + name + ".exr";
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " (run make_fixtures)";
    const FileChannels f = probe(path);
    const Layout l = resolve_layout(f, "", {}, path);
    EXPECT_EQ(l.preset.name, name) << l.detected_because;
    int resolved = 0;
    for (int i = 0; i < kRoleCount; ++i) resolved += l.roles[i].empty() ? 0 : 1;
    EXPECT_EQ(resolved, role_count) << name << ": " << l.detected_because;
    EXPECT_NE(l.detected_because.find("header attribute"), std::string::npos) << name;
    EXPECT_EQ(f.channels.size(), name == "karma" ? 8u : 1u) << name;

    // The stored depth, converted by the preset's conventions, is the 2..5 ramp of the scene
    // (Unreal's in centimetres). Exact: the values are small integers and their inverses.
    const std::vector<float> depth = read_channel(path, l.channels(Role::kDepth)[0]);
    ASSERT_EQ(depth.size(), 48u) << name;
    const double unit = name == "unreal" ? 0.01 : 1.0;
    auto planar = [&](float v) {
      return l.preset.depth_kind == DepthKind::kInverseZ ? 1.0 / v : v * unit;
    };
    EXPECT_NEAR(planar(depth[0]), 2.0, 1e-6) << name;
    EXPECT_NEAR(planar(depth[7]), 5.0, 1e-5) << name;
  }
}

TEST(LayoutOnDisk, CyclesSampleFileIsBlender) {
  const std::string path = std::string(SSGI_SHARED_DATA_DIR) + "/room/room.0001.exr";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const Layout l = resolve_layout(probe(path), "", {}, path);
  EXPECT_EQ(l.preset.name, "blender");
  EXPECT_EQ(names(l, Role::kDepth), Names{"ViewLayer.Depth.Z"});
  EXPECT_EQ(names(l, Role::kMotion).size(), 4u);
}

}  // namespace
}  // namespace ssgi
