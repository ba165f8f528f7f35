// A run's memory limit, from --max-memory or the scheduler, and the estimate of its peak.
#include "memory.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>
#include <vector>

#include "io/oiio_files.h"
#include "io/views.h"
#include "reference/reference.h"
#include "throw.h"

namespace ssgi {
namespace {

constexpr std::uint64_t kMiB = std::uint64_t{1} << 20;

// Larger than any machine: cgroup v1 writes 2^63 rounded down to a page for "no limit".
constexpr std::uint64_t kUnlimited = std::uint64_t{1} << 60;

// A whole number of bytes from a cgroup file ("max" or unreadable: 0).
std::uint64_t cgroup_bytes(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return 0;
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno != 0 || *end != '\0' || v == 0 || v >= kUnlimited) return 0;
  return v;
}

// A positive whole number from the environment, else 0.
std::uint64_t positive_env(const MemoryLimitSources& sources, const char* name) {
  const char* text = sources.getenv(name);
  if (text == nullptr || *text == '\0') return 0;
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text, &end, 10);
  // Slurm may append a unit letter to memory values in some versions ("4000M").
  std::uint64_t scale = 1;
  if (*end == 'M' || *end == 'm')
    ++end;
  else if (*end == 'G' || *end == 'g')
    scale = 1024, ++end;
  return errno == 0 && *end == '\0' && v > 0 && v < kUnlimited / kMiB ? v * scale : 0;
}

// The smaller of two limits, 0 meaning none.
void keep_smaller(MemoryLimit* best, std::uint64_t bytes, const std::string& source) {
  if (bytes == 0) return;
  if (best->bytes == 0 || bytes < best->bytes) *best = {bytes, source};
}

// This process's cgroup path from /proc/self/cgroup: the v2 line "0::/path", or for v1 the
// line of the memory controller "N:...memory...:/path". Empty when not found.
std::string own_cgroup(const std::string& self_cgroup, bool v2) {
  std::ifstream in(self_cgroup);
  std::string line;
  while (std::getline(in, line)) {
    const auto a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1);
    const bool match = v2 ? line.compare(0, a, "0") == 0 && controllers.empty()
                          : ("," + controllers + ",").find(",memory,") != std::string::npos;
    if (match) return line.substr(b + 1);
  }
  return {};
}

// The limit in `file_name` of the cgroup `path` under `root` and of each of its ancestors up to
// the root (the smallest holds). The root is looked at also when /proc/self/cgroup names no
// cgroup: inside a container the namespace's root is the container's cgroup.
void limits_up_the_tree(const std::string& root, std::string path, const char* file_name,
                        const std::string& kind, MemoryLimit* best) {
  while (!path.empty() && path.back() == '/') path.pop_back();
  while (true) {
    const std::string file = root + path + "/" + file_name;
    keep_smaller(best, cgroup_bytes(file), kind + " " + file_name + " (" + file + ")");
    if (path.empty()) break;
    const auto slash = path.find_last_of('/');
    path.resize(slash == std::string::npos ? 0 : slash);
  }
}

void cgroup_limits(const MemoryLimitSources& sources, MemoryLimit* best) {
  limits_up_the_tree(sources.cgroup_root, own_cgroup(sources.self_cgroup, true), "memory.max",
                     "cgroup v2", best);
  limits_up_the_tree(sources.cgroup_root + "/memory", own_cgroup(sources.self_cgroup, false),
                     "memory.limit_in_bytes", "cgroup v1", best);
}

// Bytes of `planes` float planes of `pixels`.
std::uint64_t planes(double count, std::uint64_t pixels) {
  return static_cast<std::uint64_t>(std::ceil(count * 4.0 * static_cast<double>(pixels)));
}

}  // namespace

