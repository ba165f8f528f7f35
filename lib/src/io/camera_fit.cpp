// Pinhole cameras from a world-space position pass: lattice samples away from silhouettes, the
// direct linear transform, its RQ decomposition, Levenberg-Marquardt refinement.
#include "io/camera_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>
#include <utility>

namespace ssgi::detail {
namespace {

// About 64 x 64 samples: thousands of equations for 11 unknowns, so that a few bad pixels do
// not move the fit, at a cost far below reading the frame.
constexpr int kLatticeSize = 64;
// A surface pixel's depth along each line through its 3x3 neighbourhood is smooth when its
// second difference stays below this fraction of its depth: on a plane it is 2 (dz/z)^2 z, so
// under 1% unless the surface is seen at a grazing angle (10% depth change per pixel), while a
// silhouette's step is the difference between two surfaces.
constexpr double kSmoothDepth = 0.01;
// Fewer usable samples than this and the fit is refused: the DLT needs 6 points, but a frame
// with so few pixels away from edges is mostly edges, and its fit would say little.
constexpr std::size_t kMinSamples = 50;
// The samples' spread out of their best plane, relative to the spread in it, below which they
// count as one plane: the DLT cannot tell a plane's image from a camera's (a homography has 8
// unknowns, the camera 11), so a fit from it would be arbitrary.
constexpr double kMinOutOfPlane = 0.01;
// An outlier is farther from its pixel centre than this many times the RMS error, and farther
// than kOutlierFloorPx: below that floor the error is a filtered pass's blend within a pixel.
constexpr double kOutlierSigmas = 3;
constexpr double kOutlierFloorPx = 0.25;
// Dropping more than this fraction as outliers means the model does not fit.
constexpr double kMaxRejectedFraction = 0.25;
// Skew (pixels of shift across the image's half-height) above which the DLT's projection is
// not a camera the library represents: the same scale as the residual threshold.
constexpr double kMaxSkewPx = kMaxFitResidualPx;

using Mat3 = std::array<std::array<double, 3>, 3>;

std::string format_px(double v) {
  char s[32];
  std::snprintf(s, sizeof s, v < 0.01 ? "%.2g" : "%.3g", v);
  return s;
}

// Eigenvalues and eigenvectors (columns of `vectors`) of the symmetric n x n matrix `a`
// (row-major), by cyclic Jacobi rotations: small and accurate for the 12 x 12 and 3 x 3
// matrices here.
void symmetric_eigen(std::vector<double> a, int n, std::vector<double>* values,
                     std::vector<double>* vectors) {
  std::vector<double>& v = *vectors;
  v.assign(static_cast<std::size_t>(n) * n, 0.0);
  for (int i = 0; i < n; ++i) v[i * n + i] = 1;
  double total = 0;
  for (double x : a) total += x * x;
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0;
    for (int p = 0; p < n; ++p)
      for (int q = p + 1; q < n; ++q) off += a[p * n + q] * a[p * n + q];
    if (!(off > 1e-32 * total)) break;
    for (int p = 0; p < n; ++p) {
      for (int q = p + 1; q < n; ++q) {
        const double apq = a[p * n + q];
        if (apq == 0) continue;
        const double theta = (a[q * n + q] - a[p * n + p]) / (2 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::hypot(theta, 1.0));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; ++k) {
          const double akp = a[k * n + p], akq = a[k * n + q];
          a[k * n + p] = c * akp - s * akq;
          a[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; ++k) {
          const double apk = a[p * n + k], aqk = a[q * n + k];
          a[p * n + k] = c * apk - s * aqk;
          a[q * n + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < n; ++k) {
          const double vkp = v[k * n + p], vkq = v[k * n + q];
          v[k * n + p] = c * vkp - s * vkq;
          v[k * n + q] = s * vkp + c * vkq;
        }
      }
    }
  }
  values->resize(n);
  for (int i = 0; i < n; ++i) (*values)[i] = a[i * n + i];
}

// Solves the n x n system a x = b by Gaussian elimination with partial pivoting; false when
// singular.
bool solve(std::vector<double> a, std::vector<double> b, int n, std::vector<double>* x) {
  for (int col = 0; col < n; ++col) {
    int pivot = col;
    for (int r = col + 1; r < n; ++r)
      if (std::fabs(a[r * n + col]) > std::fabs(a[pivot * n + col])) pivot = r;
    if (!(std::fabs(a[pivot * n + col]) > 0)) return false;
    if (pivot != col) {
      for (int k = 0; k < n; ++k) std::swap(a[pivot * n + k], a[col * n + k]);
      std::swap(b[pivot], b[col]);
    }
    for (int r = col + 1; r < n; ++r) {
      const double f = a[r * n + col] / a[col * n + col];
      if (f == 0) continue;
      for (int k = col; k < n; ++k) a[r * n + k] -= f * a[col * n + k];
      b[r] -= f * b[col];
    }
  }
  x->assign(n, 0.0);
  for (int r = n - 1; r >= 0; --r) {
    double s = b[r];
    for (int k = r + 1; k < n; ++k) s -= a[r * n + k] * (*x)[k];
    (*x)[r] = s / a[r * n + r];
  }
  for (double v : *x)
    if (!std::isfinite(v)) return false;
  return true;
}

// The camera model refined by Levenberg-Marquardt: camera point c = R w + t (column vectors),
// px = cx + (fx c.x + skew c.y) / c.z, py = cy - fy c.y / c.z. The library's cameras have no
// skew: it is fitted only to tell a sheared projection from one that fits no camera.
struct Model {
  double fx = 1, fy = 1, cx = 0, cy = 0, skew = 0;
  Mat3 r{};  // world to camera; a rotation, or a rotation times a reflection
  Imath::V3d t{0, 0, 0};

