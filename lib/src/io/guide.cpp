#include "io/guide.h"

#include <cmath>
#include <filesystem>
#include <string>

#include "io/input_frame.h"
#include "io/sequence.h"
#include "parallel.h"
#include "throw.h"

namespace ssgi::detail {
namespace {

namespace fs = std::filesystem;

// How a guide's files are read: the shot's options (layout, --channel, conventions, camera) with
// nothing of the shot's frames, context or views.
InputOptions guide_options(const InputOptions& shot) {
  InputOptions o = shot;
  o.pattern = shot.guide;
  o.frames.clear();
  o.skip_missing = false;
  o.context.clear();
  o.views.clear();
  o.guide.clear();
  return o;
}

std::string size_text(const Box2i& w) {
  return std::to_string(w.width()) + " x " + std::to_string(w.height());
}

// A guide pixel's depth agrees with the shot's at its centre within this share of the depth: the
// two renders sample a pixel at different points, so a slanted surface's depths differ a little.
constexpr float kDepthAgreement = 0.05f;
// The least share of the compared pixels whose depths agree (or that both show no surface): a
// guide of the same shot loses only silhouettes and thin features, where its samples fell
// elsewhere; another camera or another frame of a moving shot loses most of its pixels.
constexpr double kLeastAgreeing = 0.75;

}  // namespace

std::shared_ptr<const GuideInfo> open_guide(const SequenceInfo& shot, const InputOptions& options) {
  auto info = std::make_shared<GuideInfo>();
  info->pattern = options.guide;
  InputOptions o = guide_options(options);
  if (!parse_sequence_pattern(o.pattern).has_frame_field)
    throw_usage("--guide " + o.pattern +
                ": give the guide's frames as a sequence (####), as the shot's");
  const int first_frame = shot.frames.front();
  o.frames = std::to_string(first_frame);
  SequenceInfo seq;
  try {
    seq = open_view_sequence(o);
  } catch (const Error& e) {
    throw Error(e.kind(), e.file(), "--guide: " + std::string(e.what()));
  }
  const std::string first = seq.pattern.path_for(first_frame);
  if (!seq.layout.has(Role::kIndirect))
    throw_input(first,
                "--guide: has no indirect channels (the renderer's diffuse indirect light: "
                "Blender's DiffInd; name another with --channel indirect=NAME)");
  if (!seq.layout.has(Role::kDepth))
    throw_input(first, "--guide: has no depth channel, which shows that it is the shot's camera");
  if (seq.layout.preset.direct_includes_albedo && !seq.layout.has(Role::kAlbedo))
    throw_input(first, "--guide: its indirect light includes the albedo (the " +
                           seq.layout.preset.name +
                           " layout) but it has no albedo channels to divide it by");
  const Box2i& sd = shot.display_window;
  const Box2i& gd = seq.display_window;
  const int f = gd.width() > 0 ? sd.width() / gd.width() : 0;
  if (f < 1 || gd.width() * f != sd.width() || gd.height() * f != sd.height())
    throw_input(first, "--guide: its resolution " + size_text(gd) + " is not the shot's " +
                           size_text(sd) +
                           " divided by a whole number (the shot's, half, a third, ...)");
  if (!(seq.data_window == gd))
    throw_input(first, "--guide: its data window does not cover its display window (" +
                           size_text(seq.data_window) + " of " + size_text(gd) +
                           "): render the guide whole");
  info->fraction = f;
  info->sequence = std::make_shared<const SequenceInfo>(std::move(seq));
  // Every file the frames written read, opened now: a missing or unreadable one is said before
  // anything is written.
  for (int frame : shot.frames) {
    const std::string path = info->sequence->pattern.path_for(frame);
    if (!fs::exists(path))
      throw_io(path, "--guide: frame " + std::to_string(frame) + " of the guide is missing");
    open_input_exr(path);
  }
  return info;
}

void check_guide_covers(const SequenceInfo& shot, const std::vector<int>& frames) {
  if (!shot.guide) return;
  for (int f : frames) {
    const std::string path = shot.guide->sequence->pattern.path_for(f);
    if (!fs::exists(path))
      throw_io(path, "--guide: frame " + std::to_string(f) +
                         " of the guide is missing: a guide covers every frame the run reads "
                         "(those it writes and their temporal neighbours)");
  }
}

GuideFrame read_guide(const SequenceInfo& shot, int frame, const GBuffer& shot_frame,
                      const InputOptions& options, const ColorManagement* color) {
  const GuideInfo& guide = *shot.guide;
  const SequenceInfo& seq = *guide.sequence;
  const InputOptions o = guide_options(options);
  const bool with_albedo = seq.layout.preset.direct_includes_albedo;
  RoleMask roles = role_bit(Role::kDepth) | role_bit(Role::kIndirect);
  if (with_albedo) roles |= role_bit(Role::kAlbedo);
  GBuffer g = read_input_frame(seq, frame, roles, o, color, false).g;
  const std::string& path = g.path;
  if (g.sanitized > 0)
    throw_input(path, "--guide: " + std::to_string(g.sanitized) + " NaN or infinite values in " +
                          (with_albedo ? "its indirect light or albedo" : "its indirect light") +
                          ": a guide is refused rather than guessed at");
  GuideFrame out;
  out.fraction = guide.fraction;
  out.light = std::move(g.indirect);
  out.depth = std::move(g.depth);
  if (with_albedo) {
    // The reader divided the light by the albedo: where that is 0 the light is not known.
    out.known = Image(out.light.width(), out.light.height(), 3, 1.0f);
    for (int c = 0; c < 3; ++c)
      for (std::size_t p = 0; p < out.known.plane_size(); ++p)
        if (!(g.albedo.plane(c)[p] > 0)) out.known.plane(c)[p] = 0.0f;
  }
  // Its depth against the shot's at each guide pixel's centre.
  const int f = guide.fraction;
  const int gw = out.depth.width(), gh = out.depth.height();
  const Box2i& dw = shot_frame.data_window;
  const Box2i& sd = shot_frame.display_window;
  std::vector<std::size_t> compared(gh, 0), agreeing(gh, 0);
  parallel_for_rows(gh, [&](int gy) {
    const int y = gy * f + f / 2 + sd.y0;
    if (y < dw.y0 || y >= dw.y1) return;
    for (int gx = 0; gx < gw; ++gx) {
      const int x = gx * f + f / 2 + sd.x0;
      if (x < dw.x0 || x >= dw.x1) continue;
      const float zg = out.depth.plane(0)[static_cast<std::size_t>(gy) * gw + gx];
      const float zs = shot_frame.depth.at(0, x - dw.x0, y - dw.y0);
      ++compared[gy];
      const bool both_background = !std::isfinite(zg) && !std::isfinite(zs);
      if (both_background || std::fabs(zg - zs) <= kDepthAgreement * zs) ++agreeing[gy];
    }
  });
  std::size_t n = 0, agree = 0;
  for (int y = 0; y < gh; ++y) {
    n += compared[y];
    agree += agreeing[y];
  }
  if (n > 0 && static_cast<double>(agree) < kLeastAgreeing * static_cast<double>(n))
    throw_input(path, "--guide: its depth agrees with the shot's (frame " + std::to_string(frame) +
                          ") on " + std::to_string(100 * agree / n) +
                          "% of its pixels: not a render of the shot's camera at that frame");
  return out;
}

}  // namespace ssgi::detail
