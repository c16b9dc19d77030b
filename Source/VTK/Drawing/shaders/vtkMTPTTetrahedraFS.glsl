//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// MTPT fragment shader: emission-absorption over the interpolated ray segment. The
// pre-integrated branch evaluates mtpt::PreIntegrationTable::Segment
// (Source/Core/TransferFunctionTable.cxx) with the same formulas: keep the two in step.
// Their constants and series are mtpt/SegmentShared.h, which the backend inserts here:
//MTPT::SegmentShared
in vec4 classified;
in vec3 preIntegration; // front and back scalar (table entry units), segment length
in vec4 exactFrontBack;  // perspective-exact: see the vertex shader
in vec2 exactRay;
in float exactDelta;
uniform int perspectiveExact;

uniform float inverseUnitDistance; // 1 / ScalarOpacityUnitDistance
// What the vertices carry (mtpt::FragmentValues, from the frame's plan): 0 the transfer
// function's means (VTK-compatible), 1 scalars (pre-integrated, the reductions), 2 colours.
uniform int shadingMode;
uniform int tableSize;
// Entries in a row of the tables' textures: entry i at texel (i % tableWidth, i / tableWidth).
uniform int tableWidth;
uniform sampler2D transferFunction;
// Prefix integrals (T, E_r, E_g, E_b) at the table entries, as a float sum high + low so
// that differences of nearby entries keep their precision.
uniform sampler2D integralsHigh;
uniform sampler2D integralsLow;

// Shading by lights (mtpt/Lighting.h): the backend defines MTPT_LIT here in the lit variant.
//MTPT::Lit
#ifdef MTPT_LIT
// Each slot's factors, scale then offset, two texels per slot; the triangles of slot k are
// primitives 4k to 4k + 3 of the batch.
uniform samplerBuffer lightFactors;
uniform int lightSlotBase; // the slot of this draw call's first primitive
#endif

// A fragment's colour c (not premultiplied) lit as clamp(scale c + offset, 0, 1).
vec4 Lit(vec4 fragment)
{
#ifdef MTPT_LIT
  int slot = lightSlotBase + gl_PrimitiveID / 4;
  vec4 scale = texelFetch(lightFactors, 2 * slot);
  vec4 offset = texelFetch(lightFactors, 2 * slot + 1);
  return vec4(clamp(scale.rgb * fragment.rgb + offset.rgb, 0.0, 1.0), fragment.a);
#else
  return fragment;
#endif
}

// 1 - exp(-d) without cancellation for small d.
float Opacity(float d)
{
  return d < MTPT_SERIES_DEPTH ? OpacitySeries(d) : 1.0 - exp(-d);
}

ivec2 TableTexel(int i)
{
  return ivec2(i % tableWidth, i / tableWidth);
}

vec4 Entry(int i)
{
  return texelFetch(transferFunction, TableTexel(i), 0);
}

void Split(float u, out int i, out float f)
{
  i = min(int(u), max(tableSize - 2, 0));
  f = u - float(i);
}

vec4 EntryAt(float u)
{
  int i;
  float f;
  Split(u, i, f);
  return mix(Entry(i), Entry(min(i + 1, tableSize - 1)), f);
}

// Means of tau and c tau over the fractions [fa, fb] of interval i, from the values at its
// two ends, every term positive (PieceMeans).
void PieceMeans(int i, float fa, float fb, out float t, out vec3 e)
{
  vec4 a = Entry(i);
  vec4 d = Entry(min(i + 1, tableSize - 1)) - a;
  float ta = max(0.0, a.a + fa * d.a);
  float tb = max(0.0, a.a + fb * d.a);
  t = 0.5 * (ta + tb);
  e = ((a.rgb + fa * d.rgb) * (2.0 * ta + tb) + (a.rgb + fb * d.rgb) * (ta + 2.0 * tb)) / 6.0;
}

// Means of tau and c tau over the entry interval [u0, u1] (either orientation).
void SpanMeans(float u0, float u1, out float tau, out vec3 e)
{
  int i0, i1;
  float f0, f1;
  Split(u0, i0, f0);
  Split(u1, i1, f1);
  if (i0 == i1)
  {
    PieceMeans(i0, f0, f1, tau, e);
    return;
  }
  bool forward = u0 <= u1;
  int il = forward ? i0 : i1;
  int ih = forward ? i1 : i0;
  float fl = forward ? f0 : f1;
  float fh = forward ? f1 : f0;
  float tl, th;
  vec3 el, eh;
  PieceMeans(il, fl, 1.0, tl, el);
  PieceMeans(ih, 0.0, fh, th, eh);
  vec4 sums = (texelFetch(integralsHigh, TableTexel(ih), 0) - texelFetch(integralsHigh, TableTexel(il + 1), 0)) +
    (texelFetch(integralsLow, TableTexel(ih), 0) - texelFetch(integralsLow, TableTexel(il + 1), 0));
  float inverse = 1.0 / abs(u1 - u0);
  tau = ((1.0 - fl) * tl + sums.x + fh * th) * inverse;
  e = ((1.0 - fl) * el + sums.yzw + fh * eh) * inverse;
}

