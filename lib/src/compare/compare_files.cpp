// Comparing two image files: channels selected by name across all subimages, read with OIIO,
// for ssgi's metrics (compare_images()) and for idiff's comparison of chosen channels.
#include "compare/compare_files.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

#include "compare/compare.h"
#include "io/oiio_files.h"
#include "throw.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

// The text before a channel name's last '.', empty for a root channel such as `R`.
std::string layer_of(const std::string& channel) {
  const auto dot = channel.rfind('.');
  return dot == std::string::npos ? std::string() : channel.substr(0, dot);
}

std::string suffix_of(const std::string& channel) {
  const auto dot = channel.rfind('.');
  return dot == std::string::npos ? channel : channel.substr(dot + 1);
}

// Every channel of a file under the name a user knows it by, mapped to where it is. A channel
// of a named part that has no layer of its own (Karma's per-AOV parts hold plain R, G, B) is
// `<part>.<channel>`, as ssgi's writer names it; the first of two equal names wins.
struct NamedChannels {
  std::vector<std::string> names;  // file order
  std::map<std::string, ChannelRef> where;
};

NamedChannels name_channels(const FileChannels& file) {
  NamedChannels out;
  const bool multipart = file.channels.size() > 1;
  for (std::size_t s = 0; s < file.channels.size(); ++s) {
    const std::string& part = s < file.subimage_names.size() ? file.subimage_names[s] : "";
    for (const std::string& raw : file.channels[s]) {
      const bool prefix = multipart && !part.empty() && raw.find('.') == std::string::npos;
      const std::string name = prefix ? part + "." + raw : raw;
      if (out.where.emplace(name, ChannelRef{static_cast<int>(s), raw}).second)
        out.names.push_back(name);
    }
  }
  return out;
}

bool has_rgb(const NamedChannels& file, const std::string& layer) {
  const std::string prefix = layer.empty() ? "" : layer + ".";
  return file.where.count(prefix + "R") && file.where.count(prefix + "G") &&
         file.where.count(prefix + "B");
}

// Layers that have R, G and B, in file order.
std::vector<std::string> rgb_layers(const NamedChannels& file) {
  std::vector<std::string> layers;
  for (const std::string& name : file.names) {
    const std::string layer = layer_of(name);
    if (std::find(layers.begin(), layers.end(), layer) == layers.end() && has_rgb(file, layer))
      layers.push_back(layer);
  }
  return layers;
}

// A name on the command line: a channel, else a layer with R, G, B.
std::vector<std::string> resolve_name(const std::string& name, const NamedChannels& file,
                                      const std::string& path) {
  if (file.where.count(name)) return {name};
  if (has_rgb(file, name)) return {name + ".R", name + ".G", name + ".B"};
  throw_input(path, "has no channel or R,G,B layer '" + name + "'");
}

// The reference channel that marks background when the user names none: the standard `Z`, or
// a depth layer's Z (`depth.Z`, Blender's `ViewLayer.Depth.Z`).
std::string find_depth_channel(const NamedChannels& file) {
  if (file.where.count("Z")) return "Z";
  for (const std::string& name : file.names) {
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "depth.z" ||
        (lower.size() > 8 && lower.compare(lower.size() - 8, 8, ".depth.z") == 0))
      return name;
  }
  return {};
}

FileChannels probe_channels(OIIO::ImageInput& in) {
  FileChannels file;
  for (int s = 0; in.seek_subimage(s, 0); ++s) {
    file.subimage_names.push_back(in.spec().get_string_attribute("oiio:subimagename"));
    file.channels.push_back(in.spec().channelnames);
  }
  return file;
}

Box2i data_window_of(const OIIO::ImageSpec& spec) {
  return {spec.x, spec.y, spec.x + spec.width, spec.y + spec.height};
}

std::string describe(const Box2i& box) {
  return std::to_string(box.width()) + "x" + std::to_string(box.height()) + " at (" +
         std::to_string(box.x0) + ", " + std::to_string(box.y0) + ")";
}

// The data window all of `refs` share. Throws Error(kInput) when their parts differ.
Box2i common_data_window(OIIO::ImageInput& in, const std::vector<ChannelRef>& refs,
                         const std::string& path) {
  Box2i window;
  for (std::size_t i = 0; i < refs.size(); ++i) {
    in.seek_subimage(refs[i].subimage, 0);
    const Box2i w = data_window_of(in.spec());
    if (i > 0 && w != window)
      throw_input(path, "channel '" + refs[i].name + "' is in a part whose data window (" +
                            describe(w) + ") differs from " + describe(window));
    window = w;
  }
  return window;
}

