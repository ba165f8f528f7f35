// The frame loop of `ssgi run`.
#include "ssgi/run.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "frame_stages.h"
#include "io/frame_reader.h"
#include "io/frame_writer.h"
#include "io/preview.h"
#include "log.h"
#include "memory.h"
#include "memory_plan.h"
#include "sequence_processor.h"
#include "settings.h"
#include "ssgi/settings.h"
#include "ssgi/version.h"
#include "throw.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

// The path a file has, or would have once written, with symbolic links resolved.
std::string resolved(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(path, ec);
  return ec ? fs::absolute(path).lexically_normal().string() : p.string();
}

// `what` is "output" or "--preview".
void check_outputs(const SequenceInfo& seq, const SequencePattern& out, const std::string& out_spec,
                   const std::string& what) {
  if (!out.has_frame_field && seq.frames.size() > 1)
    throw_usage(what + " '" + out_spec + "' has no frame field (e.g. ####) but " +
                std::to_string(seq.frames.size()) + " frames are to be written");
  std::string extension = fs::path(out_spec).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (what == "--preview")
    detail::check_preview_pattern(out_spec);
  else if (extension != ".exr")
    throw_usage("output '" + out_spec + "' must end in .exr: ssgi writes OpenEXR");
  // Each path resolved once (a shot has thousands of frames), then looked up.
  std::map<std::string, int> inputs;
  for (int g : seq.frames_on_disk) {
    inputs.emplace(resolved(seq.pattern.path_for(g)), g);
    if (seq.context) inputs.emplace(resolved(seq.context->pattern.path_for(g)), g);
    for (const ViewInfo& v : seq.views) inputs.emplace(resolved(v.path_for(g)), g);
  }
  std::set<std::string> directories;
  for (int f : seq.frames) {
    const std::string path = out.path_for(f);
    const auto it = inputs.find(resolved(path));
    if (it != inputs.end())
      throw Error(ErrorKind::kUsage, path,
                  "output would overwrite input frame " + std::to_string(it->second));
    // Fail before any frame is computed, with one line, rather than once per frame.
    const std::string directory = fs::path(path).parent_path().string();
    if (directories.insert(directory).second) make_output_directory(path);
  }
}

// Everything besides the version that decides an output's pixels, as text for its header:
// the GI settings, how the input is read and how the output is written (not which frames:
// chunks of a shot give the same frames). --skip-existing compares it with the run's.
std::string settings_text(const RunOptions& o, const SequenceInfo& seq) {
  std::string text;
  const auto add = [&text](const std::string& name, const std::string& value) {
    text += (text.empty() ? "" : "; ") + name + "=" + value;
  };
  for (const auto& [name, value] : describe_settings(o.gi)) add(name, value);
  add("layout", seq.layout.preset.name);
  for (const std::string& c : o.input.channel_overrides) add("channel", c);
  if (!o.input.depth_kind.empty()) add("depth-kind", o.input.depth_kind);
  add("normals", seq.normals_from_depth ? "depth" : "pass");
  if (o.input.camera.hfov_deg > 0) {
    char fov[32];
    std::snprintf(fov, sizeof fov, "%.17g", o.input.camera.hfov_deg);
    add("fov", fov);
  }
  if (!o.input.camera.sidecar.empty()) add("camera", o.input.camera.sidecar);
  // Which frames the context is, like which frames the input is, is data, not a setting.
  if (seq.context) add("context", "yes");
  // The views are settings: what they show changes the light (which of their frames is read,
  // like the input's, is data).
  for (const ViewInfo& v : seq.views)
    add(v.projection == Projection::kLatLong ? "latlong-view" : "view", v.pattern);
  add("compression", o.write.compression);
  add("datatype", o.write.half ? "half" : "float");
  add("passthrough", o.write.passthrough ? "yes" : "no");
  if (!o.write.layer_prefix.empty()) add("layer-prefix", o.write.layer_prefix);
  return text;
}

// The pipeline's memory under the run's limit; throws Error(kInput) when the estimated peak is
// over the limit. `passes_read_after_composite`: PipelineMemory's.
PipelineMemory check_memory(const RunOptions& o, const SequenceInfo& seq,
                            bool passes_read_after_composite) {
  const MemoryPlan m = plan_run_memory(seq, o.gi, o.write, o.memory_limit, o.frames_in_flight,
                                       passes_read_after_composite);
  const PipelineMemory& memory = m.memory;
  log_info("memory: estimated peak " + memory_size_text(m.estimate.bytes) + " (" +
           m.estimate.parts + "); limit " + memory_limit_text(m.limit));
  if (m.over_limit())
    throw Error(ErrorKind::kInput, seq.pattern.path_for(seq.frames.front()),
                "the run needs an estimated " + memory_size_text(m.estimate.bytes) + " (" +
                    m.estimate.parts + "), over the limit of " + memory_limit_text(m.limit));
  log_info("memory: " + std::to_string(memory.frames_in_flight) + " frame" +
           (memory.frames_in_flight > 1 ? "s" : "") + " in flight" +
           (memory.read_twice ? ", each frame written decoded twice (lit, then finished and "
                                "written) so that the frames waiting for their window's later "
                                "frames hold no passes"
                              : "") +
           " (" + m.reason() + ")");
  if (o.gi.tracer == Tracer::kReference && o.gi.bounces > 1)
    log_info("memory: the reference keeps up to " + memory_size_text(memory.reference_hits_bytes) +
             " of hits for bounces after the first; rows beyond that are traced again");
  return memory;
}

}  // namespace

