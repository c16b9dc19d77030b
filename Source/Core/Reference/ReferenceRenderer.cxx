// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/ReferenceRenderer.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

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
/// plane) and the values of the data's C channels at both ends (ScalarMapping).
template <int C>
struct Segment
{
  double enter, exit, front[C], back[C];
  std::uint32_t cell; ///< the cell it crosses (its lighting)
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
    for (int k = 0; k < C; ++k)
    {
      if (this->front[k] != o.front[k])
      {
        return this->front[k] < o.front[k];
      }
    }
    for (int k = 0; k < C; ++k)
    {
      if (this->back[k] != o.back[k])
      {
        return this->back[k] < o.back[k];
      }
    }
    return this->cell < o.cell;
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
  double Tau(double s) const { return this->Opacity(s) * this->inverseUnit; }

  /// The opacity function o(s).
  double Opacity(double s) const
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
    return o;
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

/**
 * Dependent components, colour scalar and opacity scalar: along the segment the colour
 * scalar runs linearly from c0 to c1 and the opacity scalar from o0 to o1. Split where
 * either crosses a node of its function: on each piece colour and extinction are linear.
 */
void IntegrateColourAndOpacity(const TransferFunctions& tf, double length, double c0, double c1,
  double o0, double o1, RayState& ray)
{
  if (!(length > 0))
  {
    return;
  }
  thread_local std::vector<double> cuts;
  cuts.assign({ 0.0, 1.0 });
  auto addCuts = [](const std::vector<double>& nodes, double v0, double v1)
  {
    const double low = std::min(v0, v1), high = std::max(v0, v1);
    for (auto it = std::upper_bound(nodes.begin(), nodes.end(), low);
         it != nodes.end() && *it < high; ++it)
    {
      cuts.push_back((*it - v0) / (v1 - v0));
    }
  };
  addCuts(tf.colorScalar, c0, c1);
  addCuts(tf.opacityScalar, o0, o1);
  std::sort(cuts.begin(), cuts.end());
  double colourStart[3];
  tf.Color(c0, colourStart);
  double tauStart = tf.Tau(o0);
  for (std::size_t j = 1; j < cuts.size() && !ray.Done(); ++j)
  {
    const double f = cuts[j];
    double colourEnd[3];
    tf.Color(c0 + f * (c1 - c0), colourEnd);
    const double tauEnd = tf.Tau(o0 + f * (o1 - o0));
    const double pieceLength = (f - cuts[j - 1]) * length;
    if (pieceLength > 0)
    {
      IntegratePiece(pieceLength, colourStart, colourEnd, tauStart, tauEnd, ray);
    }
    std::copy(colourEnd, colourEnd + 3, colourStart);
    tauStart = tauEnd;
  }
}

/// Dependent components, colours: RGB and attenuation run linearly from `front` to `back`
/// (each clamped to [0, 1], as the mapper clamps them).
void IntegrateColours(const TransferFunctions& tf, double length, const double front[4],
  const double back[4], RayState& ray)
{
  if (!(length > 0))
  {
    return;
  }
  auto unit = [](double v) { return std::min(1.0, std::max(0.0, v)); };
  const double c0[3] = { unit(front[0]), unit(front[1]), unit(front[2]) };
  const double c1[3] = { unit(back[0]), unit(back[1]), unit(back[2]) };
  IntegratePiece(
    length, c0, c1, unit(front[3]) * tf.inverseUnit, unit(back[3]) * tf.inverseUnit, ray);
}

/// The segment integrated as its mapping says (one overload per channel count).
inline void Integrate(
  const TransferFunctions& tf, double length, const Segment<1>& s, RayState& ray)
{
  IntegrateSegment(tf, length, s.front[0], s.back[0], ray);
}
inline void Integrate(
  const TransferFunctions& tf, double length, const Segment<2>& s, RayState& ray)
{
  IntegrateColourAndOpacity(tf, length, s.front[0], s.back[0], s.front[1], s.back[1], ray);
}
inline void Integrate(
  const TransferFunctions& tf, double length, const Segment<4>& s, RayState& ray)
{
  IntegrateColours(tf, length, s.front, s.back, ray);
}

/// A cell prepared for ray clipping: face planes through its first point's frame.
struct CellPlanes
{
  double origin[3];       ///< eye coordinates of the first point
  double normal[4][3];    ///< inward normal of the face opposite point k, times |det|
  double offset[4][3];    ///< a point of that face, relative to the first point
  double value[4][4];     ///< per point, the data's channels (ScalarMapping)
  double low[4], high[4]; ///< per channel, over the points
};

/// Sets up `cell` (points ids[0..3], the first `channels` of `values` per point); false if it
/// has no volume or is not finite.
bool SetUpCell(const EyePoint* eye, const std::int64_t ids[4], const double values[4][4],
  int channels, CellPlanes& c)
{
  for (int k = 0; k < 4; ++k)
  {
    bool finite = eye[ids[k]].finite;
    for (int ch = 0; ch < channels; ++ch)
    {
      finite = finite && std::isfinite(values[k][ch]);
    }
    if (!finite)
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
  Cross3(e1, e2, c.normal[0]);
  Cross3(q[2], q[3], c.normal[1]);
  Cross3(q[3], q[1], c.normal[2]);
  Cross3(q[1], q[2], c.normal[3]);
  const double det = Dot3(q[1], c.normal[1]);
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
    for (int ch = 0; ch < channels; ++ch)
    {
      c.value[k][ch] = values[k][ch];
    }
  }
  for (int ch = 0; ch < channels; ++ch)
  {
    const double* v[4] = { &values[0][ch], &values[1][ch], &values[2][ch], &values[3][ch] };
    c.low[ch] = std::min(std::min(*v[0], *v[1]), std::min(*v[2], *v[3]));
    c.high[ch] = std::max(std::max(*v[0], *v[1]), std::max(*v[2], *v[3]));
  }
  return true;
}

/// Clips the ray origin + u * direction, u in [0, 1], by the cell; false if it misses.
template <int C>
inline bool Clip(
  const CellPlanes& c, const double origin[3], const double direction[3], Segment<C>& out)
{
  double o[3] = { origin[0] - c.origin[0], origin[1] - c.origin[1], origin[2] - c.origin[2] };
  double enter = 0, exit = 1;
  double num[4], den[4];
  for (int k = 0; k < 4; ++k)
  {
    const double rel[3] = { o[0] - c.offset[k][0], o[1] - c.offset[k][1], o[2] - c.offset[k][2] };
    num[k] = Dot3(c.normal[k], rel);
    den[k] = Dot3(c.normal[k], direction);
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
  auto valuesAt = [&](double u, double values[C])
  {
    double weighted[C] = {}, total = 0;
    for (int k = 0; k < 4; ++k)
    {
      const double lambda = std::max(0.0, num[k] + u * den[k]);
      for (int ch = 0; ch < C; ++ch)
      {
        weighted[ch] += lambda * c.value[k][ch];
      }
      total += lambda;
    }
    for (int ch = 0; ch < C; ++ch)
    {
      const double v = total > 0 ? weighted[ch] / total : c.value[0][ch];
      values[ch] = std::min(c.high[ch], std::max(c.low[ch], v));
    }
  };
  out.enter = enter;
  out.exit = exit;
  valuesAt(enter, out.front);
  valuesAt(exit, out.back);
  return true;
}

/// Each cell's lighting (ReferenceSettings::normals), lit at its centroid; empty without
/// normals, or when shading does not apply (other mappings and blend modes).
std::vector<LightFactors> CellLights(const CellsView& cells, std::size_t pointCount,
  const std::vector<EyePoint>& eye, const ReferenceSettings& s)
{
  std::vector<LightFactors> lights;
  double normalMatrix[9];
  if (!s.normals || s.mapping != ScalarMapping::TransferFunctions ||
    s.blendMode != BlendMode::Composite || !NormalMatrix(s.modelView, normalMatrix))
  {
    return lights;
  }
  lights.assign(cells.cellCount, Unlit());
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      for (std::size_t c = 0; c < cells.cellCount; ++c)
      {
        std::int64_t ids[4];
        if (!access.TetrahedronPoints(c, ids))
        {
          continue;
        }
        double corners[4][3];
        for (int i = 0; i < 4; ++i)
        {
          std::copy(eye[ids[i]].eye, eye[ids[i]].eye + 3, corners[i]);
        }
        lights[c] = LightTetrahedron(s.lighting, normalMatrix, s.normals + 3 * c, corners);
      }
    });
  return lights;
}