vec4 PreIntegrated(float ua, float ub, float len)
{
  if (!(len > 0.0))
  {
    return vec4(0.0);
  }
  float depth = len * inverseUnitDistance;
  float tau;
  vec3 e;
  SpanMeans(ua, ub, tau, e);
  int steps = int(min(float(MTPT_MAX_SEGMENT_STEPS), max(1.0, ceil(tau * depth / MTPT_STEP_DEPTH))));
  vec3 colour = vec3(0.0);
  float alpha = 0.0;
  for (int s = 0; s < steps; ++s)
  {
    float u0 = ua + (ub - ua) * float(s) / float(steps);
    float u1 = ua + (ub - ua) * float(s + 1) / float(steps);
    if (steps > 1)
    {
      SpanMeans(u0, u1, tau, e);
    }
    if (!(tau > 0.0))
    {
      continue;
    }
    float d = tau * depth / float(steps);
    float a = Opacity(d);
    float h = d < MTPT_WEIGHT_SERIES_DEPTH ? WeightSeries(d) : 1.0 / d - 1.0 / (exp(d) - 1.0);
    vec3 c0 = EntryAt(u0).rgb;
    vec3 c1 = EntryAt(u1).rgb;
    vec3 mean = clamp(e / tau, 0.0, 1.0); // as the CPU compositor: rounding kept in [0, 1]
    vec3 stepColour = clamp(mean + (c0 - c1) * (0.5 - h), min(mean, min(c0, c1)), max(mean, max(c0, c1)));
    colour += (1.0 - alpha) * a * stepColour;
    alpha += (1.0 - alpha) * a;
  }
  // As the CPU compositor: below the smallest normal float the reciprocal would overflow.
  return alpha > 1.17549435e-38 ? vec4(colour / alpha, alpha) : vec4(0.0);
}

// Depth peeling (mtpt::VolumetricPeel): the volume's parts between the window depths each
// pixel's front and back range record (x start, y end, z 1 where the pass asked), composited
// into two targets. Eye depth at window depth z: 1 / D = a z_ndc + b (perspective) or
// D = a z_ndc + b (orthographic), mtpt::DepthClipping.
uniform int peelRanges;
uniform sampler2D peelFront;
uniform sampler2D peelBack;
uniform int depthPerspective;
uniform float depthA;
uniform float depthB;
uniform vec2 viewportOrigin; // of the target drawn into, in its pixels
uniform vec2 viewportSize;
uniform vec2 rayScale;
uniform vec2 rayShift;
// Clipping planes (mtpt::ClipPlanes) in eye coordinates: each keeps n . e + d >= 0 of
// (n, d). Orthographic eye x and y: (ndc + orthoShift) * orthoScale.
uniform int clipPlaneCount;
uniform vec4 clipPlanes[8];
uniform vec2 orthoScale;
uniform vec2 orthoShift;

vec2 FragmentNdc()
{
  return (gl_FragCoord.xy - viewportOrigin) / viewportSize * 2.0 - 1.0;
}

float EyeDepth(float windowDepth)
{
  float ndc = 2.0 * windowDepth - 1.0;
  return depthPerspective == 1 ? 1.0 / (depthA * ndc + depthB) : depthA * ndc + depthB;
}

// The fragment's segment: eye depths of its front and back, eye length, and the scalars at
// its ends (table entry units; pre-integrated shading).
struct FragmentSegment
{
  float front, back, len, scalarFront, scalarBack;
};

FragmentSegment SegmentOfFragment(bool depths)
{
  FragmentSegment s;
  if (perspectiveExact == 1) // scalars only (the plan's perspectiveExact)
  {
    // Front and back faces are planes: their 1 / depth is affine in screen space. The
    // length (1 / back - 1 / front) |ray| = (-delta / front) / back |ray|, each factor
    // without cancellation (the compositor's ExactSegmentLength).
    s.front = 1.0 / exactFrontBack.y;
    s.back = 1.0 / exactFrontBack.w;
    float len = -exactDelta / exactFrontBack.y / exactFrontBack.w *
      sqrt(1.0 + dot(exactRay, exactRay));
    s.len = len > 0.0 ? len : 0.0; // and 0 for NaN
    s.scalarFront = exactFrontBack.x / exactFrontBack.y;
    s.scalarBack = exactFrontBack.z / exactFrontBack.w;
    return s;
  }
  s.len = preIntegration.z;
  s.scalarFront = preIntegration.x;
  s.scalarBack = preIntegration.y;
  s.front = 0.0;
  s.back = 0.0;
  if (!depths)
  {
    return s;
  }
  s.front = EyeDepth(gl_FragCoord.z);
  float rayLength = 1.0;
  if (depthPerspective == 1)
  {
    vec2 ray = (FragmentNdc() + rayShift) * rayScale;
    rayLength = sqrt(1.0 + dot(ray, ray));
  }
  s.back = s.front + s.len / rayLength;
  return s;
}

