// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Decompose.h"
#include "mtpt/Faults.h"

#include "detail/DecomposeBatch.h"
#include "detail/MeshAccess.h"
#include "detail/Parallel.h"
#include "detail/PixelCoverage.h"
#include "detail/Streaming.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mtpt
{

namespace
{

/// The four signed areas of a projection and the signs that classify it (ClassifyProjection).
struct ProjectionAreas
{
  double magnitude[4]; ///< |area[i]|
  int sign[4];         ///< -1, 0 (within the zero band) or +1
  int positives = 0, negatives = 0;
};

/**
 * area[i]: twice the signed area of the projected face opposite vertex i, oriented so that
 * the four sum to zero (area[i] = -orient(face without i) with alternating order). Each is
 * a screen-space barycentric numerator: the signs alone give the class. False when the
 * projection has no area to speak of (a segment or a point) or is not finite.
 */
bool SignedAreas(const double x[4], const double y[4], ProjectionAreas& a)
{
  auto orient = [&](int p, int q, int r)
  { return (x[q] - x[p]) * (y[r] - y[p]) - (y[q] - y[p]) * (x[r] - x[p]); };
  const double area2[4] = { orient(1, 2, 3), orient(0, 3, 2), orient(0, 1, 3), orient(0, 2, 1) };
  double sumAbs = 0;
  for (int i = 0; i < 4; ++i)
  {
    a.magnitude[i] = std::fabs(area2[i]);
    sumAbs += a.magnitude[i];
  }
  // sumAbs is twice the doubled hull area. Zero, non-finite, or negligible against the
  // extent: nothing to draw. (Plain comparisons: std::fmax is a library call unless NaN
  // semantics are relaxed.)
  double extent = 0;
  for (int i = 1; i < 4; ++i)
  {
    const double ex = std::fabs(x[i] - x[0]), ey = std::fabs(y[i] - y[0]);
    extent = ex > extent ? ex : extent;
    extent = ey > extent ? ey : extent;
  }
  if (!(sumAbs > 1e-12 * extent * extent) || !std::isfinite(sumAbs))
  {
    return false;
  }
  // Signs with a zero band relative to the hull area, never a test of a denominator with
  // == 0 (VTK's PT does that, and near-zero denominators then give huge alpha and beta;
  // Documentation/algorithm.md). A zero is a point on the line through an edge of the others.
  const double zeroBand = ClassificationTolerance * sumAbs;
  for (int i = 0; i < 4; ++i)
  {
    a.sign[i] = a.magnitude[i] <= zeroBand ? 0 : (area2[i] > 0 ? 1 : -1);
    a.positives += a.sign[i] > 0;
    a.negatives += a.sign[i] < 0;
  }
  return true;
}

/// Class 2: the two vertices of one sign form the diagonal that crosses the diagonal of the
/// other two. The crossing divides each diagonal in the ratio of the distances of its ends
/// from the other diagonal's line, i.e. of the areas opposite them.
Projection Quadrilateral(const ProjectionAreas& a)
{
  Projection result;
  int pos[2], neg[2], np = 0, nn = 0;
  for (int i = 0; i < 4; ++i)
  {
    (a.sign[i] > 0 ? pos[np++] : neg[nn++]) = i;
  }
  result.kind = ProjectionClass::Quadrilateral;
  result.vertex[0] = pos[0];
  result.vertex[1] = pos[1];
  result.vertex[2] = neg[0];
  result.vertex[3] = neg[1];
  result.alpha = a.magnitude[pos[1]] / (a.magnitude[pos[0]] + a.magnitude[pos[1]]);
  result.beta = a.magnitude[neg[1]] / (a.magnitude[neg[0]] + a.magnitude[neg[1]]);
  return result;
}

/// Classes 1, 3 and 4: the thick (inner) vertex and its class, or NotDrawable.
ProjectionClass InnerVertex(const ProjectionAreas& a, int& thick)
{
  const int zeros = 4 - a.positives - a.negatives;
  thick = -1;
  if ((a.positives == 3 && a.negatives == 1) || (a.positives == 1 && a.negatives == 3) ||
    (zeros == 1 && a.positives >= 1 && a.negatives >= 1))
  {
    // The inner vertex is the one whose sign no other non-zero area shares.
    const int unique = a.positives == 1 ? 1 : -1;
    for (int i = 0; i < 4; ++i)
    {
      thick = a.sign[i] == unique ? i : thick;
    }
    return zeros == 0 ? ProjectionClass::Triangle : ProjectionClass::VertexOnEdge;
  }
  if (zeros == 2 && a.positives == 1 && a.negatives == 1)
  {
    // The two faces with zero area both contain the coincident pair, which is therefore
    // the pair of vertices with non-zero opposite areas. Either may be the thick vertex:
    // take the larger index.
    for (int i = 0; i < 4; ++i)
    {
      thick = a.sign[i] != 0 ? i : thick;
    }
    return ProjectionClass::CoincidentVertices;
  }
  return ProjectionClass::NotDrawable; // not reachable for finite areas that sum to zero
}

} // namespace

namespace
{

/// The class, the corners' parts and the barycentric weights from the signed areas
/// (ClassifyProjection after its first test).
Projection Classify(const ProjectionAreas& a)
{
  if (a.positives == 2 && a.negatives == 2)
  {
    return Quadrilateral(a);
  }
  Projection result;
  int thick = -1;
  result.kind = InnerVertex(a, thick);
  if (result.kind == ProjectionClass::NotDrawable)
  {
    return result;
  }
  // The outer triangle, and the inner point's barycentric weights in it: the areas of the
  // sub-triangles opposite each outer vertex.
  int outer = 0;
  double weightSum = 0;
  for (int i = 0; i < 4; ++i)
  {
    if (i != thick)
    {
      result.vertex[outer] = i;
      result.weights[outer] = a.sign[i] != 0 ? a.magnitude[i] : 0.0;
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

/// The class and the corners' parts of every sign pattern (detail/DecomposeBatch.h), from
/// Classify itself: the batched decomposition cannot assign parts differently.
struct PatternTable
{
  detail::RoleTable roles;
  ProjectionClass kind[detail::SignPatterns];

  PatternTable()
  {
    this->roles.tolerance = ClassificationTolerance;
    for (int pattern = 0; pattern < detail::SignPatterns; ++pattern)
    {
      ProjectionAreas a;
      for (int i = 0; i < 4; ++i)
      {
        const bool positive = (pattern >> i) & 1, negative = (pattern >> (4 + i)) & 1;
        a.sign[i] = positive ? 1 : (negative ? -1 : 0);
        a.magnitude[i] = a.sign[i] != 0 ? 1.0 : 0.0;
        a.positives += a.sign[i] > 0;
        a.negatives += a.sign[i] < 0;
      }
      const bool contradictory = (pattern & (pattern >> 4) & 15) != 0;
      const Projection p = contradictory ? Projection{} : Classify(a);
      this->kind[pattern] = p.kind;
      for (int r = 0; r < 4; ++r)
      {
        this->roles.role[r][pattern] = p.vertex[r];
      }
      this->roles.quadrilateral[pattern] = p.kind == ProjectionClass::Quadrilateral;
    }
  }
};

const PatternTable& Patterns()
{
  static const PatternTable table;
  return table;
}

} // namespace

Projection ClassifyProjection(const double x[4], const double y[4])
{
  ProjectionAreas a;
  if (!SignedAreas(x, y, a))
  {
    return Projection{};
  }
  return Classify(a);
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

inline void WriteDegenerateSlot(TetVertex vertices[VerticesPerTetrahedron],
  std::uint32_t indices[IndicesPerTetrahedron], std::uint32_t base)
{
  std::memset(vertices, 0, VerticesPerTetrahedron * sizeof(TetVertex));
  for (std::size_t i = 0; i < IndicesPerTetrahedron; ++i)
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

/**
 * The geometry of one projected tetrahedron: its classification, the record of its thick
 * vertex (the ray through it enters and leaves the tetrahedron at two points, both found in
 * eye space with perspective-correct parameters, so their distance is the exact eye-space
 * segment length; no lookup table), and its silhouette as a cyclic list of corners. Both
 * the OpenGL slot and the CPU compositor's fan are written from it, so the two backends
 * draw the same triangles with the same values.
 */
struct FanGeometry
{
  Projection projection;
  TetVertex thick;
  int boundary[4] = { 0, 0, 0, 0 }; ///< corners in cyclic order around the thick vertex
  int count = 0;                    ///< 3 (triangle projection) or 4 (quadrilateral)
  int thickSlot = 4;                ///< the slot vertex the thick vertex takes
  /// The thick vertex's value as a mix of the corners' (the mean of its segment's front and
  /// back): what dependent components' colours are interpolated with.
  double weights[4] = { 0, 0, 0, 0 };
};

/// The silhouette of a drawable projection: its corners in cyclic order around the thick
/// vertex, and the slot vertex the thick vertex takes.
inline void Silhouette(const Projection& p, FanGeometry& g)
{
  if (p.kind == ProjectionClass::Quadrilateral)
  {
    // The quadrilateral's boundary runs a, d0, b, d1; the thick vertex is a fifth vertex.
    g.thickSlot = 4;
    g.count = 4;
    g.boundary[0] = p.vertex[0];
    g.boundary[1] = p.vertex[2];
    g.boundary[2] = p.vertex[1];
    g.boundary[3] = p.vertex[3];
  }
  else
  {
    // The outer triangle; the thick vertex is the inner corner.
    g.thickSlot = p.vertex[3];
    g.count = 3;
    g.boundary[0] = p.vertex[0];
    g.boundary[1] = p.vertex[1];
    g.boundary[2] = p.vertex[2];
  }
}

/// False (with projection NotDrawable) when the tetrahedron cannot be drawn.
inline bool ComputeFanGeometry(const ProjectedPoint* const c[4], const float scalars[4],
  const double x[4], const double y[4], FanGeometry& g)
{
  const Projection& p = g.projection = ClassifyProjection(x, y);
  if (p.kind == ProjectionClass::NotDrawable)
  {
    return false;
  }
  Silhouette(p, g);
  double first[3], second[3], firstZ, secondZ, firstScalar, secondScalar, thickX, thickY;
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
    g.weights[a] = 0.5 * (1.0 - tab);
    g.weights[b] = 0.5 * tab;
    g.weights[d0] = 0.5 * (1.0 - tcd);
    g.weights[d1] = 0.5 * tcd;
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
    g.weights[t] = 0.5;
    g.weights[j0] = 0.5 * u0;
    g.weights[j1] = 0.5 * u1;
    g.weights[j2] = 0.5 * u2;
  }
  const double dx = first[0] - second[0], dy = first[1] - second[1], dz = first[2] - second[2];
  const bool firstInFront = firstZ <= secondZ;
  g.thick = TetVertex{ static_cast<float>(thickX), static_cast<float>(thickY),
    static_cast<float>(firstInFront ? firstZ : secondZ),
    static_cast<float>(firstInFront ? firstScalar : secondScalar),
    static_cast<float>(firstInFront ? secondScalar : firstScalar),
    static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz)) };
  return true;
}

/// Dependent components: the records of corner `k` and of the thick vertex hold colours.
inline void ColourCorner(const float* const* colours, int k, TetVertex& vertex)
{
  StoreVertexColour(vertex, colours[k]);
}
inline void ColourThick(const float* const* colours, const FanGeometry& g, TetVertex& thick)
{
  float rgba[4];
  for (int c = 0; c < 4; ++c)
  {
    double mixed = 0;
    for (int k = 0; k < 4; ++k)
    {
      mixed += g.weights[k] * colours[k][c];
    }
    rgba[c] = static_cast<float>(mixed);
  }
  StoreVertexColour(thick, rgba);
}

/// The projected (x, y) of the corners, and whether the tetrahedron can be drawn at all.
inline bool Corners(
  const ProjectedPoint* const c[4], const float scalars[4], double x[4], double y[4])
{
  for (int i = 0; i < 4; ++i)
  {
    x[i] = c[i]->x;
    y[i] = c[i]->y;
  }
  return Drawable(c, scalars);
}

/// A corner's record: its projection and scalar (front = back, no length).
inline TetVertex CornerRecord(const ProjectedPoint* corner, float scalar)
{
  return TetVertex{ static_cast<float>(corner->x), static_cast<float>(corner->y),
    static_cast<float>(corner->z), scalar, scalar, 0.0f };
}

/// The slot of a drawable tetrahedron of geometry `g`, indices starting at `base`.
inline void FillSlot(const ProjectedPoint* const c[4], const float scalars[4],
  const float* const* colours, FanGeometry& g, TetVertex out[VerticesPerTetrahedron],
  std::uint32_t indices[IndicesPerTetrahedron], std::uint32_t base)
{
  for (int i = 0; i < 4; ++i)
  {
    out[i] = CornerRecord(c[i], scalars[i]);
    if (colours)
    {
      ColourCorner(colours, i, out[i]);
    }
  }
  if (colours)
  {
    ColourThick(colours, g, g.thick);
  }
  out[g.thickSlot] = g.thick;
  if (g.thickSlot != 4)
  {
    out[4] = g.thick; // an unused copy: every slot vertex holds a finite record
  }
  // Triangle i is (boundary[i], boundary[i+1], thick); a triangle projection pads its
  // fourth triangle as degenerate (all three indices on the thick vertex).
  const auto thick = static_cast<std::uint32_t>(g.thickSlot);
  for (int i = 0; i < static_cast<int>(TrianglesPerTetrahedron); ++i)
  {
    const bool real = i < g.count;
    indices[3 * i + 0] = base + (real ? static_cast<std::uint32_t>(g.boundary[i]) : thick);
    indices[3 * i + 1] =
      base + (real ? static_cast<std::uint32_t>(g.boundary[(i + 1) % g.count]) : thick);
    indices[3 * i + 2] = base + thick;
  }
}

/// The decomposition of one tetrahedron into a slot whose indices start at `base`.
inline Projection Decompose(const ProjectedPoint* const c[4], const float scalars[4],
  const float* const* colours, TetVertex out[VerticesPerTetrahedron],
  std::uint32_t indices[IndicesPerTetrahedron], std::uint32_t base)
{
  double x[4], y[4];
  FanGeometry g;
  if (!Corners(c, scalars, x, y) || !ComputeFanGeometry(c, scalars, x, y, g))
  {
    WriteDegenerateSlot(out, indices, base);
    return g.projection;
  }
  FillSlot(c, scalars, colours, g, out, indices, base);
  return g.projection;
}

/// The fan of a drawable tetrahedron of geometry `g`.
inline void FillFan(const ProjectedPoint* const c[4], const float scalars[4],
  const float* const* colours, FanGeometry& g, Fan& fan)
{
  if (colours)
  {
    ColourThick(colours, g, g.thick);
  }
  // Every byte is written once: clearing the whole record first (a rep stos per cell) was
  // one of the decomposition loop's hot spots in a profile.
  fan.centre = g.thick;
  for (int i = 0; i < 4; ++i)
  {
    const int k = g.boundary[i];
    fan.boundary[i] = i < g.count ? CornerRecord(c[k], scalars[k]) : TetVertex{};
    if (colours && i < g.count)
    {
      ColourCorner(colours, k, fan.boundary[i]);
    }
  }
  fan.count = static_cast<std::uint8_t>(g.count);
  fan.closed = 1;
  fan.straddles = 0;
  std::memset(fan.padding, 0, sizeof(fan.padding));
}

/// The decomposition of one tetrahedron into a fan (Decompose.h).
inline Projection DecomposeToFan(
  const ProjectedPoint* const c[4], const float scalars[4], const float* const* colours, Fan& fan)
{
  double x[4], y[4];
  FanGeometry g;
  if (!Corners(c, scalars, x, y) || !ComputeFanGeometry(c, scalars, x, y, g))
  {
    fan = Fan{};
    return g.projection;
  }
  FillFan(c, scalars, colours, g, fan);
  return g.projection;
}

/// Whether the viewport of `input` culls the tetrahedron `corners` (DecomposeInput's
/// viewport): all four corners usable and no pixel centre in their box.
inline bool CoversNoPixel(const DecomposeInput& input, const ProjectedPoint* const corners[4])
{
  return !input.imageSize.Empty() && AllUsable(corners) &&
    !detail::CoversPixelCentre(corners, input.imageSize);
}

/// Whether the tetrahedron `corners`, drawable with `scalars`, is hidden behind the opaque
/// pixels of `input` (DecomposeInput::hidden).
inline bool Hidden(
  const DecomposeInput& input, const ProjectedPoint* const corners[4], const float scalars[4])
{
  return input.hidden && Drawable(corners, scalars) && detail::HiddenBehind(corners, *input.hidden);
}

/// The tetrahedron `corners` into slot-local records with global index base `base`,
/// culled when it covers no pixel centre of the viewport or is hidden.
inline ProjectionClass DecomposeCorners(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], const float* const* colours,
  std::uint32_t base, TetVertex slotVertices[VerticesPerTetrahedron],
  std::uint32_t slotIndices[IndicesPerTetrahedron])
{
  const bool noPixel = CoversNoPixel(input, corners);
  if (noPixel || Hidden(input, corners, scalars))
  {
    WriteDegenerateSlot(slotVertices, slotIndices, base);
    return noPixel ? ProjectionClass::CoversNoPixel : ProjectionClass::Hidden;
  }
  return Decompose(corners, scalars, colours, slotVertices, slotIndices, base).kind;
}

/// Writes slots (the OpenGL buffers): slot k at vertices[5k], indices[12k].
struct SlotWriter
{
  TetVertex* vertices;
  std::uint32_t* indices;
  bool streaming;

  ProjectionClass Cell(const DecomposeInput& input, const ProjectedPoint* const corners[4],
    const float scalars[4], const float* const* colours, std::int64_t k) const
  {
    TetVertex slotVertices[VerticesPerTetrahedron];
    std::uint32_t slotIndices[IndicesPerTetrahedron];
    const ProjectionClass kind = DecomposeCorners(input, corners, scalars, colours,
      static_cast<std::uint32_t>(VerticesPerTetrahedron * k), slotVertices, slotIndices);
    detail::StoreSlot(slotVertices, slotIndices, vertices + VerticesPerTetrahedron * k,
      indices + IndicesPerTetrahedron * k, streaming);
    return kind;
  }
  /// Slot k of a drawable tetrahedron whose geometry the batch computed.
  void Write(const ProjectedPoint* const corners[4], const float scalars[4], FanGeometry& g,
    std::int64_t k) const
  {
#if defined(__x86_64__) || defined(_M_X64)
    if (streaming)
    {
      StreamSlot(corners, scalars, g, k);
      return;
    }
#endif
    TetVertex slotVertices[VerticesPerTetrahedron];
    std::uint32_t slotIndices[IndicesPerTetrahedron];
    FillSlot(corners, scalars, nullptr, g, slotVertices, slotIndices,
      static_cast<std::uint32_t>(VerticesPerTetrahedron * k));
    detail::StoreSlot(slotVertices, slotIndices, vertices + VerticesPerTetrahedron * k,
      indices + IndicesPerTetrahedron * k, streaming);
  }
#if defined(__x86_64__) || defined(_M_X64)
  /**
   * FillSlot's bytes, assembled in registers and streamed 8 bytes at a time: a slot built on
   * the stack and loaded back 8 bytes at a time waits for its 4-byte stores to retire (the
   * same as FanWriter::Write).
   */
  void StreamSlot(const ProjectedPoint* const corners[4], const float scalars[4],
    const FanGeometry& g, std::int64_t k) const
  {
    const float thick[6] = { g.thick.x, g.thick.y, g.thick.z, g.thick.scalarFront,
      g.thick.scalarBack, g.thick.thickness };
    // Field f of slot vertex v: the thick vertex's record at v = thickSlot and at v = 4 (the
    // unused copy of a triangle projection), a corner's record elsewhere.
    auto field = [&](int v, int f) -> float
    {
      if (v == 4 || v == g.thickSlot)
      {
        return thick[f];
      }
      switch (f)
      {
        case 0:
          return static_cast<float>(corners[v]->x);
        case 1:
          return static_cast<float>(corners[v]->y);
        case 2:
          return static_cast<float>(corners[v]->z);
        case 5:
          return 0.0f;
        default:
          return scalars[v];
      }
    };
    auto pack = [](std::uint32_t low, std::uint32_t high)
    { return static_cast<long long>(low | (static_cast<std::uint64_t>(high) << 32)); };
    auto bits = [](float value)
    {
      std::uint32_t word;
      std::memcpy(&word, &value, sizeof(word));
      return word;
    };
    auto* vertexWords = reinterpret_cast<long long*>(this->vertices + VerticesPerTetrahedron * k);
    constexpr int Floats = VerticesPerTetrahedron * 6;
    static_assert(sizeof(TetVertex) == 6 * sizeof(float), "a record is 6 floats");
#pragma GCC unroll 16
    for (int q = 0; q < Floats / 2; ++q)
    {
      _mm_stream_si64(vertexWords + q,
        pack(bits(field((2 * q) / 6, (2 * q) % 6)), bits(field((2 * q + 1) / 6, (2 * q + 1) % 6))));
    }
    // FillSlot's indices: triangle i is (boundary[i], boundary[i + 1], thick), the fourth of a
    // triangle projection degenerate on the thick vertex.
    const auto base = static_cast<std::uint32_t>(VerticesPerTetrahedron * k);
    const auto t = base + static_cast<std::uint32_t>(g.thickSlot);
    auto index = [&](int j) -> std::uint32_t
    {
      const int i = j / 3, corner = j % 3;
      if (corner == 2 || i >= g.count)
      {
        return t;
      }
      return base + static_cast<std::uint32_t>(g.boundary[corner == 0 ? i : (i + 1) % g.count]);
    };
    auto* indexWords = reinterpret_cast<long long*>(this->indices + IndicesPerTetrahedron * k);
#pragma GCC unroll 8
    for (int q = 0; q < static_cast<int>(IndicesPerTetrahedron) / 2; ++q)
    {
      _mm_stream_si64(indexWords + q, pack(index(2 * q), index(2 * q + 1)));
    }
  }
#endif
  /// Slot k of a hidden tetrahedron: degenerate, as OpenGL draws every slot.
  void Hidden(std::int64_t k) const { this->NotDrawable(k); }
  /// Slot k drawing nothing (not drawable, or culled).
  void NotDrawable(std::int64_t k) const
  {
    TetVertex slotVertices[VerticesPerTetrahedron];
    std::uint32_t slotIndices[IndicesPerTetrahedron];
    WriteDegenerateSlot(
      slotVertices, slotIndices, static_cast<std::uint32_t>(VerticesPerTetrahedron * k));
    detail::StoreSlot(slotVertices, slotIndices, vertices + VerticesPerTetrahedron * k,
      indices + IndicesPerTetrahedron * k, streaming);
  }
};

/// The tetrahedron `corners` as a fan, count 0 when it covers no pixel centre or is hidden.
inline ProjectionClass DecomposeFanCorners(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], const float* const* colours,
  Fan& fan)
{
  const bool noPixel = CoversNoPixel(input, corners);
  if (noPixel || Hidden(input, corners, scalars))
  {
    fan = Fan{};
    return noPixel ? ProjectionClass::CoversNoPixel : ProjectionClass::Hidden;
  }
  return DecomposeToFan(corners, scalars, colours, fan).kind;
}

/// Writes fans (the CPU compositor's input): fan k at fans[k].
struct FanWriter
{
  Fan* fans;
  bool streaming;

  ProjectionClass Cell(const DecomposeInput& input, const ProjectedPoint* const corners[4],
    const float scalars[4], const float* const* colours, std::int64_t k) const
  {
    Fan fan;
    const ProjectionClass kind = DecomposeFanCorners(input, corners, scalars, colours, fan);
    detail::StoreFan(fan, fans + k, streaming);
    return kind;
  }
  /// Fan k of a drawable tetrahedron whose geometry the batch computed.
  void Write(const ProjectedPoint* const corners[4], const float scalars[4], FanGeometry& g,
    std::int64_t k) const
  {
#if defined(__x86_64__) || defined(_M_X64)
    if (streaming)
    {
      // FillFan's bytes, assembled in registers: a record assembled on the stack and loaded
      // back 16 bytes at a time waits for its 4-byte stores to retire.
      float b[4][4]; // x, y, z, scalar of the boundary corners; zero past count
      for (int i = 0; i < 4; ++i)
      {
        const int c = g.boundary[i];
        const bool real = i < g.count;
        b[i][0] = real ? static_cast<float>(corners[c]->x) : 0.0f;
        b[i][1] = real ? static_cast<float>(corners[c]->y) : 0.0f;
        b[i][2] = real ? static_cast<float>(corners[c]->z) : 0.0f;
        b[i][3] = real ? scalars[c] : 0.0f;
      }
      const TetVertex& t = g.thick;
      const std::uint32_t tail = static_cast<std::uint32_t>(g.count) | (1u << 8); // closed
      float tailBits;
      std::memcpy(&tailBits, &tail, sizeof(tailBits));
      auto* out = reinterpret_cast<__m128*>(fans + k);
      _mm_stream_ps(reinterpret_cast<float*>(out + 0), _mm_setr_ps(t.x, t.y, t.z, t.scalarFront));
      _mm_stream_ps(reinterpret_cast<float*>(out + 1),
        _mm_setr_ps(t.scalarBack, t.thickness, b[0][0], b[0][1]));
      _mm_stream_ps(
        reinterpret_cast<float*>(out + 2), _mm_setr_ps(b[0][2], b[0][3], b[0][3], 0.0f));
      _mm_stream_ps(
        reinterpret_cast<float*>(out + 3), _mm_setr_ps(b[1][0], b[1][1], b[1][2], b[1][3]));
      _mm_stream_ps(
        reinterpret_cast<float*>(out + 4), _mm_setr_ps(b[1][3], 0.0f, b[2][0], b[2][1]));
      _mm_stream_ps(
        reinterpret_cast<float*>(out + 5), _mm_setr_ps(b[2][2], b[2][3], b[2][3], 0.0f));
      _mm_stream_ps(
        reinterpret_cast<float*>(out + 6), _mm_setr_ps(b[3][0], b[3][1], b[3][2], b[3][3]));
      _mm_stream_ps(reinterpret_cast<float*>(out + 7), _mm_setr_ps(b[3][3], 0.0f, tailBits, 0.0f));
      return;
    }
#endif
    Fan fan;
    FillFan(corners, scalars, nullptr, g, fan);
    detail::StoreFan(fan, fans + k, streaming);
  }
  /// Fan k of a hidden tetrahedron: not written (its class tells the reader to skip it).
  void Hidden(std::int64_t) const {}
  /// Fan k drawing nothing (not drawable, or culled).
  void NotDrawable(std::int64_t k) const
  {
    detail::StoreFan(Fan{}, fans + k, streaming);
  }
};

/// Slot (or fan) k, holding `cell`.
template <typename Access, typename Writer>
inline void DecomposeCell(const Access& cells, const DecomposeInput& input,
  const float* cellScalars, std::uint32_t cell, std::int64_t k, const Writer& writer,
  ProjectionClass* classes)
{
  std::int64_t ids[4];
  ProjectionClass kind = ProjectionClass::NotDrawable;
  if (cells.TetrahedronPoints(cell, ids))
  {
    const ProjectedPoint* corners[4] = { input.points + ids[0], input.points + ids[1],
      input.points + ids[2], input.points + ids[3] };
    float scalars[4];
    const float* colours[4] = { nullptr, nullptr, nullptr, nullptr };
    for (int i = 0; i < 4; ++i)
    {
      scalars[i] = cellScalars ? cellScalars[cell] : corners[i]->scalar;
      if (input.colours)
      {
        colours[i] = input.colours + 4 * (cellScalars ? static_cast<std::int64_t>(cell) : ids[i]);
      }
    }
    kind = writer.Cell(input, corners, scalars, input.colours ? colours : nullptr, k);
  }
  else
  {
    writer.NotDrawable(k);
  }
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
  detail::ForEachThreadBlock(static_cast<std::size_t>(n), threads,
    [&](detail::IndexRange r)
    {
      for (std::size_t i = r.begin; i < r.end; ++i)
      {
        body(static_cast<std::int64_t>(i));
      }
      detail::FinishStores();
    });
}

template <typename Access>
void DecomposeAll(const Access& cells, const DecomposeInput& input, const SortKey* order,
  std::size_t count, TetVertex* vertices, std::uint32_t* indices, ProjectionClass* classes,
  int threads)
{
  const float* cellScalars = CellScalars(input);
  const SlotWriter writer{ vertices, indices, detail::CanStream(vertices, indices) };
  ParallelSlots(static_cast<std::int64_t>(count), threads,
    [&](std::int64_t k)
    { DecomposeCell(cells, input, cellScalars, CellOfKey(order[k]), k, writer, classes); });
}

/**
 * Tetrahedra gathered for DecomposeBatch (detail/DecomposeBatch.h) and written out when the
 * batch is full: the decomposition of cells without vertex colours. Cells that are not
 * tetrahedra, have an unusable corner or scalar, or are culled never enter a batch.
 */
template <typename Writer>
class Batch
{
public:
  Batch(const DecomposeInput& input, const Writer& writer, ProjectionClass* classes)
    : Input(input)
    , Out(writer)
    , Classes(classes)
    , Table(Patterns())
  {
  }
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;

  /// Slot (or fan) k: the tetrahedron of points `ids` with `scalars`.
  void Add(const std::int64_t ids[4], const float scalars[4], std::int64_t k)
  {
    const ProjectedPoint* const corners[4] = { this->Input.points + ids[0],
      this->Input.points + ids[1], this->Input.points + ids[2], this->Input.points + ids[3] };
    // As DecomposeCorners: culled when it covers no pixel centre, then drawable or not.
    if (CoversNoPixel(this->Input, corners))
    {
      this->Skip(k, ProjectionClass::CoversNoPixel);
      return;
    }
    if (!Drawable(corners, scalars))
    {
      this->Skip(k, ProjectionClass::NotDrawable);
      return;
    }
    if (this->Input.hidden && detail::HiddenBehind(corners, *this->Input.hidden))
    {
      // Left unwritten where its class says so; without classes, written empty.
      if (this->Classes)
      {
        this->Out.Hidden(k);
        this->Classes[k] = ProjectionClass::Hidden;
      }
      else
      {
        this->Out.NotDrawable(k);
      }
      return;
    }
    for (int i = 0; i < 4; ++i)
    {
      this->Cells.point[i][this->Count] = ids[i];
      this->Cells.scalar[i][this->Count] = scalars[i];
    }
    this->Position[this->Count] = k;
    if (++this->Count == detail::BatchSize)
    {
      this->Flush();
    }
  }

  /// Slot k draws nothing, for `reason`.
  void Skip(std::int64_t k, ProjectionClass reason) const
  {
    this->Out.NotDrawable(k);
    if (this->Classes)
    {
      this->Classes[k] = reason;
    }
  }

  /// Decomposes the tetrahedra gathered and writes their slots (or fans).
  void Flush()
  {
    if (this->Count == 0)
    {
      return;
    }
    // Lanes past the last tetrahedron repeat the first: every lane reads valid points.
    for (int l = this->Count; l < detail::BatchSize; ++l)
    {
      for (int i = 0; i < 4; ++i)
      {
        this->Cells.point[i][l] = this->Cells.point[i][0];
        this->Cells.scalar[i][l] = this->Cells.scalar[i][0];
      }
    }
    detail::DecomposeBatch(
      this->Input.points, this->Cells, this->Count, this->Table.roles, this->Result);
    for (int l = 0; l < this->Count; ++l)
    {
      const std::int64_t pattern = this->Result.pattern[l];
      const ProjectionClass kind =
        this->Result.hasArea[l] ? this->Table.kind[pattern] : ProjectionClass::NotDrawable;
      if (kind == ProjectionClass::NotDrawable)
      {
        this->Skip(this->Position[l], kind);
        continue;
      }
      FanGeometry g;
      g.projection.kind = kind;
      for (int r = 0; r < 4; ++r)
      {
        g.projection.vertex[r] = static_cast<int>(this->Table.roles.role[r][pattern]);
      }
      Silhouette(g.projection, g);
      const auto& t = this->Result.thick;
      g.thick = TetVertex{ t[0][l], t[1][l], t[2][l], t[3][l], t[4][l], t[5][l] };
      const ProjectedPoint* const corners[4] = { this->Input.points + this->Cells.point[0][l],
        this->Input.points + this->Cells.point[1][l], this->Input.points + this->Cells.point[2][l],
        this->Input.points + this->Cells.point[3][l] };
      const float scalars[4] = { this->Cells.scalar[0][l], this->Cells.scalar[1][l],
        this->Cells.scalar[2][l], this->Cells.scalar[3][l] };
      this->Out.Write(corners, scalars, g, this->Position[l]);
      if (this->Classes)
      {
        this->Classes[this->Position[l]] = kind;
      }
    }
    this->Count = 0;
  }

private:
  const DecomposeInput& Input;
  const Writer& Out;
  ProjectionClass* Classes;
  const PatternTable& Table;
  detail::TetBatch Cells;
  detail::TetBatchResult Result;
  std::int64_t Position[detail::BatchSize]; ///< the slot (or fan) of each tetrahedron
  int Count = 0;
};

/**
 * How many visited entries ahead DecomposeBlock asks the cache for a cell's corner points.
 * A frame drawn in several batches visits, per batch, the cells of one slab of the order:
 * their points lie far apart in a point array larger than the cache, where the hardware's
 * prefetchers do not follow them (Documentation/compositor.md has the measurement).
 */
constexpr std::int64_t CornersAhead = 32;

/// Asks the cache for the corner points of entry i of those the input visits (a hint: it
/// reads the cell's point ids, never a point).
template <typename Access>
inline void PrefetchCorners(
  const Access& cells, const DecomposeInput& input, const std::uint32_t* rank, std::int64_t i)
{
  std::size_t c;
  std::uint32_t r;
  input.Visited(static_cast<std::size_t>(i), rank, c, r);
  std::int64_t ids[4];
  if (cells.TetrahedronPoints(c, ids))
  {
    for (int k = 0; k < 4; ++k)
    {
      __builtin_prefetch(input.points + ids[k]);
    }
  }
}

/// The cells of entries [begin, end) of those the input visits (DecomposeInput::Visited)
/// whose ranks fall in [firstRank, firstRank + count), in batches.
template <typename Access, typename Writer>
void DecomposeBlock(const Access& cells, const DecomposeInput& input, const float* cellScalars,
  const std::uint32_t* rank, std::size_t firstRank, std::size_t count, std::int64_t begin,
  std::int64_t end, const Writer& writer, ProjectionClass* classes)
{
  Batch<Writer> batch(input, writer, classes);
  for (std::int64_t i = begin; i < end; ++i)
  {
    if (i + CornersAhead < end)
    {
      PrefetchCorners(cells, input, rank, i + CornersAhead);
    }
    std::size_t c;
    std::uint32_t r;
    input.Visited(static_cast<std::size_t>(i), rank, c, r);
    const std::uint64_t k = static_cast<std::uint64_t>(r) - firstRank;
    if (r == NotInOrder || k >= count)
    {
      continue;
    }
    std::int64_t ids[4];
    if (!cells.TetrahedronPoints(static_cast<std::size_t>(c), ids))
    {
      batch.Skip(static_cast<std::int64_t>(k), ProjectionClass::NotDrawable);
      continue;
    }
    float scalars[4];
    for (int i = 0; i < 4; ++i)
    {
      scalars[i] = cellScalars ? cellScalars[c] : input.points[ids[i]].scalar;
    }
    batch.Add(ids, scalars, static_cast<std::int64_t>(k));
  }
  batch.Flush();
}

template <typename Access, typename Writer>
void DecomposeAllByRank(const Access& cells, const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, const Writer& writer, ProjectionClass* classes,
  int threads)
{
  const float* cellScalars = CellScalars(input);
  // Cells the depth keys already found to cover a pixel centre are not tested again.
  DecomposeInput cellInput = input;
  if (input.cellsCoverPixels)
  {
    cellInput.imageSize = {};
  }
  const auto n = static_cast<std::int64_t>(input.VisitedCount());
  if (input.colours)
  {
    // Dependent colours mix the corners' colours with the scalar code's weights.
    ParallelSlots(n, threads,
      [&](std::int64_t i)
      {
        std::size_t c;
        std::uint32_t r;
        input.Visited(static_cast<std::size_t>(i), rank, c, r);
        // One unsigned comparison: NotInOrder and ranks outside the window both fail.
        const std::uint64_t k = static_cast<std::uint64_t>(r) - firstRank;
        if (r != NotInOrder && k < count)
        {
          DecomposeCell(cells, cellInput, cellScalars, static_cast<std::uint32_t>(c),
            static_cast<std::int64_t>(k), writer, classes);
        }
      });
    return;
  }
  detail::ForEachThreadBlock(static_cast<std::size_t>(n), threads,
    [&](detail::IndexRange r)
    {
      DecomposeBlock(cells, cellInput, cellScalars, rank, firstRank, count,
        static_cast<std::int64_t>(r.begin), static_cast<std::int64_t>(r.end), writer, classes);
      detail::FinishStores();
    });
}

} // namespace

