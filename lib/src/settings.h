// The settings as text: each enum's names and the presets' as the options take them, and the
// settings named as the options are, for `ssgi info`, --stats and the output's provenance.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ssgi/settings.h"

namespace ssgi {

// Each setting's names as the options take them and the output's provenance prints them: one
// table per enum, which parsing, --help and the settings' text all read.
template <typename E>
struct EnumName {
  E value;
  const char* name;
};
inline constexpr EnumName<Tracer> kTracerNames[] = {{Tracer::kSlices, "slices"},
                                                    {Tracer::kScreenSpace, "march"},
                                                    {Tracer::kReference, "reference"}};
inline constexpr EnumName<MissMode> kMissModeNames[] = {{MissMode::kAuto, "auto"},
                                                        {MissMode::kEnvironment, "env"},
                                                        {MissMode::kExtend, "extend"},
                                                        {MissMode::kFrame, "frame"}};
inline constexpr EnumName<DenoiseMode> kDenoiseModeNames[] = {{DenoiseMode::kNone, "none"},
                                                              {DenoiseMode::kPyramid, "pyramid"}};
inline constexpr EnumName<TemporalMode> kTemporalModeNames[] = {
    {TemporalMode::kNone, "none"}, {TemporalMode::kEma, "ema"}, {TemporalMode::kWindow, "window"}};

// `value`'s name in `table` ("?" for a value the table lacks).
template <typename E, std::size_t N>
constexpr const char* enum_name(const EnumName<E> (&table)[N], E value) {
  for (const EnumName<E>& row : table)
    if (row.value == value) return row.name;
  return "?";
}

// The value named `name` in `table`, if any.
template <typename E, std::size_t N>
constexpr std::optional<E> enum_value(const EnumName<E> (&table)[N], std::string_view name) {
  for (const EnumName<E>& row : table)
    if (name == row.name) return row.value;
  return std::nullopt;
}

// The config `settings` names: its `config`, else $OCIO, else "" (none).
std::string color_config_path(const ColorSettings& settings);

// The names of the presets (--preset), in order of cost.
const std::vector<std::string>& preset_names();

// GiSettings::multiframe as --multiframe takes it: "off", "on" (kMultiframeWindow), "on:K".
std::string multiframe_text(int multiframe);

// The --miss spelling of a miss mode ("auto", "env", "frame", "extend").
const char* miss_mode_name(MissMode mode);

// --temporal as the options take it: "none", "ema:0.1", "window:2".
std::string temporal_text(const GiSettings& settings);

// Every setting that decides the result, as (name, value) pairs named as the options are,
// for `ssgi info`, --stats and the output's provenance.
std::vector<std::pair<std::string, std::string>> describe_settings(const GiSettings& settings);

}  // namespace ssgi
