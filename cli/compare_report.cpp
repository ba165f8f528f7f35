// The report of `ssgi compare`: idiff's text, line for line, with ssgi's metrics, or the JSON
// document of --json.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "compare/compare.h"
#include "compare/idiff.h"
#include "compare_command.h"
#include "ssgi/error.h"

namespace ssgi_cli {
namespace {

using Json = nlohmann::ordered_json;

std::string error_text(const ssgi::Error& e) {
  return e.file().empty() ? e.what() : e.file() + ": " + e.what();
}

const char* idiff_word(ssgi::CompareStatus status) {
  switch (status) {
    case ssgi::CompareStatus::kOk:
      return "PASS";
    case ssgi::CompareStatus::kWarn:
      return "WARNING";
    case ssgi::CompareStatus::kFail:
      return "FAILURE";
  }
  return "?";
}

// A double as fmt's "{:g}" (printf's %g) prints it, NaN as "nan" whatever its sign.
std::string g_format(double v) {
  if (std::isnan(v)) return "nan";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// A float as fmt's "{}" prints it (as idiff does thresholds and pixel values): the shortest
// digits that read back as the same float, in fixed notation when the decimal exponent is in
// [-4, 16), else as 1.5e-05.
std::string shortest_format(float v) {
  if (std::isnan(v)) return std::signbit(v) ? "-nan" : "nan";
  if (std::isinf(v)) return v < 0 ? "-inf" : "inf";
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  const std::string sci(buf, end);  // -d.ddde+XX
  const std::size_t e_pos = sci.find('e');
  const bool negative = sci[0] == '-';
  std::string digits;
  for (std::size_t i = negative ? 1 : 0; i < e_pos; ++i)
    if (sci[i] != '.') digits += sci[i];
  const int exp = std::atoi(sci.c_str() + e_pos + 1);
  std::string out = negative ? "-" : "";
  const int n = static_cast<int>(digits.size());
  if (exp < -4 || exp >= 16) {
    out += digits.substr(0, 1);
    if (n > 1) out += "." + digits.substr(1);
    char e[16];
    std::snprintf(e, sizeof e, "e%c%02d", exp < 0 ? '-' : '+', std::abs(exp));
    return out + e;
  }
  if (exp < 0) return out + "0." + std::string(-exp - 1, '0') + digits;
  if (n <= exp + 1) return out + digits + std::string(exp + 1 - n, '0');
  return out + digits.substr(0, exp + 1) + "." + digits.substr(exp + 1);
}

std::string join_values(const std::vector<float>& values) {
  std::string out;
  for (std::size_t i = 0; i < values.size(); ++i)
    out += (i ? ", " : "") + shortest_format(values[i]);
  return out;
}

std::string metric_text(std::optional<double> v) {
  if (!v) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", *v);
  return buf;
}

// JSON has no infinity: undefined and infinite values are null.
Json json_number(std::optional<double> v) {
  return v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
}

Json layer_json(const CompareArgs& args, const ssgi::LayerStats& layer,
                const ssgi::LayerChannels* channels) {
  Json j;
  j["name"] = layer.name;
  if (channels) {
    j["a_channels"] = channels->a;
    j["b_channels"] = channels->b;
  }
  for (ssgi::Metric m : args.metrics) j[ssgi::metric_name(m)] = json_number(layer.metric(m));
  j["max_error"] = json_number(layer.max_error);
  j["foreground_pixels"] = layer.foreground_pixels;
  j["samples"] = layer.samples;
  j["nonfinite_samples"] = layer.nonfinite_samples;
  j["reference_mean"] = layer.reference_mean;
  j["reference_peak"] =
      json_number(layer.samples ? std::optional(layer.reference_peak) : std::nullopt);
  return j;
}

Json subimage_json(const ssgi::IdiffSubimage& s) {
  const ssgi::IdiffStats& d = s.stats;
  Json j;
  j["subimage"] = s.subimage;
  j["width"] = s.width;
  j["height"] = s.height;
  j["channels"] = s.channels;
  j["pixels"] = s.pixels;
  j["mean_error"] = json_number(d.mean_error);
  j["rms_error"] = json_number(d.rms_error);
  j["psnr"] = json_number(d.psnr);
  j["max_error"] = json_number(d.max_error);
  j["max_error_at"] =
      d.max_error == 0.0 ? Json(nullptr)
                         : Json{{"x", d.max_x},
                                {"y", d.max_y},
                                {"channel", s.max_channel_name.empty() ? Json(d.max_channel)
                                                                       : Json(s.max_channel_name)}};
  j["warn_pixels"] = d.warn_pixels;
  j["fail_pixels"] = d.fail_pixels;
  j["status"] = ssgi::status_name(s.status);
  return j;
}

Json frame_json(const CompareArgs& args, const FrameOutcome& f) {
  Json j;
  j["frame"] = f.job.frame ? Json(*f.job.frame) : Json(nullptr);
  j["a"] = f.job.a;
  j["b"] = f.job.b;
  if (f.error) {
    j["status"] = "error";
    j["error"] = error_text(*f.error);
    return j;
  }
  const ssgi::IdiffFileResult& r = *f.idiff;
  j["status"] = ssgi::status_name(r.status);
  j["a_subimages"] = r.a_subimages;
  j["b_subimages"] = r.b_subimages;
  j["subimages"] = Json::array();
  for (const ssgi::IdiffSubimage& s : r.subimages) j["subimages"].push_back(subimage_json(s));
  if (r.diff_written) j["diff"] = f.job.diff;
  if (f.metrics) {
    const ssgi::FileCompareResult& m = *f.metrics;
    j["depth_channel"] = m.depth_channel.empty() ? Json(nullptr) : Json(m.depth_channel);
    j["layers"] = Json::array();
    for (std::size_t i = 0; i < m.result.layers.size(); ++i)
      j["layers"].push_back(layer_json(args, m.result.layers[i], &m.layers[i]));
    j["overall"] = layer_json(args, m.result.overall, nullptr);
  }
  return j;
}

Json summary_json(const CompareArgs& args, const std::vector<FrameOutcome>& frames,
                  const std::vector<int>& metric_frame, const ssgi::SequenceSummary& s,
                  const std::array<int, 3>& counts, std::optional<int> worst_frame,
                  const char* status) {
  auto frame_of = [&](int index) {
    return index < 0 || !frames[0].job.frame ? Json(nullptr) : Json(metric_frame[index]);
  };
  auto layer_summary = [&](const ssgi::LayerSummary& layer) {
    Json j;
    for (ssgi::Metric m : args.metrics) {
      const ssgi::MetricSummary& ms = layer.metrics[static_cast<int>(m)];
      j[ssgi::metric_name(m)] = {{"mean", json_number(ms.mean)},
                                 {"worst", json_number(ms.worst)},
                                 {"worst_frame", frame_of(ms.worst_index)}};
    }
    return j;
  };
  Json j;
  j["frames"] = frames.size();
  j["ok"] = counts[0];
  j["warn"] = counts[1];
  j["fail"] = counts[2];
  j["error"] = std::count_if(frames.begin(), frames.end(),
                             [](const FrameOutcome& f) { return f.error.has_value(); });
  j["status"] = status;
  j["worst_frame"] = worst_frame && frames[0].job.frame ? Json(*worst_frame) : Json(nullptr);
  if (!args.metrics.empty()) {
    j["layers"] = Json::object();
    for (const ssgi::LayerSummary& layer : s.layers) j["layers"][layer.name] = layer_summary(layer);
    j["overall"] = layer_summary(s.overall);
  }
  return j;
}

}  // namespace

void TextReport::begin(const CompareJob& job) {
  if (!args_.quiet) std::printf("Comparing \"%s\" and \"%s\"\n", job.a.c_str(), job.b.c_str());
  std::fflush(stdout);
}

void TextReport::frame(const FrameOutcome& f) {
  if (f.error) {
    std::printf("  error: %s\n", error_text(*f.error).c_str());
    std::fflush(stdout);
    return;
  }
  const ssgi::IdiffFileResult& r = *f.idiff;
  for (const ssgi::IdiffSubimage& s : r.subimages) {
    if (!args_.verbose && (s.status == ssgi::CompareStatus::kOk || args_.quiet)) continue;
    if (args_.idiff.all_subimages) {
      if (r.a_subimages > 1) std::printf("Subimage %d : ", s.subimage);
      std::printf("%d x %d, %d channels\n", s.width, s.height, s.channels);
    }
    subimage(s);
  }
  if (args_.idiff.all_subimages && r.a_subimages != r.b_subimages && !args_.quiet)
    std::fprintf(stderr, "Images had differing numbers of subimages (%d vs %d)\n", r.a_subimages,
                 r.b_subimages);
  if (!args_.idiff.all_subimages && (r.a_subimages > 1 || r.b_subimages > 1) && !args_.quiet)
    std::printf("Only compared the first subimage (of %d and %d, respectively)\n", r.a_subimages,
                r.b_subimages);
  if (f.metrics && !args_.quiet) {
    for (const ssgi::LayerStats& layer : f.metrics->result.layers) metrics_line(*f.metrics, layer);
    if (f.metrics->result.layers.size() > 1) metrics_line(*f.metrics, f.metrics->result.overall);
  }
  verdict(r.status);
  std::fflush(stdout);
}

void TextReport::summary(const std::vector<FrameOutcome>& frames, const ssgi::SequenceSummary& s,
                         const std::array<int, 3>& counts, std::optional<int> worst_frame,
                         ssgi::CompareStatus status) {
  if (frames.size() < 2 || args_.quiet) {
    if (frames.size() >= 2) verdict(status);
    return;
  }
  if (!args_.metrics.empty()) {
    for (const char* label : {"mean", "worst"}) {
      auto row = [&](const ssgi::LayerSummary& layer) {
        std::printf("ssgi %s over the frames, %s:", label, layer.name.c_str());
        for (ssgi::Metric m : args_.metrics) {
          const ssgi::MetricSummary& ms = layer.metrics[static_cast<int>(m)];
          std::printf(" %s %s", ssgi::metric_name(m),
                      metric_text(label[0] == 'm' ? ms.mean : ms.worst).c_str());
        }
        std::printf("\n");
      };
      for (const ssgi::LayerSummary& layer : s.layers) row(layer);
      if (s.layers.size() > 1) row(s.overall);
    }
  }
  const std::size_t errors = static_cast<std::size_t>(std::count_if(
      frames.begin(), frames.end(), [](const FrameOutcome& f) { return f.error.has_value(); }));
  std::printf("%zu frames: %d PASS, %d WARNING, %d FAILURE, %zu error", frames.size(), counts[0],
              counts[1], counts[2], errors);
  if (worst_frame) std::printf("; worst frame %d", *worst_frame);
  std::printf("\n");
  verdict(status);
}

void TextReport::subimage(const ssgi::IdiffSubimage& s) {
  const ssgi::IdiffStats& d = s.stats;
  std::printf("  Mean error = %s\n", g_format(d.mean_error).c_str());
  std::printf("  RMS error = %s\n", g_format(d.rms_error).c_str());
  std::printf("  Peak SNR = %s\n", g_format(d.psnr).c_str());
  std::printf("  Max error  = %s", g_format(d.max_error).c_str());
  if (d.max_error != 0.0) {
    const std::string channel = s.max_channel_name.empty()
                                    ? "channel " + std::to_string(d.max_channel)
                                    : s.max_channel_name;
    std::printf(" @ (%d, %d, %s)  values are %s vs %s", d.max_x, d.max_y, channel.c_str(),
                join_values(s.a_values).c_str(), join_values(s.b_values).c_str());
  }
  std::printf("\n");
  const double npels = static_cast<double>(s.pixels);
  std::printf("  %zu pixels (%1.3g%%) over %s\n", d.warn_pixels, 100.0 * d.warn_pixels / npels,
              shortest_format(args_.idiff.thresholds.warn).c_str());
  std::printf("  %zu pixels (%1.3g%%) over %s\n", d.fail_pixels, 100.0 * d.fail_pixels / npels,
              shortest_format(args_.idiff.thresholds.fail).c_str());
}

void TextReport::metrics_line(const ssgi::FileCompareResult& r, const ssgi::LayerStats& layer) {
  const std::string pixels = args_.file.all_pixels      ? "all pixels"
                             : !r.depth_channel.empty() ? "surface pixels by " + r.depth_channel
                                                        : "pixels where B is not 0";
  std::printf("  ssgi %s (%zu %s):", layer.name.c_str(), layer.foreground_pixels, pixels.c_str());
  for (ssgi::Metric m : args_.metrics)
    std::printf(" %s %s", ssgi::metric_name(m), metric_text(layer.metric(m)).c_str());
  std::printf("\n");
}

void TextReport::verdict(ssgi::CompareStatus status) {
  if (!args_.quiet)
    std::printf("%s\n", idiff_word(status));
  else if (status == ssgi::CompareStatus::kFail)
    std::fprintf(stderr, "FAILURE\n");
}

std::string json_report(const CompareArgs& args, const std::vector<FrameOutcome>& frames,
                        const std::vector<int>& metric_frame, const ssgi::SequenceSummary& summary,
                        const std::array<int, 3>& counts, std::optional<int> worst_frame,
                        const char* status) {
  Json out;
  out["a"] = args.a;
  out["b"] = args.b;
  const ssgi::IdiffThresholds& t = args.idiff.thresholds;
  out["thresholds"] = {{"fail", t.fail},
                       {"failrelative", t.fail_relative},
                       {"failpercent", t.fail_percent},
                       {"hardfail", json_number(t.hard_fail)},
                       {"allowfailures", t.allow_failures},
                       {"warn", t.warn},
                       {"warnrelative", t.warn_relative},
                       {"warnpercent", t.warn_percent},
                       {"hardwarn", json_number(t.hard_warn)}};
  out["metrics"] = Json::array();
  for (ssgi::Metric m : args.metrics) out["metrics"].push_back(ssgi::metric_name(m));
  out["relmse_epsilon"] = ssgi::kRelMseEpsilon;
  out["frames"] = Json::array();
  for (const FrameOutcome& f : frames) out["frames"].push_back(frame_json(args, f));
  out["summary"] = summary_json(args, frames, metric_frame, summary, counts, worst_frame, status);
  return out.dump(2);
}

}  // namespace ssgi_cli
