// Colour management with OpenColorIO: the spaces a run reads, computes, writes and shows in,
// and the processors between them, built once per run (no OCIO type in this header).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ssgi/image.h"
#include "ssgi/settings.h"

namespace ssgi {

struct SequenceInfo;

class ColorManagement {
 public:
  // No config: no transform runs on EXR data; the few that must (an sRGB environment map to
  // linear light, the preview to sRGB) use the built-in sRGB curve of IEC 61966-2-1.
  ColorManagement();
  // Loads the config of `settings` (color_config_path) and builds the run's processors.
  // `input_tag` is the input's own `oiio:ColorSpace` (OIIO says "Linear" for every EXR): it is
  // used when the config knows it and --input-colorspace is not given, else the input is in the
  // working space. Throws Error(kIO) naming the config when it cannot be read, Error(kInput)
  // when OCIO refuses it, Error(kUsage) for a colour space, display or view it does not have,
  // or for colour options given without a config.
  explicit ColorManagement(const ColorSettings& settings, const std::string& input_tag = "");
  ~ColorManagement();
  ColorManagement(const ColorManagement&);
  ColorManagement& operator=(const ColorManagement&);

  bool has_config() const;
  const std::string& config_path() const;  // "" without a config
  // The spaces by the config's own names (roles and aliases resolved); without a config,
  // "scene_linear" for all three.
  const std::string& working_space() const;
  const std::string& input_space() const;
  const std::string& output_space() const;
  // The preview's display and view ("sRGB" and "" without a config).
  const std::string& display() const;
  const std::string& view() const;
  // What was decided and why, one line each, for `ssgi info` and -v.
  const std::vector<std::string>& reasons() const;

  // The first three planes of `image` (light or albedo: R, G, B; an alpha plane is left alone)
  // from the input space to the working space, in place; nothing when they are the same.
  void input_to_working(Image* image) const;
  // The same from the working space to the output space (the colour layers ssgi writes).
  void working_to_output(Image* image) const;
  // An environment map's texels as read (R, G, B planes) to linear light in the working
  // space: from --env-colorspace, else its `tag` (oiio:ColorSpace) when the config knows it,
  // else sRGB-encoded when `integer` (8- or 16-bit: PNG, JPEG, TIFF) or tagged sRGB, else
  // the working space. `path` names the file in -v lines.
  void environment_to_working(Image* image, const std::string& path, const std::string& tag,
                              bool integer) const;
  // Working-space R, G, B planes to display-referred values in [0, 1] through the display and
  // view (without a config, the sRGB encoding of the values as Rec.709 light), in place.
  void working_to_display(Image* image) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

// The colour management of a run over `sequence`: `settings` with the input's own tag (its first
// frame's oiio:ColorSpace). Throws as the constructor does.
ColorManagement color_management_for(const ColorSettings& settings, const SequenceInfo& sequence);

}  // namespace ssgi
