// The one boundary between ssgi and OpenImageIO's files (internal: uses OIIO types): opening an
// image with a clear error, reading channel ranges as float planes or in their own formats, and
// writing whole files atomically. The reader, the writer and `compare` all go through it.
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <filesystem>
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

// A frame's input file as opened when it was read: its parts' headers. The writer copies the
// output's header from them and passes the input's channels through from the file itself, strip
// by strip (read_native_rows), so that no frame's input pixels are held while it waits to be
// written.
struct DecodedInput {
  struct Part {
    OIIO::ImageSpec spec;         // its subimage's index is its index in `parts`
    bool has_mip_levels = false;  // only the full-resolution level is passed through
  };
  std::string path;
  std::vector<Part> parts;
  // The file as it was when it was opened: a file written again since (a re-render) differs.
  std::uintmax_t file_bytes = 0;
  std::filesystem::file_time_type modified{};
};

// The headers of every part of the open file `in` (at `path`). Throws Error(kIO) naming `path`.
DecodedInput decode_input(OIIO::ImageInput& in, const std::string& path);

// Throws Error(kIO) naming input.path when the file at that path, `now` (as decode_input saw it
// later), is not the file `input` was read from: another size or modification time, other
// parts, windows, tiling, channels or formats. Pixels read from the two could not be put together
// in one frame.
void check_unchanged(const DecodedInput& input, const DecodedInput& now);

// Reads rows [top, bottom) of subimage `subimage`'s data window (counted from its first row,
// top mip level) in the file's own per-channel formats, interleaved (spec.pixel_bytes(true) bytes
// per pixel): uint32 IDs and half passes come back bit for bit. For a tiled part both ends lie on
// rows of tiles (or the part's end). Throws Error(kIO) naming `path`.
void read_native_rows(OIIO::ImageInput& in, int subimage, int top, int bottom, std::byte* pixels,
                      const std::string& path);

// The rows a strip of a part is made of, so that it starts and ends on the part's chunks: a
// tile's height, or the scanlines its compression packs into one block.
int rows_per_chunk(const OIIO::ImageSpec& spec);

// Scanlines per chunk of a scanline file compressed with `compression` ("zip", "dwaa:45", ...:
// OpenEXR's table); unknown: 32.
int scanlines_per_chunk(const std::string& compression);

// Rows the reader and the writer take at once: whole chunks of `chunk` rows, about this many
// bytes (at least one chunk, at most the part's `height`), of rows of `row_bytes` each.
constexpr std::size_t kStripBytes = std::size_t{16} << 20;
int strip_rows(std::size_t row_bytes, int chunk, int height);

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
  // With `row_multiple`, every strip but the last is also a whole number of those rows (the
  // chunks of the file the strips are read from). The bytes written are those of write_part; no
  // whole-part buffer is held.
  void write_part_in_strips(const std::function<void(int y, int rows, std::byte* pixels)>& fill,
                            int row_multiple = 1);
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