Projection DecomposeTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  TetVertex vertices[VerticesPerTetrahedron], std::uint32_t indices[IndicesPerTetrahedron],
  const float* const* colours)
{
  return Decompose(corners, scalars, colours, vertices, indices, 0);
}

ProjectionClass DecomposeIntoSlot(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], std::size_t k,
  TetVertex* vertices, std::uint32_t* indices, const float* const* colours)
{
  return DecomposeCorners(input, corners, scalars, colours,
    static_cast<std::uint32_t>(VerticesPerTetrahedron * k), vertices + VerticesPerTetrahedron * k,
    indices + IndicesPerTetrahedron * k);
}

void DecomposeTetrahedra(const DecomposeInput& input, const SortKey* order, std::size_t count,
  TetVertex* vertices, std::uint32_t* indices, ProjectionClass* classes, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  detail::DispatchCells(input.cells, input.pointCount,
    [&](const auto& cells)
    { DecomposeAll(cells, input, order, count, vertices, indices, classes, nthreads); });
}

void DecomposeTetrahedraByRank(const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, TetVertex* vertices, std::uint32_t* indices,
  ProjectionClass* classes, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const SlotWriter writer{ vertices, indices, detail::CanStream(vertices, indices) };
  detail::DispatchCells(input.cells, input.pointCount,
    [&](const auto& cells)
    { DecomposeAllByRank(cells, input, rank, firstRank, count, writer, classes, nthreads); });
}