std::uint64_t parse_memory_size(const std::string& text) {
  const auto bad = [&]() {
    throw_usage("--max-memory: '" + text + "' is not a size (e.g. 500M, 2G or bytes)");
  };
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno != 0 || end == text.c_str() || !std::isfinite(v) || !(v > 0) || text[0] == '-' ||
      text[0] == '+' || !std::isdigit(static_cast<unsigned char>(text[0])))
    bad();
  std::string unit(end);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (!unit.empty() && unit.back() == 'B') unit.pop_back();     // "MB", "B"
  if (unit.size() == 2 && unit.back() == 'I') unit.pop_back();  // "MiB"
  const std::string units = "KMGT";
  if (unit.size() > 1 || (unit.size() == 1 && units.find(unit[0]) == std::string::npos)) bad();
  double scale = 1;
  if (unit.size() == 1)
    for (std::size_t k = 0; k <= units.find(unit[0]); ++k) scale *= 1024;
  const double bytes = v * scale;
  if (bytes < 1 || bytes >= static_cast<double>(kUnlimited)) bad();
  return static_cast<std::uint64_t>(bytes);
}

std::string memory_size_text(std::uint64_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) v /= 1024, ++u;
  char text[32];
  if (u == 0 || v >= 100)
    std::snprintf(text, sizeof text, "%.0f %s", v, units[u]);
  else
    std::snprintf(text, sizeof text, "%.3g %s", v, units[u]);
  return text;
}

MemoryLimit scheduler_memory_limit(const MemoryLimitSources& sources) {
  MemoryLimit best;
  if (const std::uint64_t node = positive_env(sources, "SLURM_MEM_PER_NODE"))
    keep_smaller(&best, node * kMiB, "SLURM_MEM_PER_NODE");
  if (const std::uint64_t per_cpu = positive_env(sources, "SLURM_MEM_PER_CPU")) {
    const char* cpus_text = sources.getenv("SLURM_CPUS_PER_TASK");
    const long cpus = cpus_text ? std::max(1L, std::atol(cpus_text)) : 1L;
    keep_smaller(&best, per_cpu * kMiB * static_cast<std::uint64_t>(cpus),
                 "SLURM_MEM_PER_CPU x " + std::to_string(cpus) + " CPUs");
  }
  cgroup_limits(sources, &best);
  return best;
}

