// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ReferenceRenderer.h
 * @brief The accuracy reference: the exact emission-absorption ray integral through a
 * tetrahedral mesh, per pixel, on the CPU in double precision, with no OpenGL. Every
 * mapper's image is measured against it ("speed against error", Documentation/accuracy.md).
 *
 * Conventions (MeshView.h, Compositor.h):
 * - Matrices: row-major on column vectors; the camera looks down -z in eye space; OpenGL NDC.
 * - Window: pixel (x, y) covers [x, x+1) x [y, y+1), y up, row 0 at the bottom. Its ray runs
 *   through the window point (x + 0.5 + PixelOffsetX, y + 0.5 + PixelOffsetY): the centre,
 *   moved by a tiny irrational-looking fraction of a pixel so that no ray of a regular
 *   camera lies exactly on a shared face or edge of a regular mesh (it would be counted
 *   twice or missed). The offset changes an image by far less than any mapper error.
 * - A ray is the line through the pixel's points on the near plane (NDC z = -1) and on the
 *   far plane (NDC z = +1), unprojected by the inverse projection and model-view matrices:
 *   only the part between the two planes counts (the view volume), for orthographic and
 *   perspective cameras alike. Lengths are measured in eye coordinates, as every mapper
 *   measures them (ScalarOpacityUnitDistance is an eye-space length under a rigid view).
 *
 * The model: the scalar is linear inside each tetrahedron (point scalars; cell scalars are
 * constant per cell); colour c(s) and opacity o(s) are the piecewise-linear functions
 * through the given nodes, clamped to the end values outside their node range (VTK's
 * default clamping); extinction tau(s) = o(s) / unitDistance; pixel = integral c tau
 * exp(-integral tau) along the ray, front to back, then over the background colour with
 * the remaining transmittance.
 *
 * Exactness: each cell's ray segment is split at the transfer-function nodes; on each
 * piece c and tau are linear in the ray parameter, so the optical depth is a quadratic,
 * evaluated in closed form, and the emission integral is integrated by 8-point
 * Gauss-Legendre quadrature on equal sub-intervals of optical depth at most 0.25. There
 * the integrand (a quadratic times exp of a quadratic whose coefficients are bounded by the
 * sub-interval's depth) has a Taylor remainder of order 0.5^16 / 16! < 1e-17 relative, so a
 * pixel is exact to about 1e-12 (accumulated rounding). A ray stops when its accumulated
 * optical depth passes MaxOpticalDepth (transmittance below 1e-26).
 *
 * Intersections: each point is transformed once, in double, to eye coordinates (relative to
 * the camera, so a mesh offset by 1e7 from the origin keeps its precision); each cell's
 * arithmetic is relative to its first point (edge vectors, face planes, barycentric scalar),
 * and rays are clipped by the four face planes (Cyrus-Beck). A cell is tested against the
 * pixels of its projected bounding box; a cell reaching the eye plane has no bounded
 * projection and is tested against every pixel (slow only with very many such cells, a
 * camera deep inside a large mesh). Cells with a non-positive volume in double, or with a
 * point or scalar that is not finite, contribute nothing.
 * Non-convex meshes and several separate parts work: every segment of a pixel is collected
 * and sorted by depth before integration.
 */
#ifndef mtpt_ReferenceRenderer_h
#define mtpt_ReferenceRenderer_h

#include "mtpt/Lighting.h"
#include "mtpt/MeshView.h"
#include "mtpt/Shading.h"

#include <cstddef>
#include <string>
#include <vector>

namespace mtpt
{

/// A node of a piecewise-linear colour transfer function: scalar and linear RGB.
struct ColorNode
{
  double scalar, r, g, b;
};

/// A node of a piecewise-linear opacity transfer function: scalar and opacity (VTK's scalar
/// opacity: attenuation per unit distance).
struct OpacityNode
{
  double scalar, opacity;
};

/**
 * How the data become colour and opacity (VTK's vtkVolumeProperty::IndependentComponents).
 * - TransferFunctions: one scalar per tuple, through both transfer functions (independent
 *   components; the file comment's model).
 * - ColourAndOpacityScalars: two per tuple (dependent components): the first through the
 *   colour function, the second through the opacity function; both linear inside a cell,
 *   so each segment is split where either crosses a node of its function.
 * - Colours: four per tuple (dependent components): red, green, blue and the attenuation
 *   per unit distance themselves, each clamped to [0, 1]; linear inside a cell, so colour
 *   and extinction are linear along each segment. The transfer functions are not read.
 */
enum class ScalarMapping
{
  TransferFunctions,
  ColourAndOpacityScalars,
  Colours
};

/// Values per tuple of each mapping: 1, 2 or 4.
int ChannelsOf(ScalarMapping mapping);

/**
 * A translucent triangle seen with the volume (a surface drawn with depth peeling): its
 * corners in eye coordinates and its flat colour and opacity. A ray that crosses it is
 * composited with it at the crossing's depth, between the volume in front and behind:
 * colour = opacity * rgb + (1 - opacity) * what lies behind.
 */
struct ReferenceTriangle
{
  double eye[3][3];
  double rgb[3];
  double opacity;
};

/// Pixel-centre offset of the reference's rays, in pixels (see the file comment).
constexpr double PixelOffsetX = 2.7e-6;
constexpr double PixelOffsetY = 1.4e-6;

/// Optical depth after which a ray stops (transmittance exp(-60) < 1e-26).
constexpr double MaxOpticalDepth = 60.0;

struct ReferenceSettings
{
  int width = 0, height = 0;
  Matrix4 modelView = IdentityMatrix();
  Matrix4 projection = IdentityMatrix();
  /// Nodes in any order (sorted internally). Empty colour: black; empty opacity: 0.
  std::vector<ColorNode> color;
  std::vector<OpacityNode> opacity;
  double unitDistance = 1.0;
  double background[3] = { 0, 0, 0 };
  /// How the scalars' values become colour and opacity; the scalars then hold
  /// ChannelsOf(mapping) floats per point or cell.
  ScalarMapping mapping = ScalarMapping::TransferFunctions;
  /// Translucent triangles composited with the volume in depth order (none by default).
  std::vector<ReferenceTriangle> triangles;
  /// Clipping planes in eye coordinates: each ray integrates only the stretch every plane
  /// keeps (the translucent triangles are not clipped, as VTK's mappers clip only their own).
  ClipPlanes clipPlanes;
  /**
   * How a ray's segments become its pixel (BlendMode; ScalarMapping::TransferFunctions
   * only, without translucent triangles). The other modes reduce the segments in closed
   * form: the extreme of the scalar lies at a segment's end, and o(s) x is quadratic
   * between breakpoints, so Simpson's rule integrates it exactly. In them the scalar is
   * first clamped to `scalarRange`, over which x is normalized (as a transfer-function
   * table clamps it: set it to the table's range).
   */
  BlendMode blendMode = BlendMode::Composite;
  double scalarRange[2] = { 0.0, 1.0 };
  /// Average intensity: only the stretches whose (clamped) scalar lies in this range count.
  double averageRange[2] = { -1e300, 1e300 };
  /**
   * Shading (Lighting.h; ScalarMapping::TransferFunctions, composite blending): with
   * `normals` set (CellNormals: 3 floats per cell, model coordinates), each cell is lit by
   * LightCell at its centroid with its normal, and a segment through it of colour C and
   * opacity A (integrated as without light) becomes clamp(scale C + offset A, 0, A).
   */
  Lighting lighting;
  const float* normals = nullptr;
  /// Segments gathered at most per pass; the image is done in bands of rows that stay
  /// below it (memory: 32 bytes per segment with one scalar, as much in all with more).
  std::size_t maxSegmentsPerPass = std::size_t(1) << 23;
};

/// What a reference rendering did.
struct ReferenceStats
{
  std::size_t segments = 0; ///< ray-cell segments integrated
  std::size_t passes = 0;   ///< bands of rows
  double seconds = 0;
};

/**
 * Renders the reference image of the mesh into `rgb` (3 * width * height doubles, linear
 * RGB, row 0 at the bottom). Returns false with a message in `error` (if given) on bad input:
 * a non-positive size, a singular matrix, a negative or non-finite unit distance, a
 * non-finite node. Cells that are not tetrahedra or have point ids out of range are skipped.
 *
 * Thread safety: reentrant; runs on `threads` OpenMP threads (<= 0: all available).
 * Determinism: every pixel's segments are sorted by a total order before integration, so the
 * image is bit-identical for any thread count.
 */
bool RenderReference(const PointsView& points, const CellsView& cells, const ScalarsView& scalars,
  const ReferenceSettings& settings, std::vector<double>& rgb, int threads,
  std::string* error = nullptr, ReferenceStats* stats = nullptr);

/// Image error over linear RGB in [0, 1].
struct ImageError
{
  double rmse = 0;            ///< root mean square over all channels of all pixels
  double psnr = 0;            ///< 20 log10(1 / rmse) in dB (peak 1); +infinity for identical images
  double maxAbs = 0;          ///< largest channel difference
  std::size_t worstPixel = 0; ///< index of the pixel with the largest difference
};

/// Compares two RGB images of `pixels` pixels (3 doubles each). Thread safety: reentrant.
ImageError CompareImages(const double* a, const double* b, std::size_t pixels);

} // namespace mtpt

#endif