void DecomposeFansByRank(const DecomposeInput& input, const std::uint32_t* rank,
  std::size_t firstRank, std::size_t count, Fan* fans, ProjectionClass* classes, int threads)
{
  const int nthreads = detail::ResolveThreads(threads);
  const FanWriter writer{ fans, detail::CanStreamFans(fans) };
  detail::DispatchCells(input.cells, input.pointCount,
    [&](const auto& cells)
    { DecomposeAllByRank(cells, input, rank, firstRank, count, writer, classes, nthreads); });
}

Projection DecomposeTetrahedronToFan(const ProjectedPoint* const corners[4], const float scalars[4],
  Fan& fan, const float* const* colours)
{
  return DecomposeToFan(corners, scalars, colours, fan);
}

ProjectionClass DecomposeIntoFan(const DecomposeInput& input,
  const ProjectedPoint* const corners[4], const float scalars[4], Fan& fan,
  const float* const* colours)
{
  return DecomposeFanCorners(input, corners, scalars, colours, fan);
}

template <typename Cells, typename Piece>
bool DecompositionStage::Run(const Key& key, const DecomposeInput& input, const std::uint32_t* rank,
  const std::vector<NearPiece>& pieces, int threads, Cells&& cells, Piece&& piece)
{
  if (this->Record.Holds(key))
  {
    return false;
  }
  const std::size_t first = key.first, count = key.count;
  if (this->SlotClasses.size() < count)
  {
    this->SlotClasses.resize(count);
  }
  cells(input, first, count, this->SlotClasses.data(), threads);
  // Pieces of cells cut by the near plane: ranks after the cells'.
  const auto pieceCount = static_cast<std::int64_t>(pieces.size());
  // Few pieces are not worth waking the threads.
  detail::ParallelFor(0, pieceCount, pieceCount > 1024 ? threads : 1,
    [&](std::int64_t j)
    {
      const std::uint32_t r = rank[input.cells.cellCount + j];
      const std::uint64_t k = static_cast<std::uint64_t>(r) - first;
      if (r != NotInOrder && k < count)
      {
        const NearPiece& p = pieces[j];
        const ProjectedPoint* corners[4] = { &p.corners[0], &p.corners[1], &p.corners[2],
          &p.corners[3] };
        const float* colours[4] = { p.colours[0], p.colours[1], p.colours[2], p.colours[3] };
        this->SlotClasses[k] =
          piece(input, corners, p.scalars, input.colours ? colours : nullptr, k);
      }
    });
  // The window's slots that draw nothing: covering no pixel centre, not drawable, or hidden.
  struct Undrawn
  {
    std::size_t pixelCulled = 0, notDrawable = 0, hidden = 0;
  };
  const Undrawn undrawn = detail::ParallelReduce(
    0, static_cast<std::int64_t>(count), threads, Undrawn{},
    [](Undrawn a, Undrawn b)
    {
      return Undrawn{ a.pixelCulled + b.pixelCulled, a.notDrawable + b.notDrawable,
        a.hidden + b.hidden };
    },
    [&](std::int64_t k)
    {
      const ProjectionClass kind = this->SlotClasses[k];
      return Undrawn{ kind == ProjectionClass::CoversNoPixel ? 1u : 0u,
        kind == ProjectionClass::NotDrawable ? 1u : 0u, kind == ProjectionClass::Hidden ? 1u : 0u };
    });
  this->CoversNoPixel = undrawn.pixelCulled;
  this->Undrawable = undrawn.notDrawable;
  this->Concealed = undrawn.hidden;
  this->Record.Store(key);
  return true;
}

