// SPDX-License-Identifier: BSD-3-Clause
// Image sample distance (mtpt/ImageSampling.h): the sizes of the sampled image, the
// automatic adjustment of VTK's ray caster driven by a simulated frame time (it converges to
// the allotted time, goes to the maximum where even that is too slow, and back to the
// minimum for a still frame), the depth each sampled pixel is tested against, and the
// bilinear magnification against a direct evaluation.
#include "mtpt/ImageSampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace
{

using mtpt::PixelRegion;

TEST(ImageSampling, SampledSizeIsTheViewportOverTheDistanceRoundedDown)
{
  EXPECT_EQ(mtpt::SampledImageSize(1024, 1.0f), 1024);
  EXPECT_EQ(mtpt::SampledImageSize(1024, 2.0f), 512);
  EXPECT_EQ(mtpt::SampledImageSize(301, 2.0f), 150);
  EXPECT_EQ(mtpt::SampledImageSize(199, 2.0f), 99);
  EXPECT_EQ(mtpt::SampledImageSize(301, 1.5f), 200);
  EXPECT_EQ(mtpt::SampledImageSize(199, 1.5f), 132);
  EXPECT_EQ(mtpt::SampledImageSize(1024, 3.0f), 341);
  EXPECT_EQ(mtpt::SampledImageSize(301, 100.0f), 3);
  // Below 1: more samples than pixels; in single precision as VTK, 300 / 0.1f is 3000.
  EXPECT_EQ(mtpt::SampledImageSize(301, 0.5f), 602);
  EXPECT_EQ(mtpt::SampledImageSize(300, 0.1f), 3000);
  // Never empty.
  EXPECT_EQ(mtpt::SampledImageSize(1, 2.0f), 1);
  EXPECT_EQ(mtpt::SampledImageSize(5, 10.0f), 1);
  // No usable distance: the viewport.
  EXPECT_EQ(mtpt::SampledImageSize(300, 0.0f), 300);
  EXPECT_EQ(mtpt::SampledImageSize(300, -2.0f), 300);
  EXPECT_EQ(mtpt::SampledImageSize(300, std::numeric_limits<float>::quiet_NaN()), 300);
  EXPECT_EQ(mtpt::SampledImageSize(300, std::numeric_limits<float>::infinity()), 300);
}

TEST(ImageSampling, AdjustmentIsVTKsRule)
{
  // distance * sqrt(last / allotted), clamped to [minimum, maximum].
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(2.0, 0.4, 0.1, 1.0, 10.0), 4.0);
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(4.0, 0.025, 0.1, 1.0, 10.0), 2.0);
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(4.0, 100.0, 0.1, 1.0, 10.0), 10.0);
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(4.0, 0.001, 0.1, 1.0, 10.0), 1.0);
  // The maximum is applied first, so the minimum wins where they cross (as in VTK).
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(4.0, 0.4, 0.1, 5.0, 3.0), 5.0);
  // No frame timed yet: the minimum (VTK: a stored time of 0 scales the distance to 0).
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(4.0, 0.0, 0.1, 1.5, 10.0), 1.5);
  // No usable allotment: the distance stays (clamped); VTK would divide by zero.
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(4.0, 0.4, 0.0, 1.0, 10.0), 4.0);
  EXPECT_DOUBLE_EQ(mtpt::AdjustImageSampleDistance(40.0, 0.4, -1.0, 1.0, 10.0), 10.0);
  EXPECT_DOUBLE_EQ(
    mtpt::AdjustImageSampleDistance(4.0, 0.4, std::numeric_limits<double>::quiet_NaN(), 1, 10),
    4.0);
}

/// A simulated frame: a fixed part (transform, sort, set-up) and a part proportional to the
/// sampled image's pixels, on a 1024 x 768 viewport.
struct FrameModel
{
  double fixedSeconds, fullSeconds; ///< the frame at distance 1 takes fullSeconds
  double operator()(double distance) const
  {
    const float d = static_cast<float>(distance);
    const double pixels =
      static_cast<double>(mtpt::SampledImageSize(1024, d)) * mtpt::SampledImageSize(768, d);
    return fixedSeconds + (fullSeconds - fixedSeconds) * pixels / (1024.0 * 768.0);
  }
};

