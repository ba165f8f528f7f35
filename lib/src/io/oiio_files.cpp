#include "io/oiio_files.h"

#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <filesystem>
#include <limits>
#include <numeric>

#include "buffers.h"
#include "throw.h"

namespace ssgi::detail {

namespace fs = std::filesystem;

std::string one_line(std::string message) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  while (!message.empty() && message.back() == ' ') message.pop_back();
  return message;
}

std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw_io(path, "no such file");
  if (fs::is_directory(path, ec)) throw_io(path, "is a directory, not an image");
  // A FIFO would block the open until something writes to it; a device is no image either.
  if (!fs::is_regular_file(path, ec))
    throw_io(path, "is not a regular file (a FIFO, socket or device), not an image");
  if (fs::file_size(path, ec) == 0) throw_io(path, "empty file");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw_io(path, "cannot read image: " + one_line(OIIO::geterror()));
  return in;
}

void throw_deep(const std::string& path, int subimage) {
  throw_input(path, "part " + std::to_string(subimage) +
                        " holds deep data, which ssgi does not read yet: flatten it first "
                        "(oiiotool IN --flatten -o OUT)");
}

void refuse_deep(OIIO::ImageInput& in, int subimage, const std::string& path) {
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  if (in.spec().deep) throw_deep(path, subimage);
}

int scanlines_per_chunk(const std::string& compression) {
  const std::string name = compression.substr(0, compression.find(':'));
  if (name == "none" || name == "rle" || name == "zips") return 1;
  if (name == "zip" || name == "pxr24") return 16;
  if (name == "dwab") return 256;
  return 32;  // piz, b44, b44a, dwaa
}

int strip_rows(std::size_t row_bytes, int chunk, int height) {
  const int rows =
      chunk *
      std::max<int>(1, static_cast<int>(kStripBytes / std::max<std::size_t>(1, row_bytes * chunk)));
  return std::min(rows, height);
}

namespace {

int lines_per_chunk(const OIIO::ImageSpec& spec) {
  return scanlines_per_chunk(spec.get_string_attribute("compression", "none"));
}

}  // namespace

void read_float_channels(OIIO::ImageInput& in, int subimage,
                         const std::vector<PlaneTarget>& targets, const Box2i& window,
                         const std::string& path) {
  if (targets.empty()) return;
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  refuse_deep(in, subimage, path);
  const OIIO::ImageSpec spec = in.spec();
  int lo = spec.nchannels, hi = -1;
  for (const PlaneTarget& t : targets) {
    assert(t.channel >= 0 && t.channel < spec.nchannels);
    lo = std::min(lo, t.channel);
    hi = std::max(hi, t.channel);
  }
  const int n = hi - lo + 1;
  // The part's pixels that fall in the window.
  const int x0 = std::max(spec.x, window.x0), x1 = std::min(spec.x + spec.width, window.x1);
  const int y0 = std::max(spec.y, window.y0), y1 = std::min(spec.y + spec.height, window.y1);
  if (x1 <= x0 || y1 <= y0) return;
  const int chunk = rows_per_chunk(spec);
  const std::size_t row_bytes = static_cast<std::size_t>(spec.width) * n * sizeof(float);
  const int rows = strip_rows(row_bytes, chunk, spec.height);
  // Each read fills the rows it reads, and only those are copied out.
  detail::UninitializedVector<float> strip(static_cast<std::size_t>(rows) * spec.width * n);
  // Strips start on chunk boundaries, which count from the part's top.
  for (int top = spec.y + (y0 - spec.y) / chunk * chunk; top < y1; top += rows) {
    const int bottom = std::min(top + rows, spec.y + spec.height);
    const bool ok =
        spec.tile_width > 0
            ? in.read_tiles(subimage, 0, spec.x, spec.x + spec.width, top, bottom, spec.z,
                            spec.z + 1, lo, hi + 1, OIIO::TypeDesc::FLOAT, strip.data())
            : in.read_scanlines(subimage, 0, top, bottom, spec.z, lo, hi + 1, OIIO::TypeDesc::FLOAT,
                                strip.data());
    if (!ok) throw_io(path, "cannot read pixels: " + one_line(in.geterror()));
    for (int y = std::max(top, y0); y < std::min(bottom, y1); ++y) {
      const float* src =
          strip.data() + (static_cast<std::size_t>(y - top) * spec.width + (x0 - spec.x)) * n;
      const std::size_t dst_row =
          static_cast<std::size_t>(y - window.y0) * window.width() + (x0 - window.x0);
      for (const PlaneTarget& t : targets) {
        const float* s = src + (t.channel - lo);
        float* d = t.plane + dst_row;
        for (int x = 0; x < x1 - x0; ++x) d[x] = s[static_cast<std::size_t>(x) * n];
      }
    }
  }
}

