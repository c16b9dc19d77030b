// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Compositor.h"

#include "detail/Parallel.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace mtpt
{

void TransferFunctionTable::Lookup(float scalar, float rgba[4]) const
{
  // Texel-space coordinate of a texture sampled with linear filtering and clamp to edge.
  const double span = this->high > this->low ? this->high - this->low : 1.0;
  double t = (static_cast<double>(scalar) - this->low) / span * (this->size - 1);
  t = t < 0 ? 0 : (t > this->size - 1 ? this->size - 1 : t);
  const int i = static_cast<int>(t);
  const int j = i + 1 < this->size ? i + 1 : i;
  const auto f = static_cast<float>(t - i);
  const float* a = this->table + 4 * i;
  const float* b = this->table + 4 * j;
  for (int k = 0; k < 4; ++k)
  {
    rgba[k] = a[k] + f * (b[k] - a[k]);
  }
}

namespace
{

/// Sub-pixel precision of the fixed-point rasterizer (as GPUs and Mesa's rasterizers snap
/// vertices): 8 bits.
constexpr int SubpixelBits = 8;
constexpr double SubpixelScale = 1 << SubpixelBits;
/// Window coordinates within +-2^22 pixels keep every edge-function product below 2^62.
constexpr double FixedPointLimit = 4194304.0;

struct ScreenTriangle
{
  double x[3], y[3];          ///< window coordinates
  int xmin, xmax, ymin, ymax; ///< pixels whose centres may be covered (inclusive)
};

/// Window-space triangle `t` (slot t/4, triangle t%4); false if it cannot cover a pixel
/// centre (zero area, off screen, non-finite).
inline bool SetUp(const TetVertex* vertices, const std::uint32_t* indices, std::size_t t, int width,
  int height, ScreenTriangle& s)
{
  const std::uint32_t* tri = indices + 12 * (t / 4) + 3 * (t % 4);
  if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
  {
    return false; // padding of a class-1 slot, or a degenerate slot
  }
  double minX = 1e300, maxX = -1e300, minY = 1e300, maxY = -1e300;
  for (int k = 0; k < 3; ++k)
  {
    const TetVertex& v = vertices[tri[k]];
    s.x[k] = (static_cast<double>(v.x) + 1.0) * 0.5 * width;
    s.y[k] = (static_cast<double>(v.y) + 1.0) * 0.5 * height;
    minX = std::min(minX, s.x[k]);
    maxX = std::max(maxX, s.x[k]);
    minY = std::min(minY, s.y[k]);
    maxY = std::max(maxY, s.y[k]);
  }
  if (!(maxX - minX < 1e300) || !(maxY - minY < 1e300))
  {
    return false; // NaN or infinite
  }
  // Pixel centres x + 0.5 within [minX, maxX].
  const double x0 = std::ceil(minX - 0.5), x1 = std::floor(maxX - 0.5);
  const double y0 = std::ceil(minY - 0.5), y1 = std::floor(maxY - 0.5);
  s.xmin = static_cast<int>(std::max(0.0, x0));
  s.xmax = static_cast<int>(std::min(width - 1.0, x1));
  s.ymin = static_cast<int>(std::max(0.0, y0));
  s.ymax = static_cast<int>(std::min(height - 1.0, y1));
  return s.xmin <= s.xmax && s.ymin <= s.ymax;
}

/// Edge function of edge a->b at point p, and whether the edge owns points exactly on it
/// (top-left rule for counter-clockwise triangles, y up: a left edge goes down, a top edge
/// is horizontal and goes left).
struct Edge
{
  std::int64_t a, b, c; ///< E(p) = a * px + b * py + c, fixed point
  bool owns;
};

inline Edge MakeEdge(std::int64_t ax, std::int64_t ay, std::int64_t bx, std::int64_t by)
{
  Edge e;
  e.a = ay - by;
  e.b = bx - ax;
  e.c = ax * by - ay * bx;
  const bool left = by < ay;
  const bool top = by == ay && bx < ax;
  e.owns = left || top;
  return e;
}

} // namespace

void Compositor::Composite(const TetVertex* vertices, const std::uint32_t* indices,
  std::size_t count, const CompositeSettings& settings, std::vector<float>& rgba, int threads)
{
  const int width = std::max(0, settings.width), height = std::max(0, settings.height);
  rgba.assign(4 * static_cast<std::size_t>(width) * height, 0.0f);
  this->Rasterized = 0;
  if (width == 0 || height == 0 || count == 0 || !settings.transferFunction.table ||
    settings.transferFunction.size < 1)
  {
    return;
  }
  const int nthreads = detail::ResolveThreads(threads);
  const int tileSize = std::max(4, settings.tileSize);
  const int tilesX = (width + tileSize - 1) / tileSize;
  const int tilesY = (height + tileSize - 1) / tileSize;
  const std::size_t tiles = static_cast<std::size_t>(tilesX) * tilesY;
  const std::size_t triangles = 4 * count;

  // Binning, in two passes over the same static partition of the triangles, so that each
  // tile's list is in triangle order (thread 0's part first, then thread 1's...).
  this->BinCounts.assign(static_cast<std::size_t>(nthreads) * tiles, 0);
  auto forEachTile = [&](const ScreenTriangle& s, auto&& visit)
  {
    for (int ty = s.ymin / tileSize; ty <= s.ymax / tileSize; ++ty)
    {
      for (int tx = s.xmin / tileSize; tx <= s.xmax / tileSize; ++tx)
      {
        visit(static_cast<std::size_t>(ty) * tilesX + tx);
      }
    }
  };
#pragma omp parallel num_threads(nthreads)
  {
    const int t = omp_get_thread_num();
    const int team = omp_get_num_threads();
    const std::size_t begin = triangles * t / team, end = triangles * (t + 1) / team;
    std::uint32_t* counts = this->BinCounts.data() + static_cast<std::size_t>(t) * tiles;
    ScreenTriangle s{};
    for (std::size_t i = begin; i < end; ++i)
    {
      if (SetUp(vertices, indices, i, width, height, s))
      {
        forEachTile(s, [&](std::size_t tile) { ++counts[tile]; });
      }
    }
#pragma omp barrier
#pragma omp single
    {
      this->BinStarts.assign(tiles + 1, 0);
      std::uint32_t running = 0;
      for (std::size_t tile = 0; tile < tiles; ++tile)
      {
        this->BinStarts[tile] = running;
        for (int u = 0; u < team; ++u)
        {
          std::uint32_t& c = this->BinCounts[static_cast<std::size_t>(u) * tiles + tile];
          const std::uint32_t n = c;
          c = running; // becomes thread u's write position in this tile's list
          running += n;
        }
      }
      this->BinStarts[tiles] = running;
      this->BinTriangles.resize(running);
    } // implicit barrier
    for (std::size_t i = begin; i < end; ++i)
    {
      if (SetUp(vertices, indices, i, width, height, s))
      {
        forEachTile(s,
          [&](std::size_t tile)
          { this->BinTriangles[counts[tile]++] = static_cast<std::uint32_t>(i); });
      }
    }
  }

  // Rasterization: one thread per tile at a time, triangles in order within the tile.
  const float inverseUnit = static_cast<float>(1.0 / settings.unitDistance);
  const TransferFunctionTable& tf = settings.transferFunction;
  std::size_t rasterized = 0;
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1) reduction(+ : rasterized)
  for (std::int64_t tileIndex = 0; tileIndex < static_cast<std::int64_t>(tiles); ++tileIndex)
  {
    const int tx = static_cast<int>(tileIndex % tilesX), ty = static_cast<int>(tileIndex / tilesX);
    const int tileX0 = tx * tileSize, tileY0 = ty * tileSize;
    const int tileX1 = std::min(width - 1, tileX0 + tileSize - 1);
    const int tileY1 = std::min(height - 1, tileY0 + tileSize - 1);
    ScreenTriangle s{};
    for (std::uint32_t b = this->BinStarts[tileIndex]; b < this->BinStarts[tileIndex + 1]; ++b)
    {
      const std::size_t t = this->BinTriangles[b];
      SetUp(vertices, indices, t, width, height, s);
      const std::uint32_t* tri = indices + 12 * (t / 4) + 3 * (t % 4);
      const bool fixedPoint = std::fabs(s.x[0]) < FixedPointLimit &&
        std::fabs(s.x[1]) < FixedPointLimit && std::fabs(s.x[2]) < FixedPointLimit &&
        std::fabs(s.y[0]) < FixedPointLimit && std::fabs(s.y[1]) < FixedPointLimit &&
        std::fabs(s.y[2]) < FixedPointLimit;
      if (!fixedPoint)
      {
        continue; // beyond 4 million pixels off screen: the GL path clips such triangles
      }
      std::int64_t fx[3], fy[3];
      for (int k = 0; k < 3; ++k)
      {
        fx[k] = std::llround(s.x[k] * SubpixelScale);
        fy[k] = std::llround(s.y[k] * SubpixelScale);
      }
      // Orient counter-clockwise so that inside means all edge functions positive.
      const std::int64_t area2 =
        (fx[1] - fx[0]) * (fy[2] - fy[0]) - (fy[1] - fy[0]) * (fx[2] - fx[0]);
      if (area2 == 0)
      {
        continue;
      }
      int order[3] = { 0, 1, 2 };
      if (area2 < 0)
      {
        std::swap(order[1], order[2]);
      }
      Edge edges[3];
      for (int k = 0; k < 3; ++k)
      {
        const int a = order[(k + 1) % 3], c = order[(k + 2) % 3];
        edges[k] = MakeEdge(fx[a], fy[a], fx[c], fy[c]); // edge opposite order[k]
      }
      const double inverseArea = 1.0 / static_cast<double>(area2 < 0 ? -area2 : area2);

      bool classified = false;
      float attributes[3][6]; // per vertex: r, g, b, attenuation, length, NDC z
      const int x0 = std::max(s.xmin, tileX0), x1 = std::min(s.xmax, tileX1);
      const int y0 = std::max(s.ymin, tileY0), y1 = std::min(s.ymax, tileY1);
      bool any = false;
      for (int y = y0; y <= y1; ++y)
      {
        const std::int64_t py =
          static_cast<std::int64_t>(y) * (1 << SubpixelBits) + (1 << (SubpixelBits - 1));
        for (int x = x0; x <= x1; ++x)
        {
          const std::int64_t px =
            static_cast<std::int64_t>(x) * (1 << SubpixelBits) + (1 << (SubpixelBits - 1));
          std::int64_t e[3];
          bool inside = true;
          for (int k = 0; k < 3; ++k)
          {
            e[k] = edges[k].a * px + edges[k].b * py + edges[k].c;
            inside = inside && (e[k] > 0 || (e[k] == 0 && edges[k].owns));
          }
          if (!inside)
          {
            continue;
          }
          any = true;
          if (!classified)
          {
            for (int k = 0; k < 3; ++k)
            {
              const TetVertex& v = vertices[tri[order[k]]];
              float front[4], back[4];
              tf.Lookup(v.scalarFront, front);
              tf.Lookup(v.scalarBack, back);
              for (int c = 0; c < 4; ++c)
              {
                attributes[k][c] = 0.5f * (front[c] + back[c]);
              }
              attributes[k][4] = v.thickness;
              attributes[k][5] = v.z;
            }
            classified = true;
          }
          // Barycentric weight of vertex order[k] is its opposite edge's function / area.
          const double l0 = e[0] * inverseArea, l1 = e[1] * inverseArea, l2 = e[2] * inverseArea;
          float f[6];
          for (int c = 0; c < 6; ++c)
          {
            f[c] = static_cast<float>(
              l0 * attributes[0][c] + l1 * attributes[1][c] + l2 * attributes[2][c]);
          }
          if (f[5] < -1.0f || f[5] > 1.0f)
          {
            continue; // clipped by the near or far plane
          }
          const std::size_t pixel = static_cast<std::size_t>(y) * width + x;
          if (settings.opaqueDepth && 0.5f * (f[5] + 1.0f) > settings.opaqueDepth[pixel])
          {
            continue;
          }
          const float opacity = 1.0f - std::exp(-f[3] * f[4] * inverseUnit);
          if (!(opacity > 0.0f))
          {
            continue;
          }
          float* d = rgba.data() + 4 * pixel;
          const float keep = 1.0f - opacity;
          d[0] = opacity * f[0] + keep * d[0];
          d[1] = opacity * f[1] + keep * d[1];
          d[2] = opacity * f[2] + keep * d[2];
          d[3] = opacity + keep * d[3];
        }
      }
      rasterized += any ? 1 : 0;
    }
  }
  this->Rasterized = rasterized;
}

} // namespace mtpt
