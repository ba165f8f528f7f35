#include "gi/slices.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "gi/directions.h"
#include "gi/march.h"
#include "gi/slice_kernel.h"
#include "gi/surface_model.h"
#include "parallel.h"

namespace ssgi::detail {
namespace {

constexpr int kSectors = 32;

constexpr float kPi = kSlicePi;

// Times 1 / |a|: one division where Imath's normalized() does three, by its tiny-vector-safe
// length (with other roundings).
Imath::V3f normalized(const Imath::V3f& a) { return (1.0f / std::sqrt(a.dot(a))) * a; }

// An angle in the slice, from the view vector towards T, with its sine and cosine.
struct Angle {
  float theta, s, c;
};

// The slice's measure cos(theta - gamma) |sin theta| integrated from 0 to theta, as a function
// that increases over the hemisphere [gamma - pi/2, gamma + pi/2].
struct SliceMeasure {
  float cg, sg;
  float operator()(const Angle& a) const {
    const float g = 0.5f * (cg * a.s * a.s + sg * (a.theta - a.s * a.c));
    return a.s < 0 ? -g : g;
  }
};

// A slice at azimuth psi around the view vector weighs W(psi) = cos(beta) + gamma sin(beta)
// cos(alpha)... in full: n.V + gamma (n.T), gamma = atan2(n.T, n.V), with alpha = psi minus the
// azimuth of the normal and beta the normal's angle from the view vector; W has mean 1 over
// psi. Slices are drawn with density W / pi through this table of its inverse distribution
// (per beta, alpha at evenly spaced probabilities), so that every slice weighs about the same.
class SliceAzimuths {
 public:
  static constexpr int kBetas = 65, kProbabilities = 65;

  SliceAzimuths() {
    constexpr int kSteps = 4096;
    std::vector<double> cdf(kSteps + 1);
    for (int j = 0; j < kBetas; ++j) {
      const double beta = 0.5 * M_PI * j / (kBetas - 1);
      cdf[0] = 0;
      for (int i = 0; i < kSteps; ++i) {
        const double alpha = M_PI * (i + 0.5) / kSteps;
        cdf[i + 1] = cdf[i] + weight(std::cos(beta), std::sin(beta) * std::cos(alpha));
      }
      for (double& c : cdf) c /= cdf[kSteps];
      for (int k = 0; k < kProbabilities; ++k) {
        const double xi = static_cast<double>(k) / (kProbabilities - 1);
        const int i = static_cast<int>(std::lower_bound(cdf.begin(), cdf.end(), xi) - cdf.begin());
        double alpha = M_PI;
        if (i == 0) {
          alpha = 0;
        } else if (i <= kSteps) {
          const double f = (xi - cdf[i - 1]) / std::max(cdf[i] - cdf[i - 1], 1e-300);
          alpha = M_PI * (i - 1 + f) / kSteps;
        }
        table_[j][k] = static_cast<float>(alpha);
      }
    }
  }

  // W for n.V = nv and n.T = nt.
  static double weight(double nv, double nt) { return nv + std::atan2(nt, nv) * nt; }

  // The alpha of probability xi in [0, 1] for a normal at cos(beta) = nv, and d alpha / d xi
  // there (1 / the density the draw has).
  float alpha(float nv, float xi, float* dalpha_dxi) const {
    const float beta = std::acos(std::clamp(nv, 0.0f, 1.0f));
    const float fb = beta / (0.5f * kPi) * (kBetas - 1);
    const int j = std::min(static_cast<int>(fb), kBetas - 2);
    const float wb = fb - static_cast<float>(j);
    const float fx = std::clamp(xi, 0.0f, 1.0f) * (kProbabilities - 1);
    const int k = std::min(static_cast<int>(fx), kProbabilities - 2);
    const float wx = fx - static_cast<float>(k);
    const float a0 = table_[j][k] + wb * (table_[j + 1][k] - table_[j][k]);
    const float a1 = table_[j][k + 1] + wb * (table_[j + 1][k + 1] - table_[j][k + 1]);
    *dalpha_dxi = (a1 - a0) * (kProbabilities - 1);
    return a0 + wx * (a1 - a0);
  }