// Reads `refs` into the planes of an image of the shared data window's size, one channel-range
// read per subimage.
Image read_planes(OIIO::ImageInput& in, const std::vector<ChannelRef>& refs, const Box2i& window,
                  const std::string& path) {
  Image image(window.width(), window.height(), static_cast<int>(refs.size()));
  std::map<int, std::vector<std::size_t>> by_subimage;
  for (std::size_t i = 0; i < refs.size(); ++i) by_subimage[refs[i].subimage].push_back(i);
  for (const auto& [subimage, items] : by_subimage) {
    in.seek_subimage(subimage, 0);
    const std::vector<std::string>& names = in.spec().channelnames;
    std::vector<int> index;
    for (std::size_t i : items)
      index.push_back(
          static_cast<int>(std::find(names.begin(), names.end(), refs[i].name) - names.begin()));
    const std::vector<std::vector<float>> planes =
        detail::read_float_planes(in, subimage, index, path);
    for (std::size_t k = 0; k < items.size(); ++k)
      std::copy(planes[k].begin(), planes[k].end(), image.plane(static_cast<int>(items[k])));
  }
  return image;
}

// Every channel of subimage `subimage` as idiff reads it. Throws Error(kInput) for deep data.
WindowedImage read_subimage(OIIO::ImageInput& in, int subimage, const std::string& path) {
  detail::refuse_deep(in, subimage, path);
  const OIIO::ImageSpec spec = in.spec();
  WindowedImage image;
  image.window = data_window_of(spec);
  image.channel_names = spec.channelnames;
  image.pixels = Image(spec.width, spec.height, spec.nchannels);
  std::vector<int> all(static_cast<std::size_t>(spec.nchannels));
  for (int c = 0; c < spec.nchannels; ++c) all[c] = c;
  const std::vector<std::vector<float>> planes = detail::read_float_planes(in, subimage, all, path);
  for (int c = 0; c < spec.nchannels; ++c)
    std::copy(planes[c].begin(), planes[c].end(), image.pixels.plane(c));
  return image;
}

// idiff -o: A - B (or |A - B| with -abs) times the scale over the union of the data windows,
// in float; a channel only one image has is that image's value (as ImageBufAlgo::sub leaves
// it). Named as in A, then B for channels A lacks; A's display window.
void write_idiff_difference(const std::string& path, const WindowedImage& a, const WindowedImage& b,
                            const IdiffOptions& options, const OIIO::ImageSpec& a_spec) {
  const Box2i roi = {std::min(a.window.x0, b.window.x0), std::min(a.window.y0, b.window.y0),
                     std::max(a.window.x1, b.window.x1), std::max(a.window.y1, b.window.y1)};
  const int na = a.pixels.channels(), nb = b.pixels.channels(), n = std::max(na, nb);
  OIIO::ImageSpec spec(roi.width(), roi.height(), n, OIIO::TypeDesc::FLOAT);
  spec.x = roi.x0;
  spec.y = roi.y0;
  spec.full_x = a_spec.full_x;
  spec.full_y = a_spec.full_y;
  spec.full_width = a_spec.full_width;
  spec.full_height = a_spec.full_height;
  spec.channelnames = a.channel_names;
  for (int c = na; c < n; ++c) spec.channelnames.push_back(b.channel_names[c]);
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  spec.attribute("compression", "zip");
  std::vector<float> interleaved(static_cast<std::size_t>(roi.width()) * roi.height() * n);
  std::size_t i = 0;
  for (int y = roi.y0; y < roi.y1; ++y) {
    for (int x = roi.x0; x < roi.x1; ++x) {
      for (int c = 0; c < n; ++c, ++i) {
        float d = c >= nb   ? a.sample(x, y, c)
                  : c >= na ? b.sample(x, y, c)
                            : a.sample(x, y, c) - b.sample(x, y, c);
        if (options.diff_abs) d = std::abs(d);
        interleaved[i] = d * options.diff_scale;
      }
    }
  }
  detail::write_image_atomically(path, spec, interleaved.data(), "difference image");
}

// Every channel of a subimage at (x, y), 0 outside its data window (OIIO's getchannel).
std::vector<float> values_at(const WindowedImage& image, int x, int y) {
  std::vector<float> values;
  for (int c = 0; c < image.pixels.channels(); ++c) values.push_back(image.sample(x, y, c));
  return values;
}

}  // namespace

