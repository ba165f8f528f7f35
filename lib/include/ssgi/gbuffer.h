// A frame as the stages see it: the renderer-independent G-buffer they read, and the layers
// they make.
#pragma once

#include <cmath>
#include <cstddef>
#include <string>

#include "ssgi/camera.h"
#include "ssgi/image.h"

namespace ssgi {

// One frame's inputs in the library's conventions, as the reader converts them or a program makes
// them. Every image covers the data window; one with no channels is a pass absent or unused.
struct GBuffer {
  std::string path;  // the file it was read from
  int frame = 0;
  Box2i display_window;
  Box2i data_window;
  Camera camera;
  // The normal pass, the space it was read in and why, e.g. "ViewLayer.Normal in world space, as
  // the blender layout says"; empty when the normals are not read from a pass.
  std::string normals_source;

  Image depth;        // 1: planar camera-space z; +inf where there is no surface
  Image normal;       // 3: unit camera-space normal; 0 where there is no surface
  Image albedo;       // 3: diffuse albedo
  Image direct;       // 3: direct light the surface reflects (albedo included)
  Image emission;     // 3 or absent
  Image motion_prev;  // 2 or absent: display pixels, +y down, to the point in frame - 1
  Image motion_next;  // 2 or absent: the same to frame + 1
  Image beauty;       // 4 or absent: the renderer's composite, alpha in channel 3
  // 3 or absent: the renderer's diffuse indirect light as FrameResult::indirect is, without
  // albedo (a guide's, read only where asked for); a pass that includes the albedo is divided
  // by it, and is 0 where the albedo is.
  Image indirect;
  std::size_t sanitized = 0;  // NaN or infinite values of the colour and normal passes, read as 0

  int width() const { return data_window.width(); }
  int height() const { return data_window.height(); }
  // True where the pixel (data-window coordinates) shows a surface.
  bool is_surface(int x, int y) const { return std::isfinite(depth.at(0, x, y)); }
  std::size_t bytes() const {
    return depth.bytes() + normal.bytes() + albedo.bytes() + direct.bytes() + emission.bytes() +
           motion_prev.bytes() + motion_next.bytes() + beauty.bytes() + indirect.bytes();
  }
};

// One frame's results, each covering the data window.
struct FrameResult {
  Image indirect;   // 3: diffuse indirect light without albedo (Cycles' DiffInd)
  Image gi;         // 3: albedo x indirect
  Image composite;  // 4: direct + emission + gi on surfaces, the input beauty elsewhere
  // 1: the share of the indirect light traced rays brought (1) rather than the miss model (0);
  // 0 on background. Empty when the caller gave none to composite().
  Image coverage;
};

}  // namespace ssgi
