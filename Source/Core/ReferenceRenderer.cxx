// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/ReferenceRenderer.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

namespace mtpt
{

namespace
{

/// One cell's stretch of one pixel's ray: ray parameters (0 at the near plane, 1 at the far
/// plane) and the scalar at both ends.
struct Segment
{
  double enter, exit, scalarEnter, scalarExit;
  bool operator<(const Segment& o) const
  {
    if (this->enter != o.enter)
    {
      return this->enter < o.enter;
    }
    if (this->exit != o.exit)
    {
      return this->exit < o.exit;
    }
    if (this->scalarEnter != o.scalarEnter)
    {
      return this->scalarEnter < o.scalarEnter;
    }
    return this->scalarExit < o.scalarExit;
  }
};

/// A point in eye coordinates and window coordinates (x, y) with its clip w.
struct EyePoint
{
  double eye[3];
  double windowX, windowY, clipW;
  bool finite;
};

/// Pixels whose rays may cross a cell (inclusive); empty when xmin > xmax.
struct PixelBox
{
  int xmin, xmax, ymin, ymax;
};

/// 4x4 inverse by cofactors; false if singular or not finite.
bool Invert(const Matrix4& m, Matrix4& out)
{
  Matrix4 inv;
  inv[0] = m[5] * m[10] * m[15] - m[5] * m[11] * m[14] - m[9] * m[6] * m[15] + m[9] * m[7] * m[14] +
    m[13] * m[6] * m[11] - m[13] * m[7] * m[10];
  inv[4] = -m[4] * m[10] * m[15] + m[4] * m[11] * m[14] + m[8] * m[6] * m[15] -
    m[8] * m[7] * m[14] - m[12] * m[6] * m[11] + m[12] * m[7] * m[10];
  inv[8] = m[4] * m[9] * m[15] - m[4] * m[11] * m[13] - m[8] * m[5] * m[15] + m[8] * m[7] * m[13] +
    m[12] * m[5] * m[11] - m[12] * m[7] * m[9];
  inv[12] = -m[4] * m[9] * m[14] + m[4] * m[10] * m[13] + m[8] * m[5] * m[14] -
    m[8] * m[6] * m[13] - m[12] * m[5] * m[10] + m[12] * m[6] * m[9];
  inv[1] = -m[1] * m[10] * m[15] + m[1] * m[11] * m[14] + m[9] * m[2] * m[15] -
    m[9] * m[3] * m[14] - m[13] * m[2] * m[11] + m[13] * m[3] * m[10];
  inv[5] = m[0] * m[10] * m[15] - m[0] * m[11] * m[14] - m[8] * m[2] * m[15] + m[8] * m[3] * m[14] +
    m[12] * m[2] * m[11] - m[12] * m[3] * m[10];
  inv[9] = -m[0] * m[9] * m[15] + m[0] * m[11] * m[13] + m[8] * m[1] * m[15] - m[8] * m[3] * m[13] -
    m[12] * m[1] * m[11] + m[12] * m[3] * m[9];
  inv[13] = m[0] * m[9] * m[14] - m[0] * m[10] * m[13] - m[8] * m[1] * m[14] + m[8] * m[2] * m[13] +
    m[12] * m[1] * m[10] - m[12] * m[2] * m[9];
  inv[2] = m[1] * m[6] * m[15] - m[1] * m[7] * m[14] - m[5] * m[2] * m[15] + m[5] * m[3] * m[14] +
    m[13] * m[2] * m[7] - m[13] * m[3] * m[6];
  inv[6] = -m[0] * m[6] * m[15] + m[0] * m[7] * m[14] + m[4] * m[2] * m[15] - m[4] * m[3] * m[14] -
    m[12] * m[2] * m[7] + m[12] * m[3] * m[6];
  inv[10] = m[0] * m[5] * m[15] - m[0] * m[7] * m[13] - m[4] * m[1] * m[15] + m[4] * m[3] * m[13] +
    m[12] * m[1] * m[7] - m[12] * m[3] * m[5];
  inv[14] = -m[0] * m[5] * m[14] + m[0] * m[6] * m[13] + m[4] * m[1] * m[14] - m[4] * m[2] * m[13] -
    m[12] * m[1] * m[6] + m[12] * m[2] * m[5];
  inv[3] = -m[1] * m[6] * m[11] + m[1] * m[7] * m[10] + m[5] * m[2] * m[11] - m[5] * m[3] * m[10] -
    m[9] * m[2] * m[7] + m[9] * m[3] * m[6];
  inv[7] = m[0] * m[6] * m[11] - m[0] * m[7] * m[10] - m[4] * m[2] * m[11] + m[4] * m[3] * m[10] +
    m[8] * m[2] * m[7] - m[8] * m[3] * m[6];
  inv[11] = -m[0] * m[5] * m[11] + m[0] * m[7] * m[9] + m[4] * m[1] * m[11] - m[4] * m[3] * m[9] -
    m[8] * m[1] * m[7] + m[8] * m[3] * m[5];
  inv[15] = m[0] * m[5] * m[10] - m[0] * m[6] * m[9] - m[4] * m[1] * m[10] + m[4] * m[2] * m[9] +
    m[8] * m[1] * m[6] - m[8] * m[2] * m[5];
  const double det = m[0] * inv[0] + m[1] * inv[4] + m[2] * inv[8] + m[3] * inv[12];
  if (!(std::fabs(det) > 0) || !std::isfinite(det))
  {
    return false;
  }
  for (int i = 0; i < 16; ++i)
  {
    out[i] = inv[i] / det;
  }
  return true;
}

inline double Dot(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline void Cross(const double a[3], const double b[3], double out[3])
{
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

/// The transfer functions as sorted node arrays, and every node scalar (the breakpoints).
struct TransferFunctions
{
  std::vector<double> colorScalar, red, green, blue;
  std::vector<double> opacityScalar, opacity;
  std::vector<double> breaks;
  double inverseUnit = 1;

  /// Index i with xs[i] <= s < xs[i+1], for s strictly inside the node range.
  static std::size_t Interval(const std::vector<double>& xs, double s)
  {
    return static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), s) - xs.begin()) - 1;
  }