// The eye point at eye depth `depth` on the fragment's ray (mtpt::DepthClipping::EyePoint).
vec3 EyePoint(vec2 ndc, float depth)
{
  vec2 xy = depthPerspective == 1 ? depth * (ndc + rayShift) * rayScale
                                  : (ndc + orthoShift) * orthoScale;
  return vec3(xy, -depth);
}

// Narrows [t0, t1] to the part of the segment every clipping plane keeps
// (mtpt::ClipPlanes::Narrow); false when no part is left.
bool NarrowToPlanes(FragmentSegment s, inout float t0, inout float t1)
{
  vec2 ndc = FragmentNdc();
  vec3 front = EyePoint(ndc, s.front);
  vec3 back = EyePoint(ndc, s.back);
  for (int i = 0; i < clipPlaneCount; ++i)
  {
    float f0 = dot(clipPlanes[i].xyz, front) + clipPlanes[i].w;
    float f1 = dot(clipPlanes[i].xyz, back) + clipPlanes[i].w;
    if (isnan(f0) || isnan(f1) || (f0 >= 0.0 && f1 >= 0.0))
    {
      continue; // not a number: the plane cuts nothing, as in mtpt::ClipPlanes
    }
    if (f0 < 0.0 && f1 < 0.0)
    {
      return false;
    }
    float cut = f0 / (f0 - f1);
    if (f0 < 0.0)
    {
      t0 = max(t0, cut);
    }
    else
    {
      t1 = min(t1, cut);
    }
  }
  return t1 > t0;
}

// The fragment of the part [t0, t1] of the segment (fractions from its front).
vec4 ShadePart(FragmentSegment s, float t0, float t1)
{
  float len = t1 - t0 < 1.0 ? s.len * (t1 - t0) : s.len;
  if (shadingMode != 1)
  {
    // VTK-compatible, from the table or the vertex colours. The exponential is taken per
    // fragment: interpolating it per vertex would not match (the opacity of a segment is not
    // linear in its length).
    return vec4(classified.rgb, 1.0 - exp(-classified.a * len * inverseUnitDistance));
  }
  float ds = s.scalarBack - s.scalarFront;
  float a = t0 > 0.0 ? s.scalarFront + t0 * ds : s.scalarFront;
  float b = t1 < 1.0 ? s.scalarFront + t1 * ds : s.scalarBack;
  return PreIntegrated(a, b, len);
}

// The part of the segment inside the recorded range, or nothing.
vec4 ShadeInRange(FragmentSegment s, vec4 range)
{
  float span = s.back - s.front;
  if (range.z < 0.5 || !(span > 0.0))
  {
    return vec4(0.0);
  }
  float t0 = clamp((EyeDepth(range.x) - s.front) / span, 0.0, 1.0);
  float t1 = clamp((EyeDepth(range.y) - s.front) / span, 0.0, 1.0);
  if (clipPlaneCount > 0 && !NarrowToPlanes(s, t0, t1))
  {
    return vec4(0.0);
  }
  return t1 > t0 ? ShadePart(s, t0, t1) : vec4(0.0);
}

// Blend modes other than composite (mtpt::BlendMode): each fragment's reduced values,
// which the target folds with GL_MAX (maximum; minimum as the negated scalar) or sums
// (average, additive), and vtkMTPTReduceFS.glsl maps to colour. As the CPU compositor's
// ReduceFragment and mtpt::IntensityTable::Mean: keep them in step.
uniform int blendMode;
uniform vec2 averageRange; // entry coordinates, open (+-1e30) where it reaches an end
// W (the integral of opacity times normalized scalar) at the table entries, high and low.
uniform sampler2D intensityPrefix;

// The integral of opacity times normalized scalar over the fractions [g0, g1] of table
// interval i, in closed form (no cancellation however short).
float IntervalIntegral(int i, float g0, float g1)
{
  float a = Entry(i).a;
  float d = Entry(min(i + 1, tableSize - 1)).a - a;
  float m1 = 0.5 * (g0 + g1);
  float m2 = (g0 * g0 + g0 * g1 + g1 * g1) / 3.0;
  return (g1 - g0) * (a * float(i) + m1 * (a + d * float(i)) + m2 * d) / float(tableSize - 1);
}

