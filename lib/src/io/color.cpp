// Colour management: the OCIO config, the run's colour spaces and the processors between
// them, built once and applied row by row in the library's parallel loops.
#include "io/color.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/strutil.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "io/sequence_info.h"
#include "log.h"
#include "parallel.h"
#include "settings.h"
#include "throw.h"

namespace ssgi {

namespace OCIO = OCIO_NAMESPACE;

namespace {

// Values beyond this are clamped, as the reader clamps its inputs: sums of them stay finite.
constexpr float kHuge = 1e30f;

// IEC 61966-2-1, as OIIO's built-in sRGB transforms.
float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
float linear_to_srgb(float v) {
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

// What OCIO's configs call an sRGB-encoded texture, in the order they are looked for: the
// ACES studio and CG configs', then the usual short names.
const char* const kSrgbTextureNames[] = {"sRGB - Texture",
                                         "Utility - sRGB - Texture",
                                         "Input - Generic - sRGB - Texture",
                                         "srgb_tx",
                                         "srgb_texture",
                                         "sRGB"};

// Applies `per_pixel` to every value of the first three planes, row by row in parallel.
template <typename F>
void for_each_rgb_value(Image* image, const F& per_pixel) {
  const int w = image->width();
  detail::parallel_for_rows(image->height(), [&](int y) {
    for (int c = 0; c < 3; ++c) {
      float* row = image->plane(c) + static_cast<std::size_t>(y) * w;
      for (int x = 0; x < w; ++x) row[x] = per_pixel(row[x]);
    }
  });
}

float finite(float v) { return std::isfinite(v) ? std::clamp(v, -kHuge, kHuge) : 0.0f; }

}  // namespace

struct ColorManagement::Impl {
  std::string config_path;
  OCIO::ConstConfigRcPtr config;  // null without a config
  std::string working = "scene_linear", input = "scene_linear", output = "scene_linear";
  std::string env;  // --env-colorspace, resolved; empty: by the file
  std::string display = "sRGB", view;
  std::vector<std::string> reasons;
  // Null when the two spaces are the same (no transform runs).
  OCIO::ConstCPUProcessorRcPtr to_working, to_output, to_display;

  // The config's own name for `name` (a colour space, alias or role), or "" when unknown.
  std::string known(const std::string& name) const {
    if (!config || name.empty()) return "";
    const OCIO::ConstColorSpaceRcPtr cs = config->getColorSpace(name.c_str());
    return cs ? cs->getName() : "";
  }
  // As known(), for a name the user gave: unknown is a usage error listing the config's spaces.
  std::string given(const std::string& option, const std::string& name) const {
    const std::string n = known(name);
    if (!n.empty()) return n;
    std::vector<std::string> names;
    for (int i = 0; i < config->getNumColorSpaces(); ++i)
      names.emplace_back(config->getColorSpaceNameByIndex(i));
    throw_usage("--" + option + ": the config " + config_path + " has no colour space '" + name +
                "' (it has " + OIIO::Strutil::join(names, ", ") + ")");
  }
  OCIO::ConstCPUProcessorRcPtr processor(const std::string& from, const std::string& to) const {
    if (!config || from == to) return nullptr;
    try {
      const OCIO::ConstProcessorRcPtr p = config->getProcessor(from.c_str(), to.c_str());
      if (p->isNoOp()) return nullptr;
      return p->getOptimizedCPUProcessor(OCIO::OPTIMIZATION_DEFAULT);
    } catch (const OCIO::Exception& e) {
      throw_input(config_path, "cannot convert " + from + " to " + to + ": " + e.what());
    }
  }

