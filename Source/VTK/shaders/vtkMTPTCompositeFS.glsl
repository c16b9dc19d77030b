//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// Puts the CPU compositor's premultiplied image into the framebuffer; the blend function
// (ONE, ONE_MINUS_SRC_ALPHA) composites it over what is already drawn.
in vec2 texCoord;
uniform sampler2D image;

void main()
{
  gl_FragData[0] = texture(image, texCoord);
}