bool Fail(std::string* error, const std::string& message)
{
  if (error)
  {
    *error = message;
  }
  return false;
}

/// The transfer functions of `settings` as sorted node arrays; false (with `error`) when a
/// node is not finite or an opacity is negative.
bool BuildTransferFunctions(
  const ReferenceSettings& settings, TransferFunctions& tf, std::string* error)
{
  tf.inverseUnit = 1.0 / settings.unitDistance;
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
  return true;
}

/// Every point to eye and window coordinates, once; a mesh of parts part after part.
std::vector<EyePoint> EyePoints(
  const PointsView& points, const ReferenceSettings& settings, int nthreads)
{
  std::vector<EyePoint> eye(points.count);
  const Matrix4& mv = settings.modelView;
  const Matrix4& p = settings.projection;
  const int width = settings.width, height = settings.height;
  std::vector<PointsView> pointParts;
  for (std::size_t k = 0; k < (points.parts ? points.partCount : 1); ++k)
  {
    pointParts.push_back(points.parts ? points.parts[k].points : points);
  }
  std::size_t first = 0;
  for (const PointsView& part : pointParts)
  {
    const auto partCount = static_cast<std::int64_t>(part.count);
    detail::ParallelFor(0, partCount, nthreads,
      [&](std::int64_t j)
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
      });
    first += part.count;
  }
  return eye;
}

