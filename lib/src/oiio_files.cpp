#include "oiio_files.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>

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
  if (fs::file_size(path, ec) == 0) throw_io(path, "empty file");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw_io(path, "cannot read image: " + one_line(OIIO::geterror()));
  return in;
}

void write_image_atomically(const std::string& path, const OIIO::ImageSpec& spec,
                            const float* interleaved, const std::string& what) {
  const fs::path target = fs::absolute(path);
  const std::string tmp =
      (target.parent_path() / ("." + target.filename().string() + ".tmp" +
                               std::to_string(::getpid()) + target.extension().string()))
          .string();
  std::error_code ec;
  auto out = OIIO::ImageOutput::create(tmp);
  const bool ok = out && out->open(tmp, spec) &&
                  out->write_image(OIIO::TypeDesc::FLOAT, interleaved) && out->close();
  if (!ok) {
    const std::string why = out ? one_line(out->geterror()) : one_line(OIIO::geterror());
    out.reset();
    fs::remove(tmp, ec);
    throw_io(path, "cannot write the " + what + ": " +
                       (why.empty() ? std::string("unknown error") : why));
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string why = ec.message();  // before remove() overwrites ec
    fs::remove(tmp, ec);
    throw_io(path, "cannot move the finished " + what + " into place: " + why);
  }
}

}  // namespace ssgi::detail
