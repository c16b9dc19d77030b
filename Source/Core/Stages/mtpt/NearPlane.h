// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file NearPlane.h
 * @brief Stage 3b of a frame: cells that cross the near plane are cut by it and their visible
 * part drawn, where VTK's PT drops the whole cell (holes when the camera is near or inside
 * the mesh; Documentation/algorithm.md, "Near-plane clipping").
 *
 * The cutting plane is NDC z = NearPlaneNdcZ, a hair behind the near plane, so that the
 * rasterizer's own near clipping (z < -1) never removes a fragment of a piece. The plane
 * is written in eye coordinates as d(e) = (row 2 - NearPlaneNdcZ * row 3 of the
 * projection) . (e, 1): d >= 0 on the visible side. d is linear in eye coordinates, so a
 * cell's edge meets the plane at t = d_a / (d_a - d_b), where position and scalar are
 * interpolated linearly (exact: both are linear inside a tetrahedron). The visible part of
 * a tetrahedron is a tetrahedron (one corner visible) or a triangular prism (two or three
 * visible), cut into 3 tetrahedra. Pieces are drawn like cells: each gets its own depth
 * key and slot, so the fixed-stride buffers and the thread-count independence hold.
 */
#ifndef mtpt_NearPlane_h
#define mtpt_NearPlane_h

#include "mtpt/LargeBuffer.h"
#include "mtpt/MeshView.h"
#include "mtpt/Records.h"
#include "mtpt/Stage.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/// NDC z of the cutting plane.
constexpr double NearPlaneNdcZ = -1.0 + 1e-6;

/// The cutting plane in eye coordinates: d(e) = c[0] ex + c[1] ey + c[2] ez + c[3].
struct NearPlane
{
  double c[4];

  explicit NearPlane(const Matrix4& projection);
  /// Signed distance of a point (its eye coordinates); NaN for non-finite points.
  double Distance(const ProjectedPoint& p) const
  {
    return c[0] * p.eyeX + c[1] * p.eyeY + c[2] * p.eyeZ + c[3];
  }
};

/// True if the point's eye coordinates and scalar are finite and bounded (whether or not
/// it can be projected): such a point can be cut against the plane.
bool HasFiniteEyeCoordinates(const ProjectedPoint& p);

/// One piece of a cut tetrahedron: its 4 corners, projected, their scalars and, for
/// dependent components, their colours (zero otherwise), and the cell it was cut from
/// (set by NearPlaneStage; shading lights a piece as its cell).
struct NearPiece
{
  ProjectedPoint corners[4];
  float scalars[4];
  float colours[4][4];
  std::uint32_t cell = 0;
};

/**
 * Appends to `pieces` the part of the tetrahedron `corners` (with `scalars`, one per
 * corner, and `colours`, an RGBA per corner or null) on the visible side of `plane`:
 * nothing if no corner is on it, the tetrahedron unchanged if all are, else 1 or 3 pieces
 * whose new corners lie on the plane and are projected with `projection`, their scalars
 * and colours interpolated linearly. Returns the number of pieces appended. Every corner
 * must satisfy HasFiniteEyeCoordinates. Thread safety: pure function of its arguments.
 */
int CutTetrahedron(const ProjectedPoint* const corners[4], const float scalars[4],
  const NearPlane& plane, const Matrix4& projection, std::vector<NearPiece>& pieces,
  const float* const* colours = nullptr);

/// What the cut depends on: NearPlaneStage's key.
struct NearPlaneKey
{
  std::uint64_t keys = 0; ///< DepthKeyStage::Version()
  bool operator==(const NearPlaneKey& o) const { return keys == o.keys; }
};

/**
 * Stage 3b as a stage of FramePipeline (Stage.h; Documentation/algorithm.md,
 * "Near-plane clipping"): of the depth keys, those of cells that cross the plane are
 * replaced by the pieces of their visible part, each with a key of its own (cell id
 * cellCount + j for piece j, its centroid's depth), and those of cells wholly in front of the
 * plane are dropped. Kept until the depth keys change (their version stands for the points,
 * and so the data and the matrices, for the cells kept and the kind of projection).
 * Most frames have no point in front of the plane and cut nothing.
 */
class NearPlaneStage : public StageOf<NearPlaneKey>
{
public:
  /// Cuts the cells of `keys` unless that was done for `key`; true when it computed.
  /// `colours`: FrameInput::colours (null without dependent components).
  bool Update(const Key& key, const LargeVector<SortKey>& keys, const ProjectedPoint* points,
    std::size_t pointCount, const CellsView& cells, const ScalarsView& scalars,
    const float* colours, const Matrix4& projection, bool perspective, int threads);

  /// Whether key k of the depth keys stays in the order (false: cut or dropped).
  bool Keeps(std::size_t k) const { return !this->Cut || this->Verdicts[k] == Keep; }
  /// Whether any key was cut or dropped.
  bool CutsAny() const { return this->Cut; }
  /// The pieces; piece j has cell id cellCount + j.
  const std::vector<NearPiece>& Pieces() const { return this->Made; }
  /// The pieces' keys, sorted.
  const LargeVector<SortKey>& PieceKeys() const { return this->Keys; }
  /// Cells cut by the plane.
  std::size_t Clipped() const { return this->ClippedCells; }
  void Release() override;
  std::size_t MemoryBytes() const override;

private:
  enum Verdict : std::uint8_t
  {
    Keep = 0, ///< all corners on the visible side, or not cuttable
    Crosses,  ///< cut: replaced by its pieces
    InFront   ///< wholly in front of the plane: dropped
  };
  /// Each key's verdict (parallel); false when no point is in front of the plane at all.
  bool Classify(const LargeVector<SortKey>& keys, const ProjectedPoint* points,
    std::size_t pointCount, const CellsView& cells, const ScalarsView& scalars,
    const NearPlane& plane, int threads);
  /// Cuts the crossing cells in order (deterministic piece ids) and makes the pieces' keys.
  void CutCrossing(const LargeVector<SortKey>& keys, const ProjectedPoint* points,
    std::size_t pointCount, const CellsView& cells, const ScalarsView& scalars,
    const float* colours, const NearPlane& plane, const Matrix4& projection, bool perspective);

  LargeVector<std::uint8_t> Verdicts; ///< per depth key
  std::vector<NearPiece> Made;
  LargeVector<SortKey> Keys;
  bool Cut = false;
  std::size_t ClippedCells = 0;
};

} // namespace mtpt

#endif
