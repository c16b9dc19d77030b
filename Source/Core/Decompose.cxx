// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Decompose.h"

#include "detail/MeshAccess.h"
#include "detail/Parallel.h"

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
  double extent = 0;
  for (int i = 1; i < 4; ++i)
  {
    extent = std::fmax(extent, std::fmax(std::fabs(x[i] - x[0]), std::fabs(y[i] - y[0])));
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
  for (double& w : result.weights)
  {
    w /= weightSum; // weightSum >= the largest non-zero magnitude > zeroBand
  }
  return result;
}

namespace
{

/// Length in eye space of a model-space difference: the model-view's linear part applied.
inline double EyeLength(const Matrix4& mv, const double d[3])
{
  const double ex = mv[0] * d[0] + mv[1] * d[1] + mv[2] * d[2];
  const double ey = mv[4] * d[0] + mv[5] * d[1] + mv[6] * d[2];
  const double ez = mv[8] * d[0] + mv[9] * d[1] + mv[10] * d[2];
  return std::sqrt(ex * ex + ey * ey + ez * ez);
}

/// Parameter along a 3D segment a->b of the point that projects at screen-space parameter
/// s: 1/w is affine in screen space (perspective-correct interpolation). For orthographic
/// projections w is 1 at both ends and the result is s.
inline double PerspectiveCorrect(double s, double wa, double wb)
{
  return s * wa / ((1.0 - s) * wb + s * wa); // wa, wb > 0: the denominator is positive
}

inline void WriteDegenerateSlot(TetVertex vertices[5],
  std::uint32_t indices[12],
  std::uint32_t base)
{
  std::memset(vertices, 0, 5 * sizeof(TetVertex));
  for (int i = 0; i < 12; ++i)
  {
    indices[i] = base;
  }
}

/// Every point in front of the eye plane with finite NDC, and every scalar finite.
inline bool Drawable(const NdcPoint ndc[4], const float scalars[4])
{
  bool ok = true;
  for (int i = 0; i < 4; ++i)
  {
    ok &= ndc[i].w > 0.0 && std::isfinite(ndc[i].w) && std::isfinite(ndc[i].x) &&
      std::isfinite(ndc[i].y) && std::isfinite(ndc[i].z) && std::isfinite(scalars[i]);
  }
  return ok;
}

/// The decomposition of one tetrahedron into a slot whose indices start at `base`.
inline Projection Decompose(const NdcPoint ndc[4],
  const double model[4][3],
  const float scalars[4],
  const Matrix4& mv,
  TetVertex out[5],
  std::uint32_t indices[12],
  std::uint32_t base)
{
  Projection p;
  if (!Drawable(ndc, scalars))
  {
    WriteDegenerateSlot(out, indices, base);
    return p;
  }
  const double x[4] = { ndc[0].x, ndc[1].x, ndc[2].x, ndc[3].x };
  const double y[4] = { ndc[0].y, ndc[1].y, ndc[2].y, ndc[3].y };
  p = ClassifyProjection(x, y);
  if (p.kind == ProjectionClass::NotDrawable)
  {
    WriteDegenerateSlot(out, indices, base);
    return p;
  }
  for (int i = 0; i < 4; ++i)
  {
    out[i] = TetVertex{ static_cast<float>(ndc[i].x),
      static_cast<float>(ndc[i].y),
      static_cast<float>(ndc[i].z),
      scalars[i],
      scalars[i],
      0.0f };
  }

  // The thick vertex: the ray through it enters the tetrahedron at one point and leaves
  // at another; both are found in model space with perspective-correct parameters, so
  // their distance is the exact eye-space ray segment length (no lookup table).
  double first[3], second[3], firstZ, secondZ, firstScalar, secondScalar;
  double thickX, thickY;
  int thickSlot;
  if (p.kind == ProjectionClass::Quadrilateral)
  {
    const int a = p.vertex[0], b = p.vertex[1], c = p.vertex[2], d = p.vertex[3];
    // alpha along P_a P_b and beta along P_c P_d (VTK's OpenGL PT uses alpha for both).
    const double tab = PerspectiveCorrect(p.alpha, ndc[a].w, ndc[b].w);
    const double tcd = PerspectiveCorrect(p.beta, ndc[c].w, ndc[d].w);
    for (int k = 0; k < 3; ++k)
    {
      first[k] = model[a][k] + tab * (model[b][k] - model[a][k]);
      second[k] = model[c][k] + tcd * (model[d][k] - model[c][k]);
    }
    firstScalar = scalars[a] + tab * (static_cast<double>(scalars[b]) - scalars[a]);
    secondScalar = scalars[c] + tcd * (static_cast<double>(scalars[d]) - scalars[c]);
    // NDC z is affine in screen space: interpolate it with the screen parameters.
    firstZ = ndc[a].z + p.alpha * (ndc[b].z - ndc[a].z);
    secondZ = ndc[c].z + p.beta * (ndc[d].z - ndc[c].z);
    thickX = x[a] + p.alpha * (x[b] - x[a]);
    thickY = y[a] + p.alpha * (y[b] - y[a]);
    thickSlot = 4;
    const std::uint32_t fan[12] = {
      0u + a, 0u + c, 4u, 0u + c, 0u + b, 4u, 0u + b, 0u + d, 4u, 0u + d, 0u + a, 4u
    };
    for (int i = 0; i < 12; ++i)
    {
      indices[i] = base + fan[i];
    }
  }
  else
  {
    const int j0 = p.vertex[0], j1 = p.vertex[1], j2 = p.vertex[2], t = p.vertex[3];
    // The ray through the inner vertex meets the opposite face at screen barycentrics
    // weights[]; divided by w they become the model-space barycentrics.
    const double m0 = p.weights[0] / ndc[j0].w, m1 = p.weights[1] / ndc[j1].w,
                 m2 = p.weights[2] / ndc[j2].w;
    const double inv = 1.0 / (m0 + m1 + m2); // weights sum to 1, w > 0: positive
    const double u0 = m0 * inv, u1 = m1 * inv, u2 = m2 * inv;
    for (int k = 0; k < 3; ++k)
    {
      first[k] = model[t][k];
      second[k] = u0 * model[j0][k] + u1 * model[j1][k] + u2 * model[j2][k];
    }
    firstScalar = scalars[t];
    secondScalar = u0 * scalars[j0] + u1 * scalars[j1] + u2 * scalars[j2];
    firstZ = ndc[t].z;
    secondZ = p.weights[0] * ndc[j0].z + p.weights[1] * ndc[j1].z + p.weights[2] * ndc[j2].z;
    thickX = ndc[t].x;
    thickY = ndc[t].y;
    thickSlot = t;
    const std::uint32_t fan[12] = { 0u + j0,
      0u + j1,
      0u + t,
      0u + j1,
      0u + j2,
      0u + t,
      0u + j2,
      0u + j0,
      0u + t,
      0u + t,
      0u + t,
      0u + t };
    for (int i = 0; i < 12; ++i)
    {
      indices[i] = base + fan[i];
    }
  }
  const double difference[3] = { first[0] - second[0], first[1] - second[1], first[2] - second[2] };
  const bool firstInFront = firstZ <= secondZ;
  out[thickSlot] = TetVertex{ static_cast<float>(thickX),
    static_cast<float>(thickY),
    static_cast<float>(firstInFront ? firstZ : secondZ),
    static_cast<float>(firstInFront ? firstScalar : secondScalar),
    static_cast<float>(firstInFront ? secondScalar : firstScalar),
    static_cast<float>(EyeLength(mv, difference)) };
  if (thickSlot != 4)
  {
    out[4] = out[thickSlot];
  }
  return p;
}

template<typename Access>
void DecomposeAll(const Access& mesh,
  const DecomposeInput& input,
  const SortKey* order,
  std::size_t count,
  TetVertex* vertices,
  std::uint32_t* indices,
  ProjectionClass* classes,
  int threads)
{
  const auto n = static_cast<std::int64_t>(count);
  const float* scalarValues = input.scalars.values;
  const bool cellScalars = input.scalars.association == ScalarsView::Association::Cells;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t k = 0; k < n; ++k)
  {
    const std::uint32_t cell = CellOfKey(order[k]);
    const auto base = static_cast<std::uint32_t>(5 * k);
    TetVertex* slotVertices = vertices + 5 * k;
    std::uint32_t* slotIndices = indices + 12 * k;
    std::int64_t ids[4];
    ProjectionClass kind = ProjectionClass::NotDrawable;
    if (mesh.TetrahedronPoints(cell, ids))
    {
      NdcPoint ndc[4];
      double model[4][3];
      float scalars[4];
      for (int i = 0; i < 4; ++i)
      {
        ndc[i] = input.ndc[ids[i]];
        mesh.Point(ids[i], model[i]);
        const std::int64_t scalarId = cellScalars ? static_cast<std::int64_t>(cell) : ids[i];
        scalars[i] = scalarValues ? scalarValues[scalarId] : 0.0f;
      }
      kind = Decompose(ndc, model, scalars, input.modelView, slotVertices, slotIndices, base).kind;
    }
    if (kind == ProjectionClass::NotDrawable)
    {
      WriteDegenerateSlot(slotVertices, slotIndices, base);
    }
    if (classes)
    {
      classes[k] = kind;
    }
  }
}

} // namespace

Projection DecomposeTetrahedron(const NdcPoint ndc[4],
  const double model[4][3],
  const float scalars[4],
  const Matrix4& modelView,
  TetVertex vertices[5],
  std::uint32_t indices[12])
{
  return Decompose(ndc, model, scalars, modelView, vertices, indices, 0);
}

void DecomposeTetrahedra(const DecomposeInput& input,
  const SortKey* order,
  std::size_t count,
  TetVertex* vertices,
  std::uint32_t* indices,
  ProjectionClass* classes,
  int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchMesh(input.points,
    input.cells,
    [&](const auto& mesh)
    { DecomposeAll(mesh, input, order, count, vertices, indices, classes, nthreads); });
}

} // namespace mtpt