  void Color(double s, double c[3]) const
  {
    const std::size_t n = this->colorScalar.size();
    if (n == 0)
    {
      c[0] = c[1] = c[2] = 0;
      return;
    }
    if (s <= this->colorScalar[0] || n == 1)
    {
      c[0] = this->red[0], c[1] = this->green[0], c[2] = this->blue[0];
      return;
    }
    if (s >= this->colorScalar[n - 1])
    {
      c[0] = this->red[n - 1], c[1] = this->green[n - 1], c[2] = this->blue[n - 1];
      return;
    }
    const std::size_t i = Interval(this->colorScalar, s);
    const double f = (s - this->colorScalar[i]) / (this->colorScalar[i + 1] - this->colorScalar[i]);
    c[0] = this->red[i] + f * (this->red[i + 1] - this->red[i]);
    c[1] = this->green[i] + f * (this->green[i + 1] - this->green[i]);
    c[2] = this->blue[i] + f * (this->blue[i + 1] - this->blue[i]);
  }

  /// Extinction tau(s) = o(s) / unitDistance.
  double Tau(double s) const
  {
    const std::size_t n = this->opacityScalar.size();
    double o;
    if (n == 0)
    {
      o = 0;
    }
    else if (s <= this->opacityScalar[0] || n == 1)
    {
      o = this->opacity[0];
    }
    else if (s >= this->opacityScalar[n - 1])
    {
      o = this->opacity[n - 1];
    }
    else
    {
      const std::size_t i = Interval(this->opacityScalar, s);
      const double f =
        (s - this->opacityScalar[i]) / (this->opacityScalar[i + 1] - this->opacityScalar[i]);
      o = this->opacity[i] + f * (this->opacity[i + 1] - this->opacity[i]);
    }
    return o * this->inverseUnit;
  }
};

/// 8-point Gauss-Legendre rule on [0, 1]: exact for polynomials of degree 15.
constexpr int GaussPoints = 8;
constexpr double GaussX[GaussPoints] = { 0.5 - 0.5 * 0.9602898564975363,
  0.5 - 0.5 * 0.7966664774136267, 0.5 - 0.5 * 0.5255324099163290, 0.5 - 0.5 * 0.1834346424956498,
  0.5 + 0.5 * 0.1834346424956498, 0.5 + 0.5 * 0.5255324099163290, 0.5 + 0.5 * 0.7966664774136267,
  0.5 + 0.5 * 0.9602898564975363 };
constexpr double GaussW[GaussPoints] = { 0.5 * 0.1012285362903763, 0.5 * 0.2223810344533745,
  0.5 * 0.3137066458778873, 0.5 * 0.3626837833783620, 0.5 * 0.3626837833783620,
  0.5 * 0.3137066458778873, 0.5 * 0.2223810344533745, 0.5 * 0.1012285362903763 };

/// Largest optical depth of one quadrature sub-interval.
constexpr double MaxSubIntervalDepth = 0.25;

/// Front-to-back state of one ray: premultiplied colour, transmittance, optical depth.
struct RayState
{
  double color[3] = { 0, 0, 0 };
  double transmittance = 1;
  double depth = 0;
  bool Done() const { return this->depth > MaxOpticalDepth; }
};

/**
 * One linear piece of length `length`: colour c0 -> c1 and extinction tau0 -> tau1, both
 * linear in the distance. Equal sub-intervals, ceil(depth / (MaxSubIntervalDepth / 2)) of
 * them: the largest holds at most twice the mean extinction times its length.
 */
void IntegratePiece(
  double length, const double c0[3], const double c1[3], double tau0, double tau1, RayState& ray)
{
  const double pieceDepth = 0.5 * (tau0 + tau1) * length;
  if (!(pieceDepth > 0))
  {
    return; // transparent: no emission, no absorption
  }
  const double count = std::max(1.0, std::ceil(pieceDepth * 2.0 / MaxSubIntervalDepth));
  const double h = length / count;
  const double slope = (tau1 - tau0) / length;
  double dc[3];
  for (int k = 0; k < 3; ++k)
  {
    dc[k] = (c1[k] - c0[k]) / length;
  }
  for (double i = 0; i < count && !ray.Done(); i += 1.0)
  {
    const double t0 = i * h;
    const double tauStart = tau0 + slope * t0;
    double emitted[3] = { 0, 0, 0 };
    for (int q = 0; q < GaussPoints; ++q)
    {
      const double x = h * GaussX[q]; // distance into the sub-interval
      const double tau = tauStart + slope * x;
      const double weight = GaussW[q] * h * tau * std::exp(-(tauStart * x + 0.5 * slope * x * x));
      for (int k = 0; k < 3; ++k)
      {
        emitted[k] += weight * (c0[k] + dc[k] * (t0 + x));
      }
    }
    const double depth = h * (tauStart + 0.5 * slope * h);
    for (int k = 0; k < 3; ++k)
    {
      ray.color[k] += ray.transmittance * emitted[k];
    }
    ray.transmittance *= std::exp(-depth);
    ray.depth += depth;
  }
}

/// One cell segment of length `length` along which the scalar runs linearly from `front`
/// to `back`: split at the transfer-function breakpoints between them.
void IntegrateSegment(
  const TransferFunctions& tf, double length, double front, double back, RayState& ray)
{
  if (!(length > 0))
  {
    return;
  }
  const double low = std::min(front, back), high = std::max(front, back);
  // Breakpoints strictly inside (low, high), in ray order.
  auto first = std::upper_bound(tf.breaks.begin(), tf.breaks.end(), low);
  auto last = std::lower_bound(first, tf.breaks.end(), high);
  const std::ptrdiff_t inner = last - first;
  double s0 = front, f0 = 0;
  double c0[3];
  tf.Color(s0, c0);
  double tau0 = tf.Tau(s0);
  for (std::ptrdiff_t j = 0; j <= inner && !ray.Done(); ++j)
  {
    double s1, f1;
    if (j == inner)
    {
      s1 = back;
      f1 = 1;
    }
    else
    {
      s1 = front <= back ? first[j] : first[inner - 1 - j];
      f1 = (s1 - front) / (back - front);
    }
    double c1[3];
    tf.Color(s1, c1);
    const double tau1 = tf.Tau(s1);
    const double pieceLength = (f1 - f0) * length;
    if (pieceLength > 0)
    {
      IntegratePiece(pieceLength, c0, c1, tau0, tau1, ray);
    }
    s0 = s1;
    f0 = f1;
    c0[0] = c1[0], c0[1] = c1[1], c0[2] = c1[2];
    tau0 = tau1;
  }
}

/// A cell prepared for ray clipping: face planes through its first point's frame.
struct CellPlanes
{
  double origin[3];    ///< eye coordinates of the first point
  double normal[4][3]; ///< inward normal of the face opposite point k, times |det|
  double offset[4][3]; ///< a point of that face, relative to the first point
  double scalar[4];
  double scalarLow, scalarHigh;
};

/// Sets up `cell` (points ids[0..3]); false if it has no volume or is not finite.
bool SetUpCell(
  const EyePoint* eye, const std::int64_t ids[4], const double scalar[4], CellPlanes& c)
{
  for (int k = 0; k < 4; ++k)
  {
    if (!eye[ids[k]].finite || !std::isfinite(scalar[k]))
    {
      return false;
    }
  }
  double q[4][3];
  for (int d = 0; d < 3; ++d)
  {
    c.origin[d] = eye[ids[0]].eye[d];
    q[0][d] = 0;
  }
  for (int k = 1; k < 4; ++k)
  {
    for (int d = 0; d < 3; ++d)
    {
      q[k][d] = eye[ids[k]].eye[d] - c.origin[d];
    }
  }
  // Normals with n_k . (q_k - a_k) = det for every face; flipped to point inwards.
  double e1[3], e2[3];
  for (int d = 0; d < 3; ++d)
  {
    e1[d] = q[3][d] - q[1][d];
    e2[d] = q[2][d] - q[1][d];
  }
  Cross(e1, e2, c.normal[0]);
  Cross(q[2], q[3], c.normal[1]);
  Cross(q[3], q[1], c.normal[2]);
  Cross(q[1], q[2], c.normal[3]);
  const double det = Dot(q[1], c.normal[1]);
  if (!(std::fabs(det) > 0) || !std::isfinite(det))
  {
    return false;
  }
  const double sign = det > 0 ? 1.0 : -1.0;
  for (int k = 0; k < 4; ++k)
  {
    for (int d = 0; d < 3; ++d)
    {
      c.normal[k][d] *= sign;
      c.offset[k][d] = k == 0 ? q[1][d] : 0.0; // faces 1-3 contain the first point
    }
    c.scalar[k] = scalar[k];
  }
  c.scalarLow = std::min(std::min(scalar[0], scalar[1]), std::min(scalar[2], scalar[3]));
  c.scalarHigh = std::max(std::max(scalar[0], scalar[1]), std::max(scalar[2], scalar[3]));
  return true;
}

/// Clips the ray origin + u * direction, u in [0, 1], by the cell; false if it misses.
inline bool Clip(
  const CellPlanes& c, const double origin[3], const double direction[3], Segment& out)
{
  double o[3] = { origin[0] - c.origin[0], origin[1] - c.origin[1], origin[2] - c.origin[2] };
  double enter = 0, exit = 1;
  double num[4], den[4];
  for (int k = 0; k < 4; ++k)
  {
    const double rel[3] = { o[0] - c.offset[k][0], o[1] - c.offset[k][1], o[2] - c.offset[k][2] };
    num[k] = Dot(c.normal[k], rel);
    den[k] = Dot(c.normal[k], direction);
    if (den[k] > 0)
    {
      enter = std::max(enter, -num[k] / den[k]);
    }
    else if (den[k] < 0)
    {
      exit = std::min(exit, -num[k] / den[k]);
    }
    else if (num[k] < 0)
    {
      return false; // parallel to the face, outside it
    }
  }
  if (!(enter < exit))
  {
    return false;
  }
  // Barycentric coordinates are n_k . (x - a_k) / det; their sum is 1, so normalizing by
  // the sum needs no determinant.
  auto scalarAt = [&](double u)
  {
    double weighted = 0, total = 0;
    for (int k = 0; k < 4; ++k)
    {
      const double lambda = std::max(0.0, num[k] + u * den[k]);
      weighted += lambda * c.scalar[k];
      total += lambda;
    }
    const double s = total > 0 ? weighted / total : c.scalar[0];
    return std::min(c.scalarHigh, std::max(c.scalarLow, s));
  };
  out.enter = enter;
  out.exit = exit;
  out.scalarEnter = scalarAt(enter);
  out.scalarExit = scalarAt(exit);
  return true;
}

bool Fail(std::string* error, const std::string& message)
{
  if (error)
  {
    *error = message;
  }
  return false;
}

} // namespace

