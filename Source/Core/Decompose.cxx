// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Decompose.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

#if defined(__x86_64__) || defined(_M_X64)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mtpt
{

Projection ClassifyProjection(const double x[4], const double y[4])
{
  Projection result;
  // area2[i]: twice the signed area of the projected face opposite vertex i, oriented so
  // that the four sum to zero (area2[i] = -orient(face without i) with alternating order).
  // Each is a screen-space barycentric numerator: the signs alone give the class.
  auto orient = [&](int a, int b, int c)
  { return (x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a]); };
  const double area2[4] = { orient(1, 2, 3), orient(0, 3, 2), orient(0, 1, 3), orient(0, 2, 1) };
  double magnitude[4];
  double sumAbs = 0;
  for (int i = 0; i < 4; ++i)
  {
    magnitude[i] = std::fabs(area2[i]);
    sumAbs += magnitude[i];
  }
  // sumAbs is twice the doubled hull area. Zero, non-finite, or negligible against the
  // extent (the projection is a segment or a point): nothing to draw.
  // (Plain comparisons: std::fmax is a library call unless NaN semantics are relaxed.)
  double extent = 0;
  for (int i = 1; i < 4; ++i)
  {
    const double ex = std::fabs(x[i] - x[0]), ey = std::fabs(y[i] - y[0]);
    extent = ex > extent ? ex : extent;
    extent = ey > extent ? ey : extent;
  }
  if (!(sumAbs > 1e-12 * extent * extent) || !std::isfinite(sumAbs))
  {
    return result;
  }

  // Signs with a zero band relative to the hull area (DESIGN.md section 3: never test a
  // denominator with == 0). A zero is a point on the line through an edge of the others.
  const double zeroBand = ClassificationTolerance * sumAbs;
  int sign[4];
  int positives = 0, negatives = 0;
  for (int i = 0; i < 4; ++i)
  {
    sign[i] = magnitude[i] <= zeroBand ? 0 : (area2[i] > 0 ? 1 : -1);
    positives += sign[i] > 0;
    negatives += sign[i] < 0;
  }
  const int zeros = 4 - positives - negatives;

  if (positives == 2 && negatives == 2)
  {
    // The two vertices of one sign form the diagonal that crosses the diagonal of the
    // other two. The crossing divides each diagonal in the ratio of the distances of its
    // ends from the other diagonal's line, i.e. of the areas opposite them.
    int pos[2], neg[2], np = 0, nn = 0;
    for (int i = 0; i < 4; ++i)
    {
      (sign[i] > 0 ? pos[np++] : neg[nn++]) = i;
    }
    result.kind = ProjectionClass::Quadrilateral;
    result.vertex[0] = pos[0];
    result.vertex[1] = pos[1];
    result.vertex[2] = neg[0];
    result.vertex[3] = neg[1];
    result.alpha = magnitude[pos[1]] / (magnitude[pos[0]] + magnitude[pos[1]]);
    result.beta = magnitude[neg[1]] / (magnitude[neg[0]] + magnitude[neg[1]]);
    return result;
  }

  int thick = -1;
  if ((positives == 3 && negatives == 1) || (positives == 1 && negatives == 3))
  {
    result.kind = ProjectionClass::Triangle;
    const int unique = positives == 1 ? 1 : -1;
    for (int i = 0; i < 4; ++i)
    {
      thick = sign[i] == unique ? i : thick;
    }
  }
  else if (zeros == 1 && positives >= 1 && negatives >= 1)
  {
    // The inner vertex is the one whose sign no other non-zero area shares.
    result.kind = ProjectionClass::VertexOnEdge;
    const int unique = positives == 1 ? 1 : -1;
    for (int i = 0; i < 4; ++i)
    {
      thick = sign[i] == unique ? i : thick;
    }
  }
  else if (zeros == 2 && positives == 1 && negatives == 1)
  {
    // The two faces with zero area both contain the coincident pair, which is therefore
    // the pair of vertices with non-zero opposite areas. Either may be the thick vertex:
    // take the larger index.
    result.kind = ProjectionClass::CoincidentVertices;
    for (int i = 0; i < 4; ++i)
    {
      thick = sign[i] != 0 ? i : thick;
    }
  }
  else
  {
    return result; // not reachable for finite areas that sum to zero; stay safe
  }

  int outer = 0;
  double weightSum = 0;
  for (int i = 0; i < 4; ++i)
  {
    if (i != thick)
    {
      result.vertex[outer] = i;
      // Barycentric weight of outer vertex i: area of the sub-triangle opposite it.
      result.weights[outer] = sign[i] != 0 ? magnitude[i] : 0.0;
      weightSum += result.weights[outer];
      ++outer;
    }
  }
  result.vertex[3] = thick;
  const double inverseSum = 1.0 / weightSum; // >= the largest non-zero magnitude > zeroBand
  for (double& w : result.weights)
  {
    w *= inverseSum;
  }
  return result;
}