 private:
  float table_[kBetas][kProbabilities];
};

const SliceAzimuths& slice_azimuths() {
  static const SliceAzimuths table;
  return table;
}

// The trace grid's mesh (surface_model.h's rules) in the kernel's texels.
class PackedMesh {
 public:
  PackedMesh(const Image& depth, const Image& normal, const Image& thickness,
             const SurfaceModel& model)
      : width_(depth.width()), height_(depth.height()), texels_(depth.plane_size()) {
    const DepthMesh mesh(depth, thickness);
    parallel_for_rows(height_, [&](int j) {
      for (int i = 0; i < width_; ++i) {
        const std::size_t p = static_cast<std::size_t>(j) * width_ + i;
        MeshTexel& t = texels_[p];
        t.inverse_depth = 1.0f / depth.plane(0)[p];
        auto q = [](float v) {
          return static_cast<std::int8_t>(std::lround(std::clamp(v, -1.0f, 1.0f) * 127.0f));
        };
        t.nx = q(normal.plane(0)[p]);
        t.ny = q(normal.plane(1)[p]);
        t.nz = q(normal.plane(2)[p]);
        t.triangles = static_cast<std::uint8_t>(
            (mesh.has_triangle(i, j, true) ? kUpperTriangle : 0) |
            (mesh.has_triangle(i, j, false) ? kLowerTriangle : 0) |
            thickness_code(thickness.plane(0)[p], model.thickness) << kThicknessShift);
      }
    });
  }

  MeshView view() const { return {texels_.data(), width_, height_}; }

 private:
  int width_, height_;
  std::vector<MeshTexel> texels_;
};

// The random choices of record_slice_misses: a pure function of the pixel, frame, seed and
// slice.
std::uint64_t pixel_key(int x, int y, int frame, std::uint32_t seed) {
  return mix64(mix64(mix64(static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 32 |
                           static_cast<std::uint32_t>(y)) ^
                     static_cast<std::uint32_t>(frame)) ^
               seed);
}
std::uint64_t slice_hash(std::uint64_t key, int slice) {
  return mix64(key ^ static_cast<std::uint64_t>(slice) << 48);
}

// One per side of a slice: the missed rays read both sides' samples (MarchedSide).
SideSamples& scratch(int side) {
  thread_local SideSamples samples[2];
  return samples[side];
}

// One marched side of a slice as the missed rays read it: its samples, the steps taken (0 when
// the side was not marched) and where each step lies (SideMarch's terms).
struct MarchedSide {
  const SideSamples* samples = nullptr;
  int count = 0;
  float t_max = 0, u_step = 0;
  int steps = 1;
  float sx = 0, sy = 0;

  // Step j's screen distance from the origin, as march_side places it.
  float distance(int j) const {
    const float frac = (static_cast<float>(j) + u_step) * (1.0f / static_cast<float>(steps));
    return 1.0f + (t_max - 1.0f) * frac * frac;
  }
};

// One trace sample's hits before they join its row's.
struct PixelHits {
  std::vector<std::int32_t> pixel;
  std::vector<float> weight;
  void reserve(std::size_t n) {
    if (pixel.size() < n) pixel.resize(n), weight.resize(n);
  }
};

PixelHits& pixel_hits() {
  thread_local PixelHits hits;
  return hits;
}

// A row's hits while it is traced.
struct RowStage {
  std::vector<std::int32_t> pixels;
  std::vector<float> weights;
};

RowStage& row_stage() {
  thread_local RowStage stage;
  return stage;
}

struct SliceTracer {
  const GBuffer& g;
  const TraceGrid& grid;
  const GiSettings& settings;
  const MissModel& misses;
  SurfaceModel model;
  PackedMesh mesh;
  MeshView mesh_view;
  int w, h;              // the frame's data window
  float fx, fy, cx, cy;  // the camera in trace-grid units
  float inv_fx, inv_fy;
  int missed_runs;  // rays per slice that carry its missed sectors on (record_slice_misses)