/// The pixels whose rays may cross each cell (empty for cells that cannot be integrated or
/// lie outside the image; the whole image for cells reaching the eye plane).
std::vector<PixelBox> PixelBoxes(const CellsView& cells, std::size_t pointCount,
  const std::vector<EyePoint>& eye, int width, int height, int nthreads)
{
  const std::size_t cellCount = cells.cellCount;
  std::vector<PixelBox> boxes(cellCount);
  detail::DispatchCells(cells, pointCount,
    [&](const auto& access)
    {
      detail::ParallelFor(0, static_cast<std::int64_t>(cellCount), nthreads,
        [&](std::int64_t c)
        {
          PixelBox& box = boxes[c];
          box = { 1, 0, 1, 0 };
          std::int64_t ids[4];
          if (!access.TetrahedronPoints(static_cast<std::size_t>(c), ids))
          {
            return;
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
            return;
          }
          if (!inFront || !(x1 - x0 < 1e300) || !(y1 - y0 < 1e300))
          {
            // The cell reaches the eye plane: its projection is unbounded.
            box = { 0, width - 1, 0, height - 1 };
            return;
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
        });
    });
  return boxes;
}

/// The rays: origin on the near plane, direction to the far plane, both in eye
/// coordinates, from the window point through the inverse projection.
struct Rays
{
  Matrix4 inverseProjection;
  int width, height;

  void operator()(int x, int y, double origin[3], double direction[3]) const
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
  }
};

/// A ray's crossing of a translucent triangle: its ray parameter and the triangle.
struct Hit
{
  double u;
  const ReferenceTriangle* triangle;
  bool operator<(const Hit& o) const
  {
    // A total order (the triangle's position in the list breaks ties): deterministic.
    return this->u != o.u ? this->u < o.u : this->triangle < o.triangle;
  }
};

/// The ray parameter in [0, 1] where origin + u * direction crosses triangle `t`, or a
/// negative value if it misses (Moeller-Trumbore, in double).
double CrossTriangle(const ReferenceTriangle& t, const double origin[3], const double direction[3])
{
  double e1[3], e2[3], s[3];
  for (int d = 0; d < 3; ++d)
  {
    e1[d] = t.eye[1][d] - t.eye[0][d];
    e2[d] = t.eye[2][d] - t.eye[0][d];
    s[d] = origin[d] - t.eye[0][d];
  }
  double p[3], q[3];
  Cross3(direction, e2, p);
  const double det = Dot3(e1, p);
  if (!(std::fabs(det) > 0) || !std::isfinite(det))
  {
    return -1; // parallel to the triangle, or degenerate
  }
  const double inverse = 1.0 / det;
  const double a = Dot3(s, p) * inverse;
  Cross3(s, e1, q);
  const double b = Dot3(direction, q) * inverse;
  const double u = Dot3(e2, q) * inverse;
  const bool inside = a >= 0 && b >= 0 && a + b <= 1 && u >= 0 && u <= 1;
  return inside ? u : -1;
}

