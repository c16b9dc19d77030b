// SPDX-License-Identifier: BSD-3-Clause
#include "Plot.h"

#include "vtkAxis.h"
#include "vtkChartLegend.h"
#include "vtkChartXY.h"
#include "vtkContextScene.h"
#include "vtkContextView.h"
#include "vtkDoubleArray.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPlotLine.h"
#include "vtkPlotPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkTable.h"
#include "vtkWindowToImageFilter.h"

#include <algorithm>

namespace mtpt
{
namespace bench
{

bool WritePlot(const std::string& path, const Chart& spec, const std::vector<Series>& series,
  std::string& error)
{
  static const unsigned char colours[][3] = { { 31, 119, 180 }, { 214, 39, 40 }, { 44, 160, 44 },
    { 255, 127, 14 }, { 148, 103, 189 }, { 23, 190, 207 }, { 140, 86, 75 }, { 227, 119, 194 },
    { 127, 127, 127 }, { 188, 189, 34 }, { 0, 0, 0 }, { 174, 199, 232 } };
  static const int markers[] = { vtkPlotPoints::CIRCLE, vtkPlotPoints::SQUARE,
    vtkPlotPoints::DIAMOND, vtkPlotPoints::CROSS, vtkPlotPoints::PLUS };
  double lowX = 1e300, highX = -1e300, lowY = 1e300, highY = -1e300;
  for (const Series& s : series)
  {
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
    {
      if ((spec.logX && !(s.x[i] > 0)) || (spec.logY && !(s.y[i] > 0)))
      {
        continue; // not on a logarithmic axis
      }
      lowX = std::min(lowX, s.x[i]);
      highX = std::max(highX, s.x[i]);
      lowY = std::min(lowY, s.y[i]);
      highY = std::max(highY, s.y[i]);
    }
  }
  if (!(highX >= lowX))
  {
    error = "no point to plot";
    return false;
  }
  vtkNew<vtkContextView> view;
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(spec.width, spec.height);
  view->GetRenderer()->SetBackground(1, 1, 1);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetShowLegend(true);
  chart->GetLegend()->SetHorizontalAlignment(
    spec.legendRight ? vtkChartLegend::RIGHT : vtkChartLegend::LEFT);
  chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  chart->SetTitle(spec.title);
  vtkAxis* x = chart->GetAxis(vtkAxis::BOTTOM);
  vtkAxis* y = chart->GetAxis(vtkAxis::LEFT);
  x->SetTitle(spec.xTitle);
  y->SetTitle(spec.yTitle);
  x->SetLogScale(spec.logX);
  y->SetLogScale(spec.logY);
  const double padX = spec.logX ? 1.3 : 1.0, padY = spec.logY ? 1.3 : 1.0;
  x->SetUnscaledRange(lowX / padX, highX * padX);
  y->SetUnscaledRange(lowY / padY, highY * spec.headroom);
  x->SetBehavior(vtkAxis::FIXED);
  y->SetBehavior(vtkAxis::FIXED);
  std::vector<vtkSmartPointer<vtkTable>> tables;
  for (std::size_t k = 0; k < series.size(); ++k)
  {
    const Series& s = series[k];
    auto table = vtkSmartPointer<vtkTable>::New();
    vtkNew<vtkDoubleArray> xs, ys;
    xs->SetName("x");
    ys->SetName(s.label.c_str());
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
    {
      if ((!spec.logX || s.x[i] > 0) && (!spec.logY || s.y[i] > 0))
      {
        xs->InsertNextValue(s.x[i]);
        ys->InsertNextValue(s.y[i]);
      }
    }
    if (xs->GetNumberOfTuples() == 0)
    {
      continue;
    }
    table->AddColumn(xs);
    table->AddColumn(ys);
    tables.push_back(table);
    auto* plot =
      vtkPlotPoints::SafeDownCast(chart->AddPlot(spec.lines ? vtkChart::LINE : vtkChart::POINTS));
    plot->SetInputData(table, 0, 1);
    const unsigned char* c = colours[k % 12];
    plot->SetColor(c[0], c[1], c[2], 255);
    plot->SetMarkerStyle(markers[k % 5]);
    plot->SetMarkerSize(spec.lines ? 9 : 14);
    plot->SetWidth(2.0);
    plot->SetLabel(s.label);
  }
  view->GetRenderWindow()->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(view->GetRenderWindow());
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0)
  {
    error = "cannot write " + path;
    return false;
  }
  return true;
}

} // namespace bench
} // namespace mtpt