RunReport run_sequence(const RunOptions& options, const RunCallbacks& callbacks) {
  const SequenceInfo seq = open_sequence(options.input);
  // The frames to write come from the input; a range in an output name would be ignored.
  const auto output_pattern = [&seq](const std::string& spec, const std::string& what) {
    if (spec.empty()) return SequencePattern();
    std::vector<int> frames_in_output;
    const SequencePattern pattern = parse_sequence_pattern(spec, &frames_in_output);
    if (!frames_in_output.empty())
      throw_usage(what + " '" + spec +
                  "' names frames: give the frames with the input pattern or --frames, and the "
                  "output as e.g. out/shot.####.exr");
    check_outputs(seq, pattern, spec, what);
    return pattern;
  };
  // Over the memory limit: refused before the outputs' directories are made.
  // A callback or the preview reads a frame's passes after its composite.
  const PipelineMemory memory =
      check_memory(options, seq, callbacks.on_result || !options.preview.empty());
  const SequencePattern out = output_pattern(options.output, "output");
  const SequencePattern preview = output_pattern(options.preview, "--preview");
  const bool write_exr = !options.output.empty(), write_preview = !options.preview.empty();
  const detail::FrameStages pipeline(seq, options.gi, memory);
  const Plan& plan = pipeline.plan();
  for (const std::string& reason : plan.reasons) log_info("plan: " + reason);
  for (const std::string& warning : plan.warnings) log_warning(warning);

  // What the output's header records of how it was made; --skip-existing reads it back.
  const std::vector<std::pair<std::string, std::string>> made_by = {
      {"ssgi:version", version()}, {"ssgi:settings", settings_text(options, seq)}};
  WriteOptions write = options.write;
  write.provenance.insert(write.provenance.end(), made_by.begin(), made_by.end());
  write.provenance.emplace_back("ssgi:seed", std::to_string(options.gi.seed));
  // OIIO 2.4 neither writes oiio:ColorSpace to an EXR nor reads one back (it says "Linear"),
  // and OCIO 2.1 cannot name a space's primaries for the chromaticities attribute: ssgi's own
  // layers say their space by the config's name in an attribute of ours.
  write.provenance.emplace_back("ssgi:colorspace", pipeline.color().output_space());
  const auto preview_made_by = detail::preview_attributes(made_by, pipeline.color());

  // Which outputs are there already: reused (--skip-existing), or refused (--no-clobber) before
  // anything is computed.
  const int total = static_cast<int>(seq.frames.size());
  std::vector<char> reuse(total, 0);
  if (options.skip_existing || options.no_clobber) {
    std::vector<std::string> in_the_way;
    for (int i = 0; i < total; ++i) {
      // A frame is reused when every file it makes (the EXR, the preview) is.
      bool reusable = options.skip_existing;
      bool any = false;
      for (const bool exr : {true, false}) {
        if (!(exr ? write_exr : write_preview)) continue;
        const std::string path = (exr ? out : preview).path_for(seq.frames[i]);
        std::error_code ec;
        if (!fs::exists(fs::symlink_status(path, ec))) {
          reusable = false;
          continue;
        }
        any = true;
        if (options.no_clobber) in_the_way.push_back(path);
        if (!options.skip_existing) continue;
        const std::string why_not = why_not_reusable(path, exr ? made_by : preview_made_by);
        if (!why_not.empty()) {
          log_info(path + ": exists but is made again: " + why_not);
          reusable = false;
        }
      }
      if (reusable && any) {
        reuse[i] = 1;
        // Whatever is reused is not in the way.
        while (!in_the_way.empty() && (in_the_way.back() == out.path_for(seq.frames[i]) ||
                                       in_the_way.back() == preview.path_for(seq.frames[i])))
          in_the_way.pop_back();
      }
    }
    if (!in_the_way.empty())
      throw Error(ErrorKind::kUsage, in_the_way.front(),
                  "exists" +
                      (in_the_way.size() > 1
                           ? " (as do " + std::to_string(in_the_way.size() - 1) + " more outputs)"
                           : std::string()) +
                      " and --no-clobber does not overwrite" +
                      (options.skip_existing ? " what --skip-existing cannot reuse" : ""));
  }

  if (callbacks.on_start)
    callbacks.on_start(total, static_cast<int>(std::count(reuse.begin(), reuse.end(), 1)));
  detail::SequenceJob job;
  job.sequence = &seq;
  job.input = &options.input;
  job.pipeline = &pipeline;
  job.reuse = reuse;
  job.output_path = [&](int frame) { return write_exr ? out.path_for(frame) : std::string(); };
  job.fail_fast = options.fail_fast;
  job.in_flight = memory.frames_in_flight;
  job.read_twice = memory.read_twice;
  job.write_needs_passes = write_preview;
  job.write = [&](const GBuffer& g, FrameResult& result, const detail::DecodedInput& input) {
    if (write_preview)
      detail::write_preview(preview.path_for(g.frame), g, result.composite, pipeline.color(),
                            preview_made_by);
    if (write_exr) {
      for (Image* layer : {&result.composite, &result.indirect, &result.gi})
        pipeline.color().working_to_output(layer);
      std::vector<OutputLayer> layers = {{"", &result.composite, {"R", "G", "B", "A"}},
                                         {"indirect", &result.indirect, {"R", "G", "B"}},
                                         {"gi", &result.gi, {"R", "G", "B"}}};
      if (!result.coverage.empty()) layers.push_back({"coverage", &result.coverage, {"Y"}});
      detail::write_frame(out.path_for(g.frame), g, layers, write, input);
      write.warn_collisions = false;  // one warning per run is enough
    }
  };
  return detail::process_sequence(job, callbacks);
}

}  // namespace ssgi