/// The distances of `frames` frames adjusted with VTK's rule, starting from a first frame
/// (never timed before) and feeding each frame's simulated time to the next.
std::vector<double> Adjust(const FrameModel& model, double allotted, int frames,
  double start = 1.0, double lastSeconds = 0.0)
{
  std::vector<double> distances;
  double distance = start, last = lastSeconds;
  for (int i = 0; i < frames; ++i)
  {
    distance = mtpt::AdjustImageSampleDistance(distance, last, allotted, 1.0, 10.0);
    distances.push_back(distance);
    last = model(distance);
  }
  return distances;
}

TEST(ImageSampling, AdjustmentConvergesToTheAllottedTime)
{
  // 760 ms at full resolution, 30 ms of it fixed; 10 frames a second allotted.
  const FrameModel model{ 0.030, 0.760 };
  const double allotted = 0.1;
  const std::vector<double> d = Adjust(model, allotted, 12);
  EXPECT_EQ(d.front(), 1.0); // the first frame: the minimum
  for (std::size_t i = 6; i < d.size(); ++i)
  {
    // The floor of the sampled size quantizes the pixel count: within 2%.
    EXPECT_NEAR(model(d[i]), allotted, 0.02 * allotted) << "frame " << i << ", distance " << d[i];
  }
  // The fixed point: (full - fixed) / d^2 = allotted - fixed.
  EXPECT_NEAR(d.back(), std::sqrt((0.760 - 0.030) / (allotted - 0.030)), 0.02);
  // Other allotments converge as well, from wherever the distance was.
  for (const double other : { 0.05, 0.2, 0.4 })
  {
    const std::vector<double> e = Adjust(model, other, 12, d.back(), model(d.back()));
    EXPECT_NEAR(model(e.back()), other, 0.02 * other) << "allotted " << other;
  }
}

TEST(ImageSampling, AdjustmentStopsAtTheMaximumWhenTheFixedPartIsTooSlow)
{
  // The fixed part alone takes longer than the allotment: the distance goes to the maximum
  // and stays there.
  const FrameModel model{ 0.150, 0.760 };
  const std::vector<double> d = Adjust(model, 0.1, 8);
  EXPECT_EQ(d.back(), 10.0);
  EXPECT_EQ(d[d.size() - 2], 10.0);
}

TEST(ImageSampling, AStillFrameReturnsToTheMinimum)
{
  // Moving at 15 frames a second, then still: a render window's still update rate (0.0001
  // frames a second, VTK's default) allots 10000 s, and the very next frame is at the
  // minimum distance.
  const FrameModel model{ 0.030, 0.760 };
  const std::vector<double> moving = Adjust(model, 1.0 / 15, 10);
  ASSERT_GT(moving.back(), 2.0);
  const double still =
    mtpt::AdjustImageSampleDistance(moving.back(), model(moving.back()), 1.0 / 0.0001, 1.0, 10.0);
  EXPECT_EQ(still, 1.0);
}

TEST(ImageSampling, DepthIsThePixelUnderEachSampledCentre)
{
  const int width = 7, height = 5;
  std::vector<float> depth(width * height);
  for (int y = 0; y < height; ++y)
  {
    for (int x = 0; x < width; ++x)
    {
      depth[y * width + x] = static_cast<float>(100 * y + x);
    }
  }
  // 3 x 2: centres at x = 7/6, 7/2, 35/6 and y = 5/4, 15/4 of the viewport.
  std::vector<float> sampled(3 * 2);
  mtpt::SampleDepth(depth.data(), width, height, sampled.data(), 3, 2, 1);
  const float expected[] = { 101, 103, 105, 301, 303, 305 };
  for (int i = 0; i < 6; ++i)
  {
    EXPECT_EQ(sampled[i], expected[i]) << i;
  }
  // Distance 2 on even sizes: the centre (2i + 1, 2j + 1) lies on a pixel corner; the pixel
  // above and to the right of it, as a GL_NEAREST blit reads it.
  std::vector<float> half(3 * 2);
  mtpt::SampleDepth(depth.data(), 6, 4, half.data(), 3, 2, 2);
  for (int j = 0; j < 2; ++j)
  {
    for (int i = 0; i < 3; ++i)
    {
      EXPECT_EQ(half[j * 3 + i], depth[(2 * j + 1) * 6 + 2 * i + 1]) << i << ", " << j;
    }
  }
}

