// SPDX-License-Identifier: BSD-3-Clause
// The numbers of a pre-integrated segment, defined once for the CPU and the GPU: C++ includes
// this file as a header, and the OpenGL backend inserts it into its fragment shader, so it
// is valid C++ and valid GLSL (only the preprocessor tells the two apart). The formulas
// that use them are in mtpt::PreIntegrationTable::Segment (TransferFunctionTable.cxx), the
// CPU compositor's vector form of it (TileRaster.cxx) and vtkMTPTTetrahedraFS.glsl.
#ifndef mtpt_SegmentShared_h
#define mtpt_SegmentShared_h

#ifdef __cplusplus
#define MTPT_SHARED_REAL double
#define MTPT_SHARED_FUNCTION inline
namespace mtpt
{
#else
#define MTPT_SHARED_REAL float
#define MTPT_SHARED_FUNCTION
#endif

// A segment is composited in at most this many scalar steps: one per MTPT_STEP_ENTRIES
// transfer-function entries crossed or per unit of optical depth, whichever asks for more.
#define MTPT_MAX_SEGMENT_STEPS 8
#define MTPT_STEP_ENTRIES 32.0

// Below this optical depth d, 1 - e^-d and h(d) = 1/d - 1/(e^d - 1) lose their digits to
// cancellation; their Taylor series take over.
#define MTPT_SERIES_DEPTH 1e-3
// h(d) = 1/2 - d/12 + O(d^3): the divisor of its linear term.
#define MTPT_WEIGHT_SERIES_DIVISOR 12.0

// 1 - e^-d for d < MTPT_SERIES_DEPTH, to third order (GLSL's exp has no expm1).
MTPT_SHARED_FUNCTION MTPT_SHARED_REAL OpacitySeries(MTPT_SHARED_REAL d)
{
  return d * (1.0 - d * (0.5 - d / 6.0));
}

// h(d) for d < MTPT_SERIES_DEPTH: where a step's colour is taken between its two ends.
MTPT_SHARED_FUNCTION MTPT_SHARED_REAL WeightSeries(MTPT_SHARED_REAL d)
{
  return 0.5 - d / MTPT_WEIGHT_SERIES_DIVISOR;
}

#ifdef __cplusplus
} // namespace mtpt
#endif
#undef MTPT_SHARED_REAL
#undef MTPT_SHARED_FUNCTION

#endif
