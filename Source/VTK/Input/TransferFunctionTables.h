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
 * Several volumes drawn together in one visibility order (the mapper's
 * CompositeWithOtherVolumes) may each have a property of their own: the table then holds one
 * segment per property, each sampled over its volumes' scalar range as a table of its own
 * (Size entries and a copy of its last entry, so that a lookup a rounding error past a
 * segment's end reads that segment), its attenuation divided by its
 * ScalarOpacityUnitDistance so that the frame's unit distance is 1. The scalars are then
 * given in entry coordinates (MeshSource maps each volume's into its segment), and the
 * table's range is [0, size - 1].
 *
 * Rebuilt when, and only when, its key changes: the property objects, their MTimes (which
 * follow their transfer functions') or the scalar ranges.
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
  /// Entries of the table of one property.
  static constexpr int Size = 4096;
  /// Entries a segment of a table of several properties takes: Size and its guard entry.
  static constexpr int SegmentStride = Size + 1;

  /// One property's transfer functions over a scalar range (a constant field, low == high,
  /// gets a range of width 1).
  struct Segment
  {
    vtkVolumeProperty* property = nullptr;
    double low = 0, high = 1;
    bool operator==(const Segment& o) const
    {
      return property == o.property && low == o.low && high == o.high;
    }
  };

  /// Brings the tables up to date with `property` over the scalar range [low, high].
  void Update(vtkVolumeProperty* property, double low, double high);
  /**
   * The same with one segment per property (see above); one segment is the table of
   * Update(property, low, high).
   */
  void Update(const std::vector<Segment>& segments);
  /// Segments of the table: 1 for a table of one property.
  int Segments() const { return static_cast<int>(this->Current.size()); }
  /// The unit distance the table's attenuation is per: the property's
  /// ScalarOpacityUnitDistance for one property, 1 for several (folded into each segment).
  double UnitDistance() const { return this->Unit; }
  /// The entry coordinate of `scalar` in segment `segment` (clamped to the segment; NaN stays
  /// NaN): what the scalars of a table of several segments are given as.
  double EntryOf(int segment, double scalar) const;

  /// The table (valid until the next Update).
  TransferFunctionTable Table() const;
  /// Its integral functions, for pre-integrated shading.
  const PreIntegrationTable& PreIntegration() const { return this->Integrals; }
  /// The integral of opacity times normalized scalar, for average and additive blending.
  const IntensityTable& Intensity() const { return this->IntensityIntegral; }
  /// Changes whenever the table's content changes; 0 before the first Update.
  std::uint64_t Version() const { return this->Built; }

private:
  /// Samples `segment`'s functions into Size entries of Values from `first`, attenuation
  /// times `attenuationScale`.
  void Sample(const Segment& segment, std::size_t first, double attenuationScale);

  std::vector<Segment> Current;    ///< with each range given a width
  std::vector<vtkMTimeType> Times; ///< each segment's property's MTime
  std::vector<float> Values;       ///< 4 floats an entry: r, g, b, attenuation
  int Entries = 0;
  double Low = 0, High = 1, Unit = 1;
  PreIntegrationTable Integrals;
  IntensityTable IntensityIntegral;
  std::uint64_t Built = 0;
};

} // namespace mtpt

#endif