// The mean of opacity times normalized scalar over [u0, u1] inside the table: within one
// interval or across one boundary in closed form, across more from the prefix sums.
float IntensityMeanInside(float u0, float u1)
{
  int i0, i1;
  float f0, f1;
  Split(u0, i0, f0);
  Split(u1, i1, f1);
  if (i0 == i1)
  {
    float a = Entry(i0).a;
    float d = Entry(min(i0 + 1, tableSize - 1)).a - a;
    float m1 = 0.5 * (f0 + f1);
    float m2 = (f0 * f0 + f0 * f1 + f1 * f1) / 3.0;
    return (a * float(i0) + m1 * (a + d * float(i0)) + m2 * d) / float(tableSize - 1);
  }
  if (i1 == i0 + 1)
  {
    return (IntervalIntegral(i0, f0, 1.0) + IntervalIntegral(i1, 0.0, f1)) / (u1 - u0);
  }
  vec2 w1 = texelFetch(intensityPrefix, TableTexel(i1), 0).xy;
  vec2 w0 = texelFetch(intensityPrefix, TableTexel(i0), 0).xy;
  float sum = (w1.x - w0.x) + (w1.y - w0.y);
  return (sum + IntervalIntegral(i1, 0.0, f1) - IntervalIntegral(i0, 0.0, f0)) / (u1 - u0);
}

// The same with the scalar clamped beyond the table: 0 below it, the last opacity above.
float IntensityMean(float u0, float u1)
{
  float last = float(tableSize - 1);
  float inside0 = clamp(u0, 0.0, last);
  float inside1 = clamp(u1, 0.0, last);
  if (!(u1 > u0))
  {
    return IntensityMeanInside(inside0, inside0);
  }
  if (u0 >= 0.0 && u1 <= last)
  {
    return IntensityMeanInside(u0, u1);
  }
  float above = max(0.0, u1 - max(u0, last));
  float inside = inside1 > inside0 ? IntensityMeanInside(inside0, inside1) * (inside1 - inside0)
                                   : 0.0;
  return (inside + above * Entry(tableSize - 1).a) / (u1 - u0);
}

// The reduced values of the part [t0, t1] of the segment: R the extreme entry coordinate
// (negated for the minimum) or the integral, G the length in the average's range, A 1.
vec4 Reduced(FragmentSegment s, float t0, float t1)
{
  float len = s.len * (t1 - t0);
  float ds = s.scalarBack - s.scalarFront;
  float a = s.scalarFront + t0 * ds;
  float b = s.scalarFront + t1 * ds;
  float low = min(a, b);
  float high = max(a, b);
  float last = float(tableSize - 1);
  if (blendMode == 1)
  {
    return vec4(clamp(high, 0.0, last), 0.0, 0.0, 1.0);
  }
  if (blendMode == 2)
  {
    return vec4(-clamp(low, 0.0, last), 0.0, 0.0, 1.0);
  }
  if (blendMode == 4)
  {
    return vec4(len * IntensityMean(low, high), 0.0, 0.0, 1.0);
  }
  float from = max(low, averageRange.x);
  float to = min(high, averageRange.y);
  float fraction = high > low ? (to > from ? (to - from) / (high - low) : 0.0)
                              : (from <= to ? 1.0 : 0.0);
  if (!(fraction > 0.0))
  {
    return vec4(0.0, 0.0, 0.0, 1.0);
  }
  float part = len * fraction;
  return vec4(part * IntensityMean(from, max(from, to)), part, 0.0, 1.0);
}

void main()
{
  FragmentSegment segment = SegmentOfFragment(peelRanges == 1 || clipPlaneCount > 0);
  if (peelRanges == 1)
  {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    gl_FragData[0] = Lit(ShadeInRange(segment, texelFetch(peelFront, pixel, 0)));
    gl_FragData[1] = Lit(ShadeInRange(segment, texelFetch(peelBack, pixel, 0)));
    return;
  }
  float t0 = 0.0;
  float t1 = 1.0;
  if (clipPlaneCount > 0 && !NarrowToPlanes(segment, t0, t1))
  {
    discard;
  }
  if (blendMode != 0)
  {
    gl_FragData[0] = Reduced(segment, t0, t1);
    return;
  }
  vec4 fragment = ShadePart(segment, t0, t1);
  if (fragment.a <= 0.0)
  {
    discard;
  }
  gl_FragData[0] = Lit(fragment);
}