/// The pixels whose rays may cross each triangle (as PixelBoxes for cells).
std::vector<PixelBox> TriangleBoxes(const ReferenceSettings& settings)
{
  const Matrix4& p = settings.projection;
  const int width = settings.width, height = settings.height;
  std::vector<PixelBox> boxes;
  for (const ReferenceTriangle& t : settings.triangles)
  {
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    bool inFront = true;
    for (const auto& e : t.eye)
    {
      double clip[4];
      for (int r = 0; r < 4; ++r)
      {
        clip[r] = p[4 * r] * e[0] + p[4 * r + 1] * e[1] + p[4 * r + 2] * e[2] + p[4 * r + 3];
      }
      inFront = inFront && clip[3] > 0;
      const double wx = (clip[0] / clip[3] + 1.0) * 0.5 * width;
      const double wy = (clip[1] / clip[3] + 1.0) * 0.5 * height;
      x0 = std::min(x0, wx), x1 = std::max(x1, wx), y0 = std::min(y0, wy), y1 = std::max(y1, wy);
    }
    PixelBox box{ 0, width - 1, 0, height - 1 }; // reaching the eye plane: every pixel
    if (inFront && x1 - x0 < 1e300 && y1 - y0 < 1e300)
    {
      box.xmin = static_cast<int>(std::max(0.0, std::floor(x0 - 0.5) - 1));
      box.xmax = static_cast<int>(std::min(width - 1.0, std::ceil(x1 - 0.5) + 1));
      box.ymin = static_cast<int>(std::max(0.0, std::floor(y0 - 0.5) - 1));
      box.ymax = static_cast<int>(std::min(height - 1.0, std::ceil(y1 - 0.5) + 1));
    }
    boxes.push_back(box);
  }
  return boxes;
}

/// Everything the bands of one image share.
struct Scene
{
  const CellsView& cells;
  std::size_t pointCount;
  const ScalarsView& scalars;
  const ReferenceSettings& settings;
  const TransferFunctions& tf;
  const std::vector<EyePoint>& eye;
  const std::vector<PixelBox>& boxes;
  const std::vector<PixelBox>& triangleBoxes;
  Rays ray;
  int nthreads;
  const std::vector<LightFactors>& lights; ///< per cell (ReferenceSettings::normals); empty: none

  /// The first `channels` values of the cell's points (values[k] of point ids[k]).
  void CellValues(
    std::size_t cell, const std::int64_t ids[4], int channels, double values[4][4]) const
  {
    const bool perCell = this->scalars.association == ScalarsView::Association::Cells;
    for (int k = 0; k < 4; ++k)
    {
      const std::size_t tuple = perCell ? cell : static_cast<std::size_t>(ids[k]);
      for (int ch = 0; ch < channels; ++ch)
      {
        values[k][ch] = this->scalars.values == nullptr
          ? 0.0
          : static_cast<double>(this->scalars.values[channels * tuple + ch]);
      }
    }
  }
};

/// Rows [bandStart, end) whose estimated segments stay within `budget` (at least one row);
/// `running` carries the row estimate's prefix from row to row.
int BandEnd(
  const std::vector<double>& rowEstimate, int bandStart, int height, double budget, double& running)
{
  int bandEnd = bandStart;
  double estimate = 0;
  double r = running;
  while (bandEnd < height)
  {
    r += rowEstimate[bandEnd];
    const double next = estimate + r * 1.0;
    if (bandEnd > bandStart && next > budget)
    {
      r -= rowEstimate[bandEnd];
      break;
    }
    estimate = next;
    ++bandEnd;
  }
  running = r;
  return bandEnd;
}

/// The segments of the band's pixels, pixel after pixel (`offsets` per pixel, +1): two
/// passes over the cells that reach the band, counting, then filling.
template <int C>
void GatherSegments(const Scene& scene, int bandStart, int bandEnd,
  std::vector<std::size_t>& offsets, std::vector<Segment<C>>& segments)
{
  const int width = scene.settings.width;
  const std::size_t bandPixels = static_cast<std::size_t>(bandEnd - bandStart) * width;
  std::vector<std::uint32_t> counts(bandPixels, 0);
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
    detail::DispatchCells(scene.cells, scene.pointCount,
      [&](const auto& access)
      {
        // Cells of uneven work (their boxes' pixels) in chunks of 256.
        detail::ParallelForDynamic(
          static_cast<std::int64_t>(scene.cells.cellCount), scene.nthreads,
          [&](std::int64_t c, int)
          {
            const PixelBox& box = scene.boxes[c];
            if (box.xmin > box.xmax || box.ymax < bandStart || box.ymin >= bandEnd)
            {
              return;
            }
            std::int64_t ids[4];
            access.TetrahedronPoints(static_cast<std::size_t>(c), ids);
            double values[4][4];
            scene.CellValues(static_cast<std::size_t>(c), ids, C, values);
            CellPlanes planes;
            if (!SetUpCell(scene.eye.data(), ids, values, C, planes))
            {
              return;
            }
            const int y0 = std::max(box.ymin, bandStart), y1 = std::min(box.ymax, bandEnd - 1);
            for (int y = y0; y <= y1; ++y)
            {
              for (int x = box.xmin; x <= box.xmax; ++x)
              {
                double origin[3], direction[3];
                scene.ray(x, y, origin, direction);
                Segment<C> segment;
                if (!Clip(planes, origin, direction, segment))
                {
                  continue;
                }
                segment.cell = static_cast<std::uint32_t>(c);
                const std::size_t pixel = static_cast<std::size_t>(y - bandStart) * width + x;
                const std::uint32_t slot = detail::FetchAdd(counts[pixel], 1u);
                if (fill == 1)
                {
                  segments[offsets[pixel] + slot] = segment;
                }
              }
            }
          },
          256);
      });
  }
}

