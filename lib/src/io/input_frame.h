// A frame's input read once for a whole run (internal): the G-buffer the pipeline works on, and
// the input as decoded, from which the writer copies the header and the passed-through channels.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "oiio_files.h"
#include "ssgi/color.h"
#include "ssgi/gbuffer.h"
#include "ssgi/io.h"

namespace ssgi::detail {

struct InputFrame {
  GBuffer g;
  std::shared_ptr<const DecodedInput> input;
};

// read_gbuffer, keeping the parts' headers and, with `keep_pixels` (passthrough), every part's
// pixels in their own formats; the G-buffer is then converted from those, the file being
// decoded once. Without `report`, what is wrong with the frame (non-finite values, no
// surfaces) is not warned about: a frame read again later is warned about then.
InputFrame read_input_frame(const SequenceInfo& sequence, int frame, RoleMask roles,
                            const InputOptions& options, const ColorManagement* color,
                            bool keep_pixels, bool report = true);

// The G-buffer of `roles` again from an input whose pixels were kept, without the file: the
// same planes read_input_frame gave.
GBuffer gbuffer_from_input(const SequenceInfo& sequence, int frame, RoleMask roles,
                           const InputOptions& options, const ColorManagement* color,
                           const DecodedInput& input);

// write_frame from the input as read: its header, and with passthrough its kept pixels.
void write_frame(const std::string& path, const GBuffer& frame,
                 const std::vector<OutputLayer>& layers, const WriteOptions& options,
                 const DecodedInput& input);

}  // namespace ssgi::detail
