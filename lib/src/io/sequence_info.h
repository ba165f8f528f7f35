// A sequence as the reader finds it on disk: its frames, windows, channels and layout, its
// context and its views; and the roles a run reads, as bits.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/layout.h"
#include "io/sequence.h"
#include "ssgi/camera.h"
#include "ssgi/image.h"

namespace ssgi {

// A set of roles, as bits (1u << Role).
using RoleMask = unsigned;
constexpr RoleMask role_bit(Role role) { return 1u << static_cast<int>(role); }

struct SequenceInfo;

// An extra view as probed from its first file.
struct ViewInfo {
  std::string pattern;  // as given
  Projection projection = Projection::kPinhole;
  bool still = false;  // one file for every frame
  // Its files as a sequence of their own (its windows, channels and layout; its frames those
  // on disk). For a still, the pattern is the file name itself.
  std::shared_ptr<const SequenceInfo> sequence;
  // The file frame `frame` of the shot reads.
  std::string path_for(int frame) const;
};

// A guide (--guide, io/guide.h) as probed from its first file: a few-sample render of the shot
// carrying the renderer's diffuse indirect light.
struct GuideInfo {
  std::string pattern;  // as given
  // Its files as a sequence of their own (its windows, channels and layout).
  std::shared_ptr<const SequenceInfo> sequence;
  int fraction = 1;  // the shot's resolution over the guide's, each axis: 1, 2, 3, ...
};

// A sequence as found on disk, probed from its first frame.
struct SequenceInfo {
  SequencePattern pattern;
  std::vector<int> frames;          // the frames to write, in order, all present on disk
  std::vector<int> frames_on_disk;  // every frame the pattern matches, ascending
  Box2i display_window;             // of the first frame, absolute EXR coordinates
  Box2i data_window;
  FileChannels channels;  // of the first frame
  Layout layout;          // resolved against the first frame
  double pixel_aspect = 1.0;
  // The first frame's largest chunk in rows: what the file decodes at once (a tile's height, or
  // its compression's block of scanlines), which the reader and the writer's strips hold whole.
  int chunk_rows = 1;
  bool normals_from_depth = false;  // --normals: the reader derives normals from depth
  // --context: the context's frames as probed from their first (its frames those of this
  // sequence); the G-buffers read cover its data window. Null without --context.
  std::shared_ptr<const SequenceInfo> context;
  // --view, --latlong-view: the extra views, in the order given.
  std::vector<ViewInfo> views;
  // --guide: null without one.
  std::shared_ptr<const GuideInfo> guide;

  // The window the G-buffers read cover: the context's data window, else the data window.
  const Box2i& working_window() const { return context ? context->data_window : data_window; }
};

}  // namespace ssgi
