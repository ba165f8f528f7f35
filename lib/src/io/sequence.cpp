// Image-sequence patterns and frame lists in the manner of oiiotool.
#include "io/sequence.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numeric>
#include <optional>
#include <string_view>
#include <system_error>
#include <unordered_set>

#include "throw.h"

namespace ssgi {
namespace {

#ifdef _WIN32
constexpr char kPathSeparators[] = "/\\";
#else
constexpr char kPathSeparators[] = "/";
#endif

// No frame needs more; the cap keeps a typo such as `%0999999d` from asking for a huge string.
constexpr int64_t kMaxPadding = 32;

// Far more than any shot; a typo such as `1-2000000000` fails at once instead of allocating
// gigabytes.
constexpr int64_t kMaxFrames = 1'000'000;

// A warning names at most this many gaps: a shot that lacks every other frame still gets a line.
constexpr std::size_t kGapsNamed = 8;

constexpr int64_t kMinFrame = std::numeric_limits<int>::min();
constexpr int64_t kMaxFrame = std::numeric_limits<int>::max();

// One item of a frame list, `first[-last[(x|y)step]]`, as written (not yet range-checked).
struct FrameRange {
  int64_t first = 0;
  int64_t last = 0;
  int64_t step = 1;
  bool complement = false;  // `y`: the frames that the step skips
};

// A frame field in a pattern: the characters [begin, end) and the digits they stand for.
struct FrameField {
  size_t begin = 0;
  size_t end = 0;
  int64_t padding = 0;
};

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

std::string Quote(std::string_view text) { return "\"" + std::string(text) + "\""; }

// Where the file name starts in `path`: the field and the sign rule look at it alone.
size_t FileNameBegin(std::string_view path) {
  const size_t separator = path.find_last_of(kPathSeparators);
  return separator == std::string_view::npos ? 0 : separator + 1;
}

// Reads an optionally negative decimal integer at `*pos` and moves past it. Values beyond int64
// saturate; range checks come later and reject them with a message that names the list.
bool ReadInteger(std::string_view text, size_t* pos, int64_t* value) {
  size_t i = *pos;
  const bool negative = i < text.size() && text[i] == '-';
  if (negative) ++i;
  const size_t digits_begin = i;
  constexpr int64_t kSaturated = int64_t{1} << 40;
  int64_t magnitude = 0;
  for (; i < text.size() && IsDigit(text[i]); ++i) {
    magnitude = std::min(magnitude * 10 + (text[i] - '0'), kSaturated);
  }
  if (i == digits_begin) return false;
  *value = negative ? -magnitude : magnitude;
  *pos = i;
  return true;
}

// Splits `spec` into its comma-separated items; false when it is not a frame list at all.
bool ParseFrameRanges(std::string_view spec, std::vector<FrameRange>* ranges) {
  ranges->clear();
  size_t pos = 0;
  while (true) {
    FrameRange range;
    if (!ReadInteger(spec, &pos, &range.first)) return false;
    range.last = range.first;
    if (pos < spec.size() && spec[pos] == '-') {
      ++pos;
      if (!ReadInteger(spec, &pos, &range.last)) return false;
      if (pos < spec.size() && (spec[pos] == 'x' || spec[pos] == 'y')) {
        range.complement = spec[pos] == 'y';
        ++pos;
        // A negative step parses here so that the range check can say what is wrong with it.
        if (!ReadInteger(spec, &pos, &range.step)) return false;
      }
    }
    ranges->push_back(range);
    if (pos == spec.size()) return true;
    if (spec[pos] != ',') return false;
    ++pos;
  }
}

// Checks the items and expands them in the order given, without repeats. `what` names the list
// at the head of error messages.
std::vector<int> ExpandFrameRanges(const std::vector<FrameRange>& ranges, const std::string& what) {
  int64_t total = 0;
  for (const FrameRange& range : ranges) {
    if (std::min(range.first, range.last) < kMinFrame ||
        std::max(range.first, range.last) > kMaxFrame) {
      throw_usage(what + ": frame numbers must lie in [" + std::to_string(kMinFrame) + ", " +
                  std::to_string(kMaxFrame) + "]");
    }
    if (range.step < 1) throw_usage(what + ": the step after 'x' or 'y' must be 1 or more");
    const int64_t span = std::max(range.last - range.first, range.first - range.last);
    const int64_t on_step = span / range.step + 1;
    total += range.complement ? span + 1 - on_step : on_step;
  }
  if (total > kMaxFrames) {
    throw_usage(what + ": expands to more than " + std::to_string(kMaxFrames) + " frames");
  }

  std::vector<int> frames;
  std::unordered_set<int> seen;
  for (const FrameRange& range : ranges) {
    const int64_t direction = range.last >= range.first ? 1 : -1;
    const int64_t span = (range.last - range.first) * direction;
    const auto add = [&](int64_t n) {
      const int frame = static_cast<int>(range.first + direction * n);
      if (seen.insert(frame).second) frames.push_back(frame);
    };
    if (!range.complement) {
      for (int64_t n = 0; n <= span; n += range.step) add(n);
    } else if (range.step > 1) {  // with step 1 every frame is on the step: nothing is left
      for (int64_t n = 0; n <= span; ++n) {
        if (n % range.step != 0) add(n);
      }
    }
  }
  if (frames.empty()) throw_usage(what + " selects no frames");
  return frames;
}

// The frame fields in the file name of `pattern`, which starts at `name_begin`.
std::vector<FrameField> FindFrameFields(const std::string& pattern, size_t name_begin) {
  std::vector<FrameField> fields;
  size_t i = name_begin;
  while (i < pattern.size()) {
    FrameField field{i, i, 0};
    if (pattern[i] == '#' || pattern[i] == '@') {
      int64_t hashes = 0;
      int64_t ats = 0;
      for (; i < pattern.size() && (pattern[i] == '#' || pattern[i] == '@'); ++i) {
        if (pattern[i] == '#') {
          ++hashes;
        } else {
          ++ats;
        }
      }
      field.padding = (hashes == 1 ? 4 : hashes) + ats;
    } else if (pattern[i] == '%') {
      size_t pos = i + 1;
      while (pos < pattern.size() && IsDigit(pattern[pos])) ++pos;
      if (pos == pattern.size() || pattern[pos] != 'd') {
        ++i;  // a literal '%'
        continue;
      }
      if (pos > i + 1) {
        if (pattern[i + 1] != '0') {
          throw_usage("sequence pattern " + Quote(pattern) + ": " + pattern.substr(i, pos + 1 - i) +
                      " pads with spaces; use %0Nd to pad with zeros");
        }
        size_t width_pos = i + 1;
        ReadInteger(pattern, &width_pos, &field.padding);
      }
      i = pos + 1;
    } else {
      ++i;
      continue;
    }
    field.end = i;
    if (field.padding > kMaxPadding) {
      throw_usage("sequence pattern " + Quote(pattern) + ": frame padding " +
                  std::to_string(field.padding) + " is more than " + std::to_string(kMaxPadding) +
                  " digits");
    }
    fields.push_back(field);
  }
  return fields;
}

// Where the longest frame list that ends at `field_begin` starts (`field_begin` when there is
// none). A '-' opens a list only at the start of the file name or after '.' or '_', where it can
// only be a sign; elsewhere it belongs to the name, as in `shot-1-5#`.
size_t FindFrameListBefore(const std::string& pattern, size_t name_begin, size_t field_begin,
                           std::vector<FrameRange>* ranges) {
  const std::string_view text(pattern);
  for (size_t begin = name_begin; begin < field_begin; ++begin) {
    if (text[begin] == '-' && begin > name_begin && text[begin - 1] != '.' &&
        text[begin - 1] != '_') {
      continue;
    }
    if (ParseFrameRanges(text.substr(begin, field_begin - begin), ranges)) return begin;
  }
  return field_begin;
}

// The text path_for() puts in the field for `frame`.
std::string FormatFrame(int frame, int padding) {
  std::string digits = std::to_string(std::abs(static_cast<int64_t>(frame)));
  if (digits.size() < static_cast<size_t>(padding)) digits.insert(0, padding - digits.size(), '0');
  return frame < 0 ? "-" + digits : digits;
}

// The frame whose file name is `name`, if any. Only the text path_for() writes counts: reading
// `00012` as frame 12 of a `####` field would find a file that the reader, opening `0012`, never
// opens.
std::optional<int> FrameOfFileName(std::string_view name, std::string_view name_prefix,
                                   const SequencePattern& pattern) {
  const std::string_view suffix(pattern.suffix);
  if (name.size() <= name_prefix.size() + suffix.size() ||
      name.substr(0, name_prefix.size()) != name_prefix ||
      name.substr(name.size() - suffix.size()) != suffix) {
    return std::nullopt;
  }
  const std::string_view field =
      name.substr(name_prefix.size(), name.size() - name_prefix.size() - suffix.size());
  size_t pos = 0;
  int64_t frame = 0;
  if (!ReadInteger(field, &pos, &frame) || pos != field.size() || frame < kMinFrame ||
      frame > kMaxFrame) {
    return std::nullopt;
  }
  if (FormatFrame(static_cast<int>(frame), pattern.padding) != field) return std::nullopt;
  return static_cast<int>(frame);
}

}  // namespace

std::string SequencePattern::path_for(int frame) const {
  if (!has_frame_field) return prefix + suffix;
  return prefix + FormatFrame(frame, padding) + suffix;
}

SequencePattern parse_sequence_pattern(const std::string& pattern,
                                       std::vector<int>* frames_in_name) {
  if (frames_in_name != nullptr) frames_in_name->clear();
  if (pattern.empty()) throw_usage("empty sequence pattern");

  const size_t name_begin = FileNameBegin(pattern);
  const std::vector<FrameField> fields = FindFrameFields(pattern, name_begin);
  SequencePattern result;
  if (fields.empty()) {
    result.prefix = pattern;
    return result;
  }
  if (fields.size() > 1) {
    throw_usage("sequence pattern " + Quote(pattern) + " has " + std::to_string(fields.size()) +
                " frame fields; a file name takes one");
  }

  const FrameField& field = fields.front();
  std::vector<FrameRange> ranges;
  const size_t list_begin = FindFrameListBefore(pattern, name_begin, field.begin, &ranges);
  if (list_begin < field.begin) {
    const std::string list = pattern.substr(list_begin, field.begin - list_begin);
    std::vector<int> frames =
        ExpandFrameRanges(ranges, "frame list " + Quote(list) + " in " + Quote(pattern));
    if (frames_in_name != nullptr) *frames_in_name = std::move(frames);
  }
  result.prefix = pattern.substr(0, list_begin);
  result.suffix = pattern.substr(field.end);
  result.padding = static_cast<int>(field.padding);
  result.has_frame_field = true;
  return result;
}

std::vector<int> parse_frame_list(const std::string& spec) {
  std::vector<FrameRange> ranges;
  if (!ParseFrameRanges(spec, &ranges)) {
    throw_usage("bad frame list " + Quote(spec) +
                ": expected items F, F-L, F-LxS or F-LyS separated by commas");
  }
  return ExpandFrameRanges(ranges, "frame list " + Quote(spec));
}

std::vector<int> find_frames_on_disk(const SequencePattern& pattern) {
  namespace fs = std::filesystem;
  if (!pattern.has_frame_field) return {};

  const size_t name_begin = FileNameBegin(pattern.prefix);
  const std::string directory = name_begin == 0 ? "." : pattern.prefix.substr(0, name_begin);
  const std::string_view name_prefix = std::string_view(pattern.prefix).substr(name_begin);

  std::error_code error;
  if (!fs::is_directory(directory, error)) return {};
  std::vector<int> frames;
  for (fs::directory_iterator it(directory, error), end; !error && it != end; it.increment(error)) {
    std::error_code ignored;  // an entry that vanished or cannot be examined is not a frame
    if (!it->is_regular_file(ignored)) continue;
    const std::optional<int> frame =
        FrameOfFileName(it->path().filename().string(), name_prefix, pattern);
    if (frame.has_value()) frames.push_back(*frame);
  }
  if (error) throw_io(directory, "cannot list the directory: " + error.message());
  std::sort(frames.begin(), frames.end());
  return frames;
}

FrameGaps find_frame_gaps(const std::vector<int>& frames_on_disk) {
  FrameGaps result;
  const std::vector<int>& disk = frames_on_disk;
  if (disk.size() < 2) return result;
  int64_t step = 0;
  for (std::size_t i = 1; i < disk.size(); ++i)
    step = std::gcd(step, int64_t{disk[i]} - int64_t{disk[i - 1]});
  result.step = step;
  for (std::size_t i = 1; i < disk.size(); ++i) {
    if (int64_t{disk[i]} - int64_t{disk[i - 1]} > step)
      result.gaps.emplace_back(static_cast<int>(disk[i - 1] + step),
                               static_cast<int>(disk[i] - step));
  }
  return result;
}

std::string frame_gaps_text(const FrameGaps& gaps) {
  std::string text;
  const std::size_t named = std::min(gaps.gaps.size(), kGapsNamed);
  for (std::size_t i = 0; i < named; ++i) {
    const auto [first, last] = gaps.gaps[i];
    if (!text.empty()) text += ", ";
    text += std::to_string(first);
    if (last != first) text += "-" + std::to_string(last);
    if (last != first && gaps.step > 1) text += "x" + std::to_string(gaps.step);
  }
  if (named < gaps.gaps.size())
    text += " and " + std::to_string(gaps.gaps.size() - named) + " more gaps";
  return text;
}

}  // namespace ssgi
