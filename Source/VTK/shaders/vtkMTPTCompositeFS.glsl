//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// Puts the CPU compositor's image, already composited over the colour drawn before it, into
// the framebuffer (blending off).
in vec2 texCoord;
uniform sampler2D image;

void main()
{
  gl_FragData[0] = texture(image, texCoord);
}
