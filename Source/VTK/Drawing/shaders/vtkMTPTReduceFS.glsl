//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// Blend modes other than composite: maps the pixels' reduced values (vtkMTPTTetrahedraFS.glsl,
// Reduced) to premultiplied colour, as the CPU compositor's ReducedPixel
// (Source/Core/Compositor.cxx) maps its tiles (keep them in step), and composites them over
// the window's viewport. A sampled image is magnified as the CPU backend magnifies its
// colours (mtpt::MagnifyOver): each pixel's colour mapped first, then filtered bilinearly,
// clamped to the edge texels; at the viewport's size each pixel reads its own texel.
in vec2 texCoord;
uniform sampler2D reduced;
uniform sampler2D transferFunction;
uniform int blendMode;
uniform int tableSize;
uniform float inverseUnitDistance;

vec4 EntryAt(float u)
{
  int i = min(int(u), max(tableSize - 2, 0));
  float f = u - float(i);
  return mix(texelFetch(transferFunction, ivec2(i, 0), 0),
    texelFetch(transferFunction, ivec2(min(i + 1, tableSize - 1), 0), 0), f);
}

// The premultiplied colour of one texel's reduced values; transparent where no fragment
// came (or, for the average, none in its range).
vec4 Colour(ivec2 texel)
{
  vec4 value = texelFetch(reduced, texel, 0);
  if (!(value.a > 0.0))
  {
    return vec4(0.0);
  }
  if (blendMode == 1 || blendMode == 2)
  {
    vec4 entry = EntryAt(blendMode == 1 ? value.r : -value.r);
    float alpha = clamp(entry.a, 0.0, 1.0);
    return vec4(entry.rgb * alpha, alpha);
  }
  float grey = value.r * inverseUnitDistance;
  if (blendMode == 3)
  {
    if (!(value.g > 0.0))
    {
      return vec4(0.0);
    }
    grey = value.r / value.g;
  }
  return vec4(vec3(grey > 0.0 ? min(grey, 1.0) : 0.0), 1.0);
}

void main()
{
  ivec2 size = textureSize(reduced, 0);
  vec2 at = texCoord * vec2(size) - 0.5;
  vec2 base = floor(at);
  vec2 f = at - base;
  ivec2 i0 = clamp(ivec2(base), ivec2(0), size - 1);
  ivec2 i1 = clamp(ivec2(base) + 1, ivec2(0), size - 1);
  vec4 bottom = mix(Colour(i0), Colour(ivec2(i1.x, i0.y)), f.x);
  vec4 top = mix(Colour(ivec2(i0.x, i1.y)), Colour(i1), f.x);
  gl_FragData[0] = mix(bottom, top, f.y);
}
