// SPDX-License-Identifier: BSD-3-Clause
// The fragment loop's floor, for measurements (mtpt_bench_compositor --floor;
// Documentation/compositor.md, "The floor, per instruction set"): the compositor's fan path
// fragment loop, rung by rung, over one tile, with the instruction set the compositor runs.
#ifndef mtpt_bench_FragmentFloor_h
#define mtpt_bench_FragmentFloor_h

#include <cstddef>

namespace mtpt
{
namespace bench
{

/// The rungs of FragmentFloor: registers, memory, planes, lane lookups, coverage.
constexpr int FragmentFloorRungs = 5;

/**
 * `vectors` vectors of fragments, every lane a fragment, through rung `rung` of the fragment
 * loop's floor (FragmentFloor.cxx), over a tile (4 * TileSize^2 floats: R, G, B, A planes,
 * and TileSize^2 of opaque depth). Returns a sum of the results. Nothing on one lane (the
 * scalar target has no fan path).
 */
float FragmentFloor(int rung, std::size_t vectors, float* rgba, const float* depth);

/// The lanes of the fragment loops' vectors with the instruction set the compositor runs.
std::size_t FragmentLanes();

} // namespace bench
} // namespace mtpt

#endif
