// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TransferFunctionTables.h
 * @brief Private glue: a volume property's transfer functions as the core reads them.
 *
 * The colour (or gray) and scalar-opacity functions are sampled over the data's scalar
 * range into one RGBA table of Size entries (mtpt::TransferFunctionTable), with the prefix
 * integrals pre-integrated shading needs. Both backends shade with these, and opacity
 * culling tests against the same table, so culling is exact. The functions are piecewise
 * linear and the table is read with linear interpolation, so it reproduces them exactly
 * except within one entry (1/4095 of the range) of a breakpoint.
 *
 * Rebuilt when, and only when, its key changes: the property object, the property's MTime
 * (which follows its transfer functions') or the scalar range.
 */
#ifndef mtpt_TransferFunctionTables_h
#define mtpt_TransferFunctionTables_h

#include "vtkMTPTVTKCompatibility.h" // VTK_ABI_NAMESPACE_BEGIN/END
#include "mtpt/TransferFunctionTable.h"

#include "vtkType.h"

#include <cstdint>
#include <vector>

VTK_ABI_NAMESPACE_BEGIN
class vtkVolumeProperty;
VTK_ABI_NAMESPACE_END

namespace mtpt
{

class TransferFunctionTables
{
public:
  /// Entries of the table.
  static constexpr int Size = 4096;

  /**
   * Brings the tables up to date with `property` over the scalar range [low, high] (a
   * constant field, low == high, gets a range of width 1).
   */
  void Update(vtkVolumeProperty* property, double low, double high);

  /// The table (valid until the next Update).
  TransferFunctionTable Table() const;
  /// Its integral functions, for pre-integrated shading.
  const PreIntegrationTable& PreIntegration() const { return this->Integrals; }
  /// The integral of opacity times normalized scalar, for average and additive blending.
  const IntensityTable& Intensity() const { return this->IntensityIntegral; }
  /// Changes whenever the table's content changes; 0 before the first Update.
  std::uint64_t Version() const { return this->Built; }

private:
  struct Key
  {
    vtkVolumeProperty* property = nullptr;
    vtkMTimeType propertyTime = 0;
    double low = 0, high = 0;
    bool operator==(const Key& o) const
    {
      return property == o.property && propertyTime == o.propertyTime && low == o.low &&
        high == o.high;
    }
  };
  Key Current;
  std::vector<float> Values; ///< 4 * Size: r, g, b, attenuation
  PreIntegrationTable Integrals;
  IntensityTable IntensityIntegral;
  std::uint64_t Built = 0;
};

} // namespace mtpt

#endif
