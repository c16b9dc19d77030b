//VTK::System::Dec
// SPDX-License-Identifier: BSD-3-Clause
// MTPT vertex shader. Positions arrive in NDC (the CPU stages projected them); each vertex
// carries the scalar where the ray through it enters and leaves its tetrahedron and the
// eye-space length between (0 except at the thick vertex).
in vec3 vertexNDC;
in vec2 scalarFrontBack;
in float thickness;
// Dependent components (shadingMode 2): the same bytes as scalarFrontBack, read as the
// vertex's colour and attenuation (16-bit unsigned normalized, mtpt::StoreVertexColour).
in vec4 vertexColour;

// Colour (rgb) and scalar opacity (a) of the transfer functions, sampled over the scalar
// range: texture coordinate = scalar * scalarScale + scalarShift; table entry coordinate
// (0 at the first entry, tableSize - 1 at the last) = scalar * entryScale + entryShift.
uniform sampler2D transferFunction;
uniform float scalarScale;
uniform float scalarShift;
uniform float entryScale;
uniform float entryShift;
uniform int tableSize;
// Entries in a row of the table's texture; a table of more (several properties) is read
// texel by texel, entry i at (i % tableWidth, i / tableWidth).
uniform int tableWidth;
uniform int shadingMode; // mtpt::FragmentValues of the frame's plan: see the fragment shader
// Perspective-exact pre-integration (mtpt::PerspectiveInterpolation): 1 / eye depth =
// inverseDepthScale * z_ndc + inverseDepthOffset; eye ray per unit depth =
// ((ndc.xy + rayShift) * rayScale, -1).
uniform int perspectiveExact;
uniform int clampEntries;
uniform float inverseDepthScale;
uniform float inverseDepthOffset;
uniform vec2 rayScale;
uniform vec2 rayShift;

out vec4 classified;
out vec3 preIntegration;
// Perspective-exact only: (front scalar / front depth, 1 / front depth, back scalar / back
// depth, 1 / back depth), the eye ray and 1 / back depth - 1 / front depth; all affine in
// screen space over a triangle. The difference is formed here without cancellation (a
// segment thin against its depth would otherwise get its length from the last bits of two
// nearly equal values).
out vec4 exactFrontBack;
out vec2 exactRay;
out float exactDelta;

// The table at entry coordinate u, clamped to the table, read texel by texel.
vec4 EntryAt(float u)
{
  u = clamp(u, 0.0, float(tableSize - 1));
  int i = min(int(u), max(tableSize - 2, 0));
  int j = min(i + 1, tableSize - 1);
  return mix(texelFetch(transferFunction, ivec2(i % tableWidth, i / tableWidth), 0),
    texelFetch(transferFunction, ivec2(j % tableWidth, j / tableWidth), 0), u - float(i));
}

void main()
{
  if (shadingMode == 2)
  {
    // Dependent components: the CPU stages classified the vertex (colour, attenuation).
    classified = vertexColour;
    preIntegration = vec3(0.0, 0.0, thickness);
  }
  else if (shadingMode == 0)
  {
    // Vertex classification as VTK's PT, with float colours: at the thick vertex the
    // colour and attenuation are the mean of the front and back values.
    vec4 front, back;
    if (tableSize <= tableWidth)
    {
      front = texture(transferFunction, vec2(scalarFrontBack.x * scalarScale + scalarShift, 0.5));
      back = texture(transferFunction, vec2(scalarFrontBack.y * scalarScale + scalarShift, 0.5));
    }
    else
    {
      front = EntryAt(scalarFrontBack.x * entryScale + entryShift);
      back = EntryAt(scalarFrontBack.y * entryScale + entryShift);
    }
    classified = 0.5 * (front + back);
    preIntegration = vec3(0.0, 0.0, thickness);
  }
  else
  {
    // Pre-integrated: the scalars travel to the fragment shader (in table entry units).
    classified = vec4(0.0);
    float last = float(tableSize - 1);
    vec2 entries = scalarFrontBack * entryScale + entryShift;
    // Average and additive blending clamp only in the fragment shader: along a segment that
    // leaves the table's range the clamped scalar is not linear.
    preIntegration = vec3(clampEntries == 1 ? clamp(entries, 0.0, last) : entries, thickness);
  }
  exactFrontBack = vec4(0.0);
  exactRay = vec2(0.0);
  exactDelta = 0.0;
  if (perspectiveExact == 1)
  {
    exactRay = (vertexNDC.xy + rayShift) * rayScale;
    float depth = 1.0 / (inverseDepthScale * vertexNDC.z + inverseDepthOffset);
    float along = thickness / sqrt(1.0 + dot(exactRay, exactRay));
    float front = 1.0 / depth;
    float back = 1.0 / (depth + along);
    exactFrontBack = vec4(preIntegration.x * front, front, preIntegration.y * back, back);
    exactDelta = -along * front * back;
  }
  gl_Position = vec4(vertexNDC, 1.0);
}
