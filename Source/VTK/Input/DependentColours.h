// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DependentColours.h
 * @brief Private glue: the colours of dependent components (the volume property's
 * IndependentComponents off), mapped as VTK's PT maps them
 * (vtkProjectedTetrahedraMapper::MapScalarsToColors):
 * - two components: the first is a colour scalar, through the colour (or gray) transfer
 *   function; the second an opacity scalar, through the scalar opacity function (ParaView's
 *   "separate opacity array" for unstructured volumes);
 * - four components: the colour and the opacity themselves, in [0, 1] (MeshAdapter divides
 *   unsigned chars by 255, as VTK's PT uses them as they are).
 * Each channel is clamped to [0, 1], as VTK's PT's 8-bit colours clamp it. The result is an
 * RGBA per point or cell, the alpha being the attenuation per ScalarOpacityUnitDistance, and
 * the attenuations alone, the scalars the core culls with (NaN where a component is not
 * finite, so the cells using it are not drawn). The transfer functions are sampled as
 * TransferFunctionTables samples them (TransferFunctionTables::Size entries over each
 * component's range, read with linear interpolation).
 *
 * Rebuilt when, and only when, its key changes: the data (MeshSource's version), the
 * channel count, or the property and its MTime.
 */
#ifndef mtpt_DependentColours_h
#define mtpt_DependentColours_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/MeshView.h"

#include "vtkType.h"

#include <cstdint>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class DependentColours
{
public:
  /**
   * Brings the colours up to date with `values` (`channels` floats, 2 or 4, for each of
   * `tuples` points or cells; `dataVersion` changes whenever they do) and `property`.
   */
  void Update(const ScalarsView& values, int channels, std::size_t tuples,
    vtkVolumeProperty* property, std::uint64_t dataVersion);

  /// RGBA per tuple (valid until the next Update).
  const float* Colours() const { return this->Rgba.data(); }
  /// The attenuation of each tuple, associated as the values were.
  ScalarsView Attenuations() const { return { this->Alpha.data(), this->Association }; }
  /// Changes whenever the colours change; 0 before the first Update.
  std::uint64_t Version() const { return this->Built; }

private:
  void MapColourAndOpacity(const float* values, std::size_t tuples, vtkVolumeProperty* property);

  struct Key
  {
    std::uint64_t dataVersion = 0;
    int channels = 0;
    vtkVolumeProperty* property = nullptr;
    vtkMTimeType propertyTime = 0;
    bool operator==(const Key& o) const
    {
      return dataVersion == o.dataVersion && channels == o.channels && property == o.property &&
        propertyTime == o.propertyTime;
    }
  };
  Key Current;
  std::vector<float> Rgba, Alpha;
  ScalarsView::Association Association = ScalarsView::Association::Points;
  std::uint64_t Built = 0;
};

} // namespace mtpt

#endif
