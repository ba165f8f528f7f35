// Writing result frames: our layers plus the input's channels and header, atomically.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "io/oiio_files.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"

namespace ssgi {

// A layer of results to write: channels `<prefix><name>.<suffix>` from the planes of `image`
// (an empty name writes bare `<prefix><suffix>`, as the composite's R, G, B, A).
struct OutputLayer {
  std::string name;
  const Image* image = nullptr;
  std::vector<std::string> suffixes;
};

// Throws Error(kIO) naming `path` unless the directory `path` would be written into exists.
void check_output_directory(const std::string& path);

// Makes the directory `path` would be written into, with its missing parents (mkdir -p).
// Throws Error(kIO) naming `path` when something that is not a directory is in the way or the
// directory cannot be made.
void make_output_directory(const std::string& path);

// Writes `layers` (covering `frame`'s data window) to `path` with the input's header and,
// when asked, its channels. Written to a temporary file in the same directory, then renamed,
// so a failure never leaves a partial frame. Throws Error(kIO) naming `path` on failure.
void write_frame(const std::string& path, const GBuffer& frame,
                 const std::vector<OutputLayer>& layers, const WriteOptions& options);

// Why the file at `path` cannot stand for the frame a run would write there, or "" when it can:
// it opens as an image, the first and last chunks of every part decode (a truncated file loses
// its last), and its header holds each of `attributes` (name, value) as a string.
std::string why_not_reusable(const std::string& path,
                             const std::vector<std::pair<std::string, std::string>>& attributes);

}  // namespace ssgi

namespace ssgi::detail {

// write_frame from the input as read: its header, and with passthrough its channels, read again
// from its file strip by strip.
void write_frame(const std::string& path, const GBuffer& frame,
                 const std::vector<OutputLayer>& layers, const WriteOptions& options,
                 const DecodedInput& input);

}  // namespace ssgi::detail