namespace
{

/// Parameter along a 3D segment a->b of the point that projects at screen-space parameter
/// s: 1/w is affine in screen space (perspective-correct interpolation), so
/// t = (s / wb) / ((1 - s) / wa + s / wb). For orthographic projections w is 1 at both
/// ends and the result is s.
inline double PerspectiveCorrect(double s, double inverseWa, double inverseWb)
{
  return s * inverseWb / ((1.0 - s) * inverseWa + s * inverseWb); // both positive
}

inline void WriteDegenerateSlot(
  TetVertex vertices[5], std::uint32_t indices[12], std::uint32_t base)
{
  std::memset(vertices, 0, 5 * sizeof(TetVertex));
  for (int i = 0; i < 12; ++i)
  {
    indices[i] = base;
  }
}

/// Every corner usable: ProjectPoints checked its coordinates and point scalar.
inline bool AllUsable(const ProjectedPoint* const c[4])
{
  return (c[0]->usable & c[1]->usable & c[2]->usable & c[3]->usable) != 0;
}

/// Every corner usable and every scalar finite (cell scalars are not checked there).
inline bool Drawable(const ProjectedPoint* const c[4], const float scalars[4])
{
  return AllUsable(c) && std::isfinite(scalars[0] + scalars[1] + scalars[2] + scalars[3]);
}

/// The decomposition of one tetrahedron into a slot whose indices start at `base`.
inline Projection Decompose(const ProjectedPoint* const c[4], const float scalars[4],
  TetVertex out[5], std::uint32_t indices[12], std::uint32_t base)
{
  Projection p;
  if (!Drawable(c, scalars))
  {
    WriteDegenerateSlot(out, indices, base);
    return p;
  }
  const double x[4] = { c[0]->x, c[1]->x, c[2]->x, c[3]->x };
  const double y[4] = { c[0]->y, c[1]->y, c[2]->y, c[3]->y };
  p = ClassifyProjection(x, y);
  if (p.kind == ProjectionClass::NotDrawable)
  {
    WriteDegenerateSlot(out, indices, base);
    return p;
  }
  for (int i = 0; i < 4; ++i)
  {
    out[i] = TetVertex{ static_cast<float>(x[i]), static_cast<float>(y[i]),
      static_cast<float>(c[i]->z), scalars[i], scalars[i], 0.0f };
  }

  // The thick vertex: the ray through it enters the tetrahedron at one point and leaves
  // at another. Both are found in eye space with perspective-correct parameters, so their
  // distance is the exact eye-space ray segment length (no lookup table).
  double first[3], second[3], firstZ, secondZ, firstScalar, secondScalar, thickX, thickY;
  int thickSlot;
  if (p.kind == ProjectionClass::Quadrilateral)
  {
    const int a = p.vertex[0], b = p.vertex[1], d0 = p.vertex[2], d1 = p.vertex[3];
    // alpha along P_a P_b and beta along P_d0 P_d1 (VTK's OpenGL PT uses alpha for both).
    const double tab = PerspectiveCorrect(p.alpha, c[a]->inverseW, c[b]->inverseW);
    const double tcd = PerspectiveCorrect(p.beta, c[d0]->inverseW, c[d1]->inverseW);
    first[0] = c[a]->eyeX + tab * (c[b]->eyeX - c[a]->eyeX);
    first[1] = c[a]->eyeY + tab * (c[b]->eyeY - c[a]->eyeY);
    first[2] = c[a]->eyeZ + tab * (c[b]->eyeZ - c[a]->eyeZ);
    second[0] = c[d0]->eyeX + tcd * (c[d1]->eyeX - c[d0]->eyeX);
    second[1] = c[d0]->eyeY + tcd * (c[d1]->eyeY - c[d0]->eyeY);
    second[2] = c[d0]->eyeZ + tcd * (c[d1]->eyeZ - c[d0]->eyeZ);
    firstScalar = scalars[a] + tab * (static_cast<double>(scalars[b]) - scalars[a]);
    secondScalar = scalars[d0] + tcd * (static_cast<double>(scalars[d1]) - scalars[d0]);
    // NDC z is affine in screen space: interpolate it with the screen parameters.
    firstZ = c[a]->z + p.alpha * (c[b]->z - c[a]->z);
    secondZ = c[d0]->z + p.beta * (c[d1]->z - c[d0]->z);
    thickX = x[a] + p.alpha * (x[b] - x[a]);
    thickY = y[a] + p.alpha * (y[b] - y[a]);
    thickSlot = 4;
    // The quadrilateral's boundary runs a, d0, b, d1; fan it around the crossing.
    const std::uint32_t fan[12] = { 0u + a, 0u + d0, 4u, 0u + d0, 0u + b, 4u, 0u + b, 0u + d1, 4u,
      0u + d1, 0u + a, 4u };
    for (int i = 0; i < 12; ++i)
    {
      indices[i] = base + fan[i];
    }
  }
  else
  {
    const int j0 = p.vertex[0], j1 = p.vertex[1], j2 = p.vertex[2], t = p.vertex[3];
    // The ray through the inner vertex meets the opposite face at screen barycentrics
    // weights[]; divided by w and renormalized they are the eye-space barycentrics.
    const double m0 = p.weights[0] * c[j0]->inverseW, m1 = p.weights[1] * c[j1]->inverseW,
                 m2 = p.weights[2] * c[j2]->inverseW;
    const double inv = 1.0 / (m0 + m1 + m2); // weights sum to 1, w > 0: positive
    const double u0 = m0 * inv, u1 = m1 * inv, u2 = m2 * inv;
    first[0] = c[t]->eyeX;
    first[1] = c[t]->eyeY;
    first[2] = c[t]->eyeZ;
    second[0] = u0 * c[j0]->eyeX + u1 * c[j1]->eyeX + u2 * c[j2]->eyeX;
    second[1] = u0 * c[j0]->eyeY + u1 * c[j1]->eyeY + u2 * c[j2]->eyeY;
    second[2] = u0 * c[j0]->eyeZ + u1 * c[j1]->eyeZ + u2 * c[j2]->eyeZ;
    firstScalar = scalars[t];
    secondScalar = u0 * scalars[j0] + u1 * scalars[j1] + u2 * scalars[j2];
    firstZ = c[t]->z;
    secondZ = p.weights[0] * c[j0]->z + p.weights[1] * c[j1]->z + p.weights[2] * c[j2]->z;
    thickX = x[t];
    thickY = y[t];
    thickSlot = t;
    const std::uint32_t fan[12] = { 0u + j0, 0u + j1, 0u + t, 0u + j1, 0u + j2, 0u + t, 0u + j2,
      0u + j0, 0u + t, 0u + t, 0u + t, 0u + t };
    for (int i = 0; i < 12; ++i)
    {
      indices[i] = base + fan[i];
    }
  }
  const double dx = first[0] - second[0], dy = first[1] - second[1], dz = first[2] - second[2];
  const bool firstInFront = firstZ <= secondZ;
  out[thickSlot] = TetVertex{ static_cast<float>(thickX), static_cast<float>(thickY),
    static_cast<float>(firstInFront ? firstZ : secondZ),
    static_cast<float>(firstInFront ? firstScalar : secondScalar),
    static_cast<float>(firstInFront ? secondScalar : firstScalar),
    static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz)) };
  if (thickSlot != 4)
  {
    out[4] = out[thickSlot];
  }
  return p;
}

