// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/Lighting.h"

#include <algorithm>
#include <cmath>

namespace mtpt
{
namespace
{

/**
 * normalize(2 nDotL n - d), as the shader computes the reflected direction. With nDotL = n.d
 * for unit n and d (or n zero) that is d's reflection, unit already: `unit` skips the
 * normalization then.
 */
void Reflected(double nDotL, const double n[3], const double d[3], double r[3], bool unit)
{
  for (int k = 0; k < 3; ++k)
  {
    r[k] = 2.0 * nDotL * n[k] - d[k];
  }
  if (!unit)
  {
    Normalize3(r);
  }
}

/// x^p for the specular term, in float: the factors are floats, and powf is the faster.
double Power(double x, double p)
{
  return std::pow(static_cast<float>(x), static_cast<float>(p));
}

/// VTK's default lighting: one headlight of intensity 1 at the eye.
LightFactors HeadlightFactors(
  const Lighting& lighting, const double n[3], const double toEye[3])
{
  const Light& light = lighting.lights[0];
  const double travel[3] = { -toEye[0], -toEye[1], -toEye[2] };
  double nDotL = Dot3(n, travel);
  double r[3];
  Reflected(nDotL, n, travel, r, true);
  const double vDotR = -Dot3(r, toEye);
  if (nDotL < 0 && lighting.twoSided)
  {
    nDotL = -nDotL;
  }
  LightFactors f = Unlit();
  const double specular =
    nDotL > 0 ? Power(std::max(vDotR, 0.0), lighting.specularPower) * lighting.specular : 0.0;
  for (int k = 0; k < 3; ++k)
  {
    const double diffuse = nDotL > 0 ? nDotL * lighting.diffuse * light.diffuse[k] : 0.0;
    f.scale[k] = static_cast<float>(lighting.ambient + diffuse);
    f.offset[k] = static_cast<float>(specular * light.specular[k]);
  }
  return f;
}

/// The attenuation of a positional light at `position`, and the way its light travels there.
double Attenuation(const Light& light, const double position[3], double travel[3])
{
  for (int k = 0; k < 3; ++k)
  {
    travel[k] = position[k] - light.position[k];
  }
  const double distance = std::sqrt(Dot3(travel, travel));
  Normalize3(travel);
  double attenuation = 1.0 /
    (light.attenuation[0] + light.attenuation[1] * distance +
      light.attenuation[2] * distance * distance);
  if (light.coneAngle <= 90.0)
  {
    const double coneDot = Dot3(travel, light.direction);
    const double pi = 3.14159265358979323846;
    attenuation = coneDot >= std::cos(light.coneAngle * pi / 180.0)
      ? attenuation * std::pow(coneDot, light.exponent)
      : 0.0;
  }
  return attenuation;
}

/// Every light of `lighting` (VTK's light kit and scene lights).
LightFactors LightsFactors(
  const Lighting& lighting, const double n[3], const double position[3], const double toEye[3])
{
  double ambient[3] = { 0, 0, 0 }, diffuse[3] = { 0, 0, 0 }, specular[3] = { 0, 0, 0 };
  const int count = std::min(lighting.count, Lighting::MaxLights);
  for (int i = 0; i < count; ++i)
  {
    const Light& light = lighting.lights[i];
    double travel[3] = { light.direction[0], light.direction[1], light.direction[2] };
    const double attenuation = light.positional ? Attenuation(light, position, travel) : 1.0;
    double nDotL = Dot3(n, travel);
    const bool flipped = nDotL < 0 && lighting.twoSided;
    if (flipped)
    {
      nDotL = -nDotL;
    }
    if (nDotL > 0)
    {
      const double df = std::max(0.0, attenuation * nDotL);
      double r[3];
      Reflected(nDotL, n, travel, r, !flipped);
      double rDotV = -Dot3(r, toEye);
      if (light.positional && rDotV < 0 && lighting.twoSided)
      {
        rDotV = -rDotV;
      }
      const double sf = rDotV > 0 ? attenuation * Power(rDotV, lighting.specularPower) : 0.0;
      for (int k = 0; k < 3; ++k)
      {
        diffuse[k] += df * light.diffuse[k];
        specular[k] += sf * light.specular[k];
      }
    }
    for (int k = 0; k < 3; ++k)
    {
      ambient[k] += light.ambient[k];
    }
  }
  LightFactors f = Unlit();
  for (int k = 0; k < 3; ++k)
  {
    f.scale[k] = static_cast<float>(lighting.diffuse * diffuse[k]);
    f.offset[k] =
      static_cast<float>(lighting.ambient * ambient[k] + lighting.specular * specular[k]);
  }
  return f;
}

} // namespace

bool Normalize3(double v[3])
{
  const double length = std::sqrt(Dot3(v, v));
  if (!(length > 0) || !std::isfinite(length))
  {
    return false;
  }
  for (int k = 0; k < 3; ++k)
  {
    v[k] /= length;
  }
  return true;
}

bool operator==(const Lighting& a, const Lighting& b)
{
  auto same = [](const double* x, const double* y, int n) { return std::equal(x, x + n, y); };
  if (a.headlight != b.headlight || a.twoSided != b.twoSided || a.ambient != b.ambient ||
    a.diffuse != b.diffuse || a.specular != b.specular || a.specularPower != b.specularPower ||
    a.count != b.count)
  {
    return false;
  }
  for (int i = 0; i < std::min(a.count, Lighting::MaxLights); ++i)
  {
    const Light &p = a.lights[i], &q = b.lights[i];
    if (!same(p.ambient, q.ambient, 3) || !same(p.diffuse, q.diffuse, 3) ||
      !same(p.specular, q.specular, 3) || !same(p.direction, q.direction, 3) ||
      p.positional != q.positional || !same(p.position, q.position, 3) ||
      !same(p.attenuation, q.attenuation, 3) || p.coneAngle != q.coneAngle ||
      p.exponent != q.exponent)
    {
      return false;
    }
  }
  return true;
}

LightFactors Unlit()
{
  return { { 1.0f, 1.0f, 1.0f, 0.0f }, { 0.0f, 0.0f, 0.0f, 0.0f } };
}

/// Factors fit for float arithmetic: NaN is 0, and magnitudes stay below 1e6 (a colour times
/// one stays finite; the lit colour is clamped to [0, 1] anyway).
LightFactors Bounded(LightFactors f)
{
  for (float* v : { f.scale, f.offset })
  {
    for (int k = 0; k < 3; ++k)
    {
      v[k] = std::isnan(v[k]) ? 0.0f : std::min(1e6f, std::max(-1e6f, v[k]));
    }
  }
  return f;
}

LightFactors LightCell(const Lighting& lighting, const double normal[3], const double position[3])
{
  double toEye[3] = { -position[0], -position[1], -position[2] };
  if (!Normalize3(toEye))
  {
    toEye[0] = toEye[1] = 0;
    toEye[2] = 1;
  }
  if (lighting.count <= 0)
  {
    LightFactors f = Unlit();
    for (int k = 0; k < 3; ++k)
    {
      f.scale[k] = 0; // no light: VTK's ray caster leaves the lit sample black
    }
    return f;
  }
  return Bounded(lighting.headlight ? HeadlightFactors(lighting, normal, toEye)
                                    : LightsFactors(lighting, normal, position, toEye));
}

bool NormalMatrix(const Matrix4& m, double n[9])
{
  // The inverse transpose of A is the cofactor matrix of A divided by det A.
  const double a[3][3] = { { m[0], m[1], m[2] }, { m[4], m[5], m[6] }, { m[8], m[9], m[10] } };
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      n[3 * r + c] = a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1];
    }
  }
  const double det = a[0][0] * n[0] + a[0][1] * n[1] + a[0][2] * n[2];
  if (!(det != 0) || !std::isfinite(det))
  {
    return false;
  }
  for (int k = 0; k < 9; ++k)
  {
    n[k] /= det;
  }
  return true;
}

void EyeNormal(const double n[9], const float normal[3], double eye[3])
{
  for (int r = 0; r < 3; ++r)
  {
    eye[r] = n[3 * r] * normal[0] + n[3 * r + 1] * normal[1] + n[3 * r + 2] * normal[2];
  }
  if (!Normalize3(eye))
  {
    eye[0] = eye[1] = eye[2] = 0;
  }
}

LightFactors LightTetrahedron(const Lighting& lighting, const double normalMatrix[9],
  const float normal[3], const double corners[4][3])
{
  double centroid[3] = { 0, 0, 0 }, eye[3];
  for (int i = 0; i < 4; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      centroid[k] += 0.25 * corners[i][k];
    }
  }
  EyeNormal(normalMatrix, normal, eye);
  return LightCell(lighting, eye, centroid);
}

} // namespace mtpt
