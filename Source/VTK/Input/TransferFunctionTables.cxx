// SPDX-License-Identifier: BSD-3-Clause
#include "Input/TransferFunctionTables.h"

#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

namespace mtpt
{

void TransferFunctionTables::Update(vtkVolumeProperty* property, double low, double high)
{
  if (!(high > low))
  {
    high = low + 1.0; // a constant field still needs a table with a width
  }
  Key key;
  key.property = property;
  key.propertyTime = property->GetMTime();
  key.low = low;
  key.high = high;
  if (this->Built != 0 && key == this->Current)
  {
    return;
  }
  const int n = Size;
  std::vector<float> rgb(3 * n), opacity(n);
  if (property->GetColorChannels(0) == 1)
  {
    std::vector<float> gray(n);
    property->GetGrayTransferFunction(0)->GetTable(low, high, n, gray.data());
    for (int i = 0; i < n; ++i)
    {
      rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = gray[i];
    }
  }
  else
  {
    property->GetRGBTransferFunction(0)->GetTable(low, high, n, rgb.data());
  }
  property->GetScalarOpacity(0)->GetTable(low, high, n, opacity.data());
  this->Values.resize(4 * static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      this->Values[4 * i + c] = rgb[3 * i + c];
    }
    this->Values[4 * i + 3] = opacity[i];
  }
  this->Current = key;
  this->Integrals.Build(this->Table());
  this->IntensityIntegral.Build(this->Table());
  ++this->Built;
}

TransferFunctionTable TransferFunctionTables::Table() const
{
  return { this->Values.data(), this->Values.empty() ? 0 : Size, this->Current.low,
    this->Current.high };
}

} // namespace mtpt
