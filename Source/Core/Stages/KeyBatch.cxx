// SPDX-License-Identifier: BSD-3-Clause
// The depth keys' arithmetic for a batch of cells, one per lane (detail/KeyBatch.h).
// Google Highway compiles this file once per instruction set (foreach_target.h includes it
// again for each); the dispatch at the end picks the best the processor has. Compiled
// without floating-point contraction (CMakeLists.txt), as DepthKeys.cxx is.
#include "detail/KeyBatch.h"
#include "detail/PixelCoverage.h"

#include <cstddef>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "KeyBatch.cxx"
#include <hwy/foreach_target.h> // IWYU pragma: keep

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace mtpt
{
namespace detail
{
namespace HWY_NAMESPACE
{
namespace hn = hwy::HWY_NAMESPACE;

/// ProjectedPoint's fields in units of 8 bytes; the last holds the scalar and, in its high
/// half on these little-endian targets, `usable`.
enum KeyField : std::int64_t
{
  KeyX = 0,
  KeyY = 1,
  KeyZ = 2,
  KeyEyeX = 4,
  KeyScalarAndUsable = 7
};
static_assert(offsetof(ProjectedPoint, eyeX) == KeyEyeX * sizeof(double) &&
    offsetof(ProjectedPoint, usable) == KeyScalarAndUsable * sizeof(double) + 4 &&
    sizeof(ProjectedPoint) == 8 * sizeof(double),
  "KeyField is ProjectedPoint's layout");

/// Whether each lane's four corners (x[i], y[i], z[i]: NDC) all lie beyond one and the same
/// plane of the view frustum.
template <class D, class V = hn::Vec<D>>
HWY_INLINE hn::Mask<D> OutsideFrustum(D d, const V x[4], const V y[4], const V z[4])
{
  const auto one = hn::Set(d, 1.0), minusOne = hn::Set(d, -1.0);
  hn::Mask<D> beyond[6];
  beyond[0] = hn::Lt(x[0], minusOne);
  beyond[1] = hn::Gt(x[0], one);
  beyond[2] = hn::Lt(y[0], minusOne);
  beyond[3] = hn::Gt(y[0], one);
  beyond[4] = hn::Lt(z[0], minusOne);
  beyond[5] = hn::Gt(z[0], one);
  for (int i = 1; i < 4; ++i)
  {
    beyond[0] = hn::And(beyond[0], hn::Lt(x[i], minusOne));
    beyond[1] = hn::And(beyond[1], hn::Gt(x[i], one));
    beyond[2] = hn::And(beyond[2], hn::Lt(y[i], minusOne));
    beyond[3] = hn::And(beyond[3], hn::Gt(y[i], one));
    beyond[4] = hn::And(beyond[4], hn::Lt(z[i], minusOne));
    beyond[5] = hn::And(beyond[5], hn::Gt(z[i], one));
  }
  auto outside = beyond[0];
  for (int p = 1; p < 6; ++p)
  {
    outside = hn::Or(outside, beyond[p]);
  }
  return outside;
}

/// CoversPixelCentre (detail/PixelCoverage.h) of the lanes' boxes [low, high] along one axis
/// of `size` pixels: whether the box holds a pixel centre along it.
template <class D>
HWY_INLINE hn::Mask<D> HoldsCentre(D d, hn::Vec<D> low, hn::Vec<D> high, int size)
{
  const auto one = hn::Set(d, 1.0), half = hn::Set(d, 0.5), pixels = hn::Set(d, size);
  const auto margin = hn::Set(d, SnapMargin);
  const auto first = hn::Max(hn::Zero(d),
    hn::Ceil(hn::Sub(hn::Sub(hn::Mul(hn::Mul(hn::Add(low, one), half), pixels), half), margin)));
  const auto last = hn::Min(hn::Set(d, size - 1.0),
    hn::Floor(hn::Add(hn::Sub(hn::Mul(hn::Mul(hn::Add(high, one), half), pixels), half), margin)));
  return hn::Le(first, last);
}

void ComputeKeyBatchImpl(const ProjectedPoint* points, const KeyBatch& batch, int count,
  const KeyRules& rules, KeyBatchResult& result)
{
  using D = hn::ScalableTag<double>;
  const D d;
  const hn::RebindToSigned<D> di;
  const auto* values = reinterpret_cast<const double*>(points);
  const auto* words = reinterpret_cast<const std::int64_t*>(points);
  for (std::size_t base = 0; base < static_cast<std::size_t>(count); base += hn::Lanes(d))
  {
    hn::Vec<D> x[4], y[4], z[4], eye[3] = { hn::Zero(d), hn::Zero(d), hn::Zero(d) };
    auto usable = hn::Set(di, 1);
    for (int i = 0; i < 4; ++i)
    {
      const auto at = hn::ShiftLeft<3>(hn::LoadU(di, batch.point[i] + base));
      x[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, KeyX)));
      y[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, KeyY)));
      z[i] = hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, KeyZ)));
      for (int k = 0; k < 3; ++k)
      {
        // CentroidDepth: 0 + e0 + e1 + e2 + e3, left to right.
        eye[k] = hn::Add(eye[k], hn::GatherIndex(d, values, hn::Add(at, hn::Set(di, KeyEyeX + k))));
      }
      usable = hn::And(usable,
        hn::ShiftRight<32>(
          hn::GatherIndex(di, words, hn::Add(at, hn::Set(di, KeyScalarAndUsable)))));
    }
    // The centroid's depth, as CentroidDepth: its squared distance in perspective, -z else.
    for (auto& e : eye)
    {
      e = hn::Mul(e, hn::Set(d, 0.25));
    }
    const auto depth = rules.perspective
      ? hn::Add(hn::Add(hn::Mul(eye[0], eye[0]), hn::Mul(eye[1], eye[1])), hn::Mul(eye[2], eye[2]))
      : hn::Neg(eye[2]);
    hn::StoreU(depth, d, result.depth + base);
    // The verdict, where all four corners are usable.
    auto verdict = hn::Zero(di);
    const auto allUsable = hn::RebindMask(d, hn::Ne(usable, hn::Zero(di)));
    if (rules.frustum)
    {
      verdict = hn::IfThenElse(hn::RebindMask(di, hn::And(allUsable, OutsideFrustum(d, x, y, z))),
        hn::Set(di, KeyOutsideFrustum), verdict);
    }
    if (!rules.imageSize.Empty())
    {
      auto minX = x[0], maxX = x[0], minY = y[0], maxY = y[0];
      for (int i = 1; i < 4; ++i)
      {
        minX = hn::Min(minX, x[i]);
        maxX = hn::Max(maxX, x[i]);
        minY = hn::Min(minY, y[i]);
        maxY = hn::Max(maxY, y[i]);
      }
      const auto covers = hn::And(HoldsCentre(d, minX, maxX, rules.imageSize.width),
        HoldsCentre(d, minY, maxY, rules.imageSize.height));
      const auto none = hn::AndNot(covers, allUsable);
      // The frustum test comes first (CellKey): only lanes it kept can cover no pixel.
      verdict =
        hn::IfThenElse(hn::And(hn::RebindMask(di, none), hn::Eq(verdict, hn::Set(di, KeyKept))),
          hn::Set(di, KeyCoversNoPixel), verdict);
    }
    hn::StoreU(verdict, di, result.verdict + base);
  }
}

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace mtpt
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mtpt
{
namespace detail
{

HWY_EXPORT(ComputeKeyBatchImpl);

void ComputeKeyBatch(const ProjectedPoint* points, const KeyBatch& batch, int count,
  const KeyRules& rules, KeyBatchResult& result)
{
  HWY_DYNAMIC_DISPATCH(ComputeKeyBatchImpl)(points, batch, count, rules, result);
}

} // namespace detail
} // namespace mtpt
#endif
