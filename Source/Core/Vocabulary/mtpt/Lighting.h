// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Lighting.h
 * @brief Shading of the volume by lights (vtkVolumeProperty::ShadeOn), as VTK's GPU ray
 * caster lights a sample (Documentation/shading.md).
 *
 * The model:
 * - Every point has the gradient of the scalar: the volume-weighted mean of the gradients of
 *   the linear field over its tetrahedra (PointGradients, Gradients.h). Every tetrahedron has
 *   one normal, the mean of its points' gradients, normalized (CellNormals; zero where that
 *   mean is zero). Both are computed once per change of the data.
 * - Each frame, every drawn tetrahedron is lit once, at its centroid, with its normal
 *   (LightCell): VTK's lighting equation, which is affine in the sample's colour c, gives
 *   the lit colour clamp(scale * c + offset, 0, 1) per channel (LightFactors).
 * - Because the factors are constant over a tetrahedron, they commute with the integration
 *   along each fragment's segment: a fragment of premultiplied colour C and opacity A becomes
 *   clamp(scale * C + offset * A, 0, A). Pre-integrated shading stays exact for this model.
 *   VTK's ray caster clamps each sample's lit colour to [0, 1]; here the clamp applies to the
 *   fragment's mean colour, the same unless a sample's lit colour leaves [0, 1].
 *
 * Conventions: eye coordinates as in MeshView.h (the eye at the origin, looking down -z).
 */
#ifndef mtpt_Lighting_h
#define mtpt_Lighting_h

#include "mtpt/MeshView.h"

namespace mtpt
{

/// One light as VTK's GPU ray caster reads a vtkLight, in eye coordinates. The colours hold
/// the light's intensity multiplied in.
struct Light
{
  double ambient[3] = { 1, 1, 1 };
  double diffuse[3] = { 1, 1, 1 };
  double specular[3] = { 1, 1, 1 };
  /// The way the light travels, unit length (from its position to its focal point).
  double direction[3] = { 0, 0, -1 };
  /// A positional light shines from `position`, attenuated by 1 / (a0 + a1 d + a2 d^2) at
  /// distance d, and, with a cone angle of at most 90 degrees, only inside the cone around
  /// `direction`, attenuated further by cos^exponent of the angle to it.
  bool positional = false;
  double position[3] = { 0, 0, 0 };
  double attenuation[3] = { 1, 0, 0 };
  double coneAngle = 30;
  double exponent = 1;
};

/// The lights and the volume property's lighting coefficients.
struct Lighting
{
  static constexpr int MaxLights = 16;
  /**
   * VTK's "default lighting": a single light, a headlight of intensity 1. The ray caster then
   * lights from the eye (towards each point) and adds ambient * c instead of the light's
   * ambient colour: lit = ambient c + [n.l > 0] (diffuse (n.l) Ld c + specular (r.v)^p Ls).
   * Otherwise every light counts: lit = ambient sum(La) + diffuse sum((n.l) Ld) c +
   * specular sum((r.v)^p Ls), positional lights attenuated.
   */
  bool headlight = true;
  /// The renderer's two-sided lighting: a normal facing away from a light is flipped.
  bool twoSided = true;
  double ambient = 0.1, diffuse = 0.7, specular = 0.2, specularPower = 10;
  int count = 1;
  Light lights[MaxLights];
};

/// a . b of 3-vectors.
inline double Dot3(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// out = a x b of 3-vectors.
inline void Cross3(const double a[3], const double b[3], double out[3])
{
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

/// v normalized in place; false (v unchanged) when its length is 0 or not finite.
bool Normalize3(double v[3]);

/// Whether two lightings light every sample alike (every field of their first `count` lights).
bool operator==(const Lighting& a, const Lighting& b);
inline bool operator!=(const Lighting& a, const Lighting& b)
{
  return !(a == b);
}

/// A lit colour: clamp(scale * c + offset, 0, 1) per channel of the sample colour c (the 4th
/// entries are padding: two RGBA texels for OpenGL).
struct LightFactors
{
  float scale[4];
  float offset[4];
};

/// The factors that leave colours unlit: scale 1, offset 0.
LightFactors Unlit();

/**
 * VTK's lighting of a sample at `position` (eye coordinates) with unit `normal` (eye
 * coordinates; zero: no direction, only the ambient term lights it), as factors of its
 * colour. Factors that come out not a number (from lights or coefficients that are not
 * finite) are 0, and every factor is bounded by 1e6 in magnitude.
 * Thread safety: pure function.
 */
LightFactors LightCell(const Lighting& lighting, const double normal[3], const double position[3]);

/**
 * The matrix that takes a model normal to eye coordinates: the inverse transpose of the
 * model-view's upper 3x3 (row-major, 9 entries); false if that is singular.
 */
bool NormalMatrix(const Matrix4& modelView, double normalMatrix[9]);

/// `normal` (model coordinates) in eye coordinates, unit length (zero stays zero).
void EyeNormal(const double normalMatrix[9], const float normal[3], double eye[3]);

/**
 * The model's lighting of one tetrahedron: LightCell at the centroid of its `corners` (eye
 * coordinates) with its `normal` (model coordinates) taken to eye coordinates by
 * `normalMatrix` (NormalMatrix). The one definition the frame pipeline and the reference
 * share. Thread safety: pure function.
 */
LightFactors LightTetrahedron(const Lighting& lighting, const double normalMatrix[9],
  const float normal[3], const double corners[4][3]);

} // namespace mtpt

#endif
