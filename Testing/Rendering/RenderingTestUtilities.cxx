// SPDX-License-Identifier: BSD-3-Clause
#include "RenderingTestUtilities.h"

#include "vtkCamera.h"
#include "vtkCellArray.h"
#include "vtkColorTransferFunction.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkMath.h"
#include "vtkPNGReader.h"
#include "vtkPNGWriter.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkCellData.h"
#include "vtkPoints.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridVolumeMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"
#include "vtkXMLUnstructuredGridReader.h"

#include "vtkIdList.h"
#include "vtkMTPTReferenceRenderer.h"
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"
#include "vtkPolyDataMapper.h"
#include "vtkCubeSource.h"
#include "vtkActor.h"
#include "vtkProjectedTetrahedraMapper.h"

#include <gtest/gtest.h>
#include <vtksys/SystemTools.hxx>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>

#ifndef MTPT_SOURCE_DIR
#error "MTPT_SOURCE_DIR must be defined"
#endif

namespace mtpt
{
namespace rendering_test
{

namespace
{
/**
 * VTK's PT picks its depth sort's pivots with vtkMath::Random (vtkCellCenterDepthSort): where
 * cells lie at equal depths, its image depends on where the process's random sequence stands,
 * that is on the tests that ran before (run after others, the fly-through's count of the
 * pixels VTK's PT leaves empty went from 1548 to 0). Every test of these programs starts the
 * sequence from one seed, and the seed in place before is put back after it.
 */
class FixedRandomSequence : public ::testing::EmptyTestEventListener
{
  void OnTestStart(const ::testing::TestInfo&) override
  {
    this->Saved = vtkMath::GetSeed();
    vtkMath::RandomSeed(Seed);
  }
  void OnTestEnd(const ::testing::TestInfo&) override { vtkMath::RandomSeed(this->Saved); }

