// Writing result frames: our layers plus the input's channels and header, atomically.
#include "io/frame_writer.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>

#include "buffers.h"
#include "io/input_frame.h"
#include "io/oiio_files.h"
#include "log.h"
#include "throw.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

constexpr float kHalfMax = 65504.0f;

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
                                                    "openexr:levelmode",
                                                    "openexr:roundingmode",
                                                    "name",
                                                    "type",
                                                    "version",
                                                    "chunkCount",
                                                    "tiles"};
  return kStructural.count(name) == 0;
}

void copy_attributes(const OIIO::ImageSpec& from, OIIO::ImageSpec* to) {
  for (const OIIO::ParamValue& p : from.extra_attribs)
    if (keep_attribute(p.name().string())) to->attribute(p.name(), p.type(), p.data());
}

Box2i data_window_of(const OIIO::ImageSpec& spec) {
  return {spec.x, spec.y, spec.x + spec.width, spec.y + spec.height};
}

std::string part_label(const detail::DecodedInput& input, int subimage) {
  const std::string name = input.parts[subimage].spec.get_string_attribute("oiio:subimagename");
  return "part " + std::to_string(subimage) + (name.empty() ? "" : " (" + name + ")");
}

// Rows [y, y + rows) of our channels, interleaved in front of those rows of the host part's
// own pixels (`host_rows`, if any), in the output's per-channel formats. Counts the values
// clamped to the half range in *clamped.
void interleave_host_rows(const std::vector<const float*>& ours, bool half,
                          const std::byte* host_rows, std::size_t host_pixel_bytes, int width,
                          int y, int rows, std::byte* out, std::size_t* clamped) {
  const std::size_t our_bytes = ours.size() * (half ? sizeof(Imath::half) : sizeof(float));
  const std::size_t stride = our_bytes + host_pixel_bytes;
  const std::size_t first = static_cast<std::size_t>(y) * width;
  const std::size_t count = static_cast<std::size_t>(rows) * width;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t p = first + i;
    std::byte* px = out + i * stride;
    for (std::size_t c = 0; c < ours.size(); ++c) {
      float v = ours[c][p];
      if (half) {
        // Clamped to the half range so that no value turns into inf.
        if (std::isfinite(v) && std::fabs(v) > kHalfMax) {
          v = std::copysign(kHalfMax, v);
          ++*clamped;
        }
        const Imath::half h(v);
        std::memcpy(px + c * sizeof(Imath::half), &h, sizeof h);
      } else {
        std::memcpy(px + c * sizeof(float), &v, sizeof v);
      }
    }
    if (host_pixel_bytes)
      std::memcpy(px + our_bytes, host_rows + i * host_pixel_bytes, host_pixel_bytes);
  }
}

}  // namespace

void check_output_directory(const std::string& path) {
  const fs::path dir = fs::absolute(path).parent_path();
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  throw_io(path, "output directory " + dir.string() +
                     (fs::exists(dir, ec) ? " is not a directory" : " does not exist"));
}

void make_output_directory(const std::string& path) {
  const fs::path dir = fs::absolute(path).parent_path();
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  // The nearest part of the path that exists must be a directory.
  for (fs::path p = dir; !p.empty() && p != p.root_path(); p = p.parent_path()) {
    if (!fs::exists(p, ec)) continue;
    if (!fs::is_directory(p, ec))
      throw_io(path,
               "output directory " + dir.string() + ": " + p.string() + " is not a directory");
    break;
  }
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw_io(path, "cannot make the output directory " + dir.string() + ": " + ec.message());
}

void write_frame(const std::string& path, const GBuffer& frame,
                 const std::vector<OutputLayer>& layers, const WriteOptions& options) {
  check_output_directory(path);
  const detail::DecodedInput input =
      detail::decode_input(*detail::open_image(frame.path), frame.path);
  detail::write_frame(path, frame, layers, options, input);
}

