// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FuzzFrame.cxx
 * @brief libFuzzer target `mtpt_fuzz_frame`: one whole frame of the core on a small hostile
 * mesh, with every invariant the headers promise checked (abort() on a violation).
 *
 * The input bytes are decoded (FuzzedDataProvider) into:
 * - up to 40 points, float or double, each random, a repeat of an earlier point, on a line
 *   or a plane through earlier points, on a coarse grid (exact coincidences), huge (up to
 *   FLT_MAX, or 1e300 in double), tiny (denormal), NaN, +-Inf, or raw bit patterns;
 * - up to 48 cells in vtkCellArray layout (int32 or int64): mostly tetrahedra, some with 0,
 *   3 or 5 points, ids in range, repeated within a cell, -1, pointCount, huge;
 * - no scalars, point scalars or cell scalars (random, huge, NaN, Inf, raw);
 * - a camera: orthographic or perspective, eye outside, near or inside the mesh (cells cut
 *   by the near plane), an optional shearing or mirroring model matrix, a viewport from
 *   1x1 to 64x64, pixel culling on or off, frustum culling on or off, an opacity table
 *   (culling) or none, the partition or the radix sort.
 *
 * Checked after FramePipeline::Run (see Decompose.h, DepthKeys.h, FramePipeline.h):
 * - Run succeeds; every count is consistent (slots = sorted cells, culled <= sorted,
 *   sorted <= cells - culled + near-plane pieces, at most 3 pieces per cut cell);
 * - keys are strictly ascending (back to front), name distinct cells or pieces in range,
 *   and each cell's key is the depth of its centroid recomputed from Points();
 * - every index of slot k lies in [5k, 5k + 5); every vertex is finite, thickness >= 0;
 * - the same frame on another thread count, and on a pipeline with reuse on that first
 *   drew a slightly different frame (or a larger mesh), gives bit-identical keys and
 *   buffers;
 * - the Compositor (VTK-compatible or pre-integrated shading, perspective-exact in
 *   perspective views, with or without an opaque depth image) gives every pixel finite and
 *   in [0, 1], bit-identical for two thread counts;
 * - the CPU backend's path (DecomposeFans in batches of 1 to all, binned into tiles by
 *   Compositor::Composite, Resolve) gives the slots' image within the set-up's rounding
 *   (pre-integrated: on well-conditioned frames), draws nothing outside its touched
 *   region, and resolves over a colour beneath in float and in 8 bits alike (within half a
 *   step of 8 bits).
 */
#include "mtpt/Compositor.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/Gradients.h"
#include "mtpt/Lighting.h"

#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