/// The translucent triangles' crossings of the band's pixels, pixel after pixel
/// (`offsets` per pixel, +1), each pixel's sorted by depth.
void GatherHits(const Scene& scene, int bandStart, int bandEnd, std::vector<std::size_t>& offsets,
  std::vector<Hit>& hits)
{
  const int width = scene.settings.width;
  const std::size_t bandPixels = static_cast<std::size_t>(bandEnd - bandStart) * width;
  offsets.assign(bandPixels + 1, 0);
  hits.clear();
  if (scene.settings.triangles.empty())
  {
    return;
  }
  std::vector<std::vector<Hit>> perPixel(bandPixels);
  for (std::size_t t = 0; t < scene.settings.triangles.size(); ++t)
  {
    const PixelBox& box = scene.triangleBoxes[t];
    const int y0 = std::max(box.ymin, bandStart), y1 = std::min(box.ymax, bandEnd - 1);
    for (int y = y0; y <= y1; ++y)
    {
      for (int x = box.xmin; x <= box.xmax; ++x)
      {
        double origin[3], direction[3];
        scene.ray(x, y, origin, direction);
        const double u = CrossTriangle(scene.settings.triangles[t], origin, direction);
        if (u >= 0)
        {
          perPixel[static_cast<std::size_t>(y - bandStart) * width + x].push_back(
            { u, &scene.settings.triangles[t] });
        }
      }
    }
  }
  for (std::size_t i = 0; i < bandPixels; ++i)
  {
    std::sort(perPixel[i].begin(), perPixel[i].end());
    hits.insert(hits.end(), perPixel[i].begin(), perPixel[i].end());
    offsets[i + 1] = hits.size();
  }
}

/// Composites a translucent surface: colour += T a c, T *= 1 - a.
inline void CompositeHit(const Hit& hit, RayState& ray)
{
  const ReferenceTriangle& t = *hit.triangle;
  for (int k = 0; k < 3; ++k)
  {
    ray.color[k] += ray.transmittance * t.opacity * t.rgb[k];
  }
  ray.transmittance *= 1.0 - t.opacity;
}

/**
 * A segment integrated as Integrate does, lit by `light` (null: unlit): on its own, its
 * colour C and opacity A become clamp(scale C + offset A, 0, A) before it is composited.
 */
template <int C>
void IntegrateLit(const TransferFunctions& tf, double length, const Segment<C>& s,
  const LightFactors* light, RayState& ray)
{
  if (!light)
  {
    Integrate(tf, length, s, ray);
    return;
  }
  RayState own;
  Integrate(tf, length, s, own);
  const double alpha = 1.0 - own.transmittance;
  for (int k = 0; k < 3; ++k)
  {
    const double lit = light->scale[k] * own.color[k] + light->offset[k] * alpha;
    ray.color[k] += ray.transmittance * std::min(std::max(lit, 0.0), alpha);
  }
  ray.transmittance *= own.transmittance;
  ray.depth += own.depth;
}

