// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/MeshView.h"

namespace mtpt
{

Matrix4 IdentityMatrix()
{
  return { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
}

Matrix4 Multiply(const Matrix4& a, const Matrix4& b)
{
  Matrix4 c{};
  for (int r = 0; r < 4; ++r)
  {
    for (int k = 0; k < 4; ++k)
    {
      for (int col = 0; col < 4; ++col)
      {
        c[4 * r + col] += a[4 * r + k] * b[4 * k + col];
      }
    }
  }
  return c;
}

} // namespace mtpt
