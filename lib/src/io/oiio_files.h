// The one boundary between ssgi and OpenImageIO's files (internal: uses OIIO types): opening an
// image with a clear error, reading channel ranges as float planes or in their own formats, and
// writing whole files atomically. The reader, the writer and `compare` all go through it.
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/temporary_files.h"
#include "ssgi/image.h"

namespace ssgi::detail {

// OIIO's messages can span lines; ours are one line.
std::string one_line(std::string message);

// Opens `path` for reading. Throws Error(kIO) naming it when it does not exist, is a
// directory or empty, or OIIO cannot read it.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path);

// Throws Error(kInput) naming `path` when subimage `subimage` holds deep data (not read yet),
// Error(kIO) when it cannot be found.
void refuse_deep(OIIO::ImageInput& in, int subimage, const std::string& path);

// A channel of a part and the plane it is read into: `window`-sized, row-major (see
// read_float_channels).
struct PlaneTarget {
  int channel = 0;  // index in the part's channel list
  float* plane = nullptr;
};

// Reads the channels of `targets` (of subimage `subimage`, any order, a channel may have several
// targets) as float into planes covering `window` (absolute pixel coordinates): the part's
// pixels where they fall in the window; pixels of the window outside the part are left as they
// are. Reads the channel range that covers them in strips of whole chunks (scanline blocks or
// rows of tiles) of a few megabytes, each chunk decoded once (OIIO 2.4 decompresses every ZIP
// block again for each read of it), so that no whole-frame interleaved buffer is ever held.
// Throws Error(kIO) naming `path` when the pixels cannot be read, Error(kInput) for deep data.
void read_float_channels(OIIO::ImageInput& in, int subimage,
                         const std::vector<PlaneTarget>& targets, const Box2i& window,
                         const std::string& path);

// Reads channels `indices` (of subimage `subimage`, any order) as one float plane each, of the
// part's own data window (read_float_channels).
std::vector<std::vector<float>> read_float_planes(OIIO::ImageInput& in, int subimage,
                                                  const std::vector<int>& indices,
                                                  const std::string& path);

// Error(kInput) naming `path`: part `subimage` holds deep data, which ssgi does not read.
[[noreturn]] void throw_deep(const std::string& path, int subimage);

// Reads every channel of subimage `subimage` (top mip level) in the file's own per-channel
// formats, interleaved (spec.pixel_bytes(true) bytes per pixel): uint32 IDs and half passes
// come back bit for bit. Throws Error(kIO) naming `path`.
std::vector<std::byte> read_native_pixels(OIIO::ImageInput& in, int subimage,
                                          const std::string& path);

// A frame's input file as read once: its parts' headers and, when the output passes the input
// through, every part's pixels in the file's own per-channel formats (uint32 IDs and half passes
// bit for bit). The writer copies the output's header and passed-through channels from it, so
// that no input is opened or decoded a second time.
struct DecodedInput {
  struct Part {
    OIIO::ImageSpec spec;           // its subimage's index is its index in `parts`
    bool has_mip_levels = false;    // only the full-resolution level is kept
    std::vector<std::byte> pixels;  // interleaved, spec.pixel_bytes(true) a pixel; empty when
                                    // not kept (pixels not asked for, or deep data)
  };
  std::string path;
  std::vector<Part> parts;
  std::size_t pixel_bytes() const;  // the kept pixels' size
};

// The headers of every part of the open file `in` (at `path`) and, with `keep_pixels`, the
// pixels of every part that is not deep (read_native_pixels). Throws Error(kIO) naming `path`.
DecodedInput decode_input(OIIO::ImageInput& in, const std::string& path, bool keep_pixels);

// read_float_channels from a decoded part's kept pixels instead of the file: the same floats
// (OIIO's conversion from each channel's own format). Throws Error(kInput) naming `path` for a
// deep part; `part` must have kept its pixels otherwise.
void float_channels_from(const DecodedInput& input, int subimage,
                         const std::vector<PlaneTarget>& targets, const Box2i& window);

// A file written through a hidden temporary file in the same directory (keeping the extension,
// which tells OIIO the format) and renamed into place by commit(). Destroyed before commit(), it
// removes the temporary file, so a failure never leaves a partial file under any name.
class AtomicImageWriter {
 public:
  // Opens the temporary file for `parts` (one spec per part, written in order). `what`
  // ("frame", "difference image") names the file in messages. Throws Error(kIO) naming `path`.
  AtomicImageWriter(const std::string& path, std::vector<OIIO::ImageSpec> parts, std::string what);
  ~AtomicImageWriter();
  AtomicImageWriter(const AtomicImageWriter&) = delete;
  AtomicImageWriter& operator=(const AtomicImageWriter&) = delete;

  // Writes the next part's pixels, interleaved, all in `format`, or in the part's own
  // per-channel formats when `format` is OIIO::TypeUnknown.
  void write_part(OIIO::TypeDesc format, const void* pixels);
  // Writes the next part in strips of whole chunks (rows of tiles for a tiled part) of a few
  // megabytes: fill(y, rows, pixels) puts rows [y, y + rows) of the part's data window (y
  // counted from its top) into `pixels`, interleaved in the part's own per-channel formats.
  // The bytes written are those of write_part; no whole-part buffer is held.
  void write_part_in_strips(const std::function<void(int y, int rows, std::byte* pixels)>& fill);
  // Closes the file and renames it into place; every part must have been written.
  void commit();

 private:
  [[noreturn]] void fail(const std::string& why);
  std::string path_, tmp_, what_;
  std::optional<TemporaryFile> registered_;  // for a signal handler's remove_temporary_files()
  std::vector<OIIO::ImageSpec> parts_;
  std::unique_ptr<OIIO::ImageOutput> out_;
  std::size_t written_ = 0;
};

// Writes one part of float pixels atomically (see AtomicImageWriter).
void write_image_atomically(const std::string& path, const OIIO::ImageSpec& spec,
                            const float* interleaved, const std::string& what);

}  // namespace ssgi::detail