/// The segments and surface crossings of one ray, front to back: a crossing inside a
/// segment splits it there (the data's values interpolated linearly at the split).
/// `lights`: each cell's lighting (null: unlit).
template <int C>
void IntegrateRay(const TransferFunctions& tf, double scale, const Segment<C>* begin,
  const Segment<C>* end, const Hit* hit, const Hit* lastHit, const LightFactors* lights,
  RayState& state)
{
  for (const Segment<C>* s = begin; s != end && !state.Done(); ++s)
  {
    for (; hit != lastHit && hit->u <= s->enter; ++hit)
    {
      CompositeHit(*hit, state);
    }
    const LightFactors* light = lights ? lights + s->cell : nullptr;
    Segment<C> rest = *s;
    for (; hit != lastHit && hit->u < rest.exit; ++hit)
    {
      const double f = (hit->u - rest.enter) / (rest.exit - rest.enter);
      Segment<C> part = rest;
      part.exit = hit->u;
      for (int k = 0; k < C; ++k)
      {
        part.back[k] = rest.front[k] + f * (rest.back[k] - rest.front[k]);
      }
      IntegrateLit(tf, (part.exit - part.enter) * scale, part, light, state);
      rest.enter = part.exit;
      std::copy(part.back, part.back + C, rest.front);
      CompositeHit(*hit, state);
    }
    IntegrateLit(tf, (rest.exit - rest.enter) * scale, rest, light, state);
  }
  for (; hit != lastHit; ++hit)
  {
    CompositeHit(*hit, state);
  }
}

/**
 * The stretch [low, high] of the ray origin + u direction that every clipping plane keeps;
 * low > high when none does.
 */
void KeptStretch(const ClipPlanes& planes, const double origin[3], const double direction[3],
  double& low, double& high)
{
  low = -std::numeric_limits<double>::infinity();
  high = std::numeric_limits<double>::infinity();
  for (int i = 0; i < planes.count; ++i)
  {
    const double* p = planes.plane[i];
    const double at = p[0] * origin[0] + p[1] * origin[1] + p[2] * origin[2] + p[3];
    const double slope = p[0] * direction[0] + p[1] * direction[1] + p[2] * direction[2];
    if (slope > 0.0)
    {
      low = std::max(low, -at / slope);
    }
    else if (slope < 0.0)
    {
      high = std::min(high, -at / slope);
    }
    else if (at < 0.0)
    {
      low = 1.0; // parallel to the plane on its clipped side
      high = 0.0;
    }
  }
}

/// Cuts the segments [begin, end) (sorted) to the stretch [low, high] of the ray: a part
/// left out gets no length, a cut end the values interpolated there.
template <int C>
void CutSegments(Segment<C>* begin, Segment<C>* end, double low, double high)
{
  for (Segment<C>* s = begin; s != end; ++s)
  {
    const double from = std::max(s->enter, low), to = std::min(s->exit, high);
    if (!(from < to))
    {
      s->exit = s->enter;
      continue;
    }
    const double span = s->exit - s->enter;
    const double f0 = (from - s->enter) / span, f1 = (to - s->enter) / span;
    for (int k = 0; k < C; ++k)
    {
      const double front = s->front[k], difference = s->back[k] - s->front[k];
      s->front[k] = from > s->enter ? front + f0 * difference : front;
      s->back[k] = to < s->exit ? front + f1 * difference : s->back[k];
    }
    s->enter = from;
    s->exit = to;
  }
}

/// A ray's segments reduced by a blend mode other than Composite (ReferenceSettings).
struct Reduction
{
  bool seen = false;
  double extreme = 0, weighted = 0, length = 0;
};

/// Integrals of o x over a segment of `length` whose scalar runs linearly between `low` and
/// `high` (in either direction): split at every breakpoint of o, of the clamping and of the
/// average's range, so that on each piece the clamped scalar is linear and o x quadratic.
void IntegrateIntensity(const Scene& scene, double length, double low, double high, Reduction& r)
{
  const ReferenceSettings& s = scene.settings;
  const double lo = s.scalarRange[0], hi = s.scalarRange[1];
  const double span = hi > lo ? hi - lo : 1.0;
  auto clamped = [&](double v) { return std::min(hi, std::max(lo, v)); };
  auto ox = [&](double v)
  {
    const double c = clamped(v);
    return scene.tf.Opacity(c) * (c - lo) / span;
  };
  const bool average = s.blendMode == BlendMode::AverageIntensity;
  auto inRange = [&](double v)
  {
    const double c = clamped(v);
    return !average || (s.averageRange[0] <= c && c <= s.averageRange[1]);
  };
  if (!(high > low))
  {
    if (inRange(low))
    {
      r.weighted += length * ox(low);
      r.length += length;
    }
    return;
  }
  // The clamping's and the range's ends inside (low, high), in order, and the transfer
  // functions' breakpoints there (as IntegrateSegment finds them): the pieces' ends.
  double extra[4];
  int extras = 0;
  for (double v : { lo, hi, s.averageRange[0], s.averageRange[1] })
  {
    if (v > low && v < high)
    {
      extra[extras++] = v;
    }
  }
  std::sort(extra, extra + extras);
  auto next = std::upper_bound(scene.tf.breaks.begin(), scene.tf.breaks.end(), low);
  const auto last = std::lower_bound(next, scene.tf.breaks.end(), high);
  int e = 0;
  for (double a = low; a < high;)
  {
    double b = high;
    if (next != last && *next < b)
    {
      b = *next;
    }
    if (e < extras && extra[e] < b)
    {
      b = extra[e];
    }
    while (next != last && *next <= b)
    {
      ++next;
    }
    while (e < extras && extra[e] <= b)
    {
      ++e;
    }
    if (inRange(0.5 * (a + b)))
    {
      const double piece = length * (b - a) / (high - low);
      r.weighted += piece / 6.0 * (ox(a) + 4.0 * ox(0.5 * (a + b)) + ox(b));
      r.length += piece;
    }
    a = b;
  }
}