std::vector<LayerChannels> select_layers(const std::string& a_path, const FileChannels& a,
                                         const std::string& b_path, const FileChannels& b,
                                         const std::vector<std::string>& items) {
  const NamedChannels a_named = name_channels(a), b_named = name_channels(b);
  std::vector<std::pair<std::string, std::string>> pairs;  // (a channel, b channel)

  if (items.empty()) {
    for (const std::string& layer : rgb_layers(a_named)) {
      if (!has_rgb(b_named, layer)) continue;
      for (const char* c : {"R", "G", "B"}) {
        const std::string name = layer.empty() ? c : layer + "." + c;
        pairs.emplace_back(name, name);
      }
    }
    if (pairs.empty()) {
      auto list = [](const std::vector<std::string>& layers) {
        std::vector<std::string> shown;
        for (const std::string& l : layers) shown.push_back(l.empty() ? "R,G,B" : l);
        return shown.empty() ? std::string("none") : OIIO::Strutil::join(shown, ", ");
      };
      throw_input(b_path, "no R,G,B layer in common with " + a_path + " (it has " +
                              list(rgb_layers(b_named)) + "; the other has " +
                              list(rgb_layers(a_named)) + "); choose with --channels");
    }
  }
  for (const std::string& item : items) {
    const auto eq = item.find('=');
    const std::string a_name = item.substr(0, eq);
    const std::string b_name = eq == std::string::npos ? a_name : item.substr(eq + 1);
    if (a_name.empty() || b_name.empty() || b_name.find('=') != std::string::npos)
      throw_usage("malformed channel item '" + item + "' (NAME or A_NAME=B_NAME)");
    const std::vector<std::string> a_channels = resolve_name(a_name, a_named, a_path);
    const std::vector<std::string> b_channels = resolve_name(b_name, b_named, b_path);
    if (a_channels.size() != b_channels.size())
      throw_input(b_path, "'" + b_name + "' is " + std::to_string(b_channels.size()) +
                              " channel(s) but '" + a_name + "' in " + a_path + " is " +
                              std::to_string(a_channels.size()));
    for (std::size_t i = 0; i < a_channels.size(); ++i)
      pairs.emplace_back(a_channels[i], b_channels[i]);
  }

  // Group by layer, keyed by both sides' layer names: `indirect=ViewLayer.DiffInd` compares a
  // layer of A with a differently named one of B.
  std::vector<LayerChannels> layers;
  std::vector<std::pair<std::string, std::string>> keys;
  for (const auto& [a_channel, b_channel] : pairs) {
    const std::pair<std::string, std::string> key{layer_of(a_channel), layer_of(b_channel)};
    auto it = std::find(keys.begin(), keys.end(), key);
    if (it == keys.end()) {
      keys.push_back(key);
      LayerChannels layer;
      layer.name = key.first == key.second ? key.first : key.first + "=" + key.second;
      layers.push_back(std::move(layer));
      it = keys.end() - 1;
    }
    LayerChannels& layer = layers[it - keys.begin()];
    layer.a.push_back(a_channel);
    layer.b.push_back(b_channel);
  }
  for (LayerChannels& layer : layers) {
    layer.rgb = layer.a.size() == 3 && suffix_of(layer.a[0]) == "R" &&
                suffix_of(layer.a[1]) == "G" && suffix_of(layer.a[2]) == "B";
    if (layer.name.empty()) layer.name = OIIO::Strutil::join(layer.a, ",");
  }
  return layers;
}

FileCompareResult compare_files(const std::string& a_path, const std::string& b_path,
                                const FileCompareOptions& options) {
  auto a_in = detail::open_image(a_path);
  auto b_in = detail::open_image(b_path);
  const FileChannels a_file = probe_channels(*a_in), b_file = probe_channels(*b_in);
  const NamedChannels a_named = name_channels(a_file), b_named = name_channels(b_file);

  FileCompareResult out;
  out.layers = select_layers(a_path, a_file, b_path, b_file, options.channels);
  std::vector<ChannelRef> a_refs, b_refs;
  std::vector<CompareLayer> compare_layers;
  for (const LayerChannels& layer : out.layers) {
    CompareLayer cl{layer.name, {}, layer.rgb};
    for (std::size_t i = 0; i < layer.a.size(); ++i) {
      cl.planes.push_back(static_cast<int>(a_refs.size()));
      a_refs.push_back(a_named.where.at(layer.a[i]));
      b_refs.push_back(b_named.where.at(layer.b[i]));
      out.plane_names.push_back(layer.a[i]);
    }
    compare_layers.push_back(std::move(cl));
  }

  if (!options.all_pixels) {
    out.depth_channel =
        options.depth_channel.empty() ? find_depth_channel(b_named) : options.depth_channel;
    if (!out.depth_channel.empty()) {
      const auto it = b_named.where.find(out.depth_channel);
      if (it == b_named.where.end())
        throw_input(b_path, "has no depth channel '" + out.depth_channel + "'");
      b_refs.push_back(it->second);  // read with the others, split off below
    }
  }

  const Box2i a_window = common_data_window(*a_in, a_refs, a_path);
  const Box2i b_window = common_data_window(*b_in, b_refs, b_path);
  if (a_window != b_window)
    throw_input(b_path, "size differs: data window " + describe(b_window) + ", but " +
                            describe(a_window) + " in " + a_path);

  const Image a = read_planes(*a_in, a_refs, a_window, a_path);
  Image b = read_planes(*b_in, b_refs, b_window, b_path);
  std::vector<std::uint8_t> background;
  if (!out.depth_channel.empty()) {
    background = background_from_depth(b.plane(b.channels() - 1), b.plane_size());
    Image b_colour(b.width(), b.height(), b.channels() - 1);
    std::copy(b.data().begin(), b.data().begin() + b_colour.data().size(), b_colour.data().begin());
    b = std::move(b_colour);
  }
  CompareOptions compare = options.compare;
  if (options.all_pixels) compare.exclude_zero_reference = false;
  out.result = compare_images(a, b, compare_layers, compare, background);
  return out;
}

