//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// The mapper's part in a depth-peeling pass's volumetric peels (mtpt::VolumetricPeel). The
// pass substitutes its own code at the tags below, the code it gives a volume ray caster:
// per pixel it asks castRay(zStart, zEnd) for the volume's premultiplied colour between two
// window depths, at most twice (a front and a back range), and writes its outputs from the
// answers. A projected-tetrahedra mapper cannot answer inside one fragment, so this shader
// runs twice per peel:
// - answer 0 (record): castRay returns the range it was asked for, (zStart, zEnd, 1, 0); with
//   the pass's previous front colour read as transparent, the pass's outputs 0 and 1 then
//   hold the back and the front range (or 0 where none was asked);
// - answer 1: after the mapper has composited the volume over those ranges into
//   frontColour and backColour, castRay returns the composite of the range it is asked for,
//   and the pass's code writes its outputs as it does for a ray-cast volume.
in vec2 texCoord;

uniform int answer;
uniform vec2 in_inverseWindowSize;
uniform float g_opacityThreshold;
uniform sampler2D recordedFront; // answer 1: the ranges recorded (answer 0's outputs 1 and 0)
uniform sampler2D recordedBack;
uniform sampler2D frontColour;   // answer 1: the volume over each range, premultiplied
uniform sampler2D backColour;

//VTK::DepthPeeling::Dec

void initializeRayCast()
{
}

// Whether `recorded` holds the range (zStart, zEnd). The two shader runs compute the ranges
// with the same code from the same textures; the tolerance only guards against a compiler
// arranging that arithmetic differently in the two programs.
bool SameRange(vec4 recorded, float zStart, float zEnd)
{
  return recorded.z > 0.5 && abs(recorded.x - zStart) <= 1e-6 && abs(recorded.y - zEnd) <= 1e-6;
}

vec4 castRay(float zStart, float zEnd)
{
  if (answer == 0)
  {
    return vec4(zStart, zEnd, 1.0, 0.0);
  }
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  if (SameRange(texelFetch(recordedFront, pixel, 0), zStart, zEnd))
  {
    return texelFetch(frontColour, pixel, 0);
  }
  if (SameRange(texelFetch(recordedBack, pixel, 0), zStart, zEnd))
  {
    return texelFetch(backColour, pixel, 0);
  }
  return vec4(0.0);
}

void main()
{
  // The quad's texture coordinate is not needed (the pass's code reads gl_FragCoord), but
  // its attribute must stay active for the quad's vertex array.
  if (texCoord.x < -1.0)
  {
    discard;
  }
  gl_FragData[0] = vec4(0.0);
  gl_FragData[1] = vec4(0.0);
  //VTK::CallWorker::Impl
}