/// Folds one segment into the ray's reduction.
void ReduceSegment(const Scene& scene, double length, double front, double back, Reduction& r)
{
  const ReferenceSettings& s = scene.settings;
  const double low = std::min(front, back), high = std::max(front, back);
  const double lo = s.scalarRange[0], hi = s.scalarRange[1];
  switch (s.blendMode)
  {
    case BlendMode::MaximumIntensity:
      r.extreme = r.seen ? std::max(r.extreme, high) : high;
      break;
    case BlendMode::MinimumIntensity:
      r.extreme = r.seen ? std::min(r.extreme, low) : low;
      break;
    case BlendMode::AverageIntensity:
    case BlendMode::Additive:
      IntegrateIntensity(scene, length, low, high, r);
      break;
    case BlendMode::Composite:
      break;
  }
  r.extreme = std::min(hi, std::max(lo, r.extreme));
  r.seen = true;
}

/// The pixel of a reduced ray over the background (linear RGB).
void ReducedPixel(const Scene& scene, const Reduction& r, double out[3])
{
  const ReferenceSettings& s = scene.settings;
  double colour[3] = { 0, 0, 0 }, alpha = 0;
  if (s.blendMode == BlendMode::MaximumIntensity || s.blendMode == BlendMode::MinimumIntensity)
  {
    if (r.seen)
    {
      scene.tf.Color(r.extreme, colour);
      alpha = std::min(1.0, std::max(0.0, scene.tf.Opacity(r.extreme)));
      for (double& c : colour)
      {
        c *= alpha;
      }
    }
  }
  else if (r.seen && (s.blendMode == BlendMode::Additive || r.length > 0))
  {
    const double value = s.blendMode == BlendMode::Additive ? r.weighted * scene.tf.inverseUnit
                                                            : r.weighted / r.length;
    colour[0] = colour[1] = colour[2] = std::min(1.0, std::max(0.0, value));
    alpha = 1;
  }
  for (int k = 0; k < 3; ++k)
  {
    out[k] = colour[k] + (1 - alpha) * s.background[k];
  }
}

/// Per pixel of the band: its segments sorted by depth, integrated front to back with the
/// translucent surfaces it crosses, then the background.
template <int C>
void IntegratePixels(const Scene& scene, int bandStart, int bandEnd,
  const std::vector<std::size_t>& offsets, std::vector<Segment<C>>& segments, double* rgb)
{
  std::vector<std::size_t> hitOffsets;
  std::vector<Hit> hits;
  GatherHits(scene, bandStart, bandEnd, hitOffsets, hits);
  const int width = scene.settings.width;
  const std::size_t bandPixels = static_cast<std::size_t>(bandEnd - bandStart) * width;
  // Pixels of uneven work (their segments) in chunks of 64.
  detail::ParallelForDynamic(
    static_cast<std::int64_t>(bandPixels), scene.nthreads,
    [&](std::int64_t i, int)
    {
      Segment<C>* begin = segments.data() + offsets[i];
      Segment<C>* end = segments.data() + offsets[i + 1];
      std::sort(begin, end);
      const int x = static_cast<int>(i % width);
      const int y = bandStart + static_cast<int>(i / width);
      double origin[3], direction[3];
      scene.ray(x, y, origin, direction);
      const double scale = std::sqrt(Dot3(direction, direction));
      if (scene.settings.clipPlanes.count > 0)
      {
        double low, high;
        KeptStretch(scene.settings.clipPlanes, origin, direction, low, high);
        CutSegments(begin, end, low, high);
      }
      double* out = rgb + 3 * (static_cast<std::size_t>(y) * width + x);
      if constexpr (C == 1)
      {
        if (scene.settings.blendMode != BlendMode::Composite)
        {
          Reduction reduction;
          for (const Segment<C>* s = begin; s != end; ++s)
          {
            if (s->exit > s->enter)
            {
              ReduceSegment(
                scene, (s->exit - s->enter) * scale, s->front[0], s->back[0], reduction);
            }
          }
          ReducedPixel(scene, reduction, out);
          return;
        }
      }
      RayState state;
      IntegrateRay(scene.tf, scale, begin, end, hits.data() + hitOffsets[i],
        hits.data() + hitOffsets[i + 1], scene.lights.empty() ? nullptr : scene.lights.data(),
        state);
      for (int k = 0; k < 3; ++k)
      {
        out[k] = state.color[k] + state.transmittance * scene.settings.background[k];
      }
    },
    64);
}