/**
 * Copies a finished slot (assembled on the stack) to its place in the buffers with
 * non-temporal 8-byte stores where available. Plain stores to lines not in cache first read
 * them for ownership; with ~40 scalar stores a slot the store buffer fills and the core
 * stalls (measured: 4x slower decomposition when slots are written in scattered order). The
 * buffers are read next by the upload, not by this thread, so bypassing the cache is free.
 * Requires 8-byte aligned buffers (any new/malloc allocation); otherwise memcpy is used.
 */
inline void StoreSlot(const TetVertex source[5], const std::uint32_t sourceIndices[12],
  TetVertex* vertices, std::uint32_t* indices, bool streaming)
{
#if defined(__x86_64__) || defined(_M_X64)
  if (streaming)
  {
    static_assert(sizeof(TetVertex) * 5 == 15 * 8, "slot vertices are 15 words");
    long long words[15 + 6];
    std::memcpy(words, source, 15 * 8);
    std::memcpy(words + 15, sourceIndices, 6 * 8);
    auto* vertexWords = reinterpret_cast<long long*>(vertices);
    auto* indexWords = reinterpret_cast<long long*>(indices);
    for (int i = 0; i < 15; ++i)
    {
      _mm_stream_si64(vertexWords + i, words[i]);
    }
    for (int i = 0; i < 6; ++i)
    {
      _mm_stream_si64(indexWords + i, words[15 + i]);
    }
    return;
  }
#endif
  (void)streaming;
  std::memcpy(vertices, source, 5 * sizeof(TetVertex));
  std::memcpy(indices, sourceIndices, 12 * sizeof(std::uint32_t));
}

