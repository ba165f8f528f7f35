// A frame's input read for a run (internal): its camera, the G-buffer the pipeline works on,
// and the input's headers, from which the writer copies the output's header (the
// passed-through channels it reads from the file again).
#pragma once

#include <algorithm>
#include <cassert>
#include <memory>
#include <string>
#include <vector>

#include "io/guide_frame.h"
#include "io/oiio_files.h"
#include "io/sequence_info.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"

namespace ssgi {

class ColorManagement;

// The camera of one frame, from its header alone (or the options' sidecar / field of view).
Camera read_camera(const SequenceInfo& sequence, int frame, const InputOptions& options);

}  // namespace ssgi

namespace ssgi::detail {

struct InputFrame {
  GBuffer g;
  std::shared_ptr<const DecodedInput> input;
  std::vector<GBuffer> views;  // the frame's views (io/views.h), until it is lit
  GuideFrame guide;            // the frame's guide (io/guide.h), until it is lit
};

// read_gbuffer, keeping the parts' headers (which the writer copies, and checks the file
// against when it passes the input's channels through). Without `report`, what is wrong with the
// frame (non-finite values, no surfaces) is not warned about: a frame read again later is warned
// about then.
InputFrame read_input_frame(const SequenceInfo& sequence, int frame, RoleMask roles,
                            const InputOptions& options, const ColorManagement* color,
                            bool report = true);

// An input file opened: an OpenEXR file, or Error(kIO) naming it.
std::unique_ptr<OIIO::ImageInput> open_input_exr(const std::string& path);

// open_sequence for a view's files (io/views.h): without checking its header camera against its
// position pass, and without views of its own.
SequenceInfo open_view_sequence(const InputOptions& options);

// Copies every plane of `src`, whose pixels cover `src_window`, into `dst`, covering
// `dst_window`, where the two windows overlap; the rest of `dst` is left as it is. Both have the
// same number of channels.
inline void copy_window(const Image& src, const Box2i& src_window, Image* dst,
                        const Box2i& dst_window) {
  assert(src.channels() == dst->channels());
  const int x0 = std::max(src_window.x0, dst_window.x0),
            x1 = std::min(src_window.x1, dst_window.x1);
  const int y0 = std::max(src_window.y0, dst_window.y0),
            y1 = std::min(src_window.y1, dst_window.y1);
  if (x1 <= x0 || y1 <= y0) return;
  for (int c = 0; c < src.channels(); ++c)
    for (int y = y0; y < y1; ++y)
      std::copy_n(src.plane(c) + static_cast<std::size_t>(y - src_window.y0) * src.width() +
                      (x0 - src_window.x0),
                  x1 - x0,
                  dst->plane(c) + static_cast<std::size_t>(y - dst_window.y0) * dst->width() +
                      (x0 - dst_window.x0));
}

}  // namespace ssgi::detail
