// SPDX-License-Identifier: BSD-3-Clause
#include "Input/TransferFunctionTables.h"

#include "Input/VolumeInput.h"

#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>

namespace mtpt
{

void TransferFunctionTables::Update(vtkVolumeProperty* property, double low, double high)
{
  this->Update(std::vector<Segment>{ Segment{ property, low, high } });
}

void TransferFunctionTables::Update(const std::vector<Segment>& segments)
{
  std::vector<Segment> key = segments;
  std::vector<vtkMTimeType> times;
  for (Segment& segment : key)
  {
    if (!(segment.high > segment.low))
    {
      segment.high = segment.low + 1.0; // a constant field still needs a table with a width
    }
    times.push_back(segment.property->GetMTime());
  }
  if (this->Built != 0 && key == this->Current && times == this->Times)
  {
    return;
  }
  this->Current = key;
  this->Times = times;
  if (key.size() == 1)
  {
    // One property: its table over the scalar range, attenuation per its unit distance.
    this->Entries = Size;
    this->Values.resize(4 * static_cast<std::size_t>(Size));
    this->Sample(key[0], 0, 1.0);
    this->Low = key[0].low;
    this->High = key[0].high;
    this->Unit = mtpt::UnitDistance(key[0].property);
  }
  else
  {
    // Several: a segment each and its guard entry, scalars in entry coordinates, each
    // attenuation per unit length.
    this->Entries = SegmentStride * static_cast<int>(key.size());
    this->Values.resize(4 * static_cast<std::size_t>(this->Entries));
    for (std::size_t k = 0; k < key.size(); ++k)
    {
      const std::size_t first = SegmentStride * k;
      this->Sample(key[k], first, 1.0 / mtpt::UnitDistance(key[k].property));
      std::copy_n(&this->Values[4 * (first + Size - 1)], 4, &this->Values[4 * (first + Size)]);
    }
    this->Low = 0.0;
    this->High = this->Entries - 1.0;
    this->Unit = 1.0;
  }
  this->Integrals.Build(this->Table());
  this->IntensityIntegral.Build(this->Table());
  ++this->Built;
}

void TransferFunctionTables::Sample(
  const Segment& segment, std::size_t first, double attenuationScale)
{
  vtkVolumeProperty* property = segment.property;
  const int n = Size;
  std::vector<float> rgb(3 * n), opacity(n);
  if (property->GetColorChannels(0) == 1)
  {
    std::vector<float> gray(n);
    property->GetGrayTransferFunction(0)->GetTable(segment.low, segment.high, n, gray.data());
    for (int i = 0; i < n; ++i)
    {
      rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = gray[i];
    }
  }
  else
  {
    property->GetRGBTransferFunction(0)->GetTable(segment.low, segment.high, n, rgb.data());
  }
  property->GetScalarOpacity(0)->GetTable(segment.low, segment.high, n, opacity.data());
  float* values = &this->Values[4 * first];
  for (int i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      values[4 * i + c] = rgb[3 * i + c];
    }
    values[4 * i + 3] =
      attenuationScale == 1.0 ? opacity[i] : static_cast<float>(opacity[i] * attenuationScale);
  }
}

double TransferFunctionTables::EntryOf(int segment, double scalar) const
{
  const Segment& s = this->Current[static_cast<std::size_t>(segment)];
  const double first = static_cast<double>(SegmentStride) * segment;
  const double u = (scalar - s.low) * ((Size - 1) / (s.high - s.low));
  if (std::isnan(u))
  {
    return u;
  }
  return first + std::min(std::max(u, 0.0), Size - 1.0);
}

TransferFunctionTable TransferFunctionTables::Table() const
{
  return { this->Values.data(), this->Values.empty() ? 0 : this->Entries, this->Low, this->High };
}

} // namespace mtpt