/// Bilinear taps of viewport pixel X (texel indices clamped to the edge, weight of the
/// second), evaluated directly in double.
void Tap(int X, int sampled, int viewport, int& first, int& second, double& weight)
{
  const double u = (X + 0.5) * sampled / viewport - 0.5;
  const int i = static_cast<int>(std::floor(u));
  first = std::max(0, std::min(sampled - 1, i));
  second = std::max(0, std::min(sampled - 1, i + 1));
  weight = u - std::floor(u);
}

TEST(ImageSampling, MagnifiedRegionHoldsEveryPixelTheRegionReaches)
{
  std::mt19937 random(7);
  for (int trial = 0; trial < 300; ++trial)
  {
    const int w = 1 + static_cast<int>(random() % 40), W = 1 + static_cast<int>(random() % 90);
    const int x0 = static_cast<int>(random() % w);
    const int x1 = x0 + 1 + static_cast<int>(random() % (w - x0));
    const PixelRegion region{ x0, 0, x1, 1 };
    const PixelRegion out = mtpt::MagnifiedRegion(region, w, 1, W, 1);
    int low = W, high = -1; // the pixels that read the region with a nonzero weight
    for (int X = 0; X < W; ++X)
    {
      int a = 0, b = 0;
      double t = 0;
      Tap(X, w, W, a, b, t);
      const bool reads = (a >= x0 && a < x1 && t < 1) || (b >= x0 && b < x1 && t > 0);
      if (reads)
      {
        low = std::min(low, X);
        high = std::max(high, X);
      }
    }
    if (low > high)
    {
      continue; // minified: no pixel centre falls near these texels
    }
    EXPECT_LE(out.x0, low) << w << " -> " << W << ", [" << x0 << ", " << x1 << ")";
    EXPECT_GE(out.x1, high + 1) << w << " -> " << W << ", [" << x0 << ", " << x1 << ")";
    EXPECT_GE(out.x0, low - 1) << "conservative by at most a pixel";
    EXPECT_LE(out.x1, high + 2) << "conservative by at most a pixel";
  }
  EXPECT_TRUE(mtpt::MagnifiedRegion(PixelRegion{}, 4, 4, 8, 8).Empty());
}

/// A sampled image of w x h pixels, premultiplied (alpha >= every colour channel).
std::vector<float> RandomImage(int w, int h, unsigned seed)
{
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> rgba(4 * static_cast<std::size_t>(w) * h);
  for (std::size_t p = 0; p < rgba.size(); p += 4)
  {
    const float alpha = unit(random) < 0.2f ? 0.0f : unit(random);
    for (int c = 0; c < 3; ++c)
    {
      rgba[p + c] = alpha * unit(random);
    }
    rgba[p + 3] = alpha;
  }
  return rgba;
}

