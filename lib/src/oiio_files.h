// Small OIIO helpers shared by the reader, the writer and `compare` (internal: uses OIIO
// types): one-line messages, opening an image with a clear error, writing atomically.
#pragma once

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>

namespace ssgi::detail {

// OIIO's messages can span lines; ours are one line.
std::string one_line(std::string message);

// Opens `path` for reading. Throws Error(kIO) naming it when it does not exist, is a
// directory or empty, or OIIO cannot read it.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path);

// Writes `spec` with `interleaved` float pixels to `path` through a hidden temporary file in
// the same directory (keeping the extension, which tells OIIO the format), renamed into place,
// so that a failure never leaves a partial file. Throws Error(kIO) naming `path`, with `what`
// ("frame", "difference image") in the message.
void write_image_atomically(const std::string& path, const OIIO::ImageSpec& spec,
                            const float* interleaved, const std::string& what);

}  // namespace ssgi::detail
