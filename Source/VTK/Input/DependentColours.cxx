// SPDX-License-Identifier: BSD-3-Clause
#include "Input/DependentColours.h"

#include "Input/TransferFunctionTables.h"

#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mtpt
{

namespace
{

/// A channel clamped to [0, 1]; NaN stays NaN.
inline float Unit(float v)
{
  return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
}

/// The finite range of channel `channel` of `values` (width 1 where it is one value).
void ChannelRange(
  const float* values, int channels, std::size_t tuples, int channel, double range[2])
{
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (std::size_t t = 0; t < tuples; ++t)
  {
    const float v = values[channels * t + channel];
    if (std::isfinite(v))
    {
      low = std::min<double>(low, v);
      high = std::max<double>(high, v);
    }
  }
  if (!(low <= high))
  {
    low = high = 0;
  }
  range[0] = low;
  range[1] = high > low ? high : low + 1.0;
}

/// Linear interpolation in `table` (`size` entries of `width` floats over [low, high]) at
/// `s`, clamped at both ends, into out[0, width).
inline void Sample(
  const std::vector<float>& table, int width, const double range[2], float s, float* out)
{
  const int size = static_cast<int>(table.size()) / width;
  const double u = (s - range[0]) * (size - 1) / (range[1] - range[0]);
  const double t = u > 0.0 ? (u < size - 1 ? u : size - 1) : 0.0;
  const int i = std::min(static_cast<int>(t), size - 2);
  const float f = static_cast<float>(t - i);
  for (int c = 0; c < width; ++c)
  {
    out[c] = table[width * i + c] + f * (table[width * (i + 1) + c] - table[width * i + c]);
  }
}

} // namespace

void DependentColours::Update(const ScalarsView& values, int channels, std::size_t tuples,
  vtkVolumeProperty* property, std::uint64_t dataVersion)
{
  Key key;
  key.dataVersion = dataVersion;
  key.channels = channels;
  if (channels == 2)
  {
    // Only the two-component mapping reads the transfer functions.
    key.property = property;
    key.propertyTime = property->GetMTime();
  }
  if (this->Built != 0 && key == this->Current)
  {
    return;
  }
  this->Association = values.association;
  this->Rgba.assign(4 * tuples, 0.0f);
  this->Alpha.assign(tuples, 0.0f);
  const auto n = static_cast<std::int64_t>(tuples);
  if (channels == 2)
  {
    this->MapColourAndOpacity(values.values, tuples, property);
  }
  else
  {
    for (std::int64_t t = 0; t < n; ++t)
    {
      for (int c = 0; c < 4; ++c)
      {
        this->Rgba[4 * t + c] = Unit(values.values[4 * t + c]);
      }
    }
  }
  // The attenuations: NaN where any component is not finite (the tuple is not drawn).
  for (std::int64_t t = 0; t < n; ++t)
  {
    bool finite = true;
    for (int c = 0; c < channels; ++c)
    {
      finite = finite && std::isfinite(values.values[channels * t + c]);
    }
    this->Alpha[t] = finite ? this->Rgba[4 * t + 3] : std::numeric_limits<float>::quiet_NaN();
  }
  this->Current = key;
  ++this->Built;
}

void DependentColours::MapColourAndOpacity(
  const float* values, std::size_t tuples, vtkVolumeProperty* property)
{
  const int size = TransferFunctionTables::Size;
  double colourRange[2], opacityRange[2];
  ChannelRange(values, 2, tuples, 0, colourRange);
  ChannelRange(values, 2, tuples, 1, opacityRange);
  std::vector<float> colours(3 * static_cast<std::size_t>(size)), opacity(size);
  if (property->GetColorChannels(0) == 1)
  {
    std::vector<float> gray(size);
    property->GetGrayTransferFunction(0)->GetTable(
      colourRange[0], colourRange[1], size, gray.data());
    for (int i = 0; i < size; ++i)
    {
      colours[3 * i] = colours[3 * i + 1] = colours[3 * i + 2] = gray[i];
    }
  }
  else
  {
    property->GetRGBTransferFunction(0)->GetTable(
      colourRange[0], colourRange[1], size, colours.data());
  }
  property->GetScalarOpacity(0)->GetTable(opacityRange[0], opacityRange[1], size, opacity.data());
  const auto n = static_cast<std::int64_t>(tuples);
  for (std::int64_t t = 0; t < n; ++t)
  {
    float* rgba = this->Rgba.data() + 4 * t;
    Sample(colours, 3, colourRange, values[2 * t], rgba);
    Sample(opacity, 1, opacityRange, values[2 * t + 1], rgba + 3);
    for (int c = 0; c < 4; ++c)
    {
      rgba[c] = Unit(rgba[c]);
    }
  }
}

} // namespace mtpt