void detail::write_frame(const std::string& path, const GBuffer& frame,
                         const std::vector<OutputLayer>& layers, const WriteOptions& options,
                         const DecodedInput& input) {
  check_output_directory(path);
  const std::vector<DecodedInput::Part>& parts = input.parts;
  const Box2i& data = frame.data_window;

  // Our channels go into the first input part that covers the same pixels (the host), in front
  // of its own channels; every other part is copied as it is, in its own types and windows.
  int host = -1;
  for (std::size_t i = 0; i < parts.size() && host < 0; ++i)
    if (!parts[i].spec.deep && data_window_of(parts[i].spec) == data) host = static_cast<int>(i);
  const OIIO::ImageSpec& header = parts[host >= 0 ? host : 0].spec;

  std::vector<std::string> names;
  std::vector<const float*> ours;
  std::set<std::string> taken;
  for (const OutputLayer& layer : layers) {
    for (std::size_t c = 0; c < layer.suffixes.size(); ++c) {
      names.push_back(options.layer_prefix + (layer.name.empty() ? "" : layer.name + ".") +
                      layer.suffixes[c]);
      ours.push_back(layer.image->plane(static_cast<int>(c)));
      taken.insert(names.back());
    }
  }
  const OIIO::TypeDesc our_format = options.half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
  std::vector<OIIO::TypeDesc> formats(ours.size(), our_format);

  OIIO::ImageSpec host_spec(data.width(), data.height(), 0, OIIO::TypeDesc::FLOAT);
  host_spec.x = data.x0;
  host_spec.y = data.y0;
  host_spec.full_x = frame.display_window.x0;
  host_spec.full_y = frame.display_window.y0;
  host_spec.full_width = frame.display_window.width();
  host_spec.full_height = frame.display_window.height();
  copy_attributes(header, &host_spec);
  for (const auto& [name, value] : options.provenance) host_spec.attribute(name, value);
  host_spec.attribute("compression", options.compression);

  std::size_t host_pixel_bytes = 0;
  const bool passthrough = options.passthrough;
  if (passthrough && host >= 0) {
    // Every name in the part is unique: an input channel whose name is taken (by ours, or by
    // an earlier input channel, as when ssgi's own output is its input) gets "input." in front,
    // as often as it takes.
    const OIIO::ImageSpec& hs = parts[host].spec;
    bool renamed = false;
    for (int c = 0; c < hs.nchannels; ++c) {
      std::string name = hs.channelnames[c];
      if (taken.count(name)) {
        if (options.warn_collisions && !renamed)
          log_warning(frame.path +
                      ": input channels that share a name with ssgi's are kept as "
                      "input.<name> (e.g. input." +
                      name + ")");
        renamed = true;
        while (taken.count(name)) name = "input." + name;
      }
      taken.insert(name);
      names.push_back(name);
      formats.push_back(hs.channelformat(c));
    }
    host_spec.tile_width = hs.tile_width;
    host_spec.tile_height = hs.tile_height;
    host_spec.tile_depth = hs.tile_depth;
    host_pixel_bytes = hs.pixel_bytes(/*native=*/true);
  }
  host_spec.nchannels = static_cast<int>(names.size());
  host_spec.channelnames = names;
  host_spec.channelformats = formats;
  host_spec.format = our_format;
  host_spec.alpha_channel = -1;
  host_spec.z_channel = -1;

  // The output's parts, in the input's order; ours first when no input part hosts them.
  std::vector<OIIO::ImageSpec> specs;
  std::vector<int> source;  // per output part: input part index, or -1 for the host part
  if (host < 0 || !passthrough) {
    specs.push_back(host_spec);
    source.push_back(-1);
  }
  if (passthrough) {
    std::set<std::string> part_names;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const DecodedInput::Part& part = parts[i];
      if (static_cast<int>(i) == host) {
        specs.push_back(host_spec);
        source.push_back(-1);
      } else if (part.spec.deep) {
        if (options.warn_collisions)
          log_warning(frame.path + ": " + part_label(input, static_cast<int>(i)) +
                      " holds deep data, which ssgi does not pass through");
        continue;
      } else {
        OIIO::ImageSpec spec = part.spec;
        spec.extra_attribs.clear();
        copy_attributes(part.spec, &spec);
        spec.attribute("compression", part.spec.get_string_attribute("compression", "zip"));
        specs.push_back(std::move(spec));
        source.push_back(static_cast<int>(i));
      }
      if (part.has_mip_levels && options.warn_collisions)
        log_warning(frame.path + ": " + part_label(input, static_cast<int>(i)) +
                    " is mip-mapped: only its full-resolution level is passed through");
    }
    // A multi-part file needs a unique name per part.
    if (specs.size() > 1) {
      for (std::size_t k = 0; k < specs.size(); ++k) {
        const int from = source[k] >= 0 ? source[k] : host;
        std::string name =
            from >= 0 ? parts[from].spec.get_string_attribute("oiio:subimagename") : "ssgi";
        if (name.empty()) name = "part" + std::to_string(k);
        while (part_names.count(name)) name += "_";
        part_names.insert(name);
        specs[k].attribute("oiio:subimagename", name);
      }
    }
  }

  // The input's pixels come from its file, read again strip by strip as they are written.
  std::unique_ptr<OIIO::ImageInput> in;
  if (passthrough) {
    in = detail::open_image(input.path);
    detail::check_unchanged(input, detail::decode_input(*in, input.path));
  }
  std::size_t clamped = 0;
  detail::UninitializedVector<std::byte> host_rows;  // each strip read whole into it
  detail::AtomicImageWriter writer(path, specs, "frame");
  for (std::size_t k = 0; k < specs.size(); ++k) {
    if (source[k] < 0) {
      const bool with_input = passthrough && host >= 0;
      writer.write_part_in_strips(
          [&](int y, int rows, std::byte* strip) {
            if (with_input) {
              host_rows.resize(host_pixel_bytes * data.width() * rows);
              detail::read_native_rows(*in, host, y, y + rows, host_rows.data(), input.path);
            }
            interleave_host_rows(ours, options.half, host_rows.data(), host_pixel_bytes,
                                 data.width(), y, rows, strip, &clamped);
          },
          with_input ? detail::rows_per_chunk(parts[host].spec) : 1);
    } else {
      const int part = source[k];
      writer.write_part_in_strips(
          [&](int y, int rows, std::byte* strip) {
            detail::read_native_rows(*in, part, y, y + rows, strip, input.path);
          },
          detail::rows_per_chunk(parts[part].spec));
    }
  }
  if (clamped > 0)
    log_warning(path + ": " + std::to_string(clamped) +
                " values of ssgi's layers beyond the half-float range were clamped to "
                "+-65504 (--datatype float keeps them)");
  writer.commit();
}