/// Makes a thread's non-temporal stores visible before it leaves a parallel region.
inline void FinishStores()
{
#if defined(__x86_64__) || defined(_M_X64)
  _mm_sfence();
#endif
}

/// Whether both buffers allow 8-byte non-temporal stores.
inline bool CanStream(const TetVertex* vertices, const std::uint32_t* indices)
{
  return ((reinterpret_cast<std::uintptr_t>(vertices) | reinterpret_cast<std::uintptr_t>(indices)) &
           7u) == 0;
}

/// Whether the window-space bounding box of the corners contains a pixel centre of the
/// viewport. Conservative by 1e-6 pixel, so rounding never culls a covering cell.
inline bool CoversPixelCentre(const ProjectedPoint* const c[4], int width, int height)
{
  double minX = c[0]->x, maxX = c[0]->x, minY = c[0]->y, maxY = c[0]->y;
  for (int i = 1; i < 4; ++i)
  {
    minX = std::min(minX, c[i]->x);
    maxX = std::max(maxX, c[i]->x);
    minY = std::min(minY, c[i]->y);
    maxY = std::max(maxY, c[i]->y);
  }
  constexpr double Margin = 1e-6;
  // Pixel centres x + 0.5 for x in [0, width): window x = (ndc + 1) / 2 * width.
  const double x0 = std::max(0.0, std::ceil((minX + 1.0) * 0.5 * width - 0.5 - Margin));
  const double x1 = std::min(width - 1.0, std::floor((maxX + 1.0) * 0.5 * width - 0.5 + Margin));
  const double y0 = std::max(0.0, std::ceil((minY + 1.0) * 0.5 * height - 0.5 - Margin));
  const double y1 = std::min(height - 1.0, std::floor((maxY + 1.0) * 0.5 * height - 0.5 + Margin));
  return x0 <= x1 && y0 <= y1;
}

/// The tetrahedron `corners` into slot-local records with global index base `base`,
/// culled when it covers no pixel centre of the viewport.
inline ProjectionClass DecomposeCorners(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], std::uint32_t base,
  TetVertex slotVertices[5], std::uint32_t slotIndices[12])
{
  const bool cull = input.viewportWidth > 0 && input.viewportHeight > 0 && AllUsable(corners) &&
    !CoversPixelCentre(corners, input.viewportWidth, input.viewportHeight);
  if (cull)
  {
    WriteDegenerateSlot(slotVertices, slotIndices, base);
    return ProjectionClass::CoversNoPixel;
  }
  return Decompose(corners, scalars, slotVertices, slotIndices, base).kind;
}

/// Slot k, holding `cell`.
template <typename Access>
inline void DecomposeSlot(const Access& cells, const DecomposeInput& input,
  const float* cellScalars, std::uint32_t cell, std::int64_t k, TetVertex* vertices,
  std::uint32_t* indices, ProjectionClass* classes, bool streaming)
{
  const auto base = static_cast<std::uint32_t>(5 * k);
  TetVertex slotVertices[5];
  std::uint32_t slotIndices[12];
  std::int64_t ids[4];
  ProjectionClass kind = ProjectionClass::NotDrawable;
  if (cells.TetrahedronPoints(cell, ids))
  {
    const ProjectedPoint* corners[4] = { input.points + ids[0], input.points + ids[1],
      input.points + ids[2], input.points + ids[3] };
    float scalars[4];
    for (int i = 0; i < 4; ++i)
    {
      scalars[i] = cellScalars ? cellScalars[cell] : corners[i]->scalar;
    }
    kind = DecomposeCorners(input, corners, scalars, base, slotVertices, slotIndices);
  }
  else
  {
    WriteDegenerateSlot(slotVertices, slotIndices, base);
  }
  StoreSlot(slotVertices, slotIndices, vertices + 5 * k, indices + 12 * k, streaming);
  if (classes)
  {
    classes[k] = kind;
  }
}