IdiffFileResult idiff_files(const std::string& a_path, const std::string& b_path,
                            const IdiffOptions& options) {
  if (options.all_subimages && !options.channels.empty())
    throw_usage("-a compares subimages by index, --channels picks channels by name: not both");
  auto a_in = detail::open_image(a_path);
  auto b_in = detail::open_image(b_path);
  const FileChannels a_file = probe_channels(*a_in), b_file = probe_channels(*b_in);

  // The pairs of images to compare, with the subimage they stand for.
  std::vector<std::pair<WindowedImage, WindowedImage>> pairs;
  IdiffFileResult out;
  if (!options.channels.empty()) {
    const NamedChannels a_named = name_channels(a_file), b_named = name_channels(b_file);
    WindowedImage a, b;
    std::vector<ChannelRef> a_refs, b_refs;
    for (const LayerChannels& layer :
         select_layers(a_path, a_file, b_path, b_file, options.channels)) {
      for (std::size_t i = 0; i < layer.a.size(); ++i) {
        a_refs.push_back(a_named.where.at(layer.a[i]));
        b_refs.push_back(b_named.where.at(layer.b[i]));
        a.channel_names.push_back(layer.a[i]);
        b.channel_names.push_back(layer.b[i]);
      }
    }
    for (const ChannelRef& ref : a_refs) detail::refuse_deep(*a_in, ref.subimage, a_path);
    for (const ChannelRef& ref : b_refs) detail::refuse_deep(*b_in, ref.subimage, b_path);
    a.window = common_data_window(*a_in, a_refs, a_path);
    b.window = common_data_window(*b_in, b_refs, b_path);
    a.pixels = read_planes(*a_in, a_refs, a.window, a_path);
    b.pixels = read_planes(*b_in, b_refs, b.window, b_path);
    pairs.emplace_back(std::move(a), std::move(b));
  } else {
    out.a_subimages = static_cast<int>(a_file.channels.size());
    out.b_subimages = static_cast<int>(b_file.channels.size());
    for (int s = 0; s < out.a_subimages && s < out.b_subimages; ++s) {
      if (s > 0 && !options.all_subimages) break;
      WindowedImage a = read_subimage(*a_in, s, a_path);
      pairs.emplace_back(std::move(a), read_subimage(*b_in, s, b_path));
    }
  }

  std::string diff_path = options.diff_path;
  for (std::size_t s = 0; s < pairs.size(); ++s) {
    const WindowedImage& a = pairs[s].first;
    const WindowedImage& b = pairs[s].second;
    IdiffSubimage sub;
    sub.subimage = static_cast<int>(s);
    sub.width = a.window.width();
    sub.height = a.window.height();
    sub.channels = a.pixels.channels();
    sub.pixels = std::max<std::size_t>(1, static_cast<std::size_t>(sub.width) * sub.height);
    sub.stats = idiff_compare(a, b, options.thresholds);
    out.status = idiff_status(sub.stats, sub.pixels, options.thresholds, out.status);
    sub.status = out.status;
    const int c = sub.stats.max_channel;
    sub.max_channel_name = c < static_cast<int>(a.channel_names.size())   ? a.channel_names[c]
                           : c < static_cast<int>(b.channel_names.size()) ? b.channel_names[c]
                                                                          : std::string();
    sub.a_values = values_at(a, sub.stats.max_x, sub.stats.max_y);
    sub.b_values = values_at(b, sub.stats.max_x, sub.stats.max_y);
    // idiff writes the first subimage compared, or with -od the first that differs.
    if (!diff_path.empty() && (sub.stats.max_error != 0.0 || !options.diff_only_if_different)) {
      a_in->seek_subimage(static_cast<int>(s), 0);
      write_idiff_difference(diff_path, a, b, options, a_in->spec());
      out.diff_written = true;
      diff_path.clear();
    }
    out.subimages.push_back(std::move(sub));
  }
  if (options.all_subimages && out.a_subimages != out.b_subimages)
    out.status = CompareStatus::kFail;
  return out;
}

}  // namespace ssgi
