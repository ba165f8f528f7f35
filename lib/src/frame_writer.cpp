// Writing result frames: our layers plus the input's channels and header, atomically.
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <set>

#include "oiio_files.h"
#include "ssgi/error.h"
#include "ssgi/io.h"
#include "ssgi/log.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

constexpr float kHalfMax = 65504.0f;

// One output channel: its name, pixel format and where its data window values come from.
struct OutChannel {
  std::string name;
  OIIO::TypeDesc format;
  const float* source = nullptr;              // our planes
  std::shared_ptr<std::vector<float>> owned;  // passthrough planes
};

// The input's channels, all subimages, as float planes in their original formats. Channels of
// a named part are prefixed with the part name when they have no layer of their own (Karma's
// per-AOV parts hold plain R, G, B), so that a single-part output keeps them apart.
std::vector<OutChannel> read_passthrough(OIIO::ImageInput* in, const std::string& path,
                                         const Box2i& data) {
  std::vector<OutChannel> out;
  int nsub = 0;
  while (in->seek_subimage(nsub, 0)) ++nsub;
  for (int s = 0; s < nsub; ++s) {
    in->seek_subimage(s, 0);
    const OIIO::ImageSpec spec = in->spec();
    if (spec.x != data.x0 || spec.y != data.y0 || spec.width != data.width() ||
        spec.height != data.height())
      continue;  // a part with another data window cannot share our single part
    const int n = spec.nchannels;
    const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
    std::vector<float> interleaved(pixels * n);
    if (!in->read_image(s, 0, 0, n, OIIO::TypeDesc::FLOAT, interleaved.data()))
      throw_io(path, "cannot read pixels: " + detail::one_line(in->geterror()));
    const std::string part = spec.get_string_attribute("oiio:subimagename");
    for (int c = 0; c < n; ++c) {
      OutChannel ch;
      ch.name = spec.channelnames[c];
      if (nsub > 1 && !part.empty() && ch.name.find('.') == std::string::npos)
        ch.name = part + "." + ch.name;
      ch.format = spec.channelformat(c);
      ch.owned = std::make_shared<std::vector<float>>(pixels);
      for (std::size_t p = 0; p < pixels; ++p) (*ch.owned)[p] = interleaved[p * n + c];
      ch.source = ch.owned->data();
      out.push_back(std::move(ch));
    }
  }
  return out;
}

// Header attributes worth keeping from the input: everything but what describes the file's
// own structure, which the writer sets anew.
bool keep_attribute(const std::string& name) {
  static const std::set<std::string> kStructural = {"compression",
                                                    "oiio:subimages",
                                                    "oiio:subimagename",
                                                    "openexr:chunkCount",
                                                    "oiio:BitsPerSample",
                                                    "openexr:dwaCompressionLevel",
                                                    "openexr:lineOrder",
                                                    "name",
                                                    "type",
                                                    "version",
                                                    "chunkCount",
                                                    "tiles"};
  return kStructural.count(name) == 0;
}

}  // namespace

std::string parse_compression(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  static const std::set<std::string> kKnown = {"none",  "rle", "zips", "zip",  "piz",
                                               "pxr24", "b44", "b44a", "dwaa", "dwab"};
  if (!kKnown.count(name))
    throw_usage("unknown --compression '" + spec +
                "' (none, rle, zips, zip, piz, pxr24, b44, b44a, dwaa[:level], dwab[:level])");
  if (colon != std::string::npos) {
    if (name != "dwaa" && name != "dwab")
      throw_usage("--compression '" + spec + "': only dwaa and dwab take a level");
    const std::string level = spec.substr(colon + 1);
    char* end = nullptr;
    const double v = std::strtod(level.c_str(), &end);
    if (level.empty() || *end != '\0' || !(v > 0) || v > 1e6)
      throw_usage("--compression '" + spec + "': the level must be a positive number");
  }
  return spec;
}

void check_output_directory(const std::string& path) {
  const fs::path dir = fs::absolute(path).parent_path();
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  throw_io(path, "output directory " + dir.string() +
                     (fs::exists(dir, ec) ? " is not a directory" : " does not exist"));
}

void write_frame(const std::string& path, const GBuffer& frame,
                 const std::vector<OutputLayer>& layers, const WriteOptions& options) {
  check_output_directory(path);
  // The input is opened once: its header (part 0) for the metadata, its pixels to pass through.
  auto in = detail::open_image(frame.path);
  const OIIO::ImageSpec in_spec = in->spec();
  const Box2i& data = frame.data_window;
  const std::size_t pixels = static_cast<std::size_t>(data.width()) * data.height();
  const OIIO::TypeDesc our_format = options.half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;

  std::vector<OutChannel> channels;
  std::set<std::string> ours;
  for (const OutputLayer& layer : layers) {
    for (std::size_t c = 0; c < layer.suffixes.size(); ++c) {
      OutChannel ch;
      ch.name =
          options.layer_prefix + (layer.name.empty() ? "" : layer.name + ".") + layer.suffixes[c];
      ch.format = our_format;
      ch.source = layer.image->plane(static_cast<int>(c));
      ours.insert(ch.name);
      channels.push_back(std::move(ch));
    }
  }
  if (options.passthrough) {
    // Every output name is unique: an input channel whose name is taken (by ours, or by an
    // earlier input channel, as when ssgi's own output is its input) gets "input." in front,
    // as often as it takes.
    bool warned = false;
    for (OutChannel& ch : read_passthrough(in.get(), frame.path, data)) {
      if (ours.count(ch.name)) {
        if (options.warn_collisions && !warned)
          log_warning(frame.path +
                      ": input channels that share a name with ssgi's are kept as "
                      "input.<name> (e.g. input." +
                      ch.name + ")");
        warned = true;
        while (ours.count(ch.name)) ch.name = "input." + ch.name;
      }
      ours.insert(ch.name);
      channels.push_back(std::move(ch));
    }
  }

  in.reset();

  const int n = static_cast<int>(channels.size());
  OIIO::ImageSpec spec(data.width(), data.height(), n, OIIO::TypeDesc::FLOAT);
  spec.x = data.x0;
  spec.y = data.y0;
  spec.full_x = frame.display_window.x0;
  spec.full_y = frame.display_window.y0;
  spec.full_width = frame.display_window.width();
  spec.full_height = frame.display_window.height();
  spec.channelnames.clear();
  spec.channelformats.clear();
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  for (const OutChannel& ch : channels) {
    spec.channelnames.push_back(ch.name);
    spec.channelformats.push_back(ch.format);
  }
  for (const OIIO::ParamValue& p : in_spec.extra_attribs)
    if (keep_attribute(p.name().string())) spec.attribute(p.name(), p.type(), p.data());
  for (const auto& [name, value] : options.provenance) spec.attribute(name, value);
  spec.attribute("compression", options.compression);

  // Interleave; our channels are clamped to the half range when written as half, so that no
  // value turns into inf.
  std::vector<float> interleaved(pixels * n);
  for (int c = 0; c < n; ++c) {
    const bool clamp_half = channels[c].format == OIIO::TypeDesc::HALF;
    const float* src = channels[c].source;
    for (std::size_t p = 0; p < pixels; ++p) {
      float v = src[p];
      if (clamp_half && std::isfinite(v)) v = std::clamp(v, -kHalfMax, kHalfMax);
      interleaved[p * n + c] = v;
    }
  }

  detail::write_image_atomically(path, spec, interleaved.data(), "frame");
}

}  // namespace ssgi
