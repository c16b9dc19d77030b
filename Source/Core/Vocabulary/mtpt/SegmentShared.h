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

// A segment is composited in at most this many scalar steps, one per MTPT_STEP_DEPTH of its
// optical depth: most segments of a fine mesh take one.
#define MTPT_MAX_SEGMENT_STEPS 8
#define MTPT_STEP_DEPTH 0.5

// Below this optical depth d, 1 - e^-d loses its digits to cancellation (GLSL's exp has no
// expm1): its Taylor series takes over.
#define MTPT_SERIES_DEPTH 1e-3
// Below this optical depth, h(d) = 1/d - 1/(e^d - 1) loses its digits to cancellation in
// single precision (1/d and the other term both near 1/d): its Taylor series takes over.
#define MTPT_WEIGHT_SERIES_DEPTH 0.1

// 1 - e^-d for d < MTPT_SERIES_DEPTH, to third order.
MTPT_SHARED_FUNCTION MTPT_SHARED_REAL OpacitySeries(MTPT_SHARED_REAL d)
{
  return d * (1.0 - d * (0.5 - d / 6.0));
}

// h(d) for d < MTPT_WEIGHT_SERIES_DEPTH, where a step's colour is taken between its two ends:
// 1/2 - d/12 + d^3/720, whose next term, d^5/30240, is below 4e-10 there.
MTPT_SHARED_FUNCTION MTPT_SHARED_REAL WeightSeries(MTPT_SHARED_REAL d)
{
  return 0.5 - d * (1.0 / 12.0 - d * d / 720.0);
}

#ifdef __cplusplus
} // namespace mtpt
#endif
#undef MTPT_SHARED_REAL
#undef MTPT_SHARED_FUNCTION

#endif
