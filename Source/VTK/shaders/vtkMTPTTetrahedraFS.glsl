//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// MTPT fragment shader: emission-absorption over the interpolated segment length.
in vec4 classified;
in float segmentLength;

uniform float inverseUnitDistance; // 1 / ScalarOpacityUnitDistance

void main()
{
  // The exponential is taken per fragment: interpolating it per vertex would not match
  // (the opacity of a segment is not linear in its length).
  float opacity = 1.0 - exp(-classified.a * segmentLength * inverseUnitDistance);
  if (opacity <= 0.0)
  {
    discard;
  }
  gl_FragData[0] = vec4(classified.rgb, opacity);
}