  Imath::V3d to_camera(const Imath::V3d& w) const {
    return {r[0][0] * w.x + r[0][1] * w.y + r[0][2] * w.z + t.x,
            r[1][0] * w.x + r[1][1] * w.y + r[1][2] * w.z + t.y,
            r[2][0] * w.x + r[2][1] * w.y + r[2][2] * w.z + t.z};
  }
};

// Squared reprojection errors of each sample; a point at or behind the camera gets +inf.
std::vector<double> squared_errors(const Model& m, const std::vector<PositionSample>& samples) {
  std::vector<double> e(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Imath::V3d c = m.to_camera(samples[i].world);
    if (!(c.z > 0)) {
      e[i] = std::numeric_limits<double>::infinity();
      continue;
    }
    const double du = m.cx + (m.fx * c.x + m.skew * c.y) / c.z - samples[i].px;
    const double dv = m.cy - m.fy * c.y / c.z - samples[i].py;
    e[i] = du * du + dv * dv;
  }
  return e;
}

double total(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

// Rodrigues' rotation matrix of the rotation vector w.
Mat3 rotation(const Imath::V3d& w) {
  const double theta = std::sqrt(w.dot(w));
  Mat3 k{{{0, -w.z, w.y}, {w.z, 0, -w.x}, {-w.y, w.x, 0}}};
  const double a = theta > 1e-12 ? std::sin(theta) / theta : 1.0;
  const double b = theta > 1e-12 ? (1 - std::cos(theta)) / (theta * theta) : 0.5;
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double kk = 0;
      for (int l = 0; l < 3; ++l) kk += k[i][l] * k[l][j];
      r[i][j] = (i == j ? 1.0 : 0.0) + a * k[i][j] + b * kk;
    }
  return r;
}

// Levenberg-Marquardt on the reprojection error over 10 parameters: fx, fy, cx, cy, a rotation
// of camera space about its origin (R <- exp(w) R, t <- exp(w) t: the camera turns in place)
// and a step of t; with `fit_skew` an 11th, the skew (else it stays as it is).
Model refine(Model m, const std::vector<PositionSample>& samples, bool fit_skew) {
  constexpr int kMaxParams = 11;
  const int params = fit_skew ? 11 : 10;
  double cost = total(squared_errors(m, samples));
  if (!std::isfinite(cost)) return m;
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 100; ++iteration) {
    std::vector<double> jtj(params * params, 0.0), jtr(params, 0.0);
    for (const PositionSample& s : samples) {
      const Imath::V3d c = m.to_camera(s.world);
      const double iz = 1 / c.z;
      const double ru = m.cx + (m.fx * c.x + m.skew * c.y) * iz - s.px;
      const double rv = m.cy - m.fy * c.y * iz - s.py;
      // d(residual)/d(camera point), then through dc/dw = -[c]x and dc/dt = I.
      const Imath::V3d gu{m.fx * iz, m.skew * iz, -(m.fx * c.x + m.skew * c.y) * iz * iz};
      const Imath::V3d gv{0, -m.fy * iz, m.fy * c.y * iz * iz};
      const auto row = [&](const Imath::V3d& g, double dfx, double dfy, double dcx, double dcy,
                           double* j) {
        j[0] = dfx;
        j[1] = dfy;
        j[2] = dcx;
        j[3] = dcy;
        // g . (w x c) = w . (c x g)
        const Imath::V3d dw = c.cross(g);
        j[4] = dw.x;
        j[5] = dw.y;
        j[6] = dw.z;
        j[7] = g.x;
        j[8] = g.y;
        j[9] = g.z;
      };
      double ju[kMaxParams], jv[kMaxParams];
      row(gu, c.x * iz, 0, 1, 0, ju);
      row(gv, 0, -c.y * iz, 0, 1, jv);
      ju[10] = c.y * iz;
      jv[10] = 0;
      for (int i = 0; i < params; ++i) {
        jtr[i] += ju[i] * ru + jv[i] * rv;
        for (int k = 0; k < params; ++k) jtj[i * params + k] += ju[i] * ju[k] + jv[i] * jv[k];
      }
    }
    bool improved = false;
    while (lambda < 1e12) {
      std::vector<double> a = jtj, b(params), step;
      for (int i = 0; i < params; ++i) {
        a[i * params + i] += lambda * std::max(jtj[i * params + i], 1e-300);
        b[i] = -jtr[i];
      }
      if (!solve(a, b, params, &step)) {
        lambda *= 10;
        continue;
      }
      Model next = m;
      next.fx += step[0];
      next.fy += step[1];
      next.cx += step[2];
      next.cy += step[3];
      const Mat3 dr = rotation({step[4], step[5], step[6]});
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          next.r[i][j] = dr[i][0] * m.r[0][j] + dr[i][1] * m.r[1][j] + dr[i][2] * m.r[2][j];
      next.t = Imath::V3d(dr[0][0] * m.t.x + dr[0][1] * m.t.y + dr[0][2] * m.t.z,
                          dr[1][0] * m.t.x + dr[1][1] * m.t.y + dr[1][2] * m.t.z,
                          dr[2][0] * m.t.x + dr[2][1] * m.t.y + dr[2][2] * m.t.z) +
               Imath::V3d(step[7], step[8], step[9]);
      if (fit_skew) next.skew += step[10];
      const double next_cost = total(squared_errors(next, samples));
      if (next_cost < cost) {
        const bool small = cost - next_cost <= 1e-15 * cost;
        m = next;
        cost = next_cost;
        lambda = std::max(lambda / 10, 1e-12);
        improved = !small;
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  return m;
}

// The 3x4 projection u ~ P (X, 1) of `samples` by the DLT, in normalised coordinates: pixel
// centres moved to their centroid and scaled to a mean distance of sqrt(2), world points to
// theirs and sqrt(3). The null vector of the 2n x 12 system is the eigenvector of its normal
// matrix with the smallest eigenvalue. False when degenerate.
bool direct_linear_transform(const std::vector<PositionSample>& samples,
                             std::array<std::array<double, 4>, 3>* p) {
  const double n = static_cast<double>(samples.size());
  double mu = 0, mv = 0;
  Imath::V3d mw(0);
  for (const PositionSample& s : samples) {
    mu += s.px;
    mv += s.py;
    mw += s.world;
  }
  mu /= n;
  mv /= n;
  mw /= n;
  double du = 0, dw = 0;
  for (const PositionSample& s : samples) {
    du += std::hypot(s.px - mu, s.py - mv);
    const Imath::V3d d = s.world - mw;
    dw += std::sqrt(d.dot(d));
  }
  if (!(du > 0 && dw > 0)) return false;
  const double su = std::sqrt(2.0) * n / du, sw = std::sqrt(3.0) * n / dw;
  std::vector<double> ata(144, 0.0);
  for (const PositionSample& s : samples) {
    const Imath::V3d w = (s.world - mw) * sw;
    const double x[4] = {w.x, w.y, w.z, 1};
    const double u = (s.px - mu) * su, v = (s.py - mv) * su;
    double r1[12] = {}, r2[12] = {};
    for (int k = 0; k < 4; ++k) {
      r1[k] = x[k];
      r1[8 + k] = -u * x[k];
      r2[4 + k] = x[k];
      r2[8 + k] = -v * x[k];
    }
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j) ata[i * 12 + j] += r1[i] * r1[j] + r2[i] * r2[j];
  }
  std::vector<double> values, vectors;
  symmetric_eigen(ata, 12, &values, &vectors);
  const int smallest =
      static_cast<int>(std::min_element(values.begin(), values.end()) - values.begin());
  double pn[3][4];
  for (int i = 0; i < 12; ++i) pn[i / 4][i % 4] = vectors[i * 12 + smallest];
  // P = T_image^-1 Pn T_world, T_image = [su 0 -su mu; 0 su -su mv; 0 0 1], T_world likewise.
  double left[3][4];
  for (int j = 0; j < 4; ++j) {
    left[0][j] = pn[0][j] / su + mu * pn[2][j];
    left[1][j] = pn[1][j] / su + mv * pn[2][j];
    left[2][j] = pn[2][j];
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) (*p)[i][j] = left[i][j] * sw;
    (*p)[i][3] = left[i][3] - sw * (left[i][0] * mw.x + left[i][1] * mw.y + left[i][2] * mw.z);
  }
  for (const auto& row : *p)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

// P = K [R | t] with K upper triangular, by Gram-Schmidt from the last row (an RQ
// decomposition), in the library's signs: K = [fx s cx; 0 -fy cy; 0 0 1] with fx, fy > 0, and
// the samples in front (camera z > 0); the skew s goes to m->skew.
bool decompose(std::array<std::array<double, 4>, 3> p, const std::vector<PositionSample>& samples,
               Model* m) {
  double in_front = 0;
  for (const PositionSample& s : samples)
    in_front += p[2][0] * s.world.x + p[2][1] * s.world.y + p[2][2] * s.world.z + p[2][3];
  if (in_front < 0)
    for (auto& row : p)
      for (double& v : row) v = -v;
  const Imath::V3d m1(p[0][0], p[0][1], p[0][2]), m2(p[1][0], p[1][1], p[1][2]),
      m3(p[2][0], p[2][1], p[2][2]);
  const double k22 = std::sqrt(m3.dot(m3));
  if (!(k22 > 0)) return false;
  const Imath::V3d r3 = m3 / k22;
  const double k12 = m2.dot(r3);
  Imath::V3d r2 = m2 - r3 * k12;
  const double k11 = std::sqrt(r2.dot(r2));
  if (!(k11 > 0)) return false;
  r2 /= k11;
  const double k02 = m1.dot(r3), k01 = m1.dot(r2);
  Imath::V3d r1 = m1 - r3 * k02 - r2 * k01;
  const double k00 = std::sqrt(r1.dot(r1));
  if (!(k00 > 0)) return false;
  r1 /= k00;
  // Image y points down, camera y up: K's middle column and R's middle row change sign.
  m->fx = k00 / k22;
  m->fy = k11 / k22;
  m->cx = k02 / k22;
  m->cy = k12 / k22;
  m->skew = -k01 / k22;
  const Imath::V3d rows[3] = {r1, -r2, r3};
  for (int i = 0; i < 3; ++i) {
    m->r[i][0] = rows[i].x;
    m->r[i][1] = rows[i].y;
    m->r[i][2] = rows[i].z;
  }
  // t = K^-1 p4 / k22 with K = [fx s cx; 0 -fy cy; 0 0 1].
  const double t2 = p[2][3] / k22;
  const double t1 = -(p[1][3] / k22 - m->cy * t2) / m->fy;
  const double t0 = (p[0][3] / k22 - m->cx * t2 - m->skew * t1) / m->fx;
  m->t = Imath::V3d(t0, t1, t2);
  return std::isfinite(m->fx) && std::isfinite(m->fy) && std::isfinite(t0) && std::isfinite(t1) &&
         std::isfinite(t2);
}

// The samples' spread out of their best plane over the spread in it: the square root of the
// smallest over the largest eigenvalue of their covariance.
double out_of_plane_ratio(const std::vector<PositionSample>& samples) {
  Imath::V3d mean(0);
  for (const PositionSample& s : samples) mean += s.world;
  mean /= static_cast<double>(samples.size());
  std::vector<double> cov(9, 0.0);
  for (const PositionSample& s : samples) {
    const Imath::V3d d = s.world - mean;
    const double v[3] = {d.x, d.y, d.z};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) cov[i * 3 + j] += v[i] * v[j];
  }
  std::vector<double> values, vectors;
  symmetric_eigen(cov, 3, &values, &vectors);
  const double hi = *std::max_element(values.begin(), values.end());
  const double lo = std::max(0.0, *std::min_element(values.begin(), values.end()));
  return hi > 0 ? std::sqrt(lo / hi) : 0.0;
}

Camera camera_of(const Model& m) {
  Camera c;
  std::tie(c.fx, c.fy, c.cx, c.cy) = std::tie(m.fx, m.fy, m.cx, m.cy);
  c.has_world_transform = true;
  // Row-vector convention: p' = p * M, so M holds R transposed and t in row 3.
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c.world_to_camera[i][j] = m.r[j][i];
    c.world_to_camera[i][3] = 0;
  }
  c.world_to_camera[3][0] = m.t.x;
  c.world_to_camera[3][1] = m.t.y;
  c.world_to_camera[3][2] = m.t.z;
  c.world_to_camera[3][3] = 1;
  return c;
}

double rms(const std::vector<double>& squared) {
  return squared.empty() ? 0.0 : std::sqrt(total(squared) / static_cast<double>(squared.size()));
}

}  // namespace