std::vector<std::vector<float>> read_float_planes(OIIO::ImageInput& in, int subimage,
                                                  const std::vector<int>& indices,
                                                  const std::string& path) {
  if (indices.empty()) return {};
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  const OIIO::ImageSpec& spec = in.spec();
  const Box2i part = {spec.x, spec.y, spec.x + spec.width, spec.y + spec.height};
  std::vector<std::vector<float>> planes(
      indices.size(), std::vector<float>(static_cast<std::size_t>(spec.width) * spec.height));
  std::vector<PlaneTarget> targets;
  for (std::size_t i = 0; i < indices.size(); ++i)
    targets.push_back({indices[i], planes[i].data()});
  read_float_channels(in, subimage, targets, part, path);
  return planes;
}

void read_native_rows(OIIO::ImageInput& in, int subimage, int top, int bottom, std::byte* pixels,
                      const std::string& path) {
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  const OIIO::ImageSpec& spec = in.spec();
  assert(top >= 0 && top < bottom && bottom <= spec.height);
  const bool ok =
      spec.tile_width > 0
          ? in.read_tiles(subimage, 0, spec.x, spec.x + spec.width, spec.y + top, spec.y + bottom,
                          spec.z, spec.z + 1, 0, spec.nchannels, OIIO::TypeUnknown, pixels)
          : in.read_scanlines(subimage, 0, spec.y + top, spec.y + bottom, spec.z, 0, spec.nchannels,
                              OIIO::TypeUnknown, pixels);
  if (!ok) throw_io(path, "cannot read pixels: " + one_line(in.geterror()));
}

int rows_per_chunk(const OIIO::ImageSpec& spec) {
  return spec.tile_width > 0 ? spec.tile_height : lines_per_chunk(spec);
}

DecodedInput decode_input(OIIO::ImageInput& in, const std::string& path) {
  DecodedInput input;
  input.path = path;
  std::error_code ec;
  input.file_bytes = fs::file_size(path, ec);
  input.modified = fs::last_write_time(path, ec);
  for (int s = 0; in.seek_subimage(s, 0); ++s) {
    DecodedInput::Part part;
    part.spec = in.spec();
    part.has_mip_levels = in.seek_subimage(s, 1);
    input.parts.push_back(std::move(part));
  }
  in.geterror();  // seek_subimage past the last part leaves a message
  return input;
}

void check_unchanged(const DecodedInput& input, const DecodedInput& now) {
  const auto changed = [&](const std::string& what) {
    throw_io(input.path,
             "changed since it was read (" + what + "): its pixels cannot make one frame");
  };
  if (now.file_bytes != input.file_bytes || now.modified != input.modified)
    changed("its size or modification time");
  if (now.parts.size() != input.parts.size())
    changed(std::to_string(now.parts.size()) + " parts, not " + std::to_string(input.parts.size()));
  for (std::size_t i = 0; i < now.parts.size(); ++i) {
    const OIIO::ImageSpec& a = input.parts[i].spec;
    const OIIO::ImageSpec& b = now.parts[i].spec;
    const std::string part = "part " + std::to_string(i);
    if (a.x != b.x || a.y != b.y || a.width != b.width || a.height != b.height || a.deep != b.deep)
      changed(part + "'s data window");
    if (a.tile_width != b.tile_width || a.tile_height != b.tile_height) changed(part + "'s tiles");
    if (a.channelnames != b.channelnames) changed(part + "'s channels");
    for (int c = 0; c < b.nchannels; ++c)
      if (a.channelformat(c) != b.channelformat(c)) changed(part + "'s channel formats");
  }
}

