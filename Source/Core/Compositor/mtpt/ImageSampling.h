// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ImageSampling.h
 * @brief Compositing at an image sample distance other than 1, as VTK's other
 * unstructured-grid mappers do (vtkUnstructuredGridVolumeRayCastMapper's
 * ImageSampleDistance and AutoAdjustSampleDistances): the volume is composited into an
 * image of fewer (or more) pixels than the viewport, which is then magnified (or minified)
 * onto the viewport with bilinear filtering. The view, the projection and NDC are those of
 * the viewport either way: only the number of samples across it changes.
 *
 * Conventions (those of Compositor.h): pixel (x, y) of an image w pixels wide covers
 * [x, x+1) in its own pixel units and is sampled at its centre; NDC x in [-1, 1] spans the
 * whole image, whatever its size. So pixel X of the viewport (W pixels) and the position
 * u = (X + 0.5) * w / W in the sampled image's pixel units lie on the same ray, and
 * bilinear filtering reads the sampled image at u as OpenGL's linear texture filtering does
 * with texture coordinate (X + 0.5) / W: between the two texels whose centres surround it,
 * clamped to the edge texels.
 *
 * Everything here is a pure function of its arguments; the loops run on OpenMP threads and
 * give the same result for any thread count.
 */
#ifndef mtpt_ImageSampling_h
#define mtpt_ImageSampling_h

#include "mtpt/Records.h"

#include <cstdint>

namespace mtpt
{

/**
 * Pixels along one side of the image composited for a viewport side of `viewport` pixels at
 * image sample distance `distance`: viewport / distance rounded down, as
 * vtkUnstructuredGridVolumeRayCastMapper sizes its image (computed in single precision as
 * VTK does, so that 300 / 0.1f gives 3000), and at least 1. A distance that is not positive
 * or not finite gives `viewport` (distance 1). Pure function.
 */
int SampledImageSize(int viewport, float distance);

/**
 * The image sample distance of the next frame with automatic adjustment, the rule of
 * vtkUnstructuredGridVolumeRayCastMapper (AutoAdjustSampleDistances): the distance scaled by
 * sqrt(lastSeconds / allottedSeconds), so that the next frame's pixels, and with them the
 * pixel-bound part of its time, scale by allottedSeconds / lastSeconds; then at most
 * `maximum`, then at least `minimum` (so `minimum` wins where the two cross, as in VTK).
 * A frame never timed (lastSeconds <= 0) gives `minimum`; an allotment that is not a
 * positive finite number leaves the distance as it is (clamped), where VTK would divide by
 * it. Iterated on a frame whose time is fixed + k * pixels, the distance converges to the
 * one whose frame takes `allottedSeconds` whenever the fixed part takes less (unit tests in
 * Testing/Core/TestImageSampling.cxx). Pure function.
 */
double AdjustImageSampleDistance(
  double distance, double lastSeconds, double allottedSeconds, double minimum, double maximum);

/**
 * The opaque depth for a sampled image: `sampled` (sampledWidth x sampledHeight floats)
 * receives, for each sampled pixel, the depth of the viewport pixel under its centre
 * (`depth`: width x height floats; row 0 at the bottom in both). This is the pixel an
 * OpenGL blit with GL_NEAREST filtering copies, so both backends test fragments against
 * the same depth. Thread safety: reentrant; `threads` OpenMP threads (<= 0: all).
 */
void SampleDepth(const float* depth, int width, int height, float* sampled, int sampledWidth,
  int sampledHeight, int threads);

/**
 * The viewport pixels that bilinear filtering of a sampled image (sampledWidth x
 * sampledHeight) onto a viewport (width x height) reads from the sampled pixels of
 * `region`: outside it, a magnified image that is transparent outside `region` is
 * transparent too. Conservative by at most a pixel on each side. Pure function.
 */
PixelRegion MagnifiedRegion(const PixelRegion& region, int sampledWidth, int sampledHeight,
  int width, int height);

/// A region of a sampled image: premultiplied RGBA floats of the pixels of `region`, row
/// major, row 0 at the bottom; the image is transparent outside the region.
struct SampledImage
{
  const float* rgba = nullptr;
  PixelRegion region;
  int width = 0, height = 0; ///< of the whole sampled image
};

/**
 * Magnifies (or minifies) `image` onto a width x height viewport with bilinear filtering
 * (see the file comment) and composites it over `below` in the viewport's `target` region:
 * rgba = filtered + (1 - filtered alpha) * below, in 8 bits per channel rounded to nearest,
 * as Compositor::Resolve does. `below` and `rgba` hold the target region's pixels, row
 * major, row 0 at the bottom. Thread safety: reentrant; `threads` OpenMP threads (<= 0:
 * all); the same bytes for any thread count.
 */
void MagnifyOver(const SampledImage& image, int width, int height, const PixelRegion& target,
  const std::uint8_t* below, std::uint8_t* rgba, int threads);

} // namespace mtpt

#endif