namespace
{

#define FUZZ_CHECK(condition, ...)                                                                 \
  do                                                                                               \
  {                                                                                                \
    if (!(condition))                                                                              \
    {                                                                                              \
      std::fprintf(stderr, "mtpt_fuzz_frame: invariant violated at %s:%d: %s\n  ", __FILE__,       \
        __LINE__, #condition);                                                                     \
      std::fprintf(stderr, __VA_ARGS__);                                                           \
      std::fprintf(stderr, "\n");                                                                  \
      std::abort();                                                                                \
    }                                                                                              \
  } while (false)

using mtpt::Matrix4;

constexpr int MaxPoints = 40;
constexpr int MaxCells = 48;
constexpr int MaxViewport = 64;

struct Vec3
{
  double x, y, z;
};

Vec3 Sub(const Vec3& a, const Vec3& b)
{
  return { a.x - b.x, a.y - b.y, a.z - b.z };
}
double Dot(const Vec3& a, const Vec3& b)
{
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 Cross(const Vec3& a, const Vec3& b)
{
  return { a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x };
}
bool Normalize(Vec3& a)
{
  const double n = std::sqrt(Dot(a, a));
  if (!(n > 1e-12))
  {
    return false;
  }
  a = { a.x / n, a.y / n, a.z / n };
  return true;
}

/// A float drawn from the classes that break geometry code.
float HostileFloat(FuzzedDataProvider& in, float low, float high)
{
  switch (in.ConsumeIntegralInRange<int>(0, 15))
  {
    case 0:
      return 0.0f;
    case 1:
      return in.ConsumeBool() ? 1e30f : -1e30f;
    case 2:
      return in.ConsumeBool() ? std::numeric_limits<float>::max()
                              : -std::numeric_limits<float>::max();
    case 3:
      return in.ConsumeBool() ? 1e-40f : -1e-30f; // denormal, tiny
    case 4:
      return std::numeric_limits<float>::quiet_NaN();
    case 5:
      return in.ConsumeBool() ? std::numeric_limits<float>::infinity()
                              : -std::numeric_limits<float>::infinity();
    case 6:
    {
      const auto bits = in.ConsumeIntegral<std::uint32_t>();
      float f;
      std::memcpy(&f, &bits, sizeof(f));
      return f;
    }
    default:
      return in.ConsumeFloatingPointInRange<float>(low, high);
  }
}

/// The decoded mesh in the layouts the views read.
struct Mesh
{
  std::vector<float> pointsF;
  std::vector<double> pointsD;
  std::vector<std::int32_t> connectivity32, offsets32;
  std::vector<std::int64_t> connectivity64, offsets64;
  std::vector<float> scalars;
  bool doublePoints = false, int32Cells = false;
  std::size_t pointCount = 0, cellCount = 0;

  mtpt::PointsView Points() const
  {
    return doublePoints ? mtpt::PointsView::FromDouble(pointsD.data(), pointCount)
                        : mtpt::PointsView::FromFloat(pointsF.data(), pointCount);
  }
  mtpt::CellsView Cells() const
  {
    return int32Cells
      ? mtpt::CellsView::FromInt32(connectivity32.data(), offsets32.data(), cellCount)
      : mtpt::CellsView::FromInt64(connectivity64.data(), offsets64.data(), cellCount);
  }
};

void DecodePoints(FuzzedDataProvider& in, Mesh& mesh)
{
  mesh.doublePoints = in.ConsumeBool();
  mesh.pointCount = in.ConsumeIntegralInRange<std::size_t>(0, MaxPoints);
  const double scale = in.PickValueInArray({ 1.0, 1.0, 1e-3, 1e3, 1e-7 });
  std::vector<double> p;
  p.reserve(3 * mesh.pointCount);
  for (std::size_t i = 0; i < mesh.pointCount; ++i)
  {
    const std::size_t have = i;
    const auto earlier = [&]() { return 3 * in.ConsumeIntegralInRange<std::size_t>(0, have - 1); };
    double xyz[3];
    const int kind = in.ConsumeIntegralInRange<int>(0, 11);
    if (kind == 0 && have > 0)
    {
      const std::size_t a = earlier(); // repeated point
      std::copy(p.begin() + a, p.begin() + a + 3, xyz);
    }
    else if (kind == 1 && have > 1)
    {
      const std::size_t a = earlier(), b = earlier(); // collinear
      const double t = in.ConsumeFloatingPointInRange<double>(-2.0, 2.0);
      for (int k = 0; k < 3; ++k)
      {
        xyz[k] = p[a + k] + t * (p[b + k] - p[a + k]);
      }
    }
    else if (kind == 2 && have > 2)
    {
      const std::size_t a = earlier(), b = earlier(), c = earlier(); // coplanar
      const double s = in.ConsumeFloatingPointInRange<double>(-2.0, 2.0);
      const double t = in.ConsumeFloatingPointInRange<double>(-2.0, 2.0);
      for (int k = 0; k < 3; ++k)
      {
        xyz[k] = p[a + k] + s * (p[b + k] - p[a + k]) + t * (p[c + k] - p[a + k]);
      }
    }
    else if (kind == 3)
    {
      for (double& v : xyz) // a coarse grid: exactly shared positions and edges
      {
        v = scale * 0.25 * in.ConsumeIntegralInRange<int>(-4, 4);
      }
    }
    else if (kind == 4)
    {
      for (double& v : xyz)
      {
        v = HostileFloat(in, -1.0f, 1.0f);
      }
    }
    else if (kind == 5 && mesh.doublePoints)
    {
      for (double& v : xyz) // beyond float range: only double points can hold these
      {
        v = in.PickValueInArray({ 1e300, -1e300, 1e40, std::numeric_limits<double>::max(),
          std::numeric_limits<double>::denorm_min() });
      }
    }
    else
    {
      for (double& v : xyz)
      {
        v = scale * in.ConsumeFloatingPointInRange<double>(-1.0, 1.0);
      }
    }
    if (!mesh.doublePoints)
    {
      for (double& v : xyz)
      {
        // Float points hold float values: clamp what does not fit (a double beyond
        // FLT_MAX converted to float is undefined behaviour in the decoder, not the core).
        if (std::isfinite(v) && std::fabs(v) > std::numeric_limits<float>::max())
        {
          v = std::copysign(std::numeric_limits<float>::infinity(), v);
        }
      }
    }
    p.insert(p.end(), xyz, xyz + 3);
  }
  if (mesh.doublePoints)
  {
    mesh.pointsD = p;
  }
  else
  {
    mesh.pointsF.assign(p.size(), 0.0f);
    for (std::size_t i = 0; i < p.size(); ++i)
    {
      mesh.pointsF[i] = static_cast<float>(p[i]);
    }
  }
  if (mesh.pointsD.empty())
  {
    mesh.pointsD.push_back(0.0); // never read: keeps data() non-null for an empty mesh
  }
  if (mesh.pointsF.empty())
  {
    mesh.pointsF.push_back(0.0f);
  }
}

void DecodeCells(FuzzedDataProvider& in, Mesh& mesh)
{
  mesh.int32Cells = in.ConsumeBool();
  mesh.cellCount = in.ConsumeIntegralInRange<std::size_t>(0, MaxCells);
  const auto n = static_cast<std::int64_t>(mesh.pointCount);
  std::vector<std::int64_t> connectivity, offsets{ 0 };
  for (std::size_t c = 0; c < mesh.cellCount; ++c)
  {
    int size = 4;
    if (in.ConsumeIntegralInRange<int>(0, 15) == 0)
    {
      size = in.PickValueInArray({ 0, 3, 5, 1 }); // not a tetrahedron
    }
    const std::size_t first = connectivity.size();
    for (int i = 0; i < size; ++i)
    {
      std::int64_t id = 0;
      switch (in.ConsumeIntegralInRange<int>(0, 19))
      {
        case 0:
          id = i > 0 ? connectivity[first + in.ConsumeIntegralInRange<int>(0, i - 1)] : 0;
          break;
        case 1:
          id = -1;
          break;
        case 2:
          id = n;
          break;
        case 3:
          id = in.PickValueInArray<std::int64_t>({ std::numeric_limits<std::int32_t>::max(),
            std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int64_t>::max(),
            std::numeric_limits<std::int64_t>::min(), std::int64_t(1) << 32 });
          break;
        default:
          id = n > 0 ? in.ConsumeIntegralInRange<std::int64_t>(0, n - 1) : 0;
          break;
      }
      connectivity.push_back(id);
    }
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  mesh.connectivity64 = connectivity;
  mesh.offsets64 = offsets;
  mesh.connectivity32.resize(connectivity.size());
  mesh.offsets32.resize(offsets.size());
  for (std::size_t i = 0; i < connectivity.size(); ++i)
  {
    // Wraps as vtkCellArray's int32 storage would hold a truncated id.
    mesh.connectivity32[i] = static_cast<std::int32_t>(static_cast<std::uint32_t>(connectivity[i]));
  }
  for (std::size_t i = 0; i < offsets.size(); ++i)
  {
    mesh.offsets32[i] = static_cast<std::int32_t>(offsets[i]);
  }
  if (connectivity.empty())
  {
    mesh.connectivity32.push_back(0); // never read: keeps data() non-null
    mesh.connectivity64.push_back(0);
  }
}

mtpt::ScalarsView DecodeScalars(FuzzedDataProvider& in, Mesh& mesh)
{
  mtpt::ScalarsView view;
  const int mode = in.ConsumeIntegralInRange<int>(0, 2);
  if (mode == 0)
  {
    return view; // no scalars
  }
  view.association =
    mode == 1 ? mtpt::ScalarsView::Association::Points : mtpt::ScalarsView::Association::Cells;
  const std::size_t count = mode == 1 ? mesh.pointCount : mesh.cellCount;
  mesh.scalars.resize(std::max<std::size_t>(count, 1));
  for (std::size_t i = 0; i < count; ++i)
  {
    mesh.scalars[i] = HostileFloat(in, -1.0f, 2.0f);
  }
  view.values = mesh.scalars.data();
  return view;
}

Matrix4 LookAt(const Vec3& eye, const Vec3& target, Vec3 up)
{
  Vec3 f = Sub(target, eye);
  if (!Normalize(f))
  {
    f = { 0, 0, -1 };
  }
  Vec3 s = Cross(f, up);
  if (!Normalize(s))
  {
    up = std::fabs(f.x) < 0.9 ? Vec3{ 1, 0, 0 } : Vec3{ 0, 1, 0 };
    s = Cross(f, up);
    Normalize(s);
  }
  const Vec3 u = Cross(s, f);
  return { s.x, s.y, s.z, -Dot(s, eye), u.x, u.y, u.z, -Dot(u, eye), -f.x, -f.y, -f.z, Dot(f, eye),
    0, 0, 0, 1 };
}

/// A camera the way VTK builds one: a rigid view matrix, an optional model matrix and a
/// glOrtho or gluPerspective projection.
void DecodeCamera(FuzzedDataProvider& in, mtpt::FrameInput& frame)
{
  frame.perspective = in.ConsumeBool();
  const double theta = in.ConsumeFloatingPointInRange<double>(0.0, 6.2832);
  const double phi = in.ConsumeFloatingPointInRange<double>(-1.57, 1.57);
  // Distance 0.05 puts the eye inside the mesh: cells are cut by the near plane.
  const double distance = in.PickValueInArray({ 4.0, 2.0, 0.5, 0.05, 10.0, 1e4 });
  const Vec3 target{ in.ConsumeFloatingPointInRange<double>(-1.0, 1.0),
    in.ConsumeFloatingPointInRange<double>(-1.0, 1.0),
    in.ConsumeFloatingPointInRange<double>(-1.0, 1.0) };
  const Vec3 eye{ target.x + distance * std::cos(phi) * std::cos(theta),
    target.y + distance * std::cos(phi) * std::sin(theta), target.z + distance * std::sin(phi) };
  const Vec3 up{ in.ConsumeFloatingPointInRange<double>(-1.0, 1.0),
    in.ConsumeFloatingPointInRange<double>(-1.0, 1.0), 1.0 };
  Matrix4 view = LookAt(eye, target, up);
  if (in.ConsumeIntegralInRange<int>(0, 3) == 0)
  {
    // A volume matrix: scale, shear or mirror (affine, finite).
    Matrix4 model = mtpt::IdentityMatrix();
    for (int r = 0; r < 3; ++r)
    {
      for (int c = 0; c < 4; ++c)
      {
        model[4 * r + c] += in.ConsumeFloatingPointInRange<double>(-2.0, 2.0);
      }
    }
    view = mtpt::Multiply(view, model);
  }
  frame.modelView = view;

  frame.imageSize.width = in.ConsumeIntegralInRange<int>(1, MaxViewport);
  frame.imageSize.height = in.ConsumeIntegralInRange<int>(1, MaxViewport);
  const double aspect = static_cast<double>(frame.imageSize.width) / frame.imageSize.height;
  const double nearZ = in.PickValueInArray({ 0.1, 1e-3, 1.0, 3.0, 1e-6 });
  const double farZ = nearZ + in.PickValueInArray({ 10.0, 1e-3, 100.0, 1e6, 3.0 });
  if (frame.perspective)
  {
    const double fovy = in.ConsumeFloatingPointInRange<double>(1.0, 170.0);
    const double c = 1.0 / std::tan(fovy * 3.14159265358979323846 / 360.0);
    frame.projection = { c / aspect, 0, 0, 0, 0, c, 0, 0, 0, 0, (farZ + nearZ) / (nearZ - farZ),
      2 * farZ * nearZ / (nearZ - farZ), 0, 0, -1, 0 };
  }
  else
  {
    const double h = in.PickValueInArray({ 1.5, 0.01, 3.0, 1e-5, 100.0 });
    const double w = h * aspect;
    // The view volume's centre is shifted as VTK's parallel projection does for a
    // window centre.
    const double cx = in.ConsumeFloatingPointInRange<double>(-0.5, 0.5) * w;
    const double cy = in.ConsumeFloatingPointInRange<double>(-0.5, 0.5) * h;
    const double l = cx - w, r = cx + w, b = cy - h, t = cy + h;
    frame.projection = { 2 / (r - l), 0, 0, -(r + l) / (r - l), 0, 2 / (t - b), 0,
      -(t + b) / (t - b), 0, 0, -2 / (farZ - nearZ), -(farZ + nearZ) / (farZ - nearZ), 0, 0, 0, 1 };
  }
}

/// A transfer function table: colours in [0, 1], attenuation >= 0 (often zero, to cull).
struct Table
{
  std::vector<float> rgba;
  mtpt::TransferFunctionTable view;
};

void DecodeTable(FuzzedDataProvider& in, Table& table)
{
  const int size = in.ConsumeIntegralInRange<int>(1, 9);
  table.rgba.resize(4 * size);
  for (int i = 0; i < size; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      table.rgba[4 * i + k] = in.ConsumeProbability<float>();
    }
    table.rgba[4 * i + 3] =
      in.ConsumeBool() ? 0.0f : in.PickValueInArray({ 0.5f, 1.0f, 20.0f, 1e4f, 1e-6f });
  }
  table.view.table = table.rgba.data();
  table.view.size = size;
  table.view.low = in.PickValueInArray({ 0.0, -1.0, 0.5, -3e38, 1.0 });
  table.view.high = table.view.low + in.PickValueInArray({ 1.0, 0.0, 1e-6, 3.0, 3e38 });
}

void CheckFrame(const mtpt::FramePipeline& pipeline, const mtpt::FrameInput& frame)
{
  const std::size_t n = frame.cells.cellCount;
  const mtpt::FrameStats& s = pipeline.Stats();
  const std::size_t count = pipeline.SortedCount();
  FUZZ_CHECK(s.cells == n, "cells %zu, mesh %zu", s.cells, n);
  FUZZ_CHECK(s.sorted == count, "stats.sorted %zu, SortedCount %zu", s.sorted, count);
  FUZZ_CHECK(pipeline.TetrahedronCount() == count, "slots %zu, sorted %zu",
    pipeline.TetrahedronCount(), count);
  FUZZ_CHECK(s.opacityCulled + s.frustumCulled <= n, "culled %zu + %zu of %zu", s.opacityCulled,
    s.frustumCulled, n);
  FUZZ_CHECK(
    s.nearPieces <= 3 * s.nearClipped, "%zu pieces of %zu cut cells", s.nearPieces, s.nearClipped);
  // Every cell is sorted, cut by the near plane, or culled once; pixelCulled counts cells
  // culled before the sort and near-plane pieces (in the order) culled after it.
  FUZZ_CHECK(count + s.nearClipped + s.pixelCulled <=
      n - s.opacityCulled - s.frustumCulled + 2 * s.nearPieces,
    "sorted %zu, cut %zu, pixel culled %zu, pieces %zu, cells %zu, culled %zu + %zu", count,
    s.nearClipped, s.pixelCulled, s.nearPieces, n, s.opacityCulled, s.frustumCulled);
  FUZZ_CHECK(s.notDrawable <= count, "not drawable %zu of %zu", s.notDrawable, count);
  FUZZ_CHECK(s.batches == 1, "batches %zu", s.batches);

  // Keys: strictly ascending (back to front), distinct cells or pieces, and each cell's key
  // the depth of its centroid (DepthKeys.h) recomputed here from the projected points.
  const mtpt::LargeVector<mtpt::SortKey>& keys = pipeline.Keys();
  FUZZ_CHECK(keys.size() >= count, "keys %zu, sorted %zu", keys.size(), count);
  std::vector<std::uint8_t> seen(n + s.nearPieces, 0);
  const mtpt::LargeVector<mtpt::ProjectedPoint>& points = pipeline.Points();
  for (std::size_t k = 0; k < count; ++k)
  {
    FUZZ_CHECK(k == 0 || keys[k - 1] < keys[k], "keys %zu and %zu out of order", k - 1, k);
    const std::uint32_t cell = mtpt::CellOfKey(keys[k]);
    FUZZ_CHECK(cell < seen.size(), "key %zu names cell %u of %zu", k, cell, seen.size());
    FUZZ_CHECK(!seen[cell], "cell %u twice in the order", cell);
    seen[cell] = 1;
    if (cell >= n)
    {
      continue; // a near-plane piece: its corners are not visible from here
    }
    std::int64_t ids[4];
    bool tetrahedron = false;
    if (frame.cells.type == mtpt::CellsView::Type::Int32)
    {
      const auto* o = static_cast<const std::int32_t*>(frame.cells.offsets);
      const auto* c = static_cast<const std::int32_t*>(frame.cells.connectivity);
      tetrahedron = o[cell + 1] - o[cell] == 4;
      for (int i = 0; tetrahedron && i < 4; ++i)
      {
        ids[i] = c[o[cell] + i];
      }
    }
    else
    {
      const auto* o = static_cast<const std::int64_t*>(frame.cells.offsets);
      const auto* c = static_cast<const std::int64_t*>(frame.cells.connectivity);
      tetrahedron = o[cell + 1] - o[cell] == 4;
      for (int i = 0; tetrahedron && i < 4; ++i)
      {
        ids[i] = c[o[cell] + i];
      }
    }
    for (int i = 0; tetrahedron && i < 4; ++i)
    {
      tetrahedron = ids[i] >= 0 && static_cast<std::size_t>(ids[i]) < frame.points.count;
    }
    float depth = std::numeric_limits<float>::infinity();
    if (tetrahedron)
    {
      double x = 0, y = 0, z = 0;
      for (int i = 0; i < 4; ++i)
      {
        x += points[ids[i]].eyeX;
        y += points[ids[i]].eyeY;
        z += points[ids[i]].eyeZ;
      }
      x *= 0.25;
      y *= 0.25;
      z *= 0.25;
      depth = static_cast<float>(frame.perspective ? x * x + y * y + z * z : -z);
    }
    FUZZ_CHECK(mtpt::MakeSortKey(depth, cell) == keys[k],
      "key %zu of cell %u: %016llx, its centroid depth %g gives %016llx", k, cell,
      static_cast<unsigned long long>(keys[k]), static_cast<double>(depth),
      static_cast<unsigned long long>(mtpt::MakeSortKey(depth, cell)));
  }

  // Buffers: slot k's indices in [5k, 5k + 5); every vertex finite, thickness >= 0.
  const mtpt::LargeVector<mtpt::TetVertex>& vertices = pipeline.Vertices();
  const mtpt::LargeVector<std::uint32_t>& indices = pipeline.Indices();
  FUZZ_CHECK(vertices.size() >= 5 * count && indices.size() >= 12 * count,
    "buffers %zu vertices, %zu indices for %zu slots", vertices.size(), indices.size(), count);
  for (std::size_t k = 0; k < count; ++k)
  {
    for (std::size_t i = 12 * k; i < 12 * k + 12; ++i)
    {
      FUZZ_CHECK(indices[i] >= 5 * k && indices[i] < 5 * k + 5, "slot %zu index %zu is %u", k,
        i - 12 * k, indices[i]);
    }
    for (std::size_t i = 5 * k; i < 5 * k + 5; ++i)
    {
      const mtpt::TetVertex& v = vertices[i];
      FUZZ_CHECK(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) &&
          std::isfinite(v.scalarFront) && std::isfinite(v.scalarBack) && std::isfinite(v.thickness),
        "slot %zu vertex %zu: %g %g %g %g %g %g", k, i - 5 * k, v.x, v.y, v.z, v.scalarFront,
        v.scalarBack, v.thickness);
      FUZZ_CHECK(
        v.thickness >= 0.0f, "slot %zu vertex %zu: thickness %g", k, i - 5 * k, v.thickness);
    }
  }
}

void CheckSameFrame(const mtpt::FramePipeline& a, const mtpt::FramePipeline& b, const char* what)
{
  const std::size_t count = a.SortedCount();
  FUZZ_CHECK(b.SortedCount() == count, "%s: %zu slots, not %zu", what, b.SortedCount(), count);
  FUZZ_CHECK(std::equal(a.Keys().begin(), a.Keys().begin() + count, b.Keys().begin()),
    "%s: another order", what);
  FUZZ_CHECK(count == 0 ||
      std::memcmp(a.Vertices().data(), b.Vertices().data(), 5 * count * sizeof(mtpt::TetVertex)) ==
        0,
    "%s: other vertices", what);
  FUZZ_CHECK(std::equal(a.Indices().begin(), a.Indices().begin() + 12 * count, b.Indices().begin()),
    "%s: other indices", what);
}

/**
 * Whether float planes resolve the frame's segments as well as the triangles' set-up does:
 * a depth range of at most 1e4 (VTK's clipping range keeps it at 1e3), point coordinates
 * within 1e6, and finite scalars within 1e4 table widths of the table. The fuzzer's
 * extreme values (coordinates of 1e30, scalars of 1e38, a near plane 1e-6 before a far one
 * at 1e6) are outside: there the fan path and the slots both round, differently.
 */
bool WellConditioned(
  const Mesh& mesh, const mtpt::FrameInput& frame, const mtpt::TransferFunctionTable& table)
{
  if (frame.perspective)
  {
    const double p10 = frame.projection[10];
    if (!(std::fabs((p10 - 1.0) / (p10 + 1.0)) <= 1e4))
    {
      return false;
    }
  }
  for (std::size_t i = 0; i < 3 * mesh.pointCount; ++i)
  {
    const double v = mesh.doublePoints ? mesh.pointsD[i] : mesh.pointsF[i];
    if (std::isfinite(v) && !(std::fabs(v) <= 1e6))
    {
      return false;
    }
  }
  const double width = table.high - table.low;
  const double low = table.low - 1e4 * width, high = table.high + 1e4 * width;
  for (const float v : mesh.scalars)
  {
    if (std::isfinite(v) && !(v >= low && v <= high))
    {
      return false;
    }
  }
  return true;
}

void CheckImage(const std::vector<float>& rgba, int width, int height)
{
  FUZZ_CHECK(rgba.size() == 4u * width * height, "image of %zu floats for %dx%d", rgba.size(),
    width, height);
  for (std::size_t i = 0; i < rgba.size(); ++i)
  {
    FUZZ_CHECK(std::isfinite(rgba[i]) && rgba[i] >= 0.0f && rgba[i] <= 1.0f,
      "pixel %zu channel %zu: %g", i / 4, i % 4, rgba[i]);
  }
}

/**
 * The pipeline's order composited into `tiles` (Begin with `s`) as the CPU backend does it:
 * windows of `batch` cells front to back, each behind those before it, the cells behind what
 * they made opaque left undecomposed (FramePipeline::DrawBatches, Compositor::Opaque). Every
 * fan written is checked; a hidden one is not read.
 */
void FansFrontToBack(mtpt::FramePipeline& pipeline, const mtpt::CompositeSettings& s,
  std::size_t batch, int threads, mtpt::Compositor& tiles)
{
  mtpt::FramePlan plan;
  plan.target = mtpt::BatchTarget::Fans;
  plan.batchSize = batch;
  plan.frontToBack = true;
  plan.threads = threads;
  tiles.Begin(s);
  std::size_t windows = 0;
  pipeline.DrawBatches(
    plan,
    [&](const mtpt::Batch& b)
    {
      ++windows;
      FUZZ_CHECK(b.count == std::min(batch, pipeline.SortedCount() - b.first),
        "%zu fans in the batch from %zu", b.count, b.first);
      for (std::size_t k = 0; k < b.count; ++k)
      {
        const mtpt::Fan& fan = b.fans[k];
        FUZZ_CHECK(b.classes[k] == mtpt::ProjectionClass::Hidden || fan.count == 0 ||
            ((fan.count == 3 || fan.count == 4) && fan.closed == 1),
          "fan %zu: %d corners, closed %d", b.first + k, fan.count, fan.closed);
        FUZZ_CHECK(windows > 1 || b.classes[k] != mtpt::ProjectionClass::Hidden,
          "fan %zu hidden in the first batch", b.first + k);
      }
      tiles.CompositeBehind(b.fans, b.count, threads, nullptr, b.classes);
      return true;
    },
    &tiles.Opaque());
}

/**
 * The CPU backend's batches, front to back with the cells behind what they made opaque left
 * undecomposed (FansFrontToBack), in windows of `batch`: the image of one batch of the whole
 * order bit for bit, whatever the frame.
 */
void CheckFrontToBack(mtpt::FramePipeline& pipeline, const mtpt::CompositeSettings& s,
  std::size_t batch, int threadsA, int threadsB)
{
  std::vector<float> whole(4u * s.width * s.height), batched(whole.size());
  mtpt::Compositor one, several;
  FansFrontToBack(pipeline, s, pipeline.SortedCount(), threadsA, one);
  one.Resolve({ 0, 0, s.width, s.height }, nullptr, whole.data(), threadsB);
  FansFrontToBack(pipeline, s, batch, threadsB, several);
  several.Resolve({ 0, 0, s.width, s.height }, nullptr, batched.data(), threadsA);
  CheckImage(batched, s.width, s.height);
  FUZZ_CHECK(batched == whole, "fans front to back in batches of %zu differ from one batch", batch);
}

/// The pipeline's fans (decomposed already) composited with `s` on `threads` threads.
std::vector<float> CompositeFans(const mtpt::FramePipeline& pipeline,
  const mtpt::CompositeSettings& s, int threads, const mtpt::LightFactors* lights = nullptr)
{
  std::vector<float> rgba(4u * s.width * s.height);
  mtpt::Compositor compositor;
  compositor.Begin(s);
  compositor.Composite(pipeline.Fans().data(), pipeline.FanCount(), threads, lights);
  compositor.Resolve({ 0, 0, s.width, s.height }, nullptr, rgba.data(), threads);
  return rgba;
}

/**
 * Clipping planes on the fans of the whole order in one batch: planes that keep everything
 * give the image without planes bit for bit; any planes (degenerate, huge or not a number
 * ones too) give a valid image, the same for both thread counts.
 */
void CheckClippingPlanes(FuzzedDataProvider& in, mtpt::FramePipeline& pipeline,
  const mtpt::CompositeSettings& settings, const mtpt::FrameInput& frame, int threadsA,
  int threadsB)
{
  pipeline.DecomposeFans(0, pipeline.SortedCount(), threadsA);
  auto composite = [&](const mtpt::CompositeSettings& s, int threads)
  { return CompositeFans(pipeline, s, threads); };
  mtpt::CompositeSettings clipped = settings;
  clipped.clipping = mtpt::DepthClipping::FromProjection(frame.projection);
  const std::vector<float> whole = composite(clipped, threadsA);
  clipped.clipPlanes.count = 1;
  const double keepAll[4] = { 0.0, 0.0, 0.0, 1.0 };
  std::copy(keepAll, keepAll + 4, clipped.clipPlanes.plane[0]);
  FUZZ_CHECK(composite(clipped, threadsB) == whole, "a plane keeping everything changed the image");
  const double inf = std::numeric_limits<double>::infinity();
  clipped.clipPlanes.count = in.ConsumeIntegralInRange(0, mtpt::ClipPlanes::Max);
  for (int i = 0; i < clipped.clipPlanes.count; ++i)
  {
    for (double& v : clipped.clipPlanes.plane[i])
    {
      v = in.PickValueInArray(
        { 0.0, 1.0, -1.0, 0.3, -2.5, 1e30, -1e-30, inf, std::nan(""), 4.0, -0.7 });
    }
  }
  const std::vector<float> a = composite(clipped, threadsA);
  CheckImage(a, clipped.width, clipped.height);
  FUZZ_CHECK(composite(clipped, threadsB) == a, "clipped: %d and %d threads differ", threadsA,
    threadsB);
}

/**
 * A blend mode other than composite (fuzzed, with a fuzzed average range) on the same fans:
 * a valid image, the same for two thread counts.
 */
void CheckBlendModes(FuzzedDataProvider& in, mtpt::FramePipeline& pipeline,
  const mtpt::CompositeSettings& settings, const mtpt::FrameInput& frame, int threadsA,
  int threadsB)
{
  pipeline.DecomposeFans(0, pipeline.SortedCount(), threadsA);
  mtpt::CompositeSettings reduced = settings;
  reduced.blendMode = static_cast<mtpt::BlendMode>(in.ConsumeIntegralInRange(1, 4));
  mtpt::IntensityTable intensity;
  intensity.Build(reduced.transferFunction);
  reduced.intensity = &intensity;
  reduced.interpolation = mtpt::PerspectiveInterpolation::FromProjection(frame.projection);
  reduced.clipping = mtpt::DepthClipping::FromProjection(frame.projection);
  for (double& v : reduced.averageRange)
  {
    v = in.PickValueInArray({ -1e300, 1e300, 0.0, 0.5, 1.0, -3.0, std::nan("") });
  }
  const std::vector<float> a = CompositeFans(pipeline, reduced, threadsA);
  CheckImage(a, reduced.width, reduced.height);
  FUZZ_CHECK(CompositeFans(pipeline, reduced, threadsB) == a, "blend mode %d: %d and %d threads differ",
    static_cast<int>(reduced.blendMode), threadsA, threadsB);
}

/**
 * Shading (mtpt/Lighting.h) with fuzzed coefficients and lights (degenerate, huge, not a
 * number ones too) on the fans of the whole order: gradients, normals and factors of any
 * mesh and view; the factors of unit lighting give the unlit image; any give a valid image,
 * the same for two thread counts.
 */
void CheckShading(FuzzedDataProvider& in, mtpt::FramePipeline& pipeline,
  const mtpt::CompositeSettings& settings, const mtpt::FrameInput& frame, int threadsA,
  int threadsB)
{
  std::vector<float> gradients, normals, one;
  mtpt::PointGradients(frame.points, frame.cells, frame.scalars, gradients, threadsA);
  mtpt::PointGradients(frame.points, frame.cells, frame.scalars, one, threadsB);
  FUZZ_CHECK(one == gradients, "gradients: %d and %d threads differ", threadsA, threadsB);
  for (float g : gradients)
  {
    FUZZ_CHECK(std::isfinite(g), "a gradient that is not finite: %g", g);
  }
  mtpt::CellNormals(frame.cells, frame.points.count, gradients, normals, threadsA);
  for (std::size_t c = 0; c < normals.size() / 3; ++c)
  {
    const float* n = normals.data() + 3 * c;
    const float length = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    FUZZ_CHECK(length == 0.0f || std::fabs(length - 1.0f) < 1e-5f, "cell %zu: normal of length %g",
      c, std::sqrt(length));
  }
  pipeline.DecomposeFans(0, pipeline.SortedCount(), threadsA);
  mtpt::CompositeSettings lit = settings;
  lit.clipping = mtpt::DepthClipping::FromProjection(frame.projection);
  std::vector<mtpt::LightFactors> factors;
  mtpt::Lighting unit;
  unit.ambient = 1;
  unit.diffuse = unit.specular = 0;
  pipeline.LightWindow(0, pipeline.SortedCount(), unit, normals.data(), frame.modelView, factors,
    threadsA);
  const std::vector<float> unlit = CompositeFans(pipeline, lit, threadsA);
  const std::vector<float> same = CompositeFans(pipeline, lit, threadsA, factors.data());
  for (std::size_t i = 0; i < unlit.size(); ++i)
  {
    // Only a mean colour rounded past 1 may change: lit colours are clamped to 1.
    FUZZ_CHECK(std::fabs(same[i] - unlit[i]) <= 1e-6f, "unit lighting changed value %zu: %g, %g",
      i, same[i], unlit[i]);
  }
  const double inf = std::numeric_limits<double>::infinity();
  auto value = [&]
  {
    return in.PickValueInArray(
      { 0.0, 1.0, -1.0, 0.3, 0.7, 1e30, -1e-30, inf, std::nan(""), 8.0 });
  };
  mtpt::Lighting lighting;
  lighting.headlight = in.ConsumeBool();
  lighting.twoSided = in.ConsumeBool();
  lighting.ambient = value();
  lighting.diffuse = value();
  lighting.specular = value();
  lighting.specularPower = value();
  lighting.count = in.ConsumeIntegralInRange(0, 3);
  for (int i = 0; i < lighting.count; ++i)
  {
    mtpt::Light& l = lighting.lights[i];
    l.positional = in.ConsumeBool();
    for (int k = 0; k < 3; ++k)
    {
      l.diffuse[k] = value();
      l.direction[k] = value();
      l.position[k] = value();
      l.attenuation[k] = value();
    }
    l.coneAngle = value() * 60;
  }
  pipeline.LightWindow(0, pipeline.SortedCount(), lighting, normals.data(), frame.modelView,
    factors, threadsA);
  const std::vector<float> a = CompositeFans(pipeline, lit, threadsA, factors.data());
  CheckImage(a, lit.width, lit.height);
  pipeline.LightWindow(0, pipeline.SortedCount(), lighting, normals.data(), frame.modelView,
    factors, threadsB);
  FUZZ_CHECK(CompositeFans(pipeline, lit, threadsB, factors.data()) == a,
    "shaded: %d and %d threads differ", threadsA, threadsB);
}

/// The decoded case, for reproducing a failure: MTPT_FUZZ_VERBOSE=1 mtpt_fuzz_frame <input>.
void Dump(const Mesh& mesh, const mtpt::FrameInput& frame, const mtpt::FramePipeline& pipeline,
  const mtpt::TransferFunctionTable& table, const mtpt::CompositeSettings& settings)
{
  std::fprintf(stderr, "points (%s):\n", mesh.doublePoints ? "double" : "float");
  for (std::size_t i = 0; i < mesh.pointCount; ++i)
  {
    const double* d = mesh.pointsD.data() + 3 * i;
    const float* f = mesh.pointsF.data() + 3 * i;
    std::fprintf(stderr, "  %zu: %.9g %.9g %.9g\n", i, mesh.doublePoints ? d[0] : f[0],
      mesh.doublePoints ? d[1] : f[1], mesh.doublePoints ? d[2] : f[2]);
  }
  std::fprintf(stderr, "cells (%s):\n", mesh.int32Cells ? "int32" : "int64");
  for (std::size_t c = 0; c < mesh.cellCount; ++c)
  {
    std::fprintf(stderr, "  %zu:", c);
    for (auto k = mesh.offsets64[c]; k < mesh.offsets64[c + 1]; ++k)
    {
      std::fprintf(stderr, " %lld", static_cast<long long>(mesh.connectivity64[k]));
    }
    std::fprintf(stderr, "\n");
  }
  std::fprintf(stderr, "scalars (%s):",
    frame.scalars.values
      ? (frame.scalars.association == mtpt::ScalarsView::Association::Points ? "points" : "cells")
      : "none");
  for (float v : mesh.scalars)
  {
    std::fprintf(stderr, " %.9g", v);
  }
  std::fprintf(
    stderr, "\n%s; modelView, projection:\n", frame.perspective ? "perspective" : "orthographic");
  for (const Matrix4* m : { &frame.modelView, &frame.projection })
  {
    for (int r = 0; r < 4; ++r)
    {
      std::fprintf(stderr, "  %.17g %.17g %.17g %.17g\n", (*m)[4 * r], (*m)[4 * r + 1],
        (*m)[4 * r + 2], (*m)[4 * r + 3]);
    }
  }
  std::fprintf(stderr, "viewport %dx%d, image %dx%d, cull frustum %d, opacity table %d\n",
    frame.imageSize.width, frame.imageSize.height, settings.width, settings.height,
    frame.cullFrustum, frame.opacity.size);
  std::fprintf(
    stderr, "colour table [%.9g, %.9g], %d entries:\n", table.low, table.high, table.size);
  for (int i = 0; i < table.size; ++i)
  {
    std::fprintf(stderr, "  %.9g %.9g %.9g %.9g\n", table.table[4 * i], table.table[4 * i + 1],
      table.table[4 * i + 2], table.table[4 * i + 3]);
  }
  std::fprintf(stderr, "shading %s, unit distance %.9g, opaque depth %s\n",
    settings.shading == mtpt::Shading::PreIntegrated ? "pre-integrated" : "VTK-compatible",
    settings.unitDistance, settings.opaqueDepth ? "yes" : "no");
  std::fprintf(stderr, "%zu slots:\n", pipeline.TetrahedronCount());
  for (std::size_t k = 0; k < pipeline.TetrahedronCount(); ++k)
  {
    std::fprintf(stderr, "  slot %zu (cell %u):\n", k, mtpt::CellOfKey(pipeline.Keys()[k]));
    for (std::size_t i = 5 * k; i < 5 * k + 5; ++i)
    {
      const mtpt::TetVertex& v = pipeline.Vertices()[i];
      std::fprintf(stderr, "    %.9g %.9g %.9g  front %.9g back %.9g length %.9g\n", v.x, v.y, v.z,
        v.scalarFront, v.scalarBack, v.thickness);
    }
    std::fprintf(stderr, "   ");
    for (std::size_t i = 12 * k; i < 12 * k + 12; ++i)
    {
      std::fprintf(stderr, " %u", pipeline.Indices()[i] - static_cast<std::uint32_t>(5 * k));
    }
    std::fprintf(stderr, "\n");
  }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  FuzzedDataProvider in(data, size);
  Mesh mesh;
  DecodePoints(in, mesh);
  DecodeCells(in, mesh);

  mtpt::FrameInput frame;
  frame.scalars = DecodeScalars(in, mesh);
  frame.points = mesh.Points();
  frame.cells = mesh.Cells();
  DecodeCamera(in, frame);
  frame.cullFrustum = in.ConsumeBool();
  const bool cullPixels = in.ConsumeBool();
  if (!cullPixels)
  {
    frame.imageSize = {}; // multisampled target: no pixel culling
  }
  Table opacity, colour;
  if (in.ConsumeBool())
  {
    DecodeTable(in, opacity);
    frame.opacity = opacity.view;
  }
  DecodeTable(in, colour);
  const bool partition = in.ConsumeBool();
  const std::size_t maxSubArray = in.PickValueInArray<std::size_t>({ 16, 1, 1u << 15 });
  const int threadsA = in.ConsumeIntegralInRange<int>(1, 3);
  const int threadsB = in.ConsumeIntegralInRange<int>(1, 3);
  const int variant = in.ConsumeIntegralInRange<int>(0, 4);
  const int width =
    frame.imageSize.width > 0 ? frame.imageSize.width : in.ConsumeIntegralInRange(1, 16);
  const int height =
    frame.imageSize.height > 0 ? frame.imageSize.height : in.ConsumeIntegralInRange(1, 16);

  mtpt::FramePipeline a;
  if (partition)
  {
    a.SetOrderMethod(mtpt::OrderMethod::PartitionSort, maxSubArray);
  }
  FUZZ_CHECK(a.Run(frame, threadsA), "Run failed on %zu cells", mesh.cellCount);
  CheckFrame(a, frame);

  // The same frame on another thread count and through the reuse paths: a pipeline with
  // reuse on first draws a neighbouring frame (the same, a small rotation, another opacity
  // table version, another viewport, a larger mesh), then this one.
  mtpt::FramePipeline b;
  b.SetOrderMethod(
    partition ? mtpt::OrderMethod::RadixSort : mtpt::OrderMethod::PartitionSort, maxSubArray);
  b.SetReuse(true);
  mtpt::FrameInput previous = frame;
  if (variant == 1)
  {
    const double angle = 0.004; // below FramePipeline::NearlySortedMaxAngle
    const Matrix4 rotation = { std::cos(angle), 0, std::sin(angle), 0, 0, 1, 0, 0, -std::sin(angle),
      0, std::cos(angle), 0, 0, 0, 0, 1 };
    previous.modelView = mtpt::Multiply(rotation, frame.modelView);
  }
  else if (variant == 2)
  {
    previous.opacity = mtpt::TransferFunctionTable{};
    previous.opacityVersion = 7;
  }
  else if (variant == 3)
  {
    previous.imageSize.width = frame.imageSize.width > 0 ? frame.imageSize.width + 1 : 0;
  }
  Mesh twice; // variant 4: a larger mesh first (every cell twice), so buffers hold stale data
  if (variant == 4)
  {
    twice = mesh;
    twice.cellCount = 2 * mesh.cellCount;
    const std::size_t length = mesh.cellCount > 0 ? mesh.offsets64[mesh.cellCount] : 0;
    twice.connectivity64.resize(2 * length);
    twice.connectivity32.resize(2 * length);
    twice.offsets64.resize(2 * mesh.cellCount + 1);
    twice.offsets32.resize(2 * mesh.cellCount + 1);
    for (std::size_t i = 0; i < length; ++i)
    {
      twice.connectivity64[length + i] = mesh.connectivity64[i];
      twice.connectivity32[length + i] = mesh.connectivity32[i];
    }
    for (std::size_t c = 1; c <= mesh.cellCount; ++c)
    {
      twice.offsets64[mesh.cellCount + c] = static_cast<std::int64_t>(length) + mesh.offsets64[c];
      twice.offsets32[mesh.cellCount + c] = static_cast<std::int32_t>(length) + mesh.offsets32[c];
    }
    if (frame.scalars.values && frame.scalars.association == mtpt::ScalarsView::Association::Cells)
    {
      twice.scalars.resize(std::max<std::size_t>(2 * mesh.cellCount, 1));
      std::copy(mesh.scalars.begin(), mesh.scalars.begin() + mesh.cellCount,
        twice.scalars.begin() + mesh.cellCount);
    }
    previous.points = twice.Points();
    previous.cells = twice.Cells();
    previous.scalars.values = frame.scalars.values ? twice.scalars.data() : nullptr;
    previous.dataVersion = frame.dataVersion + 1;
  }
  FUZZ_CHECK(b.Run(previous, threadsB), "Run (previous frame) failed");
  CheckFrame(b, previous);
  FUZZ_CHECK(b.Run(frame, threadsB), "Run (reuse) failed");
  CheckFrame(b, frame);
  CheckSameFrame(a, b, "another thread count, order method and reuse path");

  // The compositor on the result.
  mtpt::CompositeSettings settings;
  settings.width = width;
  settings.height = height;
  settings.transferFunction = colour.view;
  mtpt::PreIntegrationTable preIntegration;
  if (in.ConsumeBool())
  {
    preIntegration.Build(colour.view);
    settings.UsePreIntegration(
      preIntegration, mtpt::PerspectiveInterpolation::FromProjection(frame.projection));
  }
  settings.unitDistance = in.PickValueInArray({ 1.0, 1e-3, 0.37, 100.0, 1e-7 });
  std::vector<float> depth;
  if (in.ConsumeBool())
  {
    depth.resize(static_cast<std::size_t>(width) * height);
    for (float& d : depth)
    {
      d = in.PickValueInArray({ 1.0f, 0.5f, 0.0f, 0.999f });
    }
    settings.opaqueDepth = depth.data();
  }
  std::vector<float> imageA, imageB;
  mtpt::Compositor compositor;
  compositor.Composite(
    a.Vertices().data(), a.Indices().data(), a.TetrahedronCount(), settings, imageA, threadsA);
  if (std::getenv("MTPT_FUZZ_VERBOSE"))
  {
    Dump(mesh, frame, a, colour.view, settings);
  }
  CheckImage(imageA, width, height);
  compositor.Composite(
    a.Vertices().data(), a.Indices().data(), a.TetrahedronCount(), settings, imageB, threadsB);
  FUZZ_CHECK(imageA == imageB, "compositor: %d and %d threads differ", threadsA, threadsB);

  // The order decomposed into fans, batch after batch, binned into tiles and rasterized
  // there. The same triangles in the same order as the slots. In one batch: the same image up
  // to the fan path's set-up rounding (fans drawn whole, within 2e-6 of their triangles
  // VTK-compatible, 2e-5 pre-integrated). Batches given back to front (Compositor::Composite):
  // each drawn front to back on its own and composited over those behind it, so a batch's
  // own opaque pixels skip only what adds at most 2^-11 (OpaqueAlpha), plus the rounding of
  // the extra compositing. Pre-integrated, the slots' triangles queue their fragments and skip
  // them by the alpha a pixel had when they were queued, the fans by the alpha they leave:
  // where a pixel turns opaque they may differ by that 2^-11 in one batch too (found by the
  // fuzzer: 1.6e-4). Pre-integrated, the bound holds on well-conditioned frames
  // (WellConditioned); on the others the images are only checked to be finite and in range.
  // The CPU backend's own order of batches, front to back, is checked against one batch below.
  const std::size_t batch = in.PickValueInArray<std::size_t>({ 1, 3, 7, 1u << 20 });
  std::vector<float> fanImage(imageA.size());
  mtpt::Compositor tiles;
  tiles.Begin(settings);
  for (std::size_t first = 0; first < b.SortedCount(); first += batch)
  {
    b.DecomposeFans(first, batch, threadsB);
    FUZZ_CHECK(b.FanCount() == std::min(batch, b.SortedCount() - first), "%zu fans in a batch",
      b.FanCount());
    for (std::size_t k = 0; k < b.FanCount(); ++k)
    {
      const mtpt::Fan& fan = b.Fans()[k];
      FUZZ_CHECK(fan.count == 0 || ((fan.count == 3 || fan.count == 4) && fan.closed == 1),
        "fan %zu: %d corners, closed %d", first + k, fan.count, fan.closed);
    }
    tiles.Composite(b.Fans().data(), b.FanCount(), threadsA);
  }
  const mtpt::PixelRegion touched = tiles.TouchedRegion();
  FUZZ_CHECK(touched.Empty() || (touched.x0 >= 0 && touched.y0 >= 0 && touched.x1 <= width &&
                                  touched.y1 <= height),
    "touched region [%d, %d) x [%d, %d) outside %dx%d", touched.x0, touched.x1, touched.y0,
    touched.y1, width, height);
  tiles.Resolve({ 0, 0, width, height }, nullptr, fanImage.data(), threadsB);
  CheckImage(fanImage, width, height);
  CheckFrontToBack(b, settings, batch, threadsA, threadsB);
  const bool batched = batch < b.SortedCount();
  const bool queued = settings.shading == mtpt::Shading::PreIntegrated;
  const float fanBound = (batched || queued ? 1.0f / 2048 : 0.0f) + (queued ? 2e-5f : 1e-5f);
  float fanWorst = 0;
  std::size_t worstAt = 0;
  for (std::size_t i = 0; i < fanImage.size(); ++i)
  {
    const float difference = std::fabs(fanImage[i] - imageA[i]);
    if (difference > fanWorst)
    {
      fanWorst = difference;
      worstAt = i;
    }
  }
  if (std::getenv("MTPT_FUZZ_VERBOSE"))
  {
    const std::size_t pixel = worstAt / 4;
    const float* s = &imageA[4 * pixel];
    const float* t = &fanImage[4 * pixel];
    std::printf("fans in batches of %zu: worst difference from the slots %g at pixel %zu,%zu: "
                "slots %g %g %g %g, fans %g %g %g %g, opaque depth %g\n",
      batch, fanWorst, pixel % width, pixel / width, s[0], s[1], s[2], s[3], t[0], t[1], t[2], t[3],
      depth.empty() ? 1.0 : depth[pixel]);
    std::fflush(stdout); // before the check below may abort
  }
  FUZZ_CHECK(fanWorst <= fanBound || (queued && !WellConditioned(mesh, frame, colour.view)),
    "fans in batches of %zu differ from the slots by %g (bound %g)", batch, fanWorst, fanBound);
  for (int y = 0; y < height; ++y) // nothing drawn outside the touched region
  {
    for (int x = 0; x < width; ++x)
    {
      const bool inside = !touched.Empty() && x >= touched.x0 && x < touched.x1 &&
        y >= touched.y0 && y < touched.y1;
      FUZZ_CHECK(inside || fanImage[4 * (static_cast<std::size_t>(y) * width + x) + 3] == 0.0f,
        "pixel %d,%d drawn outside the touched region", x, y);
    }
  }
  // Resolved over a colour beneath, in float and in 8 bits, as the CPU backend writes it.
  std::vector<float> below(imageA.size()), over(imageA.size());
  std::vector<std::uint8_t> below8(imageA.size()), over8(imageA.size());
  for (std::size_t i = 0; i < below.size(); ++i)
  {
    below8[i] = in.ConsumeIntegral<std::uint8_t>();
    below[i] = below8[i] / 255.0f;
  }
  tiles.Resolve({ 0, 0, width, height }, below.data(), over.data(), threadsA);
  CheckImage(over, width, height);
  tiles.Resolve({ 0, 0, width, height }, below8.data(), over8.data(), threadsA);
  for (std::size_t i = 0; i < over8.size(); ++i)
  {
    FUZZ_CHECK(std::fabs(over8[i] / 255.0f - over[i]) <= 0.5f / 255.0f + 1e-6f,
      "8-bit resolve %u against %g at value %zu", over8[i], over[i], i);
  }
  CheckClippingPlanes(in, b, settings, frame, threadsA, threadsB);
  CheckBlendModes(in, b, settings, frame, threadsA, threadsB);
  CheckShading(in, b, settings, frame, threadsA, threadsB);
  return 0;
}