  SliceTracer(const GBuffer& gb, const TraceGrid& gr, const GiSettings& s, const MissModel& m,
              int runs)
      : g(gb),
        grid(gr),
        settings(s),
        misses(m),
        model{static_cast<float>(s.thickness)},
        mesh(gr.depth, gr.normal, gr.thickness, model),
        mesh_view(mesh.view()),
        w(gb.width()),
        h(gb.height()),
        fx(gr.fx),
        fy(gr.fy),
        cx(gr.cx),
        cy(gr.cy),
        inv_fx(1.0f / gr.fx),
        inv_fy(1.0f / gr.fy),
        missed_runs(runs) {}

  // The camera-space direction through trace-grid coordinates (sx, sy), at z = 1.
  Imath::V3f ray(float sx, float sy) const {
    return {(sx - cx) * inv_fx, (cy - sy) * inv_fy, 1.0f};
  }

  // What the missed sectors of a slice bring (misses.h): the half-disc cut into kMissBins
  // equal angles, each bin's missed sectors (those whose coordinate falls in it) sent along the
  // bin's middle direction. The angles' sines and cosines by rotation from the lowest's, not by
  // libm.
  void add_slice_misses(std::uint32_t missed, const SliceMeasure& measure, const Angle& lowest,
                        float h_lo, float to_sector, float u_rot, const Imath::V3f& view,
                        const Imath::V3f& t, float sector_weight, float env_light[3],
                        float cube[kCubeFaces]) const {
    // The half-disc spans pi from its lowest angle: the bins' steps are constants.
    constexpr int kMissBins = 8;
    constexpr float step = kPi / kMissBins;
    static const float cos_step = std::cos(step), sin_step = std::sin(step);
    static const float cos_half = std::cos(0.5f * step), sin_half = std::sin(0.5f * step);
    const float lo_theta = lowest.theta;
    // The sectors below coordinate u: bits 0 .. ceil(u) - 1.
    auto below = [](float u) {
      const float k = std::min(std::max(std::ceil(u), 0.0f), 32.0f);
      return k >= 32.0f ? ~0u : (1u << static_cast<std::uint32_t>(k)) - 1u;
    };
    float c = lowest.c, s = lowest.s;
    std::uint32_t done = below(-u_rot);
    for (int i = 0; i < kMissBins; ++i) {
      const float cm = c * cos_half - s * sin_half, sm = s * cos_half + c * sin_half;
      const float cn = c * cos_step - s * sin_step, sn = s * cos_step + c * sin_step;
      c = cn, s = sn;
      const std::uint32_t upto =
          i + 1 == kMissBins
              ? ~0u
              : below((measure(Angle{lo_theta + static_cast<float>(i + 1) * step, s, c}) - h_lo) *
                          to_sector -
                      u_rot);
      const int count = sector_count(missed & upto & ~done);
      done |= upto;
      if (count == 0) continue;
      const Imath::V3f d = normalized(cm * view + sm * t);
      misses.add(d, sector_weight * static_cast<float>(count), env_light, cube);
    }
  }

  // Where missed ray (o, d), of sector coordinate u, first passes behind a slab that a sample of
  // its side shows: its parameter at the sample before (0 before the first), or the infinite
  // float when it never does. The slice's plane holds the camera, so the ray meets each sample's
  // line of sight, and lies beyond its slab's back exactly when its coordinate lies beyond the
  // back's, away from the front's; a sample beyond where the ray's projection ends (its
  // vanishing point) it never reaches, nor any after it. The ray's screen distance along the
  // side at parameter x is x a / (o.z (o.z + x d.z)).
  float hidden_from(const MarchedSide& side, float u, const Imath::V3f& o,
                    const Imath::V3f& d) const {
    if (side.count == 0 || (!(u > side.samples->beyond_above) && !(u < side.samples->beyond_below)))
      return std::numeric_limits<float>::infinity();
    const float a = fx * (o.z * d.x - o.x * d.z) * side.sx - fy * (o.z * d.y - o.y * d.z) * side.sy;
    auto parameter = [&](float e) { return e * o.z * o.z / (a - e * o.z * d.z); };
    for (int j = 0; j < side.count; ++j) {
      if (side.samples->pixel[j + 1] < 0) continue;
      const float front = side.samples->front_u[j + 1], back = side.samples->back_u[j + 1];
      if (!((u - back) * (back - front) > 0)) continue;
      if (!(a - side.distance(j) * o.z * d.z > 0)) break;
      return j == 0 ? 0.0f : parameter(side.distance(j - 1));
    }
    return std::numeric_limits<float>::infinity();
  }