MemoryEstimate estimate_run_memory(const SequenceInfo& seq, const Plan& plan, const GiSettings& s,
                                   const WriteOptions& write, int threads,
                                   const PipelineMemory& memory) {
  const int w = seq.working_window().width(), h = seq.working_window().height();
  const std::uint64_t pixels = static_cast<std::uint64_t>(w) * h;
  const int scale = std::max(1, plan.trace_scale);
  const std::uint64_t grid = static_cast<std::uint64_t>((w + scale - 1) / scale) *
                             static_cast<std::uint64_t>((h + scale - 1) / scale);
  threads = std::max(1, threads);

  // A frame as read: the planes of the roles the plan reads (motion both ways) and the strip
  // of rows the reader decodes at a time (16 MB). Read twice, the first reading has what
  // tracing needs (no beauty, emission only when gathered), the second what finishing needs (no
  // motion); a frame is the larger.
  const auto role_planes = [&](RoleMask roles) {
    double n = 0;
    for (int r = 0; r < kRoleCount; ++r) {
      const Role role = static_cast<Role>(r);
      if (!(roles & role_bit(role))) continue;
      n += role == Role::kMotion ? 4 : static_cast<double>(seq.layout.channels(role).size());
    }
    return n;
  };
  const bool read_twice = memory.read_twice && plan.temporal == TemporalMode::kWindow;
  const double read = role_planes(plan.roles);
  const double motion = (plan.roles & role_bit(Role::kMotion)) ? 4 : 0;
  // Whole chunks of the input's, about 16 MB (detail::strip_rows): a file with tall chunks
  // (DWA's 256 scanlines, tall tiles) takes more.
  std::uint64_t input_bytes = 0;  // a pixel of every channel of the input, 4 bytes each at most
  for (const auto& c : seq.channels.channels) input_bytes += 4 * c.size();
  const int own_width = seq.data_window.width(), own_height = seq.data_window.height();
  const auto strip_of = [&](std::uint64_t pixel_bytes, int chunk) {
    const std::uint64_t row = pixel_bytes * static_cast<std::uint64_t>(own_width);
    return row * static_cast<std::uint64_t>(detail::strip_rows(row, chunk, own_height));
  };
  const std::uint64_t strip = strip_of(input_bytes, seq.chunk_rows);
  RoleMask lit_roles = plan.roles;
  if (read_twice) {
    lit_roles &= ~role_bit(Role::kBeauty);
    if (!plan.gather_emission) lit_roles &= ~role_bit(Role::kEmission);
  }
  const std::uint64_t frame = planes(role_planes(lit_roles), pixels) + strip;
  // The temporal ring: every frame of the window on the trace grid (its light, coverage, depth,
  // normal and motion: 12 planes; in the window its misses' shares and reflected light, 6
  // more, and the levelled light of each while the centre is filtered, 3), and the frames
  // waiting for their window's later frames with their passes (without motion), unless they are
  // read twice.
  const std::uint64_t frame_grid = planes(plan.temporal == TemporalMode::kWindow ? 21 : 12, grid);
  std::uint64_t ring_frames = 1, waiting = 0;
  if (plan.temporal == TemporalMode::kWindow) {
    ring_frames = 2 * s.temporal_radius + 1;
    waiting = read_twice ? 0 : s.temporal_radius;
  }
  if (plan.temporal == TemporalMode::kEma) ring_frames = 2;
  const std::uint64_t ring = ring_frames * frame_grid + waiting * planes(read - motion, pixels);

  // Tracing: the trace grid (10 planes and origins), the tracer's hits, then the bounces'
  // light (4 + 3 + 3 planes).
  std::uint64_t tracer = 0;
  switch (s.tracer) {
    case Tracer::kSlices:  // at most 32 sectors a slice, each hit 8 bytes, and 20 per sample
      tracer = grid * (static_cast<std::uint64_t>(s.slices) * 32 * 8 + 20);
      break;
    case Tracer::kScreenSpace:  // every ray's end (4), then as weighted hits (8)
      tracer = pixels * (static_cast<std::uint64_t>(s.rays) * 12 + 20);
      break;
    case Tracer::kReference: {
      // The Embree scene: vertices, faces (kept while the BVH is built) and the BVH itself,
      // bounded at 400 bytes a pixel (tests/bench/memory.sh); the kept hits; per worker a
      // row of hits being traced again.
      const std::uint64_t row = detail::ReferenceHits::row_bytes(w, s.rays);
      const std::uint64_t kept =
          s.bounces > 1 ? std::min<std::uint64_t>(memory.reference_hits_bytes / row, h) * row : 0;
      tracer = pixels * (400 + 16) + kept + static_cast<std::uint64_t>(threads) * 2 * row;
      break;
    }
  }
  const std::uint64_t tracing = planes(11, grid) + tracer + planes(10, grid);
  // Multiframe: every frame of the ring keeps its trace grid (11 planes and origins); the
  // frames not yet finished their hits too (as the tracer's) and their missed rays (8 groups of
  // sectors a slice, 16 bytes each, and a 12-byte origin and 4-byte start per sample); while a
  // frame is continued, each frame's view of it (its mesh, 5 bytes, and the light its hits
  // bring, 24 a sample) and the frame's miss shares, environment and found light (13 planes).
  std::uint64_t multiframe = 0;
  if (plan.multiframe > 0) {
    const std::uint64_t own = tracer + grid * (static_cast<std::uint64_t>(s.slices) * 8 * 16 + 16);
    // The frames lit and not yet finished: the window's later half and its centre, read twice
    // or not.
    const std::uint64_t unfinished =
        plan.temporal == TemporalMode::kWindow ? s.temporal_radius + 1 : 1;
    multiframe =
        ring_frames * (planes(12, grid) + grid * (5 + 24)) + unfinished * own + planes(13, grid);
  }
  // Views (--view): while a frame is lit, its views' G-buffers (13 planes) and each view's
  // trace (its grid, 11 planes; its hits and missed rays, as a frame's own; its mesh and the light
  // its hits bring, 29 bytes a sample, and its light, 3 planes) at the plan's trace scale; the
  // frame's own missed rays, kept for them, as multiframe's; and the views read ahead for the
  // frames in flight. A lat-long is six faces a quarter of its width square.
  std::uint64_t views = 0;
  if (plan.views) {
    std::uint64_t view_pixels = 0;
    for (const ViewInfo& v : seq.views) {
      const std::uint64_t vw = v.sequence->data_window.width(),
                          vh = v.sequence->data_window.height();
      const std::uint64_t face = detail::latlong_face_size(v.sequence->display_window);
      view_pixels += v.projection == Projection::kLatLong ? 6 * face * face : vw * vh;
    }
    const std::uint64_t view_grid = view_pixels / (static_cast<std::uint64_t>(scale) * scale) + 1;
    const std::uint64_t missed = static_cast<std::uint64_t>(s.slices) * 8 * 16 + 16;
    const std::uint64_t read_views = planes(13, view_pixels);
    const std::uint64_t lit_views =
        planes(14, view_grid) + view_grid * (s.slices * 32 * 8 + 20 + missed + 29);
    views = std::clamp(memory.frames_in_flight, 1, 3) * read_views + lit_views +
            (plan.multiframe > 0 ? 0 : grid * missed);
  }
  // The denoiser's pyramid and guides at full resolution when the light enters it there; from
  // a coarser trace grid, only the depths whole, the coarser levels (a third of a plane per
  // plane of the half-resolution level's 6 guides and light) and the light upsampled (the
  // last two levels' 3 planes each, the last the frame's light): 9 planes. Beside them the
  // coverage (1), and the composite's gi and composite (7) unless they are written over the
  // passes' albedo and beauty (composite_frame_in_place).
  // Without the denoiser on the full-resolution grid, the light alone (3).
  const std::uint64_t denoise =
      scale > 1 ? planes(9, pixels) : planes(plan.denoise ? 24 : 3, pixels);
  const bool over_passes = !memory.passes_read_after_composite && seq.layout.has(Role::kBeauty);
  const std::uint64_t composite = planes(over_passes ? 1 : 8, pixels);
  // The writer encodes strips of rows of ours (11 channels, 4 bytes each at most) and the
  // passed-through channels, which it reads from the input's file a strip at a time; strips of
  // whole chunks of both files.
  const int out_chunk = std::lcm(detail::scanlines_per_chunk(write.compression), seq.chunk_rows);
  const std::uint64_t writer = strip_of(44 + (write.passthrough ? input_bytes : 0), out_chunk) +
                               (write.passthrough ? strip_of(input_bytes, out_chunk) : 0);
  // A frame's phases, one after the other: lit (read, traced), finished (its passes, the
  // denoiser's upsampling, the composite), written (the four layers, 11 planes, and the strips).
  // A frame being finished holds its passes: in the window without motion (read again, or kept
  // since it was lit), else as read.
  const std::uint64_t finishing_passes =
      planes(plan.temporal == TemporalMode::kWindow ? read - motion : read, pixels);
  const std::uint64_t lighting = frame + tracing + views;
  const std::uint64_t finishing = finishing_passes + denoise + composite;
  // With a callback or the preview the passes stay until the frame is written.
  const std::uint64_t writing =
      planes(11, pixels) + writer + (memory.passes_read_after_composite ? finishing_passes : 0);
  // What a phase frees goes back before the next (ssgi's own allocator is told so:
  // cli/fast_malloc.h), so the phases' peaks do not add up.
  const std::uint64_t phases = std::max({lighting, finishing, writing});
  // Overlapping, the next frame is read while one is lit and the last written (its layers).
  const int in_flight = std::clamp(memory.frames_in_flight, 1, 3);
  // Read twice, the frame read ahead may be a second reading, of the passes without motion.
  const std::uint64_t ahead = read_twice ? std::max(frame, finishing_passes + strip) : frame;
  const std::uint64_t overlap = (in_flight >= 2 ? ahead : 0) + (in_flight >= 3 ? writing : 0);
  // The program, its libraries (OIIO's plugins, OCIO) and the allocator's pools, and per worker
  // its stack and buffers: sized from the peak of runs on a frame too small to weigh
  // (tests/bench/README.md, "The memory estimate").
  const std::uint64_t program = 140 * kMiB + static_cast<std::uint64_t>(threads) * 4 * kMiB;

  MemoryEstimate e;
  // What multiframe keeps of the ring's frames stays through every phase.
  e.bytes = program + ring + multiframe + phases + overlap;
  e.parts =
      "frames " + memory_size_text(ring) + " (" + std::to_string(ring_frames) + " in the ring, " +
      (read_twice ? std::string("read twice") : std::to_string(waiting) + " waiting") + ")" +
      (multiframe ? ", multiframe " + memory_size_text(multiframe) : std::string()) + ", lit " +
      memory_size_text(lighting) + " (read " + memory_size_text(frame) + ", tracing " +
      memory_size_text(tracing) + (views ? ", views " + memory_size_text(views) : std::string()) +
      "), finished " + memory_size_text(finishing) + ", written " + memory_size_text(writing) +
      ", " +
      (in_flight > 1 ? std::to_string(in_flight - 1) + " more frame" + (in_flight > 2 ? "s" : "") +
                           " in flight " + memory_size_text(overlap) + ", "
                     : std::string()) +
      "program " + memory_size_text(program);
  return e;
}