namespace {

// Decodes one chunk's worth of pixels at (x, y) of the current subimage and level: the
// scanline block or tile holding it. False when it cannot be read.
bool chunk_decodes(OIIO::ImageInput& in, int subimage, int level, int x, int y) {
  const OIIO::ImageSpec& spec = in.spec();
  std::vector<float> pixels;
  if (spec.tile_width > 0) {
    const int x0 = spec.x + (x - spec.x) / spec.tile_width * spec.tile_width;
    const int y0 = spec.y + (y - spec.y) / spec.tile_height * spec.tile_height;
    const int x1 = std::min(x0 + spec.tile_width, spec.x + spec.width);
    const int y1 = std::min(y0 + spec.tile_height, spec.y + spec.height);
    pixels.resize(static_cast<std::size_t>(x1 - x0) * (y1 - y0) * spec.nchannels);
    return in.read_tiles(subimage, level, x0, x1, y0, y1, spec.z, spec.z + 1, 0, spec.nchannels,
                         OIIO::TypeDesc::FLOAT, pixels.data());
  }
  pixels.resize(static_cast<std::size_t>(spec.width) * spec.nchannels);
  return in.read_scanlines(subimage, level, y, y + 1, spec.z, 0, spec.nchannels,
                           OIIO::TypeDesc::FLOAT, pixels.data());
}

}  // namespace

std::string why_not_reusable(const std::string& path,
                             const std::vector<std::pair<std::string, std::string>>& attributes) {
  std::unique_ptr<OIIO::ImageInput> in;
  try {
    in = detail::open_image(path);
  } catch (const Error& e) {
    return e.what();
  }
  for (const auto& [name, value] : attributes) {
    const OIIO::ParamValue* p = in->spec().find_attribute(name, OIIO::TypeDesc::STRING);
    if (p == nullptr) return "no " + name + " in its header: not written by this ssgi";
    if (p->get_string() != value)
      return name + " is '" + p->get_string() + "', not '" + value + "'";
  }
  for (int subimage = 0; in->seek_subimage(subimage, 0); ++subimage) {
    if (in->spec().deep) continue;
    int levels = 1;
    while (in->seek_subimage(subimage, levels)) ++levels;
    for (int level = 0; level < levels; ++level) {
      if (!in->seek_subimage(subimage, level))
        return "part " + std::to_string(subimage) + " is unreadable";
      const OIIO::ImageSpec& spec = in->spec();
      const bool whole =
          (level > 0 || chunk_decodes(*in, subimage, level, spec.x, spec.y)) &&
          chunk_decodes(*in, subimage, level, spec.x + spec.width - 1, spec.y + spec.height - 1);
      if (!whole) {
        const std::string error = detail::one_line(in->geterror());
        return "incomplete or damaged (part " + std::to_string(subimage) + ": " +
               (error.empty() ? std::string("cannot read its pixels") : error) + ")";
      }
    }
  }
  in->geterror();  // seek_subimage past the last part leaves a message
  return "";
}

}  // namespace ssgi