/// The input's cell scalars, or null when its scalars are per point.
inline const float* CellScalars(const DecomposeInput& input)
{
  return input.scalars.association == ScalarsView::Association::Cells ? input.scalars.values
                                                                      : nullptr;
}

/// Runs body(i) for i in [0, n) on `threads` threads, each making its streaming stores
/// visible before the region ends.
template <typename Body>
void ParallelSlots(std::int64_t n, int threads, Body&& body)
{
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static) nowait
    for (std::int64_t i = 0; i < n; ++i)
    {
      body(i);
    }
    FinishStores();
  }
}

template <typename Access>
void DecomposeAll(const Access& cells, const DecomposeInput& input, const SortKey* order,
  std::size_t count, TetVertex* vertices, std::uint32_t* indices, ProjectionClass* classes,
  int threads)
{
  const float* cellScalars = CellScalars(input);
  const bool streaming = CanStream(vertices, indices);
  ParallelSlots(static_cast<std::int64_t>(count), threads,
    [&](std::int64_t k)
    {
      DecomposeSlot(
        cells, input, cellScalars, CellOfKey(order[k]), k, vertices, indices, classes, streaming);
    });
}

template <typename Access>
void DecomposeAllByRank(const Access& cells, const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, TetVertex* vertices, std::uint32_t* indices,
  ProjectionClass* classes, int threads)
{
  const float* cellScalars = CellScalars(input);
  const bool streaming = CanStream(vertices, indices);
  ParallelSlots(static_cast<std::int64_t>(input.cells.cellCount), threads,
    [&](std::int64_t c)
    {
      // One unsigned comparison: NotInOrder and ranks outside the window both fail.
      const std::uint64_t k = static_cast<std::uint64_t>(rank[c]) - firstRank;
      if (rank[c] != NotInOrder && k < count)
      {
        DecomposeSlot(cells, input, cellScalars, static_cast<std::uint32_t>(c),
          static_cast<std::int64_t>(k), vertices, indices, classes, streaming);
      }
    });
}

} // namespace

Projection DecomposeTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  TetVertex vertices[5], std::uint32_t indices[12])
{
  return Decompose(corners, scalars, vertices, indices, 0);
}

ProjectionClass DecomposeIntoSlot(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], std::size_t k,
  TetVertex* vertices, std::uint32_t* indices)
{
  return DecomposeCorners(
    input, corners, scalars, static_cast<std::uint32_t>(5 * k), vertices + 5 * k, indices + 12 * k);
}

void DecomposeTetrahedra(const DecomposeInput& input, const SortKey* order, std::size_t count,
  TetVertex* vertices, std::uint32_t* indices, ProjectionClass* classes, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchCells(input.cells, input.pointCount,
    [&](const auto& cells)
    { DecomposeAll(cells, input, order, count, vertices, indices, classes, nthreads); });
}

void InvertOrder(
  const SortKey* order, std::size_t count, std::size_t cellCount, std::uint32_t* rank, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const auto cells = static_cast<std::int64_t>(cellCount);
  const auto n = static_cast<std::int64_t>(count);
#pragma omp parallel num_threads(nthreads)
  {
    if (n < cells) // only a partial order leaves ranks to mark
    {
#pragma omp for schedule(static)
      for (std::int64_t c = 0; c < cells; ++c)
      {
        rank[c] = NotInOrder;
      }
    }
#pragma omp for schedule(static)
    for (std::int64_t k = 0; k < n; ++k)
    {
      rank[CellOfKey(order[k])] = static_cast<std::uint32_t>(k);
    }
  }
}

void DecomposeTetrahedraByRank(const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, TetVertex* vertices, std::uint32_t* indices,
  ProjectionClass* classes, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchCells(input.cells, input.pointCount,
    [&](const auto& cells)
    {
      DecomposeAllByRank(
        cells, input, rank, firstRank, count, vertices, indices, classes, nthreads);
    });
}

} // namespace mtpt
