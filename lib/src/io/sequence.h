// Image-sequence patterns and frame lists in the manner of oiiotool.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace ssgi {

// A file name with an optional frame-number field. The field is looked for in the last path
// component only: a `#`, `@` or `%` in a directory name is plain text (as in Blender), since
// `user@host` or `take#2` directories exist. The field is one of:
//   - a run of `#` and `@`: a lone `#` is four digits (oiiotool), otherwise each `#` and each
//     `@` is one digit (`####` and `@@@@` are four digits, as Nuke and Blender users write
//     them); a lone `#` with `@`s adds up as in oiiotool (`#@@` is six digits);
//   - `%0Nd` (N digits) or `%d` (no padding), as in printf.
// A `%` that does not start such a field is plain text. A file name holds at most one field.
struct SequencePattern {
  std::string prefix;  // text before the frame field (the whole pattern when there is none)
  std::string suffix;  // text after it
  int padding = 0;     // minimum digits; negative frames are written as '-' + padded |frame|
  bool has_frame_field = false;

  // The file name of `frame` (the pattern itself when it has no frame field); frame -5 in a
  // four-digit field is `-0005`, as Blender writes it (printf's `%04d` would give `-005`).
  std::string path_for(int frame) const;
};

// Parses `pattern`. The longest frame list (the syntax of parse_frame_list()) that ends right
// before the field is removed from the name and returned in `frames_in_name`, which is left
// empty when there is none: `shot.1-50x2####.exr` is `shot.####.exr` with frames 1, 3, ..., 49.
// As in oiiotool, digits right before the field are such a list (`take2#.exr` is frame 2 of
// `take#.exr`). A list starts with a minus sign only at the start of the file name or after `.`
// or `_`: `shot.-5--1#.exr` is frames -5 to -1, while `shot-1-5#.exr` is frames 1 to 5 of
// `shot-#.exr`. Throws Error(kUsage) on an empty pattern, two frame fields, `%4d` (space
// padding), padding over 32 digits, or a frame list that parses but is invalid (`1-5x0#`).
SequencePattern parse_sequence_pattern(const std::string& pattern,
                                       std::vector<int>* frames_in_name = nullptr);

// Parses a frame list: comma-separated items `F`, `F-L` (descending when L < F), `F-LxS` (every
// S-th frame from F) and `F-LyS` (the frames that `F-LxS` skips, as in oiiotool); frames may be
// negative (`-5--1`, `-3-2`). Keeps the order given and drops repeats. Throws Error(kUsage),
// naming the list, when it is malformed, has a step below 1 or a frame outside `int`, expands to
// more than a million frames, or selects none.
std::vector<int> parse_frame_list(const std::string& spec);

// The frames for which a regular file named path_for(frame) exists, ascending. Only names that
// path_for() would write match, so that what is found is what the reader opens: a four-digit
// field matches `0012` and `12345` but not `00012`, `012` or `-005`. Empty for a pattern without
// a frame field and for a directory that does not exist; throws Error(kIO) when the directory
// cannot be read.
std::vector<int> find_frames_on_disk(const SequencePattern& pattern);

// The frames a shot lacks between its first and last frames on disk. The shot's step is the
// greatest common divisor of the differences between its frames (2 for a shot rendered on twos,
// 1 when it has fewer than two frames); a gap is a run of frames on that step, between two
// frames on disk, of which none is there. The temporal stage ends the shot at a gap as at its
// first and last frames.
struct FrameGaps {
  int64_t step = 1;
  std::vector<std::pair<int, int>> gaps;  // the first and last frame missing in each, ascending
};

// The gaps of `frames_on_disk` (ascending, without repeats: find_frames_on_disk's result).
FrameGaps find_frame_gaps(const std::vector<int>& frames_on_disk);

// The missing frames of `gaps` as a frame list: "3, 7-9" (with step 2, "7, 13-17x2"). A long one
// names the first gaps and counts the others.
std::string frame_gaps_text(const FrameGaps& gaps);

}  // namespace ssgi