  // Applies `cpu` to the first three planes of `image`, row by row in parallel.
  static void apply(const OCIO::ConstCPUProcessorRcPtr& cpu, Image* image) {
    const int w = image->width();
    detail::parallel_for_rows(image->height(), [&](int y) {
      const std::size_t row = static_cast<std::size_t>(y) * w;
      OCIO::PlanarImageDesc desc(image->plane(0) + row, image->plane(1) + row,
                                 image->plane(2) + row, nullptr, w, 1);
      cpu->apply(desc);
      for (int c = 0; c < 3; ++c) {
        float* values = image->plane(c) + row;
        for (int x = 0; x < w; ++x) values[x] = finite(values[x]);
      }
    });
  }
};

ColorManagement::ColorManagement() : impl_(std::make_shared<Impl>()) {
  auto impl = std::const_pointer_cast<Impl>(impl_);
  impl->reasons.push_back(
      "colour: no OCIO config (--colorconfig, $OCIO): the EXR passes are used and written as "
      "they are; an 8- or 16-bit environment map is decoded with the sRGB curve, the preview "
      "encoded with it");
}

ColorManagement::ColorManagement(const ColorSettings& s, const std::string& input_tag)
    : ColorManagement() {
  auto impl = std::make_shared<Impl>();
  impl->config_path = color_config_path(s);
  if (impl->config_path.empty()) {
    const char* option = !s.input.empty()     ? "--input-colorspace"
                         : !s.output.empty()  ? "--output-colorspace"
                         : !s.env.empty()     ? "--env-colorspace"
                         : !s.working.empty() ? "--working-space"
                         : !s.display.empty() ? "--display"
                         : !s.view.empty()    ? "--view"
                                              : nullptr;
    if (option)
      throw_usage(std::string(option) +
                  " needs an OCIO config: give --colorconfig FILE or set OCIO");
    return;  // the no-config state the delegated constructor made
  }
  const std::string& path = impl->config_path;
  const std::string from = s.config.empty() ? " ($OCIO)" : "";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw_io(path, "cannot read the OCIO config" + from + ": " +
                       (std::filesystem::exists(path, ec) ? "not a regular file" : "no such file"));
  try {
    impl->config = OCIO::Config::CreateFromFile(path.c_str());
    impl->config->validate();
  } catch (const OCIO::Exception& e) {
    throw_input(path, "OCIO refuses the config" + from + ": " +
                          OIIO::Strutil::replace(e.what(), "\n", " ", true));
  }
  std::vector<std::string> lines = {"colour: OCIO config " + path + from};
  if (!s.working.empty()) {
    impl->working = impl->given("working-space", s.working);
    lines.push_back("working space " + impl->working + " (--working-space)");
  } else {
    impl->working = impl->known(OCIO::ROLE_SCENE_LINEAR);
    if (impl->working.empty())
      throw_input(path, "the config has no scene_linear role: give --working-space");
    lines.push_back("working space " + impl->working + " (the config's scene_linear role)");
  }
  if (!s.input.empty()) {
    impl->input = impl->given("input-colorspace", s.input);
    lines.push_back("light and albedo passes read as " + impl->input + " (--input-colorspace)");
  } else if (!impl->known(input_tag).empty()) {
    impl->input = impl->known(input_tag);
    lines.push_back("light and albedo passes read as " + impl->input +
                    " (the input's oiio:ColorSpace)");
  } else {
    impl->input = impl->working;
    lines.push_back("light and albedo passes read as the working space" +
                    (input_tag.empty() ? std::string()
                                       : " (the input says '" + input_tag +
                                             "', which the config does not know: taken as "
                                             "scene-linear)"));
  }
  if (!s.output.empty()) {
    impl->output = impl->given("output-colorspace", s.output);
    lines.push_back("ssgi's layers written as " + impl->output + " (--output-colorspace)");
  } else {
    impl->output = impl->working;
    lines.push_back("ssgi's layers written in the working space");
  }
  if (!s.env.empty()) impl->env = impl->given("env-colorspace", s.env);
  try {
    impl->display = s.display.empty() ? impl->config->getDefaultDisplay() : s.display;
    bool display_known = false;
    for (int i = 0; i < impl->config->getNumDisplays(); ++i)
      display_known = display_known || impl->display == impl->config->getDisplay(i);
    if (!display_known)
      throw_usage("--display: the config " + path + " has no display '" + impl->display + "'");
    impl->view = s.view.empty() ? impl->config->getDefaultView(impl->display.c_str()) : s.view;
    bool view_known = false;
    for (int i = 0; i < impl->config->getNumViews(impl->display.c_str()); ++i)
      view_known = view_known || impl->view == impl->config->getView(impl->display.c_str(), i);
    if (!view_known)
      throw_usage("--view: display '" + impl->display + "' of the config " + path +
                  " has no view '" + impl->view + "'");
    const OCIO::DisplayViewTransformRcPtr dv = OCIO::DisplayViewTransform::Create();
    dv->setSrc(impl->working.c_str());
    dv->setDisplay(impl->display.c_str());
    dv->setView(impl->view.c_str());
    impl->to_display =
        impl->config->getProcessor(dv)->getOptimizedCPUProcessor(OCIO::OPTIMIZATION_DEFAULT);
  } catch (const OCIO::Exception& e) {
    throw_input(path, "cannot build the preview's display transform: " +
                          OIIO::Strutil::replace(e.what(), "\n", " ", true));
  }
  lines.push_back("preview through display " + impl->display + ", view " + impl->view);
  impl->to_working = impl->processor(impl->input, impl->working);
  impl->to_output = impl->processor(impl->working, impl->output);
  impl->reasons = {OIIO::Strutil::join(lines, "; ")};
  impl_ = std::move(impl);
}

ColorManagement::~ColorManagement() = default;
ColorManagement::ColorManagement(const ColorManagement&) = default;
ColorManagement& ColorManagement::operator=(const ColorManagement&) = default;

bool ColorManagement::has_config() const { return impl_->config != nullptr; }
const std::string& ColorManagement::config_path() const { return impl_->config_path; }
const std::string& ColorManagement::working_space() const { return impl_->working; }
const std::string& ColorManagement::input_space() const { return impl_->input; }
const std::string& ColorManagement::output_space() const { return impl_->output; }
const std::string& ColorManagement::display() const { return impl_->display; }
const std::string& ColorManagement::view() const { return impl_->view; }
const std::vector<std::string>& ColorManagement::reasons() const { return impl_->reasons; }

void ColorManagement::input_to_working(Image* image) const {
  if (impl_->to_working) Impl::apply(impl_->to_working, image);
}

void ColorManagement::working_to_output(Image* image) const {
  if (impl_->to_output) Impl::apply(impl_->to_output, image);
}

void ColorManagement::environment_to_working(Image* image, const std::string& path,
                                             const std::string& tag, bool integer) const {
  const Impl& m = *impl_;
  const bool tagged_srgb = OIIO::Strutil::iequals(tag, "sRGB");
  std::string space = m.env;
  std::string why = "--env-colorspace";
  if (space.empty() && !m.known(tag).empty()) {
    space = m.known(tag);
    why = "its oiio:ColorSpace";
  }
  if (space.empty() && (integer || tagged_srgb)) {
    for (const char* name : kSrgbTextureNames) {
      space = m.known(name);
      if (!space.empty()) break;
    }
    why = integer ? "an 8- or 16-bit map is sRGB-encoded" : "it says it is sRGB";
    if (space.empty()) {
      // No config, or one without an sRGB texture space: the built-in curve, to Rec.709 light.
      log_info(path + ": environment map is sRGB-encoded (" + why +
               "), decoded to linear light with the sRGB curve");
      for_each_rgb_value(image, srgb_to_linear);
      return;
    }
  }
  if (space.empty()) {
    if (!tag.empty() && m.config && !OIIO::Strutil::iequals(tag, "Linear"))
      log_info(path + ": environment map says it is '" + tag +
               "', which the config does not know: taken as scene-linear");
    return;
  }
  log_info(path + ": environment map read as " + space + " (" + why + "), converted to " +
           m.working);
  if (const auto cpu = m.processor(space, m.working)) Impl::apply(cpu, image);
}

void ColorManagement::working_to_display(Image* image) const {
  if (impl_->to_display) {
    Impl::apply(impl_->to_display, image);
    for_each_rgb_value(image, [](float v) { return std::clamp(v, 0.0f, 1.0f); });
  } else if (!impl_->config) {
    for_each_rgb_value(image,
                       [](float v) { return linear_to_srgb(std::clamp(finite(v), 0.0f, 1.0f)); });
  } else {
    for_each_rgb_value(image, [](float v) { return std::clamp(v, 0.0f, 1.0f); });
  }
}

ColorManagement color_management_for(const ColorSettings& settings, const SequenceInfo& sequence) {
  const auto tag = sequence.channels.attributes.find("oiio:ColorSpace");
  return ColorManagement(settings,
                         tag == sequence.channels.attributes.end() ? std::string() : tag->second);
}

}  // namespace ssgi
