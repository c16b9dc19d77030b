// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/ImageSampling.h"

#include "detail/Parallel.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace mtpt
{

int SampledImageSize(int viewport, float distance)
{
  if (!(distance > 0.0f) || !std::isfinite(distance))
  {
    return viewport;
  }
  // Single precision, as vtkUnstructuredGridVolumeRayCastMapper divides an int by its float
  // distance: 300 / 0.1f is 3000 in float and 2999.99996 in double.
  const float size = std::floor(static_cast<float>(viewport) / distance);
  if (!(size < 2147483647.0f))
  {
    return 2147483647;
  }
  return std::max(1, static_cast<int>(size));
}

double AdjustImageSampleDistance(
  double distance, double lastSeconds, double allottedSeconds, double minimum, double maximum)
{
  if (!(lastSeconds > 0.0))
  {
    distance = 0.0; // no frame timed yet: start at the minimum, as VTK does
  }
  else if (allottedSeconds > 0.0 && std::isfinite(allottedSeconds) && std::isfinite(lastSeconds))
  {
    distance *= std::sqrt(lastSeconds / allottedSeconds);
  }
  // VTK's order: the maximum first, then the minimum.
  distance = distance > maximum ? maximum : distance;
  distance = distance < minimum ? minimum : distance;
  return distance;
}

void SampleDepth(const float* depth, int width, int height, float* sampled, int sampledWidth,
  int sampledHeight, int threads)
{
  if (width <= 0 || height <= 0 || sampledWidth <= 0 || sampledHeight <= 0)
  {
    return;
  }
  // The viewport column and row under each sampled pixel's centre.
  std::vector<int> columns(static_cast<std::size_t>(sampledWidth));
  for (int i = 0; i < sampledWidth; ++i)
  {
    const double x = (i + 0.5) * width / sampledWidth;
    columns[static_cast<std::size_t>(i)] = std::min(width - 1, static_cast<int>(x));
  }
  const std::size_t pixels = static_cast<std::size_t>(sampledWidth) * sampledHeight;
  const int team = ThreadsForWork(pixels, detail::PixelsPerThread, threads);
  detail::ParallelFor(0, sampledHeight, team,
    [&](std::int64_t j)
    {
      const double y = (j + 0.5) * height / sampledHeight;
      const int row = std::min(height - 1, static_cast<int>(y));
      const float* in = depth + static_cast<std::size_t>(row) * width;
      float* out = sampled + static_cast<std::size_t>(j) * sampledWidth;
      for (int i = 0; i < sampledWidth; ++i)
      {
        out[i] = in[columns[static_cast<std::size_t>(i)]];
      }
    });
}

namespace
{

/// The viewport pixels [begin, end) on one axis whose bilinear footprint reaches the sampled
/// pixels [low, high): those whose sample position u = (X + 0.5) * sampled / viewport - 0.5
/// (in texel-centre units) lies in (low - 1, high).
void MagnifiedRange(int low, int high, int sampled, int viewport, int& begin, int& end)
{
  const double scale = static_cast<double>(viewport) / sampled;
  begin = static_cast<int>(std::floor((low - 0.5) * scale - 0.5));
  end = static_cast<int>(std::ceil((high + 0.5) * scale - 0.5)) + 1;
  begin = std::max(0, std::min(viewport, begin));
  end = std::max(begin, std::min(viewport, end));
}

/// Bilinear taps along one axis for each viewport pixel: the two sampled pixels (relative to
/// the region's first, -1 when outside the region) and the weight of the second.
struct Taps
{
  std::vector<int> first, second;
  std::vector<float> weight;

  Taps(int begin, int end, int sampled, int viewport, int low, int high)
  {
    const std::size_t n = static_cast<std::size_t>(std::max(0, end - begin));
    this->first.resize(n);
    this->second.resize(n);
    this->weight.resize(n);
    const auto relative = [low, high](int texel)
    { return texel >= low && texel < high ? texel - low : -1; };
    for (int X = begin; X < end; ++X)
    {
      const double u = (X + 0.5) * sampled / viewport - 0.5;
      const double base = std::floor(u);
      const int i0 = static_cast<int>(base);
      const std::size_t k = static_cast<std::size_t>(X - begin);
      // Clamped to the edge texels, as GL_CLAMP_TO_EDGE.
      this->first[k] = relative(std::max(0, std::min(sampled - 1, i0)));
      this->second[k] = relative(std::max(0, std::min(sampled - 1, i0 + 1)));
      this->weight[k] = static_cast<float>(u - base);
    }
  }
};

inline void StoreUnit(float value, std::uint8_t& out)
{
  out = static_cast<std::uint8_t>(std::min(1.0f, std::max(0.0f, value)) * 255.0f + 0.5f);
}

} // namespace

PixelRegion MagnifiedRegion(
  const PixelRegion& region, int sampledWidth, int sampledHeight, int width, int height)
{
  PixelRegion out;
  if (region.Empty() || sampledWidth <= 0 || sampledHeight <= 0 || width <= 0 || height <= 0)
  {
    return out;
  }
  MagnifiedRange(region.x0, region.x1, sampledWidth, width, out.x0, out.x1);
  MagnifiedRange(region.y0, region.y1, sampledHeight, height, out.y0, out.y1);
  return out;
}

void MagnifyOver(const SampledImage& image, int width, int height, const PixelRegion& target,
  const std::uint8_t* below, std::uint8_t* rgba, int threads)
{
  if (target.Empty() || width <= 0 || height <= 0 || image.width <= 0 || image.height <= 0)
  {
    return;
  }
  const PixelRegion& source = image.region;
  const Taps columns(target.x0, target.x1, image.width, width, source.x0, source.x1);
  const Taps rows(target.y0, target.y1, image.height, height, source.y0, source.y1);
  const int targetWidth = target.x1 - target.x0, sourceWidth = source.x1 - source.x0;
  const float zero[4] = { 0, 0, 0, 0 };
  // A texel of the region, or transparent outside it.
  const auto texel = [&](int row, int column) -> const float*
  {
    return row < 0 || column < 0
      ? zero
      : image.rgba + 4 * (static_cast<std::size_t>(row) * sourceWidth + column);
  };
  const std::size_t pixels = static_cast<std::size_t>(targetWidth) * (target.y1 - target.y0);
  const int team = ThreadsForWork(pixels, detail::PixelsPerThread, threads);
  detail::ParallelFor(0, target.y1 - target.y0, team,
    [&](std::int64_t y)
    {
      const int r0 = rows.first[static_cast<std::size_t>(y)];
      const int r1 = rows.second[static_cast<std::size_t>(y)];
      const float wy = rows.weight[static_cast<std::size_t>(y)];
      for (int x = 0; x < targetWidth; ++x)
      {
        const std::size_t c = static_cast<std::size_t>(x);
        const float wx = columns.weight[c];
        const float *a = texel(r0, columns.first[c]), *b = texel(r0, columns.second[c]);
        const float *d = texel(r1, columns.first[c]), *e = texel(r1, columns.second[c]);
        float filtered[4];
        for (int k = 0; k < 4; ++k)
        {
          const float lower = a[k] + wx * (b[k] - a[k]);
          const float upper = d[k] + wx * (e[k] - d[k]);
          filtered[k] = lower + wy * (upper - lower);
        }
        const std::size_t i = 4 * (static_cast<std::size_t>(y) * targetWidth + c);
        const float rest = 1.0f - filtered[3];
        for (int k = 0; k < 4; ++k)
        {
          StoreUnit(filtered[k] + rest * (below[i + k] * (1.0f / 255.0f)), rgba[i + k]);
        }
      }
    });
}

} // namespace mtpt