AtomicImageWriter::AtomicImageWriter(const std::string& path, std::vector<OIIO::ImageSpec> parts,
                                     std::string what)
    : path_(path), what_(std::move(what)), parts_(std::move(parts)) {
  assert(!parts_.empty());
  tmp_ = temporary_path_for(path);
  registered_.emplace(tmp_);  // before the file exists
  out_ = OIIO::ImageOutput::create(tmp_);
  if (!out_) fail(one_line(OIIO::geterror()));
  const bool ok = parts_.size() == 1
                      ? out_->open(tmp_, parts_[0])
                      : out_->open(tmp_, static_cast<int>(parts_.size()), parts_.data());
  if (!ok) fail(one_line(out_->geterror()));
}

AtomicImageWriter::~AtomicImageWriter() {
  out_.reset();
  std::error_code ec;
  if (!tmp_.empty()) fs::remove(tmp_, ec);
}

void AtomicImageWriter::fail(const std::string& why) {
  out_.reset();
  std::error_code ec;
  fs::remove(tmp_, ec);
  tmp_.clear();
  throw_io(path_,
           "cannot write the " + what_ + ": " + (why.empty() ? std::string("unknown error") : why));
}

void AtomicImageWriter::write_part(OIIO::TypeDesc format, const void* pixels) {
  assert(out_ && written_ < parts_.size());
  if (written_ > 0 && !out_->open(tmp_, parts_[written_], OIIO::ImageOutput::AppendSubimage))
    fail(one_line(out_->geterror()));
  if (!out_->write_image(format, pixels)) fail(one_line(out_->geterror()));
  ++written_;
}

void AtomicImageWriter::write_part_in_strips(
    const std::function<void(int y, int rows, std::byte* pixels)>& fill, int row_multiple) {
  assert(out_ && written_ < parts_.size() && row_multiple >= 1);
  const OIIO::ImageSpec& spec = parts_[written_];
  if (written_ > 0 && !out_->open(tmp_, spec, OIIO::ImageOutput::AppendSubimage))
    fail(one_line(out_->geterror()));
  const std::size_t row_bytes = spec.scanline_bytes(/*native=*/true);
  const int rows = strip_rows(row_bytes, std::lcm(rows_per_chunk(spec), row_multiple), spec.height);
  // Zeroed: the file gets every byte of it, and a fill need not write padding it does not use.
  detail::UninitializedVector<std::byte> strip(row_bytes * rows, std::byte{0});
  for (int y = 0; y < spec.height; y += rows) {
    const int n = std::min(rows, spec.height - y);
    fill(y, n, strip.data());
    const bool ok = spec.tile_width > 0
                        ? out_->write_tiles(spec.x, spec.x + spec.width, spec.y + y, spec.y + y + n,
                                            spec.z, spec.z + 1, OIIO::TypeUnknown, strip.data())
                        : out_->write_scanlines(spec.y + y, spec.y + y + n, spec.z,
                                                OIIO::TypeUnknown, strip.data());
    if (!ok) fail(one_line(out_->geterror()));
  }
  ++written_;
}

void AtomicImageWriter::commit() {
  assert(out_ && written_ == parts_.size());
  if (!out_->close()) fail(one_line(out_->geterror()));
  out_.reset();
  move_into_place(tmp_, path_, what_);
  tmp_.clear();
  registered_.reset();
}

void write_image_atomically(const std::string& path, const OIIO::ImageSpec& spec,
                            const float* interleaved, const std::string& what) {
  AtomicImageWriter writer(path, {spec}, what);
  writer.write_part(OIIO::TypeDesc::FLOAT, interleaved);
  writer.commit();
}

}  // namespace ssgi::detail
