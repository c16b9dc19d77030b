// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Plot.h
 * @brief Charts of benchmark figures as PNG files, drawn with VTK's own charts (off-screen),
 * shared by the benchmark programs.
 */
#ifndef mtpt_bench_Plot_h
#define mtpt_bench_Plot_h

#include <string>
#include <vector>

namespace mtpt
{
namespace bench
{

/// One labelled series of (x, y) points.
struct Series
{
  std::string label;
  std::vector<double> x, y;
};

/// What a chart shows.
struct Chart
{
  std::string title, xTitle, yTitle;
  bool logX = true, logY = true;
  bool lines = true;      ///< points joined by lines (false: points only)
  double headroom = 1.5;  ///< the y range reaches this factor above the largest value
  bool legendRight = false; ///< the legend in the top right corner (default: top left)
  int width = 900, height = 600;
};

/// Draws the series on one chart and writes it to `path` (PNG); false with `error` set
/// when nothing could be drawn or written.
bool WritePlot(const std::string& path, const Chart& chart, const std::vector<Series>& series,
  std::string& error);

} // namespace bench
} // namespace mtpt

#endif
