#include "oiio_files.h"

#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <filesystem>
#include <limits>

#include "ssgi/error.h"

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

void refuse_deep(OIIO::ImageInput& in, int subimage, const std::string& path) {
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  if (in.spec().deep)
    throw_input(path, "part " + std::to_string(subimage) +
                          " holds deep data, which ssgi does not read yet: flatten it first "
                          "(oiiotool IN --flatten -o OUT)");
}

std::vector<std::vector<float>> read_float_planes(OIIO::ImageInput& in, int subimage,
                                                  const std::vector<int>& indices,
                                                  const std::string& path) {
  if (indices.empty()) return {};
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  refuse_deep(in, subimage, path);
  const OIIO::ImageSpec& spec = in.spec();
  const int lo = *std::min_element(indices.begin(), indices.end());
  const int hi = *std::max_element(indices.begin(), indices.end());
  assert(lo >= 0 && hi < spec.nchannels);
  const int n = hi - lo + 1;
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
  std::vector<float> interleaved(pixels * n);
  if (!in.read_image(subimage, 0, lo, hi + 1, OIIO::TypeDesc::FLOAT, interleaved.data()))
    throw_io(path, "cannot read pixels: " + one_line(in.geterror()));
  std::vector<std::vector<float>> planes(indices.size(), std::vector<float>(pixels));
  for (std::size_t i = 0; i < indices.size(); ++i) {
    const int c = indices[i] - lo;
    float* dst = planes[i].data();
    for (std::size_t p = 0; p < pixels; ++p) dst[p] = interleaved[p * n + c];
  }
  return planes;
}

std::vector<std::byte> read_native_pixels(OIIO::ImageInput& in, int subimage,
                                          const std::string& path) {
  if (!in.seek_subimage(subimage, 0))
    throw_io(path, "cannot read part " + std::to_string(subimage));
  const OIIO::ImageSpec& spec = in.spec();
  std::vector<std::byte> pixels(spec.image_bytes(/*native=*/true));
  if (!in.read_image(subimage, 0, 0, spec.nchannels, OIIO::TypeUnknown, pixels.data()))
    throw_io(path, "cannot read pixels: " + one_line(in.geterror()));
  return pixels;
}

AtomicImageWriter::AtomicImageWriter(const std::string& path, std::vector<OIIO::ImageSpec> parts,
                                     std::string what)
    : path_(path), what_(std::move(what)), parts_(std::move(parts)) {
  assert(!parts_.empty());
  const fs::path target = fs::absolute(path);
  tmp_ = (target.parent_path() / ("." + target.filename().string() + ".tmp" +
                                  std::to_string(::getpid()) + target.extension().string()))
             .string();
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

void AtomicImageWriter::commit() {
  assert(out_ && written_ == parts_.size());
  if (!out_->close()) fail(one_line(out_->geterror()));
  out_.reset();
  std::error_code ec;
  fs::rename(tmp_, fs::absolute(path_), ec);
  if (ec) {
    const std::string why = ec.message();  // before remove() overwrites ec
    fs::remove(tmp_, ec);
    tmp_.clear();
    throw_io(path_, "cannot move the finished " + what_ + " into place: " + why);
  }
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