  // The missed sectors of a slice as rays for other frames to continue (continuation.h): the
  // missed sectors in order, cut into `missed_runs` runs of (nearly) equal count, and per
  // run the ray of one of its sectors, drawn at random, weighing the whole run: an unbiased
  // estimate of what the run's rays would find. The ray's angle inverts the slice's measure by
  // interpolation in a table of it over the half-disc; the sides' samples (`marched`) tell where
  // it passes behind what the frame shows (hidden_from).
  void record_slice_misses(std::uint32_t missed, const SliceMeasure& measure, const Angle& lowest,
                           float h_lo, float to_sector, float u_rot, const Imath::V3f& origin,
                           const Imath::V3f& view, const Imath::V3f& t, float sector_weight,
                           const MarchedSide marched[2], std::uint64_t key,
                           PixelMisses* record) const {
    // A coarse table: the measure is smooth, and the tracer runs this for every slice with a
    // miss (64 steps took a tenth of the final preset's tracing at 1080p, perf).
    constexpr int kSteps = 16;
    constexpr float step = kPi / kSteps;
    static const float cos_step = std::cos(step), sin_step = std::sin(step);
    float table[kSteps + 1], cosines[kSteps + 1], sines[kSteps + 1];
    float c = lowest.c, s = lowest.s;
    for (int i = 0; i <= kSteps; ++i) {
      cosines[i] = c;
      sines[i] = s;
      table[i] = measure(Angle{lowest.theta + static_cast<float>(i) * step, s, c});
      const float cn = c * cos_step - s * sin_step;
      s = s * cos_step + c * sin_step;
      c = cn;
    }
    int sectors[kSectors], count = 0;
    for (int k = 0; k < kSectors; ++k)
      if (missed >> k & 1u) sectors[count++] = k;
    const int runs = std::min(count, missed_runs);
    int i = 0;
    for (int run = 0; run < runs; ++run) {
      const int first = run * count / runs, size = (run + 1) * count / runs - first;
      key = mix64(key + static_cast<std::uint64_t>(run));
      const int pick =
          std::min(static_cast<int>(unit_float(key) * static_cast<float>(size)), size - 1);
      // Sector k is the ray at coordinate k (slice_kernel.h).
      const float u = static_cast<float>(sectors[first + pick]);
      const float m = std::clamp((u + u_rot) / to_sector + h_lo, table[0], table[kSteps]);
      while (i < kSteps - 1 && table[i + 1] < m) ++i;
      const float span = table[i + 1] - table[i];
      const float delta = span > 0 ? (m - table[i]) / span * step : 0.0f;
      // cos and sin of angle i + delta by rotation (delta < pi / 16: the series are exact to
      // a few 1e-6).
      const float d2 = delta * delta;
      const float cd = 1.0f - 0.5f * d2 + d2 * d2 / 24.0f, sd = delta * (1.0f - d2 / 6.0f);
      const float cm = cosines[i] * cd - sines[i] * sd, sm = sines[i] * cd + cosines[i] * sd;
      const Imath::V3f d = normalized(cm * view + sm * t);
      const float hidden = sm > 0   ? hidden_from(marched[0], u, origin, d)
                           : sm < 0 ? hidden_from(marched[1], u, origin, d)
                                    : std::numeric_limits<float>::infinity();
      record->push_back({d, sector_weight * static_cast<float>(size), hidden});
    }
  }