PipelineMemory pipeline_memory_within(const MemoryLimit& limit, const SequenceInfo& seq,
                                      const Plan& plan, const GiSettings& s,
                                      const WriteOptions& write, int threads, int frames_in_flight,
                                      bool passes_read_after_composite) {
  PipelineMemory memory;
  memory.passes_read_after_composite = passes_read_after_composite;
  const bool asked = frames_in_flight > 0;
  memory.frames_in_flight = asked ? std::clamp(frames_in_flight, 1, 3) : 2;
  const bool window = plan.temporal == TemporalMode::kWindow;
  if (limit.bytes == 0) {
    if (!asked) {
      memory.frames_in_flight = 1;
      memory.read_twice = window;
    }
    return memory;
  }
  const int most = memory.frames_in_flight;
  const auto fits = [&] {
    return estimate_run_memory(seq, plan, s, write, threads, memory).bytes <= limit.bytes;
  };
  // Less overlap before fewer kept passes: as many frames in flight as fit. The window's frames
  // are read twice only when one frame in flight does not fit, and then with as many in flight
  // as fit: decoding every frame again costs more time than overlapping less.
  while (memory.frames_in_flight > 1 && !fits()) --memory.frames_in_flight;
  if (!fits() && window) {
    memory.read_twice = true;
    memory.frames_in_flight = most;
    while (memory.frames_in_flight > 1 && !fits()) --memory.frames_in_flight;
  }
  if (s.tracer != Tracer::kReference) return memory;
  PipelineMemory none = memory;
  none.reference_hits_bytes = 0;
  const std::uint64_t rest = estimate_run_memory(seq, plan, s, write, threads, none).bytes;
  memory.reference_hits_bytes = static_cast<std::size_t>(std::min<std::uint64_t>(
      memory.reference_hits_bytes, limit.bytes > rest ? limit.bytes - rest : 0));
  return memory;
}

}  // namespace ssgi
