// Image-sequence patterns and frame lists in the manner of oiiotool.
#pragma once

#include <string>
#include <vector>

namespace ssgi {

// A file name with an optional frame-number field: `shot.####.exr`, `shot.#.exr` (one `#` is
// four digits, as in oiiotool), `shot.@@@.exr` (one digit per `@`), `shot.%04d.exr`, or a
// plain file name with no field (a single frame). A range inside the name, as in
// `shot.1-50#.exr`, is taken out by parse_sequence_pattern().
struct SequencePattern {
  std::string prefix;   // text before the frame field
  std::string suffix;   // text after it
  int padding = 0;      // minimum digits; negative frames are written as '-' + padded |frame|
  bool has_frame_field = false;

  // The file name of `frame` (the pattern itself when it has no frame field).
  std::string path_for(int frame) const;
};

// Parses `pattern`; a frame range in the name (`shot.1-50#.exr`, `shot.1-50x2%04d.exr`) is
// removed from it and returned in `frames_in_name` (left empty when there is none).
// Throws Error(kUsage) on a malformed pattern.
SequencePattern parse_sequence_pattern(const std::string& pattern,
                                       std::vector<int>* frames_in_name = nullptr);

// Parses a frame list: `7`, `1-50`, `1-50x2`, `50-1` (descending), `-5--1`, and comma lists of
// these. Keeps the order given, drops repeats. Throws Error(kUsage) when malformed.
std::vector<int> parse_frame_list(const std::string& spec);

// The frames for which a file matching `pattern` exists on disk, ascending. Only file names
// whose frame field parses as an integer with at least `padding` digits match.
std::vector<int> find_frames_on_disk(const SequencePattern& pattern);

}  // namespace ssgi