/// The image in bands of rows that keep the gathered segments within the settings' budget.
template <int C>
void IntegrateBands(const Scene& scene, double* rgb, ReferenceStats& stats)
{
  const int height = scene.settings.height;
  // Segments per row, from the cells' box widths.
  std::vector<double> rowEstimate(static_cast<std::size_t>(height) + 1, 0.0);
  for (const PixelBox& b : scene.boxes)
  {
    if (b.xmin <= b.xmax && b.ymin <= b.ymax)
    {
      rowEstimate[b.ymin] += b.xmax - b.xmin + 1;
      rowEstimate[b.ymax + 1] -= b.xmax - b.xmin + 1;
    }
  }
  // The budget is in bytes of the scalar mapping's segments.
  const double budget = static_cast<double>(scene.settings.maxSegmentsPerPass) *
    sizeof(Segment<1>) / sizeof(Segment<C>);
  std::vector<std::size_t> offsets;
  std::vector<Segment<C>> segments;
  double running = 0;
  for (int bandStart = 0; bandStart < height;)
  {
    const int bandEnd = BandEnd(rowEstimate, bandStart, height, budget, running);
    ++stats.passes;
    GatherSegments<C>(scene, bandStart, bandEnd, offsets, segments);
    stats.segments += segments.size();
    IntegratePixels<C>(scene, bandStart, bandEnd, offsets, segments, rgb);
    bandStart = bandEnd;
  }
}

} // namespace

int ChannelsOf(ScalarMapping mapping)
{
  return mapping == ScalarMapping::TransferFunctions
    ? 1
    : (mapping == ScalarMapping::ColourAndOpacityScalars ? 2 : 4);
}

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
  if (settings.blendMode != BlendMode::Composite &&
    (settings.mapping != ScalarMapping::TransferFunctions || !settings.triangles.empty()))
  {
    return Fail(error,
      "blend modes other than composite take one scalar per tuple and no translucent "
      "triangles");
  }
  if (settings.blendMode != BlendMode::Composite &&
    (!std::isfinite(settings.scalarRange[0]) || !std::isfinite(settings.scalarRange[1]) ||
      settings.scalarRange[1] < settings.scalarRange[0] || std::isnan(settings.averageRange[0]) ||
      std::isnan(settings.averageRange[1])))
  {
    return Fail(error, "the scalar range must be finite and ordered, the average's range a number");
  }
  TransferFunctions tf;
  if (!BuildTransferFunctions(settings, tf, error))
  {
    return false;
  }
  const int nthreads = detail::ResolveThreads(threads);
  rgb.assign(3 * static_cast<std::size_t>(width) * height, 0.0);
  const std::vector<EyePoint> eye = EyePoints(points, settings, nthreads);
  const std::vector<PixelBox> boxes = PixelBoxes(cells, points.count, eye, width, height, nthreads);
  const std::vector<PixelBox> triangleBoxes = TriangleBoxes(settings);
  const std::vector<LightFactors> lights = CellLights(cells, points.count, eye, settings);
  const Scene scene{ cells, points.count, scalars, settings, tf, eye, boxes, triangleBoxes,
    Rays{ inverseProjection, width, height }, nthreads, lights };
  ReferenceStats counted;
  switch (settings.mapping)
  {
    case ScalarMapping::TransferFunctions:
      IntegrateBands<1>(scene, rgb.data(), counted);
      break;
    case ScalarMapping::ColourAndOpacityScalars:
      IntegrateBands<2>(scene, rgb.data(), counted);
      break;
    case ScalarMapping::Colours:
      IntegrateBands<4>(scene, rgb.data(), counted);
      break;
  }
  if (stats)
  {
    *stats = counted;
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