bool SlotStage::Update(const Key& key, const DecomposeInput& input, const std::uint32_t* rank,
  const std::vector<NearPiece>& pieces, int threads)
{
  return this->Run(
    key, input, rank, pieces, threads,
    [&](const DecomposeInput& in, std::size_t first, std::size_t n, ProjectionClass* classes,
      int team)
    {
      AllocationPoint(AllocationSite::Decomposition);
      if (this->VertexBuffer.size() < VerticesPerTetrahedron * n)
      {
        this->VertexBuffer.resize(VerticesPerTetrahedron * n);
      }
      if (this->IndexBuffer.size() < IndicesPerTetrahedron * n)
      {
        this->IndexBuffer.resize(IndicesPerTetrahedron * n);
      }
      DecomposeTetrahedraByRank(
        in, rank, first, n, this->VertexBuffer.data(), this->IndexBuffer.data(), classes, team);
    },
    [&](const DecomposeInput& in, const ProjectedPoint* const corners[4], const float* scalars,
      const float* const* colours, std::uint64_t k)
    {
      return DecomposeIntoSlot(
        in, corners, scalars, k, this->VertexBuffer.data(), this->IndexBuffer.data(), colours);
    });
}

bool DecompositionStage::ReserveClasses(std::size_t slots)
{
  return ReserveDiscarding(this->SlotClasses, slots);
}