TEST(ImageSampling, MagnificationIsBilinearOverTheColourBelow)
{
  for (const int W : { 12, 17, 20, 5 })
  {
    const int w = 6, h = 4, H = 2 * W / 3 + 1;
    const std::vector<float> whole = RandomImage(w, h, 3);
    // The region [1, 5) x [1, 3) of it; the image is transparent outside.
    const PixelRegion region{ 1, 1, 5, 3 };
    std::vector<float> part;
    for (int y = region.y0; y < region.y1; ++y)
    {
      for (int x = region.x0; x < region.x1; ++x)
      {
        part.insert(part.end(), &whole[4 * (y * w + x)], &whole[4 * (y * w + x)] + 4);
      }
    }
    const PixelRegion target{ 0, 0, W, H };
    std::vector<std::uint8_t> below(4 * static_cast<std::size_t>(W) * H);
    for (std::size_t i = 0; i < below.size(); ++i)
    {
      below[i] = static_cast<std::uint8_t>((37 * i) % 256);
    }
    std::vector<std::uint8_t> one(below.size()), two(below.size());
    mtpt::MagnifyOver({ part.data(), region, w, h }, W, H, target, below.data(), one.data(), 1);
    mtpt::MagnifyOver({ part.data(), region, w, h }, W, H, target, below.data(), two.data(), 2);
    EXPECT_EQ(one, two) << "the same bytes for any thread count";
    const auto texel = [&](int x, int y, int c)
    {
      const bool inside = x >= region.x0 && x < region.x1 && y >= region.y0 && y < region.y1;
      return inside ? static_cast<double>(whole[4 * (y * w + x) + c]) : 0.0;
    };
    for (int Y = 0; Y < H; ++Y)
    {
      for (int X = 0; X < W; ++X)
      {
        int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
        double tx = 0, ty = 0;
        Tap(X, w, W, x0, x1, tx);
        Tap(Y, h, H, y0, y1, ty);
        double filtered[4];
        for (int c = 0; c < 4; ++c)
        {
          const double lower = (1 - tx) * texel(x0, y0, c) + tx * texel(x1, y0, c);
          const double upper = (1 - tx) * texel(x0, y1, c) + tx * texel(x1, y1, c);
          filtered[c] = (1 - ty) * lower + ty * upper;
        }
        for (int c = 0; c < 4; ++c)
        {
          const std::size_t i = 4 * (static_cast<std::size_t>(Y) * W + X) + c;
          const double expected =
            255 * std::min(1.0, filtered[c] + (1 - filtered[3]) * below[i] / 255.0);
          EXPECT_NEAR(one[i], expected, 0.5 + 1e-3) << W << ": (" << X << ", " << Y << ") " << c;
        }
      }
    }
  }
}

TEST(ImageSampling, MagnificationOfTwoTexelsByTwo)
{
  // Two texels onto four pixels: clamped, 3/4-1/4, 1/4-3/4, clamped; over transparent black.
  const float image[8] = { 0.8f, 0.0f, 0.0f, 0.8f, 0.0f, 0.4f, 0.0f, 0.4f };
  const std::uint8_t below[16] = {};
  std::uint8_t out[16];
  mtpt::MagnifyOver({ image, PixelRegion{ 0, 0, 2, 1 }, 2, 1 }, 4, 1, PixelRegion{ 0, 0, 4, 1 },
    below, out, 1);
  const double red[4] = { 0.8, 0.6, 0.2, 0.0 }, green[4] = { 0.0, 0.1, 0.3, 0.4 };
  for (int x = 0; x < 4; ++x)
  {
    EXPECT_NEAR(out[4 * x], 255 * red[x], 0.5 + 1e-3) << x;
    EXPECT_NEAR(out[4 * x + 1], 255 * green[x], 0.5 + 1e-3) << x;
    EXPECT_NEAR(out[4 * x + 3], 255 * (red[x] + green[x]), 0.5 + 1e-3) << x;
  }
}

TEST(ImageSampling, EqualSizesGiveTheImageItself)
{
  // Sampled at the viewport's size, every pixel reads its own texel with weight 0 beside it:
  // the result is the image composited over the colour below, as Compositor::Resolve does.
  const int w = 9, h = 7;
  const std::vector<float> image = RandomImage(w, h, 11);
  std::vector<std::uint8_t> below(4 * w * h, 90), out(4 * w * h);
  mtpt::MagnifyOver({ image.data(), PixelRegion{ 0, 0, w, h }, w, h }, w, h,
    PixelRegion{ 0, 0, w, h }, below.data(), out.data(), 1);
  for (int p = 0; p < w * h; ++p)
  {
    for (int c = 0; c < 4; ++c)
    {
      const float value = image[4 * p + c] + (1.0f - image[4 * p + 3]) * (90 * (1.0f / 255.0f));
      const auto expected =
        static_cast<std::uint8_t>(std::min(1.0f, std::max(0.0f, value)) * 255.0f + 0.5f);
      EXPECT_EQ(out[4 * p + c], expected) << p << ", " << c;
    }
  }
}

} // namespace