std::vector<PositionSample> position_samples(const Image& position, const Image& distance,
                                             const Box2i& display, const Box2i& data,
                                             std::size_t* lattice_points) {
  const int w = position.width(), h = position.height();
  const int step_x = std::max(1, w / kLatticeSize), step_y = std::max(1, h / kLatticeSize);
  std::vector<PositionSample> samples;
  std::size_t lattice = 0;
  const auto surface = [&](int x, int y) {
    const float d = distance.at(0, x, y);
    return std::isfinite(d) && d > 0 && std::isfinite(position.at(0, x, y)) &&
           std::isfinite(position.at(1, x, y)) && std::isfinite(position.at(2, x, y));
  };
  for (int y = step_y / 2; y < h; y += step_y) {
    for (int x = step_x / 2; x < w; x += step_x) {
      ++lattice;
      if (x < 1 || y < 1 || x + 1 >= w || y + 1 >= h) continue;
      bool ok = true;
      for (int dy = -1; dy <= 1 && ok; ++dy)
        for (int dx = -1; dx <= 1 && ok; ++dx) ok = surface(x + dx, y + dy);
      if (!ok) continue;
      const double z = distance.at(0, x, y);
      static constexpr int kLines[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
      for (const auto& line : kLines) {
        const double a = distance.at(0, x + line[0], y + line[1]);
        const double b = distance.at(0, x - line[0], y - line[1]);
        ok = ok && std::fabs(a - 2 * z + b) <= kSmoothDepth * z;
      }
      if (!ok) continue;
      samples.push_back(
          {Imath::V3d(position.at(0, x, y), position.at(1, x, y), position.at(2, x, y)),
           x + data.x0 - display.x0 + 0.5, y + data.y0 - display.y0 + 0.5});
    }
  }
  if (lattice_points) *lattice_points = lattice;
  return samples;
}

CameraFitResult fit_camera_to_positions(const std::vector<PositionSample>& samples,
                                        std::size_t lattice_points, const std::string& pass_name) {
  CameraFitResult result;
  const std::string what = "position pass " + pass_name;
  const std::string remedy = "; give --camera or --fov";
  if (samples.size() < kMinSamples) {
    result.problem = what + ": too few surface pixels away from edges to fit a camera (" +
                     std::to_string(samples.size()) + " of " + std::to_string(lattice_points) +
                     " lattice points, " + std::to_string(kMinSamples) + " needed)" + remedy;
    return result;
  }
  const double spread = out_of_plane_ratio(samples);
  if (spread < kMinOutOfPlane) {
    char ratio[32];
    std::snprintf(ratio, sizeof ratio, "%.2g%%", 100 * spread);
    result.problem =
        what + ": its surfaces lie on one plane (out-of-plane spread " + std::string(ratio) +
        " of the in-plane spread), from which no pinhole camera can be fitted" + remedy;
    return result;
  }
  std::array<std::array<double, 4>, 3> p{};
  Model projection;
  if (!direct_linear_transform(samples, &p) || !decompose(p, samples, &projection) ||
      !(projection.fx > 0 && projection.fy > 0)) {
    result.problem =
        what + ": its positions give no projection (a degenerate configuration)" + remedy;
    return result;
  }
  Model model = projection;
  model.skew = 0;
  model = refine(model, samples, false);
  std::vector<double> errors = squared_errors(model, samples);
  const double all_rms = rms(errors);
  // One round of outlier rejection: pixels whose positions are blends the lattice test missed.
  const double limit = std::max(kOutlierSigmas * all_rms, kOutlierFloorPx);
  std::vector<PositionSample> kept;
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (errors[i] <= limit * limit) kept.push_back(samples[i]);
  result.rejected = samples.size() - kept.size();
  if (result.rejected > 0 && kept.size() >= kMinSamples &&
      result.rejected <= kMaxRejectedFraction * static_cast<double>(samples.size())) {
    model = refine(model, kept, false);
    errors = squared_errors(model, kept);
  } else {
    kept = samples;
    result.rejected = 0;
  }
  result.samples = kept.size();
  result.residual_px = rms(errors);
  // The same fit with skew: a sheared projection is refused as such when skew explains it (the
  // camera with skew fits) and shifts the image's top or bottom row by more than kMaxSkewPx.
  const Model sheared = refine(projection, kept, true);
  double half_height = 0;
  for (const PositionSample& s : kept)
    half_height = std::max(half_height, std::fabs(s.py - sheared.cy));
  const double skew_px = std::fabs(sheared.skew) * half_height / sheared.fy;
  if (skew_px > kMaxSkewPx && rms(squared_errors(sheared, kept)) <= kMaxFitResidualPx) {
    result.problem = what + ": the projection it gives has skew (" + format_px(skew_px) +
                     " px across the image), which no pinhole camera has" + remedy;
    return result;
  }
  if (!(result.residual_px <= kMaxFitResidualPx)) {
    result.problem =
        what + " does not fit a pinhole camera (residual " +
        (std::isfinite(result.residual_px) ? format_px(result.residual_px) + " px"
                                           : std::string("infinite: points behind it")) +
        "): a fisheye or panoramic lens, motion-blurred positions, or a position pass not in "
        "world space" +
        remedy;
    return result;
  }
  if (!(model.fx > 0 && model.fy > 0 && std::isfinite(model.fx) && std::isfinite(model.fy))) {
    result.problem = what + ": the fit gives no positive focal length" + remedy;
    return result;
  }
  result.ok = true;
  result.camera = camera_of(model);
  result.camera.fit_residual_px = result.residual_px;
  result.camera.source = what + " (fit, residual " + format_px(result.residual_px) + " px)";
  return result;
}

double reprojection_rms_px(const Camera& camera, const std::vector<PositionSample>& samples,
                           const Box2i& display) {
  if (samples.empty()) return 0;
  const double far = display.width();
  double sum = 0;
  for (const PositionSample& s : samples) {
    const Imath::V3d c = s.world * camera.world_to_camera;
    double d2 = far * far;
    if (c.z > 0) {
      double px, py;
      camera.project(c, &px, &py);
      d2 = std::min(d2, (px - s.px) * (px - s.px) + (py - s.py) * (py - s.py));
    }
    sum += d2;
  }
  return std::sqrt(sum / static_cast<double>(samples.size()));
}

}  // namespace ssgi::detail