  static constexpr int Seed = 7;
  int Saved = 0;
};

const bool FixedRandomSequenceRegistered = []
{
  ::testing::UnitTest::GetInstance()->listeners().Append(new FixedRandomSequence);
  return true;
}();
} // namespace

const double Background[3] = { 0.1, 0.1, 0.2 };

const View Views[3] = { { 30, 20 }, { 200, -35 }, { 115, 65 } };

vtkSmartPointer<vtkUnstructuredGrid> MakeTetrahedralBox(int n)
{
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> points;
  vtkNew<vtkFloatArray> field;
  field->SetName("field");
  auto id = [n](int i, int j, int k)
  { return static_cast<vtkIdType>((k * (n + 1) + j) * (n + 1) + i); };
  auto value = [](double x, double y, double z) {
    return std::exp(-2.0 * (x * x + y * y + z * z)) + 0.3 * std::sin(3.0 * x) * std::cos(2.0 * y);
  };
  const double h = 2.0 / n;
  for (int k = 0; k <= n; ++k)
  {
    for (int j = 0; j <= n; ++j)
    {
      for (int i = 0; i <= n; ++i)
      {
        const double x = -1 + h * i, y = -1 + h * j, z = -1 + h * k;
        points->InsertNextPoint(x, y, z);
        field->InsertNextValue(static_cast<float>(value(x, y, z)));
      }
    }
  }
  grid->SetPoints(points);
  grid->GetPointData()->SetScalars(field);
  vtkNew<vtkFloatArray> cellField;
  cellField->SetName("cellField");
  // 5-tetrahedron split with alternating orientation so faces match between cubes.
  static const int even[5][4] = { { 0, 1, 3, 4 }, { 1, 2, 3, 6 }, { 1, 4, 5, 6 }, { 3, 4, 6, 7 },
    { 1, 3, 4, 6 } };
  static const int odd[5][4] = { { 0, 1, 2, 5 }, { 0, 2, 3, 7 }, { 0, 4, 5, 7 }, { 2, 5, 6, 7 },
    { 0, 2, 5, 7 } };
  for (int k = 0; k < n; ++k)
  {
    for (int j = 0; j < n; ++j)
    {
      for (int i = 0; i < n; ++i)
      {
        const vtkIdType corner[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k),
          id(i, j + 1, k), id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
          id(i, j + 1, k + 1) };
        const auto& split = ((i + j + k) % 2 == 0) ? even : odd;
        for (const auto& tet : split)
        {
          const vtkIdType ids[4] = { corner[tet[0]], corner[tet[1]], corner[tet[2]],
            corner[tet[3]] };
          grid->InsertNextCell(VTK_TETRA, 4, ids);
          double c[3] = { 0, 0, 0 };
          for (vtkIdType p : ids)
          {
            double q[3];
            points->GetPoint(p, q);
            c[0] += q[0] / 4;
            c[1] += q[1] / 4;
            c[2] += q[2] / 4;
          }
          cellField->InsertNextValue(static_cast<float>(value(c[0], c[1], c[2])));
        }
      }
    }
  }
  grid->GetCellData()->AddArray(cellField);
  return grid;
}

vtkSmartPointer<vtkUnstructuredGrid> LoadBluntFin()
{
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(MTPT_SOURCE_DIR "/Data/bluntfin_tets.vtu");
  reader->Update();
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(reader->GetOutput());
  grid->GetPointData()->SetActiveScalars("Density");
  return grid;
}

vtkSmartPointer<vtkVolumeProperty> MakeProperty(double low, double high, double unitDistance)
{
  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(low, 0.2, 0.3, 0.9);
  color->AddRGBPoint(0.5 * (low + high), 0.95, 0.95, 0.6);
  color->AddRGBPoint(high, 0.9, 0.2, 0.1);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(low, 0.05);
  opacity->AddPoint(high, 0.9);
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(unitDistance);
  return property;
}

vtkSmartPointer<vtkVolumeProperty> MakeBluntFinProperty()
{
  return MakeProperty(0.19, 4.98, 1.5);
}

Stage MakeStage(vtkDataObject* input, vtkVolumeProperty* property,
  vtkUnstructuredGridVolumeMapper* mapper, int width, int height, WindowSettings settings)
{
  Stage stage;
  mapper->SetInputDataObject(input);
  stage.volume = vtkSmartPointer<vtkVolume>::New();
  stage.volume->SetMapper(mapper);
  stage.volume->SetProperty(property);
  stage.renderer = vtkSmartPointer<vtkRenderer>::New();
  stage.renderer->SetBackground(Background[0], Background[1], Background[2]);
  stage.renderer->AddVolume(stage.volume);
  stage.window = vtkSmartPointer<vtkRenderWindow>::New();
  stage.window->SetOffScreenRendering(settings.offScreen ? 1 : 0);
  if (settings.multiSamples >= 0)
  {
    stage.window->SetMultiSamples(settings.multiSamples);
  }
  stage.window->SetSize(width, height);
  stage.window->AddRenderer(stage.renderer);
  return stage;
}

void SetView(vtkRenderer* renderer, const View& view, bool perspective)
{
  renderer->ResetCamera();
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetParallelProjection(perspective ? 0 : 1);
  camera->Azimuth(view.azimuth);
  camera->Elevation(view.elevation);
  camera->OrthogonalizeViewUp();
  renderer->ResetCameraClippingRange();
}

vtkSmartPointer<vtkUnstructuredGrid> ShuffleCells(vtkUnstructuredGrid* grid, unsigned seed)
{
  const vtkIdType cells = grid->GetNumberOfCells();
  std::vector<vtkIdType> order(static_cast<std::size_t>(cells));
  std::iota(order.begin(), order.end(), vtkIdType(0));
  std::mt19937 random(seed);
  std::shuffle(order.begin(), order.end(), random);
  auto shuffled = vtkSmartPointer<vtkUnstructuredGrid>::New();
  shuffled->SetPoints(grid->GetPoints());
  shuffled->GetPointData()->PassData(grid->GetPointData());
  shuffled->GetCellData()->CopyAllocate(grid->GetCellData(), cells);
  shuffled->Allocate(cells);
  vtkNew<vtkIdList> ids;
  for (const vtkIdType c : order)
  {
    grid->GetCellPoints(c, ids);
    const vtkIdType id = shuffled->InsertNextCell(grid->GetCellType(c), ids);
    shuffled->GetCellData()->CopyData(grid->GetCellData(), c, id);
  }
  return shuffled;
}

Stage RenderStage(const Scene& scene, vtkUnstructuredGridVolumeMapper* mapper, int frames)
{
  Stage stage = MakeStage(scene.grid, scene.property, mapper, scene.size, scene.size, scene.window);
  if (scene.customize)
  {
    scene.customize(stage.volume, stage.renderer);
  }
  SetView(stage.renderer, { scene.azimuth, scene.elevation }, scene.perspective);
  for (int f = 0; f < frames; ++f)
  {
    stage.window->Render();
  }
  return stage;
}

vtkSmartPointer<vtkVolumeProperty> MakeNarrowPeakProperty(double unitDistance)
{
  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(0.0, 0.9, 0.5, 0.1);
  color->AddRGBPoint(1.0, 0.2, 0.4, 0.95);
  vtkNew<vtkPiecewiseFunction> opacity;
  opacity->AddPoint(0.0, 0.0);
  opacity->AddPoint(0.49, 0.0);
  opacity->AddPoint(0.5, 20.0);
  opacity->AddPoint(0.51, 0.0);
  opacity->AddPoint(1.0, 0.0);
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(unitDistance);
  return property;
}

vtkSmartPointer<vtkImageData> Render(
  const Scene& scene, vtkUnstructuredGridVolumeMapper* mapper, int frames)
{
  Stage stage = RenderStage(scene, mapper, frames);
  auto image = Grab(stage.window);
  // The mapper may outlive this window: free its GL resources while the context exists.
  mapper->ReleaseGraphicsResources(stage.window);
  return image;
}

vtkSmartPointer<vtkImageData> ReferenceImage(const Stage& stage, vtkUnstructuredGridBase* input)
{
  vtkNew<vtkMTPTReferenceRenderer> reference;
  if (auto* mapper = vtkMultiThreadedProjectedTetrahedraMapper::SafeDownCast(
        stage.volume->GetMapper()))
  {
    reference->SetAverageIPScalarRange(mapper->GetAverageIPScalarRange());
  }
  if (!reference->Render(stage.renderer, stage.volume, input))
  {
    ADD_FAILURE() << "no reference image";
    return nullptr;
  }
  return ImageOf(reference);
}

vtkSmartPointer<vtkImageData> VolumesReferenceImage(vtkRenderer* renderer)
{
  vtkNew<vtkMTPTReferenceRenderer> reference;
  if (!reference->RenderVolumes(renderer, renderer->GetVolumes()))
  {
    ADD_FAILURE() << "no reference image of the volumes";
    return nullptr;
  }
  return ImageOf(reference);
}

vtkSmartPointer<vtkImageData> ImageOf(vtkMTPTReferenceRenderer* reference)
{
  const int* size = reference->GetSize();
  vtkDoubleArray* rgb = reference->GetImage();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(size[0], size[1], 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* pixels = static_cast<unsigned char*>(image->GetScalarPointer());
  for (vtkIdType i = 0; i < 3 * static_cast<vtkIdType>(size[0]) * size[1]; ++i)
  {
    pixels[i] =
      static_cast<unsigned char>(std::lround(std::clamp(rgb->GetValue(i), 0.0, 1.0) * 255));
  }
  return image;
}

vtkSmartPointer<vtkImageData> Grab(vtkRenderWindow* window, bool rerender)
{
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetShouldRerender(rerender);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->DeepCopy(grab->GetOutput());
  return image;
}

namespace
{
/// Whether pixel `p` of `values` (`components` per pixel) differs from the background.
bool IsCovered(
  vtkUnsignedCharArray* values, int components, vtkIdType p, const double background[3])
{
  for (int c = 0; c < 3; ++c)
  {
    if (std::fabs(values->GetValue(p * components + c) - 255.0 * background[c]) > 2.0)
    {
      return true;
    }
  }
  return false;
}
} // namespace

ImageDifference Compare(vtkImageData* a, vtkImageData* b, const double* background)
{
  background = background ? background : Background;
  ImageDifference d;
  auto* pa = vtkUnsignedCharArray::SafeDownCast(a->GetPointData()->GetScalars());
  auto* pb = vtkUnsignedCharArray::SafeDownCast(b->GetPointData()->GetScalars());
  if (!pa || !pb || pa->GetNumberOfValues() != pb->GetNumberOfValues() ||
    pa->GetNumberOfComponents() != pb->GetNumberOfComponents())
  {
    d.rmse = d.coveredRmse = d.worst = d.fractionOver = 1;
    return d;
  }
  const int components = pa->GetNumberOfComponents();
  const vtkIdType pixels = pa->GetNumberOfTuples();
  double sum = 0, coveredSum = 0;
  vtkIdType over = 0, covered = 0;
  for (vtkIdType p = 0; p < pixels; ++p)
  {
    double pixelWorst = 0, pixelSum = 0;
    for (int c = 0; c < 3 && c < components; ++c)
    {
      const double diff =
        std::fabs(pa->GetValue(p * components + c) - pb->GetValue(p * components + c)) / 255.0;
      pixelSum += diff * diff;
      pixelWorst = std::max(pixelWorst, diff);
    }
    sum += pixelSum;
    d.worst = std::max(d.worst, pixelWorst);
    if (IsCovered(pa, components, p, background) || IsCovered(pb, components, p, background))
    {
      ++covered;
      coveredSum += pixelSum;
      over += pixelWorst > 0.1 ? 1 : 0;
    }
  }
  d.rmse = std::sqrt(sum / (3.0 * static_cast<double>(pixels)));
  d.coveredRmse = covered ? std::sqrt(coveredSum / (3.0 * static_cast<double>(covered))) : 0.0;
  d.fractionOver = covered ? static_cast<double>(over) / static_cast<double>(covered) : 0.0;
  d.covered = static_cast<double>(covered) / static_cast<double>(pixels);
  return d;
}

void ExpectClose(vtkImageData* ours, vtkImageData* theirs, const Limits& limits,
  const std::string& label, double minCovered, const double* background)
{
  background = background ? background : Background;
  const ImageDifference d = Compare(ours, theirs, background);
  const double coverage = CoveredFraction(ours, background);
  std::printf("%s: RMSE over covered pixels %.5f (all pixels %.5f), worst %.3f, covered "
              "pixels over 0.1: %.3f%%, covered %.1f%%\n",
    label.c_str(), d.coveredRmse, d.rmse, d.worst, 100 * d.fractionOver, 100 * coverage);
  ::testing::Test::RecordProperty(label + "_rmse", std::to_string(d.coveredRmse));
  EXPECT_LE(d.coveredRmse, limits.coveredRmse) << label;
  EXPECT_LE(d.worst, limits.worst) << label;
  EXPECT_LE(d.fractionOver, limits.fractionOver) << label;
  EXPECT_GE(coverage, minCovered) << label << ": not a blank frame";
}

double CoveredFraction(vtkImageData* image, const double background[3])
{
  auto* p = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetScalars());
  const int components = p->GetNumberOfComponents();
  vtkIdType covered = 0;
  for (vtkIdType i = 0; i < p->GetNumberOfTuples(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      if (std::fabs(p->GetValue(i * components + c) - 255.0 * background[c]) > 2.0)
      {
        ++covered;
        break;
      }
    }
  }
  return static_cast<double>(covered) / static_cast<double>(p->GetNumberOfTuples());
}

void Save(vtkImageData* image, const std::string& name)
{
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName((name + ".png").c_str());
  writer->SetInputData(image);
  writer->Write();
}

ImageDifference CompareWithBaseline(vtkImageData* image, const std::string& name)
{
  const std::string path = std::string(MTPT_SOURCE_DIR) + "/Testing/Data/Baseline/" + name + ".png";
  const char* update = std::getenv("MTPT_UPDATE_BASELINES");
  if (update && std::string(update) == "1")
  {
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(path.c_str());
    writer->SetInputData(image);
    writer->Write();
    return {};
  }
  if (!vtksys::SystemTools::FileExists(path))
  {
    ImageDifference missing;
    missing.rmse = missing.worst = missing.fractionOver = 1;
    return missing;
  }
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  return Compare(image, reader->GetOutput());
}

void MessageObserver::Execute(vtkObject*, unsigned long event, void* data)
{
  const std::string text = data ? static_cast<const char*>(data) : "";
  if (event == vtkCommand::ErrorEvent)
  {
    this->errors.push_back(text);
  }
  else if (event == vtkCommand::WarningEvent)
  {
    this->warnings.push_back(text);
  }
}

vtkSmartPointer<vtkMultiThreadedProjectedTetrahedraMapper> MakeMapper(int backend)
{
  auto mapper = vtkSmartPointer<vtkMultiThreadedProjectedTetrahedraMapper>::New();
  mapper->SetBackend(backend);
  return mapper;
}

const char* ShortBackendName(int backend)
{
  return backend == vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND ? "cpu" : "gl";
}

vtkSmartPointer<vtkImageData> FreshMapperImage(const Stage& stage,
  vtkMultiThreadedProjectedTetrahedraMapper* under,
  const std::function<void(vtkMultiThreadedProjectedTetrahedraMapper*)>& setUp)
{
  vtkNew<vtkMultiThreadedProjectedTetrahedraMapper> fresh;
  fresh->SetInputData(under->GetInput());
  setUp(fresh);
  stage.volume->SetMapper(fresh);
  stage.window->Render();
  auto image = Grab(stage.window, false);
  fresh->ReleaseGraphicsResources(stage.window);
  stage.volume->SetMapper(under);
  return image;
}

const char* BackendName(int backend)
{
  using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;
  return backend == Mapper::CPU_BACKEND
    ? "CPU"
    : (backend == Mapper::OPENGL_BACKEND ? "OpenGL" : "automatic");
}

const int Backends[2] = { vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND,
  vtkMultiThreadedProjectedTetrahedraMapper::OPENGL_BACKEND };

void ExpectCloseToVTK(
  const Scene& scene, const std::string& name, const Limits& limits, TheirWindow window)
{
  for (std::size_t v = 0; v < std::size(Views); ++v)
  {
    const Scene ours = scene.From(Views[v]);
    Scene theirs = ours;
    if (window == TheirWindow::SingleSampled)
    {
      theirs.window.multiSamples = 0;
    }
    vtkNew<vtkProjectedTetrahedraMapper> vtkpt;
    auto reference = Render(theirs, vtkpt);
    const std::string view = name + "-view" + std::to_string(v);
    Save(reference, view + "-vtkpt");
    for (int backend : { vtkMultiThreadedProjectedTetrahedraMapper::OPENGL_BACKEND,
           vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND })
    {
      const std::string label = view + "-" + ShortBackendName(backend);
      auto mapper = MakeMapper(backend);
      auto image = Render(ours, mapper);
      EXPECT_EQ(mapper->GetLastBackend(), backend);
      Save(image, label);
      ExpectClose(image, reference, limits, label + " vs VTK PT", 0.1);
    }
  }
}

void ExpectCloseToReference(
  const Scene& scene, const std::string& name, const Limits& limits, int shading)
{
  for (std::size_t v = 0; v < std::size(Views); ++v)
  {
    const std::string view = name + "-view" + std::to_string(v);
    vtkSmartPointer<vtkImageData> reference;
    for (int backend : { vtkMultiThreadedProjectedTetrahedraMapper::OPENGL_BACKEND,
           vtkMultiThreadedProjectedTetrahedraMapper::CPU_BACKEND })
    {
      auto mapper = MakeMapper(backend);
      mapper->SetShadingMode(shading);
      const Stage stage = RenderStage(scene.From(Views[v]), mapper);
      if (!reference)
      {
        reference = ReferenceImage(stage);
        ASSERT_TRUE(reference);
        Save(reference, view + "-reference");
      }
      const std::string label = view + "-" + ShortBackendName(backend) +
        (shading == vtkMultiThreadedProjectedTetrahedraMapper::PRE_INTEGRATED_SHADING
            ? "-preintegrated"
            : "");
      auto image = Grab(stage.window, false);
      mapper->ReleaseGraphicsResources(stage.window);
      Save(image, label);
      ExpectClose(image, reference, limits, label + " vs reference", 0.1);
    }
  }
}

void AddOpaqueCube(vtkRenderer* renderer, double h)
{
  vtkNew<vtkCubeSource> cube;
  cube->SetBounds(-h, h, -h, h, -h, h);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputConnection(cube->GetOutputPort());
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  renderer->AddActor(actor);
}

vtkSmartPointer<vtkUnstructuredGrid> ShuffledBoxTest::Box;

void ShuffledBoxTest::SetUpTestSuite()
{
  Box = ShuffleCells(MakeTetrahedralBox(10), 5);
}

void ShuffledBoxTest::TearDownTestSuite()
{
  Box = nullptr;
}

} // namespace rendering_test
} // namespace mtpt