void SlotStage::Reserve(std::size_t slots)
{
  if (this->VertexBuffer.capacity() >= VerticesPerTetrahedron * slots &&
    this->IndexBuffer.capacity() >= IndicesPerTetrahedron * slots &&
    this->SlotClasses.capacity() >= slots)
  {
    return;
  }
  AllocationPoint(AllocationSite::Decomposition);
  this->Forget(); // the held window's buffers are dropped
  ReserveDiscarding(this->VertexBuffer, VerticesPerTetrahedron * slots);
  ReserveDiscarding(this->IndexBuffer, IndicesPerTetrahedron * slots);
  this->ReserveClasses(slots);
}

void SlotStage::Release()
{
  LargeVector<TetVertex>().swap(this->VertexBuffer);
  LargeVector<std::uint32_t>().swap(this->IndexBuffer);
  LargeVector<ProjectionClass>().swap(this->SlotClasses);
  this->Forget();
}

std::size_t SlotStage::MemoryBytes() const
{
  return this->VertexBuffer.capacity() * sizeof(TetVertex) +
    this->IndexBuffer.capacity() * sizeof(std::uint32_t) + this->SlotClasses.capacity();
}

bool FanStage::Update(const Key& key, const DecomposeInput& input, const std::uint32_t* rank,
  const std::vector<NearPiece>& pieces, int threads)
{
  return this->Run(
    key, input, rank, pieces, threads,
    [&](const DecomposeInput& in, std::size_t first, std::size_t n, ProjectionClass* classes,
      int team)
    {
      AllocationPoint(AllocationSite::Decomposition);
      if (this->FanBuffer.size() < n)
      {
        this->FanBuffer.resize(n);
      }
      DecomposeFansByRank(in, rank, first, n, this->FanBuffer.data(), classes, team);
    },
    [&](const DecomposeInput& in, const ProjectedPoint* const corners[4], const float* scalars,
      const float* const* colours, std::uint64_t k)
    { return DecomposeIntoFan(in, corners, scalars, this->FanBuffer[k], colours); });
}

void FanStage::Reserve(std::size_t slots)
{
  if (this->FanBuffer.capacity() >= slots && this->SlotClasses.capacity() >= slots)
  {
    return;
  }
  AllocationPoint(AllocationSite::Decomposition);
  this->Forget(); // the held window's buffers are dropped
  ReserveDiscarding(this->FanBuffer, slots);
  this->ReserveClasses(slots);
}

void FanStage::Release()
{
  LargeVector<Fan>().swap(this->FanBuffer);
  LargeVector<ProjectionClass>().swap(this->SlotClasses);
  this->Forget();
}

std::size_t FanStage::MemoryBytes() const
{
  return this->FanBuffer.capacity() * sizeof(Fan) + this->SlotClasses.capacity();
}

} // namespace mtpt