bool RenderReference(const PointsView& points, const CellsView& cells, const ScalarsView& scalars,
  const ReferenceSettings& settings, std::vector<double>& rgb, int threads, std::string* error,
  ReferenceStats* stats)
{
  const auto start = std::chrono::steady_clock::now();
  const int width = settings.width, height = settings.height;
  if (width <= 0 || height <= 0)
  {
    return Fail(error, "the image size must be positive");
  }
  if (!(settings.unitDistance > 0) || !std::isfinite(settings.unitDistance))
  {
    return Fail(error, "the unit distance must be positive and finite");
  }
  Matrix4 inverseProjection;
  if (!Invert(settings.projection, inverseProjection))
  {
    return Fail(error, "the projection matrix is singular");
  }
  TransferFunctions tf;
  tf.inverseUnit = 1.0 / settings.unitDistance;
  {
    std::vector<ColorNode> color = settings.color;
    std::vector<OpacityNode> opacity = settings.opacity;
    for (const ColorNode& n : color)
    {
      if (!std::isfinite(n.scalar) || !std::isfinite(n.r) || !std::isfinite(n.g) ||
        !std::isfinite(n.b))
      {
        return Fail(error, "a colour node is not finite");
      }
    }
    for (const OpacityNode& n : opacity)
    {
      if (!std::isfinite(n.scalar) || !std::isfinite(n.opacity) || n.opacity < 0)
      {
        return Fail(error, "an opacity node is not finite or negative");
      }
    }
    std::stable_sort(color.begin(), color.end(),
      [](const ColorNode& a, const ColorNode& b) { return a.scalar < b.scalar; });
    std::stable_sort(opacity.begin(), opacity.end(),
      [](const OpacityNode& a, const OpacityNode& b) { return a.scalar < b.scalar; });
    for (const ColorNode& n : color)
    {
      if (!tf.colorScalar.empty() && n.scalar == tf.colorScalar.back())
      {
        continue; // a repeated scalar: the first node wins
      }
      tf.colorScalar.push_back(n.scalar);
      tf.red.push_back(n.r);
      tf.green.push_back(n.g);
      tf.blue.push_back(n.b);
      tf.breaks.push_back(n.scalar);
    }
    for (const OpacityNode& n : opacity)
    {
      if (!tf.opacityScalar.empty() && n.scalar == tf.opacityScalar.back())
      {
        continue;
      }
      tf.opacityScalar.push_back(n.scalar);
      tf.opacity.push_back(n.opacity);
      tf.breaks.push_back(n.scalar);
    }
    std::sort(tf.breaks.begin(), tf.breaks.end());
    tf.breaks.erase(std::unique(tf.breaks.begin(), tf.breaks.end()), tf.breaks.end());
  }

  const int nthreads = detail::ResolveThreads(threads);
  const std::size_t pixelCount = static_cast<std::size_t>(width) * height;
  rgb.assign(3 * pixelCount, 0.0);

  // Points to eye and window coordinates, once; a mesh of parts part after part.
  std::vector<EyePoint> eye(points.count);
  const Matrix4& mv = settings.modelView;
  const Matrix4& p = settings.projection;
  std::vector<PointsView> pointParts;
  for (std::size_t k = 0; k < (points.parts ? points.partCount : 1); ++k)
  {
    pointParts.push_back(points.parts ? points.parts[k].points : points);
  }
  std::size_t first = 0;
  for (const PointsView& part : pointParts)
  {
    const auto partCount = static_cast<std::int64_t>(part.count);
#pragma omp parallel for num_threads(nthreads) schedule(static)
    for (std::int64_t j = 0; j < partCount; ++j)
    {
      double m[3];
      for (int d = 0; d < 3; ++d)
      {
        m[d] = part.type == PointsView::Type::Float32
          ? static_cast<const float*>(part.data)[3 * j + d]
          : static_cast<const double*>(part.data)[3 * j + d];
      }
      EyePoint& e = eye[first + static_cast<std::size_t>(j)];
      double w = 1;
      for (int r = 0; r < 3; ++r)
      {
        e.eye[r] = mv[4 * r] * m[0] + mv[4 * r + 1] * m[1] + mv[4 * r + 2] * m[2] + mv[4 * r + 3];
      }
      w = mv[12] * m[0] + mv[13] * m[1] + mv[14] * m[2] + mv[15];
      for (int r = 0; r < 3; ++r)
      {
        e.eye[r] /= w;
      }
      double clip[4];
      for (int r = 0; r < 4; ++r)
      {
        clip[r] =
          p[4 * r] * e.eye[0] + p[4 * r + 1] * e.eye[1] + p[4 * r + 2] * e.eye[2] + p[4 * r + 3];
      }
      e.clipW = clip[3];
      e.windowX = (clip[0] / clip[3] + 1.0) * 0.5 * width;
      e.windowY = (clip[1] / clip[3] + 1.0) * 0.5 * height;
      e.finite = std::isfinite(e.eye[0]) && std::isfinite(e.eye[1]) && std::isfinite(e.eye[2]) &&
        std::isfinite(w) && w != 0;
    }
    first += part.count;
  }

  // Pixel boxes of the cells, and an estimate of segments per row (box widths) for banding.
  const std::size_t cellCount = cells.cellCount;
  std::vector<PixelBox> boxes(cellCount);
  const bool perCell = scalars.association == ScalarsView::Association::Cells;
  auto cellScalars = [&](std::size_t cell, const std::int64_t ids[4], double s[4])
  {
    for (int k = 0; k < 4; ++k)
    {
      s[k] = scalars.values == nullptr
        ? 0.0
        : static_cast<double>(perCell ? scalars.values[cell] : scalars.values[ids[k]]);
    }
  };
  detail::DispatchCells(cells, points.count,
    [&](const auto& access)
    {
#pragma omp parallel for num_threads(nthreads) schedule(static)
      for (std::int64_t c = 0; c < static_cast<std::int64_t>(cellCount); ++c)
      {
        PixelBox& box = boxes[c];
        box = { 1, 0, 1, 0 };
        std::int64_t ids[4];
        if (!access.TetrahedronPoints(static_cast<std::size_t>(c), ids))
        {
          continue;
        }
        bool inFront = true, finite = true;
        double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
        for (std::int64_t id : ids)
        {
          const EyePoint& e = eye[id];
          finite = finite && e.finite;
          inFront = inFront && e.clipW > 0;
          x0 = std::min(x0, e.windowX);
          x1 = std::max(x1, e.windowX);
          y0 = std::min(y0, e.windowY);
          y1 = std::max(y1, e.windowY);
        }
        if (!finite)
        {
          continue;
        }
        if (!inFront || !(x1 - x0 < 1e300) || !(y1 - y0 < 1e300))
        {
          // The cell reaches the eye plane: its projection is unbounded.
          box = { 0, width - 1, 0, height - 1 };
          continue;
        }
        // Centres x + 0.5 within [x0, x1], one pixel of margin for rounding.
        box.xmin = static_cast<int>(std::max(0.0, std::floor(x0 - 0.5) - 1));
        box.xmax = static_cast<int>(std::min(width - 1.0, std::ceil(x1 - 0.5) + 1));
        box.ymin = static_cast<int>(std::max(0.0, std::floor(y0 - 0.5) - 1));
        box.ymax = static_cast<int>(std::min(height - 1.0, std::ceil(y1 - 0.5) + 1));
        if (x1 < -1.0 || x0 > width + 1.0 || y1 < -1.0 || y0 > height + 1.0)
        {
          box = { 1, 0, 1, 0 };
        }
      }
    });
  std::vector<double> rowEstimate(static_cast<std::size_t>(height) + 1, 0.0);
  for (const PixelBox& b : boxes)
  {
    if (b.xmin <= b.xmax && b.ymin <= b.ymax)
    {
      rowEstimate[b.ymin] += b.xmax - b.xmin + 1;
      rowEstimate[b.ymax + 1] -= b.xmax - b.xmin + 1;
    }
  }

  // The rays: origin on the near plane, direction to the far plane, both in eye
  // coordinates, from the window point through the inverse projection.
  auto ray = [&](int x, int y, double origin[3], double direction[3])
  {
    const double nx = 2.0 * (x + 0.5 + PixelOffsetX) / width - 1.0;
    const double ny = 2.0 * (y + 0.5 + PixelOffsetY) / height - 1.0;
    double nearPoint[3], farPoint[3];
    for (int end = 0; end < 2; ++end)
    {
      const double nz = end == 0 ? -1.0 : 1.0;
      double h[4];
      for (int r = 0; r < 4; ++r)
      {
        h[r] = inverseProjection[4 * r] * nx + inverseProjection[4 * r + 1] * ny +
          inverseProjection[4 * r + 2] * nz + inverseProjection[4 * r + 3];
      }
      double* out = end == 0 ? nearPoint : farPoint;
      for (int d = 0; d < 3; ++d)
      {
        out[d] = h[d] / h[3];
      }
    }
    for (int d = 0; d < 3; ++d)
    {
      origin[d] = nearPoint[d];
      direction[d] = farPoint[d] - nearPoint[d];
    }
  };

  std::vector<std::uint32_t> counts;
  std::vector<std::size_t> offsets;
  std::vector<Segment> segments;
  std::size_t totalSegments = 0, passes = 0;
  int bandStart = 0;
  double running = 0;
  while (bandStart < height)
  {
    // The band: rows while the estimate stays below the budget (at least one row).
    int bandEnd = bandStart;
    double estimate = 0;
    {
      double r = running;
      while (bandEnd < height)
      {
        r += rowEstimate[bandEnd];
        const double next = estimate + r * 1.0;
        if (bandEnd > bandStart && next > static_cast<double>(settings.maxSegmentsPerPass))
        {
          r -= rowEstimate[bandEnd];
          break;
        }
        estimate = next;
        ++bandEnd;
      }
      running = r;
    }
    ++passes;
    const std::size_t bandPixels = static_cast<std::size_t>(bandEnd - bandStart) * width;
    counts.assign(bandPixels, 0);

    // Two passes over the cells that reach the band: count, then fill.
    for (int fill = 0; fill < 2; ++fill)
    {
      if (fill == 1)
      {
        offsets.assign(bandPixels + 1, 0);
        for (std::size_t i = 0; i < bandPixels; ++i)
        {
          offsets[i + 1] = offsets[i] + counts[i];
        }
        segments.resize(offsets[bandPixels]);
        std::fill(counts.begin(), counts.end(), 0);
      }
      detail::DispatchCells(cells, points.count,
        [&](const auto& access)
        {
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 256)
          for (std::int64_t c = 0; c < static_cast<std::int64_t>(cellCount); ++c)
          {
            const PixelBox& box = boxes[c];
            if (box.xmin > box.xmax || box.ymax < bandStart || box.ymin >= bandEnd)
            {
              continue;
            }
            std::int64_t ids[4];
            access.TetrahedronPoints(static_cast<std::size_t>(c), ids);
            double s[4];
            cellScalars(static_cast<std::size_t>(c), ids, s);
            CellPlanes planes;
            if (!SetUpCell(eye.data(), ids, s, planes))
            {
              continue;
            }
            const int y0 = std::max(box.ymin, bandStart), y1 = std::min(box.ymax, bandEnd - 1);
            for (int y = y0; y <= y1; ++y)
            {
              for (int x = box.xmin; x <= box.xmax; ++x)
              {
                double origin[3], direction[3];
                ray(x, y, origin, direction);
                Segment segment;
                if (!Clip(planes, origin, direction, segment))
                {
                  continue;
                }
                const std::size_t pixel = static_cast<std::size_t>(y - bandStart) * width + x;
                std::uint32_t slot;
#pragma omp atomic capture
                slot = counts[pixel]++;
                if (fill == 1)
                {
                  segments[offsets[pixel] + slot] = segment;
                }
              }
            }
          }
        });
    }
    totalSegments += segments.size();

    // Per pixel: sort by depth, integrate front to back, then the background.
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 64)
    for (std::int64_t i = 0; i < static_cast<std::int64_t>(bandPixels); ++i)
    {
      Segment* begin = segments.data() + offsets[i];
      Segment* end = segments.data() + offsets[i + 1];
      std::sort(begin, end);
      const int x = static_cast<int>(i % width);
      const int y = bandStart + static_cast<int>(i / width);
      double origin[3], direction[3];
      ray(x, y, origin, direction);
      const double scale = std::sqrt(Dot(direction, direction));
      RayState state;
      for (Segment* s = begin; s != end && !state.Done(); ++s)
      {
        IntegrateSegment(tf, (s->exit - s->enter) * scale, s->scalarEnter, s->scalarExit, state);
      }
      double* out = rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x);
      for (int k = 0; k < 3; ++k)
      {
        out[k] = state.color[k] + state.transmittance * settings.background[k];
      }
    }
    bandStart = bandEnd;
  }
  if (stats)
  {
    stats->segments = totalSegments;
    stats->passes = passes;
    stats->seconds = detail::SecondsSince(start);
  }
  return true;
}

ImageError CompareImages(const double* a, const double* b, std::size_t pixels)
{
  ImageError e;
  double sum = 0;
  for (std::size_t i = 0; i < pixels; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      const double d = std::fabs(a[3 * i + k] - b[3 * i + k]);
      sum += d * d;
      if (d > e.maxAbs)
      {
        e.maxAbs = d;
        e.worstPixel = i;
      }
    }
  }
  e.rmse = pixels > 0 ? std::sqrt(sum / (3.0 * static_cast<double>(pixels))) : 0.0;
  e.psnr = e.rmse > 0 ? -20.0 * std::log10(e.rmse) : std::numeric_limits<double>::infinity();
  return e;
}

} // namespace mtpt