  // Traces the slices of trace sample `s` from pixel `p`; appends its hits, and with `record`
  // appends its missed rays (record_slice_misses) and writes into *ray_origin where they start.
  void trace(int p, std::vector<std::int32_t>* pixels, std::vector<float>* weights, float* miss,
             float env_light[3], float cube[kCubeFaces], PixelMisses* record,
             Imath::V3f* ray_origin) const {
    const int x = p % w, y = p / w;
    const float z0 = g.depth.plane(0)[p];
    const Imath::V3f n{g.normal.plane(0)[p], g.normal.plane(1)[p], g.normal.plane(2)[p]};
    const float offset = static_cast<float>(settings.start_offset) * z0;
    const float to_grid = 1.0f / static_cast<float>(grid.scale);
    const Imath::V3f origin = z0 * ray((x + 0.5f) * to_grid, (y + 0.5f) * to_grid) + offset * n;
    const Imath::V3f view = normalized(-1.0f * origin);
    if (ray_origin) *ray_origin = origin;
    // A point floats cannot hold (a depth near FLT_MAX; found by fuzzing) brings no light, rather
    // than NaN angles indexing the azimuth table.
    if (!std::isfinite(view.x + view.y + view.z)) return;
    // Azimuths around the view vector are measured from the normal's own (basis_x), so that
    // the slices can be drawn with the density of their weight (SliceAzimuths).
    const float nv_pixel = std::clamp(n.dot(view), 0.0f, 1.0f);
    Imath::V3f across = n - nv_pixel * view;
    if (!(across.dot(across) > 1e-12f)) across = Imath::V3f(1, 0, 0) - view.x * view;
    const Imath::V3f basis_x = normalized(across);
    const Imath::V3f basis_y = view.cross(basis_x);
    const SliceAzimuths& azimuths = slice_azimuths();
    // Where the origin is on the screen: every sample lies on a line through it.
    const float qx = cx + fx * origin.x / origin.z, qy = cy - fy * origin.y / origin.z;
    const int display_x = x + g.data_window.x0 - g.display_window.x0;
    const int display_y = y + g.data_window.y0 - g.display_window.y0;
    const PixelNoise noise = pixel_noise(display_x, display_y, g.frame, settings.seed);
    const std::uint64_t noise_key =
        record ? pixel_key(display_x, display_y, g.frame, settings.seed) : 0;
    const int slices = settings.slices, steps = settings.max_steps;
    const float max_distance = static_cast<float>(settings.max_distance);
    const std::uint32_t all = ~0u;
    float total_weight = 0;  // the slices' weights, whose mean is 1 over all slice angles
    // The pixel's hits, staged here (room for every sample) and appended normalised at the end.
    PixelHits& hits = pixel_hits();
    hits.reserve(static_cast<std::size_t>(slices) * 2 * static_cast<std::size_t>(steps));
    int kept = 0;
    const std::size_t recorded = record ? record->size() : 0;  // the rays of samples before

    for (int i = 0; i < slices; ++i) {
      float u_phi, u_rot, u_step;
      ray_sample(noise, i, &u_phi, &u_rot, &u_step);
      // The slice's azimuth around the view vector, stratified over [0, pi): uniform in this
      // angle (not in the screen's) is what the measure asks for under perspective.
      // Stratified in probability; alpha in [0, pi) gives every slice plane once.
      float dalpha_dxi;
      const float xi = (static_cast<float>(i) + u_phi) / static_cast<float>(slices);
      const float psi = azimuths.alpha(nv_pixel, xi, &dalpha_dxi);
      const Imath::V3f t = std::cos(psi) * basis_x + std::sin(psi) * basis_y;
      const Imath::V3f plane_normal = view.cross(t);
      // The slice's screen line: where the projection of origin + e t moves as e grows.
      float dx = fx * (t.x * origin.z - origin.x * t.z);
      float dy = -fy * (t.y * origin.z - origin.y * t.z);
      const float screen_length = std::sqrt(dx * dx + dy * dy);
      if (!(screen_length > 0)) continue;
      dx /= screen_length;
      dy /= screen_length;
      // The normal in the slice: its angle gamma from the view vector and its length.
      const Imath::V3f np = n - n.dot(plane_normal) * plane_normal;
      const float nv = std::max(np.dot(view), 1e-6f), nt = np.dot(t);
      const float np_length = std::sqrt(nv * nv + nt * nt);
      if (!(np_length > 0)) continue;
      const float cg = nv / np_length, sg = nt / np_length;
      const float gamma = fast_atan2(sg, cg);
      const SliceMeasure measure{cg, sg};
      const Angle lowest{gamma - 0.5f * kPi, -cg, sg}, highest{gamma + 0.5f * kPi, cg, -sg};
      const float h_lo = measure(lowest), h_total = measure(highest) - h_lo;
      if (!(h_total > 0)) continue;
      // Each sector's share of the pixel's hemisphere: the slice's weight over the sectors.
      // The slice's weight over the density it was drawn with: W / (W_table / pi) ~ 1.
      const float sector_weight = np_length * h_total * dalpha_dxi /
                                  (kPi * static_cast<float>(kSectors) * static_cast<float>(slices));
      const float to_sector = static_cast<float>(kSectors) / h_total;
      total_weight += sector_weight * static_cast<float>(kSectors);
      const SliceFrame frame{origin.x,      origin.y, origin.z,  view.x, view.y, view.z,
                             t.x,           t.y,      t.z,       cg,     sg,     lowest.theta,
                             highest.theta, h_lo,     to_sector, u_rot};

      std::uint32_t mask = 0;
      MarchedSide marched[2];
      for (int side = 0; side < 2 && mask != all; ++side) {
        const float sx = side ? -dx : dx, sy = side ? -dy : dy;
        // Distance to the data window's border along the side.
        float t_max = std::numeric_limits<float>::infinity();
        if (sx > 0) t_max = std::min(t_max, (static_cast<float>(w) * to_grid - qx) / sx);
        if (sx < 0) t_max = std::min(t_max, -qx / sx);
        if (sy > 0) t_max = std::min(t_max, (static_cast<float>(h) * to_grid - qy) / sy);
        if (sy < 0) t_max = std::min(t_max, -qy / sy);
        t_max *= 0.99999f;
        if (!(t_max > 1.0f)) continue;
        // The samples along the side that meet the mesh, quadratically spaced: dense near the
        // origin (contact), sparse far away; up to the first beyond --max-distance. A sector
        // first shadowed by a sample is a ray that hits it first.
        const SideMarch march{qx,
                              qy,
                              sx,
                              sy,
                              t_max,
                              u_step,
                              steps,
                              cx,
                              cy,
                              inv_fx,
                              inv_fy,
                              max_distance * max_distance,
                              model.thickness};
        SideSamples& samples = scratch(side);
        const int count = march_side(mesh_view, frame, march, &samples);
        marched[side] = {&samples, count, t_max, u_step, steps, sx, sy};
        kept += collect_hits(samples, count, sector_weight, &mask, hits.pixel.data() + kept,
                             hits.weight.data() + kept);
      }
      const std::uint32_t missed = ~mask;
      *miss += sector_weight * static_cast<float>(sector_count(missed));
      if (missed)
        add_slice_misses(missed, measure, lowest, h_lo, to_sector, u_rot, view, t, sector_weight,
                         env_light, cube);
      if (missed && record)
        record_slice_misses(missed, measure, lowest, h_lo, to_sector, u_rot, origin, view, t,
                            sector_weight, marched, slice_hash(noise_key, i), record);
    }
    // Each slice's weight |n_p| x its measure has mean 1 over the slice angles; dividing by the
    // sampled slices' own total makes a pixel's weights sum to 1 exactly (a ratio estimator:
    // the furnace stays exact, and the weights' variance is gone), at the same limit.
    if (!(total_weight > 0)) {
      *miss = 1.0f;
      if (record) record->resize(recorded);
      return;
    }
    const float norm = 1.0f / total_weight;
    if (record)
      for (std::size_t k = recorded; k < record->size(); ++k) (*record)[k].weight *= norm;
    pixels->insert(pixels->end(), hits.pixel.begin(), hits.pixel.begin() + kept);
    for (int e = 0; e < kept; ++e) weights->push_back(hits.weight[e] * norm);
    *miss *= norm;
    for (int c = 0; c < 3; ++c) env_light[c] *= norm;
    for (int f = 0; f < kCubeFaces; ++f) cube[f] *= norm;
  }
};

}  // namespace

WeightedHits trace_slices(const GBuffer& g, const TraceGrid& grid, const GiSettings& settings,
                          const MissModel& misses, MissedRays* missed, int missed_runs) {
  const SliceTracer tracer(g, grid, settings, misses, missed_runs);
  WeightedHits hits;
  hits.miss = Image(grid.width, grid.height, 1);
  hits.env = Image(grid.width, grid.height, 3);
  hits.cube = Image(grid.width, grid.height, kCubeFaces);
  // Each row collects its hits apart; joined in row order, so the result is the same for any
  // thread count.
  RowEntries<std::int32_t> row_pixels(grid.height);
  RowEntries<float> row_weights(grid.height);
  std::vector<std::vector<std::uint32_t>> row_counts(grid.height);
  std::vector<PixelMisses> row_missed(missed ? grid.height : 0);
  std::vector<std::vector<std::uint32_t>> row_missed_counts(row_missed.size());
  if (missed) missed->origin.assign(grid.origin.size(), Imath::V3f{0, 0, 0});
  parallel_for_rows(grid.height, [&](int by) {
    if (missed) row_missed_counts[by].assign(grid.width, 0);
    // The row's hits grow in this thread's staging vectors, which keep their room from row to
    // row, and are copied out once, into the thread's blocks (RowEntries): the row's own
    // vectors grown hit by hit would take a dozen fresh blocks each.
    RowStage& stage = row_stage();
    std::vector<std::int32_t>& px = stage.pixels;
    std::vector<float>& wt = stage.weights;
    px.clear();
    wt.clear();
    std::vector<std::uint32_t>& counts = row_counts[by];
    counts.assign(grid.width, 0);
    for (int bx = 0; bx < grid.width; ++bx) {
      const int s = by * grid.width + bx;
      const int p = grid.origin[s];
      if (p < 0) continue;
      const std::size_t before = px.size();
      float miss = 0, env_light[3] = {0, 0, 0}, cube[kCubeFaces] = {0, 0, 0, 0, 0, 0};
      const std::size_t missed_before = missed ? row_missed[by].size() : 0;
      tracer.trace(p, &px, &wt, &miss, env_light, cube, missed ? &row_missed[by] : nullptr,
                   missed ? &missed->origin[s] : nullptr);
      counts[bx] = static_cast<std::uint32_t>(px.size() - before);
      if (missed)
        row_missed_counts[by][bx] =
            static_cast<std::uint32_t>(row_missed[by].size() - missed_before);
      hits.miss.plane(0)[s] = miss;
      for (int c = 0; c < 3; ++c) hits.env.plane(c)[s] = env_light[c];
      for (int f = 0; f < kCubeFaces; ++f) hits.cube.plane(f)[s] = cube[f];
    }
    row_pixels.put(by, px.data(), px.size());
    row_weights.put(by, wt.data(), wt.size());
  });
  join_rows(
      grid, row_pixels, [&](int by, int bx) { return row_counts[by][bx]; }, &hits.begin,
      &hits.pixel);
  join_rows(grid, row_weights, &hits.weight);
  if (missed)
    join_rows(
        grid, row_missed, [&](int by, int bx) { return row_missed_counts[by][bx]; }, &missed->begin,
        &missed->rays);
  return hits;
}

}  // namespace ssgi::detail
