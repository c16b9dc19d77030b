//VTK::System::Dec
//VTK::Output::Dec
// SPDX-License-Identifier: BSD-3-Clause
// Writes an image the size of the viewport into the framebuffer, texel for pixel (nearest
// filtering, blending off): the CPU compositor's image, or the OpenGL backend's float
// target, each already composited over the colour drawn before it
// (mtpt::BlendTarget::WriteToWindow). At an image sample distance other than 1, the OpenGL
// backend's sampled image instead, stretched over the viewport with linear filtering and
// blended over it (mtpt::BlendTarget::BlendOverWindow).
in vec2 texCoord;
uniform sampler2D image;

void main()
{
  gl_FragData[0] = texture(image, texCoord);
}
