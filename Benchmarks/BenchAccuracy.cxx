// SPDX-License-Identifier: BSD-3-Clause
// mtpt_bench_accuracy: speed against error (Documentation/accuracy.md). For real meshes and a
// generated grid, each with a smooth transfer function and one of narrow opacity peaks
// (narrower than the spacing of the vertex scalars), in orthographic and perspective views,
// it renders every contender -- MTPT in each shading mode (CPU backend at 1 and 2 threads,
// OpenGL at 2), VTK's projected tetrahedra, its unstructured ray caster with each of its four
// ray integrators, and its Z-sweep mapper -- and measures the median frame time and the
// image's error against the exact reference (vtkMTPTReferenceRenderer): RMSE and PSNR over
// linear RGB in [0, 1] and the worst pixel. Timing and windows follow the benchmark
// harness (Harness.h): the camera turns before every timed frame; the image compared is
// drawn at the start view afterwards; every contender runs in VTK's default window
// (multisampled) and single-sampled (--multisampling), and the targets take each mapper
// in its faster window. Every contender and the reference run in their
// own forked child process, so a crash (VTK's ray caster crashes on some inputs) is reported
// as such. Writes accuracy.md, accuracy.csv and accuracy.png (time against RMSE, log-log,
// geometric means over the scenes) to --out; --from-csv re-plots a previous run. Run under a
// display (Testing/xvfb-launch.sh on machines without one).
#include "Harness.h"
#include "Plot.h"

#include "vtkMTPTReferenceRenderer.h"
#include "vtkMultiThreadedProjectedTetrahedraMapper.h"

#include "mtpt/Timing.h"

#include "vtkAxis.h"
#include "vtkCamera.h"
#include "vtkChartLegend.h"
#include "vtkChartXY.h"
#include "vtkColorTransferFunction.h"
#include "vtkContextScene.h"
#include "vtkContextView.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPlotPoints.h"
#include "vtkPointData.h"
#include "vtkProjectedTetrahedraMapper.h"
#include "vtkRenderer.h"
#include "vtkTable.h"
#include "vtkUnstructuredGrid.h"
#include "vtkUnstructuredGridHomogeneousRayIntegrator.h"
#include "vtkUnstructuredGridLinearRayIntegrator.h"
#include "vtkUnstructuredGridPartialPreIntegration.h"
#include "vtkUnstructuredGridPreIntegration.h"
#include "vtkUnstructuredGridVolumeRayCastMapper.h"
#include "vtkUnstructuredGridVolumeZSweepMapper.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"

#include <CLI/CLI.hpp>

#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace
{
using namespace mtpt::bench;
using Mapper = vtkMultiThreadedProjectedTetrahedraMapper;

struct Options
{
  int size = 256;
  CommonOptions common; ///< repeat, step, slow limit, data folder
  std::string out = "accuracy";
  std::string fromCsv;
  std::string meshes = "grid,pulley,bluntfin,comb";
  long long gridTets = 200000;
  bool images = false;               ///< also save every image as PNG under out/images
  std::string contenders;            ///< only the contenders whose names contain one of these
  std::string loadBefore, loadAfter; ///< /proc/loadavg at the start and the end of the run
  std::string renderer = "unknown";  ///< the OpenGL renderer string
};

/// The contenders, in table order.
struct Contender
{
  std::string name;
  std::string family; ///< plot series
};

const std::vector<Contender>& Contenders()
{
  static const std::vector<Contender> list = {
    { "MTPT VTK-compatible CPU 1t", "MTPT VTK-compatible" },
    { "MTPT VTK-compatible CPU 2t", "MTPT VTK-compatible" },
    { "MTPT VTK-compatible GL 2t", "MTPT VTK-compatible" },
    { "MTPT pre-integrated CPU 1t", "MTPT pre-integrated" },
    { "MTPT pre-integrated CPU 2t", "MTPT pre-integrated" },
    { "MTPT pre-integrated GL 2t", "MTPT pre-integrated" },
    { "VTK PT", "VTK PT" },
    { "VTK ray cast homogeneous", "VTK ray cast" },
    { "VTK ray cast linear", "VTK ray cast" },
    { "VTK ray cast partial pre-integration", "VTK ray cast" },
    { "VTK ray cast pre-integration", "VTK ray cast" },
    { "VTK Z-sweep", "VTK Z-sweep" },
  };
  return list;
}

vtkSmartPointer<vtkUnstructuredGridVolumeMapper> MakeContender(const std::string& name)
{
  if (name.rfind("MTPT", 0) == 0)
  {
    MapperSettings settings;
    settings.shading = name.find("pre-integrated") != std::string::npos ? "pre-integrated" : "vtk";
    settings.threads = name.find(" 1t") != std::string::npos ? 1 : 2;
    return MakeMapper(name.find(" GL ") != std::string::npos ? "mtpt-gl" : "mtpt-cpu", settings);
  }
  if (name == "VTK PT")
  {
    return MakeMapper("vtk-pt");
  }
  if (name.rfind("VTK ray cast", 0) == 0)
  {
    auto mapper = MakeMapper("raycast");
    auto* m = vtkUnstructuredGridVolumeRayCastMapper::SafeDownCast(mapper);
    if (name.find("homogeneous") != std::string::npos)
    {
      m->SetRayIntegrator(vtkSmartPointer<vtkUnstructuredGridHomogeneousRayIntegrator>::New());
    }
    else if (name.find("partial") != std::string::npos)
    {
      m->SetRayIntegrator(vtkSmartPointer<vtkUnstructuredGridPartialPreIntegration>::New());
    }
    else if (name.find("pre-integration") != std::string::npos)
    {
      m->SetRayIntegrator(vtkSmartPointer<vtkUnstructuredGridPreIntegration>::New());
    }
    else
    {
      m->SetRayIntegrator(vtkSmartPointer<vtkUnstructuredGridLinearRayIntegrator>::New());
    }
    return mapper;
  }
  return MakeMapper("zsweep");
}

/// The suffix of a contender timed in a single-sampled window (multisampling off); without
/// it, in VTK's default window (multisampled).
const std::string Single = " single-sampled";

bool EndsWithSingle(const std::string& name)
{
  return name.size() > Single.size() &&
    name.compare(name.size() - Single.size(), Single.size(), Single) == 0;
}

/// The name of contender `c` in a window of this kind (its row's name).
std::string InWindow(const Contender& c, bool multisampling)
{
  return multisampling ? c.name : c.name + Single;
}

/// One scene: a mesh, a transfer function, a view.
struct AccuracyScene
{
  const Scene* mesh = nullptr;
  std::string tf;   ///< "smooth" or "narrow"
  bool perspective; ///< else orthographic
  std::string Name() const
  {
    return mesh->name + "-" + tf + "-" + (perspective ? "persp" : "ortho");
  }
};

vtkSmartPointer<vtkVolumeProperty> MakeAccuracyProperty(const AccuracyScene& scene)
{
  const double* range = scene.mesh->range;
  const double low = range[0], high = range[1], span = high - low;
  vtkNew<vtkColorTransferFunction> color;
  color->AddRGBPoint(low, 0.23, 0.30, 0.75);
  color->AddRGBPoint(low + 0.5 * span, 0.87, 0.87, 0.87);
  color->AddRGBPoint(high, 0.71, 0.02, 0.15);
  vtkNew<vtkPiecewiseFunction> opacity;
  const double diagonal = scene.mesh->grid->GetLength();
  if (scene.tf == "smooth")
  {
    opacity->AddPoint(low, 0.0);
    opacity->AddPoint(high, 1.0);
  }
  else
  {
    // Three peaks of half-width 0.2% of the range: far narrower than the scalar step
    // between neighbouring vertices of any of the meshes.
    opacity->AddPoint(low, 0.0);
    for (double centre : { 0.25, 0.5, 0.75 })
    {
      const double c = low + centre * span, w = 0.002 * span;
      opacity->AddPoint(c - w, 0.0);
      opacity->AddPoint(c, 40.0);
      opacity->AddPoint(c + w, 0.0);
    }
    opacity->AddPoint(high, 0.0);
  }
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(diagonal / 50);
  return property;
}

bool WriteImage(const std::string& path, vtkDoubleArray* rgb)
{
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(rgb->GetPointer(0)),
    static_cast<std::streamsize>(sizeof(double) * rgb->GetNumberOfValues()));
  return static_cast<bool>(out);
}

std::vector<double> ReadImage(const std::string& path)
{
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  std::vector<double> v;
  if (!in)
  {
    return v;
  }
  const std::streamsize bytes = in.tellg();
  in.seekg(0);
  v.resize(static_cast<std::size_t>(bytes) / sizeof(double));
  in.read(reinterpret_cast<char*>(v.data()), bytes);
  return v;
}

/// Child process body: renders (or integrates, for "reference") and writes
/// `<base>.bin` (the image) and `<base>.txt` ("ok|slow milliseconds").
int RunChild(const AccuracyScene& scene, const std::string& contender, const Options& o,
  const std::string& base)
{
  const bool reference = contender == "reference";
  const bool single = EndsWithSingle(contender);
  auto mapper = MakeContender(
    reference ? "VTK PT" : contender.substr(0, contender.size() - (single ? Single.size() : 0)));
  auto property = MakeAccuracyProperty(scene);
  StageOptions look;
  look.view.parallel = !scene.perspective;
  look.multisampling = !single;
  Stage stage(*scene.mesh, property, mapper, o.size, o.size, look);
  vtkNew<vtkDoubleArray> rgb;
  double ms = 0;
  bool slow = false;
  if (reference)
  {
    vtkNew<vtkMTPTReferenceRenderer> integrator;
    const auto start = mtpt::Clock::now();
    if (!integrator->Render(stage.GetRenderer(), stage.GetVolume()))
    {
      return 3;
    }
    ms = 1e3 * mtpt::SecondsSince(start);
    rgb->DeepCopy(integrator->GetImage());
  }
  else
  {
    const FrameTiming timing = TimeFrames(stage, o.common.timing);
    ms = timing.median;
    slow = timing.slow;
    // The image compared: the start view, as the reference sees it.
    stage.StartView();
    stage.Frame();
    if (!vtkMTPTReferenceRenderer::ReadPixels(stage.GetRenderer(), rgb, 0))
    {
      return 4;
    }
  }
  if (!WriteImage(base + ".bin", rgb))
  {
    return 5;
  }
  std::ofstream(base + ".txt") << (slow ? "slow " : "ok ") << ms << "\n";
  return 0;
}

/// One measured cell of the table.
struct Row
{
  std::string scene, mesh, tf, view, contender, status;
  std::size_t tets = 0;
  double ms = 0, rmse = 0, psnr = 0, worst = 0;
  bool Valid() const { return this->status == "ok" || this->status == "slow"; }
};

/// Forks a child for one run, with a watchdog; returns the status and fills ms and image.
std::string RunInChild(const AccuracyScene& scene, const std::string& contender, const Options& o,
  const std::string& base, double& ms, std::vector<double>& image)
{
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid == 0)
  {
    _exit(RunChild(scene, contender, o, base));
  }
  if (pid < 0)
  {
    return "fork failed";
  }
  // The watchdog: a warm-up frame past the slow limit is still let finish, up to 6 times
  // the limit plus a minute for input analysis.
  const double limit = 6 * o.common.timing.slowLimit + 60;
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  bool timedOut = false;
  while (true)
  {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid)
    {
      break;
    }
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > limit)
    {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      timedOut = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::string result;
  if (timedOut)
  {
    char text[64];
    std::snprintf(text, sizeof(text), "timeout (> %.0f s)", limit);
    result = text;
  }
  else if (WIFSIGNALED(status))
  {
    result = std::string("crash (") + strsignal(WTERMSIG(status)) + ")";
  }
  else if (WEXITSTATUS(status) != 0)
  {
    result = "failed (exit " + std::to_string(WEXITSTATUS(status)) + ")";
  }
  else
  {
    std::ifstream in(base + ".txt");
    in >> result >> ms;
    image = ReadImage(base + ".bin");
    if (image.size() != 3 * static_cast<std::size_t>(o.size) * o.size)
    {
      result = "failed (no image)";
    }
  }
  std::remove((base + ".txt").c_str());
  std::remove((base + ".bin").c_str());
  return result;
}

/// An RGB image of doubles in [0, 1] (row 0 at the bottom) as an 8-bit PNG.
void SavePng(const std::vector<double>& rgb, int size, const std::string& path)
{
  vtkNew<vtkImageData> image;
  image->SetDimensions(size, size, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  for (std::size_t i = 0; i < rgb.size(); ++i)
  {
    out[i] = static_cast<unsigned char>(std::lround(255 * std::min(1.0, std::max(0.0, rgb[i]))));
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(image);
  writer->Write();
}

std::string FileName(std::string name)
{
  for (char& c : name)
  {
    c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  }
  return name;
}

/// The system load: "1, 5 and 15 minute averages" from /proc/loadavg.
std::string LoadAverage()
{
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  in >> a >> b >> c;
  char text[64];
  std::snprintf(text, sizeof(text), "%.2f %.2f %.2f", a, b, c);
  return text;
}

double ImageRmse(const std::vector<double>& a, const std::vector<double>& b, double& worst)
{
  double sum = 0;
  worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    const double d = std::fabs(a[i] - b[i]);
    sum += d * d;
    worst = std::max(worst, d);
  }
  return std::sqrt(sum / static_cast<double>(a.size()));
}

/// The run's settings as "# key: value" lines ahead of the CSV header (read back by
/// --from-csv, so a re-plot describes the run that measured).
void WriteCsv(const std::string& path, const std::vector<Row>& rows, const Options& o)
{
  std::ofstream out(path);
  out << "# size: " << o.size << "\n# repeat: " << o.common.timing.repeat
      << "\n# step: " << o.common.timing.step << "\n# slow-limit: " << o.common.timing.slowLimit
      << "\n# renderer: " << o.renderer << "\n# load-before: " << o.loadBefore
      << "\n# load-after: " << o.loadAfter << "\n";
  out << "scene,mesh,tets,tf,view,contender,status,ms,rmse,psnr,worst\n";
  for (const Row& r : rows)
  {
    char line[512];
    std::snprintf(line, sizeof(line), "%s,%s,%zu,%s,%s,%s,%s,%.4f,%.7f,%.3f,%.6f\n",
      r.scene.c_str(), r.mesh.c_str(), r.tets, r.tf.c_str(), r.view.c_str(), r.contender.c_str(),
      r.status.c_str(), r.ms, r.rmse, r.psnr, r.worst);
    out << line;
  }
}

std::vector<Row> ReadCsv(const std::string& path, Options& o)
{
  std::vector<Row> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line))
  {
    if (line.rfind("# ", 0) == 0)
    {
      const auto colon = line.find(": ");
      const std::string key = line.substr(2, colon - 2);
      const std::string value = colon == std::string::npos ? "" : line.substr(colon + 2);
      if (key == "size")
        o.size = std::atoi(value.c_str());
      else if (key == "repeat")
        o.common.timing.repeat = std::atoi(value.c_str());
      else if (key == "step")
        o.common.timing.step = std::atof(value.c_str());
      else if (key == "slow-limit")
        o.common.timing.slowLimit = std::atof(value.c_str());
      else if (key == "renderer")
        o.renderer = value;
      else if (key == "load-before")
        o.loadBefore = value;
      else if (key == "load-after")
        o.loadAfter = value;
      continue;
    }
    if (line.rfind("scene,", 0) == 0)
    {
      continue; // the header
    }
    const auto f = SplitList(line);
    // SplitList drops empty fields: an unmeasured row keeps its 11 fields with 0 values.
    if (f.size() < 11)
    {
      continue;
    }
    Row r;
    r.scene = f[0];
    r.mesh = f[1];
    r.tets = std::strtoull(f[2].c_str(), nullptr, 10);
    r.tf = f[3];
    r.view = f[4];
    r.contender = f[5];
    r.status = f[6];
    r.ms = std::atof(f[7].c_str());
    r.rmse = std::atof(f[8].c_str());
    r.psnr = std::atof(f[9].c_str());
    r.worst = std::atof(f[10].c_str());
    rows.push_back(r);
  }
  return rows;
}

struct Summary
{
  std::string contender, family;
  int scenes = 0;
  double ms = 0, rmse = 0; ///< geometric means
};

/// Geometric means per contender (in each kind of window) over the scenes where it produced
/// an image.
std::vector<Summary> Summarize(const std::vector<Row>& rows)
{
  std::vector<Summary> out;
  std::vector<std::pair<std::string, std::string>> names; // (row name, family)
  for (const Contender& c : Contenders())
  {
    for (bool multisampling : { true, false })
    {
      const std::string name = InWindow(c, multisampling);
      const bool present =
        std::any_of(rows.begin(), rows.end(), [&](const Row& r) { return r.contender == name; });
      if (present)
      {
        names.emplace_back(name, c.family);
      }
    }
  }
  for (const auto& c : names)
  {
    Summary s;
    s.contender = c.first;
    s.family = c.second;
    double logMs = 0, logRmse = 0;
    for (const Row& r : rows)
    {
      if (r.contender == c.first && r.Valid())
      {
        ++s.scenes;
        logMs += std::log(std::max(r.ms, 1e-3));
        logRmse += std::log(std::max(r.rmse, 1e-9));
      }
    }
    if (s.scenes > 0)
    {
      s.ms = std::exp(logMs / s.scenes);
      s.rmse = std::exp(logRmse / s.scenes);
    }
    out.push_back(s);
  }
  return out;
}

const Row* Find(const std::vector<Row>& rows, const std::string& scene, const std::string& who)
{
  for (const Row& r : rows)
  {
    if (r.scene == scene && r.contender == who)
    {
      return &r;
    }
  }
  return nullptr;
}

/// Contender `who` in its faster kind of window on `scene` (of those with an image); null
/// when it has none.
const Row* FindFaster(
  const std::vector<Row>& rows, const std::string& scene, const std::string& who)
{
  const Row* best = nullptr;
  for (const std::string& name : { who, who + Single })
  {
    const Row* r = Find(rows, scene, name);
    if (r && r->Valid() && (!best || r->ms < best->ms))
    {
      best = r;
    }
  }
  return best;
}

/// The targets, per scene: (a) pre-integrated RMSE <= 1/4 of VTK PT's; (b)
/// VTK-compatible faster than every VTK mapper with RMSE <= VTK PT's. MTPT at 2 threads on
/// the CPU backend (the automatic choice on a software OpenGL). Every mapper is taken in
/// its faster kind of window (multisampled or not), VTK's PT with that window's error.
std::string Verdicts(const std::vector<Row>& rows, int& passA, int& passB, int& passBestB,
  int& passAFloor, int& scenes)
{
  std::vector<std::string> names;
  for (const Row& r : rows)
  {
    if (std::find(names.begin(), names.end(), r.scene) == names.end())
    {
      names.push_back(r.scene);
    }
  }
  std::ostringstream md;
  md << "| scene | pre-integrated RMSE | VTK PT RMSE | (a) pre-int <= PT / 4 | VTK-compatible ms "
        "| fastest VTK mapper | VTK-compatible RMSE | (b) faster than every VTK mapper and "
        "RMSE <= PT | (b) with MTPT's fastest VTK-compatible configuration | 8-bit floor | "
        "(a) above the floor |\n"
        "|---|---:|---:|---|---:|---|---:|---|---|---:|---|\n";
  passA = passB = passBestB = passAFloor = scenes = 0;
  for (const std::string& scene : names)
  {
    const Row* pre = FindFaster(rows, scene, "MTPT pre-integrated CPU 2t");
    const Row* vc = FindFaster(rows, scene, "MTPT VTK-compatible CPU 2t");
    const Row* pt = FindFaster(rows, scene, "VTK PT");
    if (!pre || !vc || !pt || !pre->Valid() || !vc->Valid() || !pt->Valid())
    {
      md << "| " << scene << " | | | no data | | | | no data | no data | | no data |\n";
      continue;
    }
    ++scenes;
    const bool a = pre->rmse <= pt->rmse / 4;
    const Row* fastest = nullptr;
    bool faster = true;
    for (const Row& r : rows)
    {
      if (r.scene != scene || r.contender.rfind("VTK ", 0) != 0)
      {
        continue;
      }
      // A VTK mapper that crashed or timed out is not faster; one that produced no image
      // at all cannot be compared.
      if (r.Valid())
      {
        if (!fastest || r.ms < fastest->ms)
        {
          fastest = &r;
        }
        faster = faster && vc->ms < r.ms;
      }
    }
    const bool b = faster && vc->rmse <= pt->rmse;
    // The same with whichever VTK-compatible configuration was fastest on this scene.
    const Row* best = vc;
    for (const char* other : { "MTPT VTK-compatible CPU 1t", "MTPT VTK-compatible GL 2t" })
    {
      const Row* r = FindFaster(rows, scene, other);
      if (r && r->Valid() && r->ms < best->ms)
      {
        best = r;
      }
    }
    bool bestFaster = true;
    for (const Row& r : rows)
    {
      if (r.scene == scene && r.contender.rfind("VTK ", 0) == 0 && r.Valid())
      {
        bestFaster = bestFaster && best->ms < r.ms;
      }
    }
    const bool bestB = bestFaster && best->rmse <= pt->rmse;
    // Errors above the 8-bit floor (rounding noise and mapper error add in quadrature).
    const Row* ref = Find(rows, scene, "reference");
    const double floor = ref ? ref->rmse : 0.0;
    auto excess = [floor](double rmse)
    { return std::sqrt(std::max(0.0, rmse * rmse - floor * floor)); };
    const bool aFloor = excess(pre->rmse) <= excess(pt->rmse) / 4;
    passA += a ? 1 : 0;
    passB += b ? 1 : 0;
    passBestB += bestB ? 1 : 0;
    passAFloor += aFloor ? 1 : 0;
    char line[512];
    std::snprintf(line, sizeof(line),
      "| %s | %.5f | %.5f | %s | %.1f | %s (%.1f ms) | %.5f | %s | %s: %s (%.1f ms, RMSE %.5f) "
      "| %.5f | %s (%.5f vs %.5f) |\n",
      scene.c_str(), pre->rmse, pt->rmse, a ? "yes" : "**no**", vc->ms,
      fastest ? fastest->contender.c_str() : "-", fastest ? fastest->ms : 0.0, vc->rmse,
      b ? "yes"
        : (faster ? "**no** (RMSE)"
                  : (vc->rmse <= pt->rmse ? "**no** (time)" : "**no** (time, RMSE)")),
      bestB ? "yes" : "**no**", best->contender.c_str() + 5, best->ms, best->rmse, floor,
      aFloor ? "yes" : "**no**", excess(pre->rmse), excess(pt->rmse));
    md << line;
  }
  return md.str();
}

std::string Markdown(const std::vector<Row>& rows, const Options& o)
{
  std::ostringstream md;
  md << "# Speed against error\n\n"
     << "Generated by `mtpt_bench_accuracy` (Benchmarks/BenchAccuracy.cxx). Each image is "
        "compared with the exact emission-absorption integral of the same scene "
        "(vtkMTPTReferenceRenderer: linear scalar per tetrahedron, piecewise-linear transfer "
        "functions, exact to about 1e-12). RMSE and PSNR over linear RGB in [0, 1] (8-bit "
        "window read-back: an error floor of about 0.0011 RMSE for any mapper); worst = "
        "largest channel difference. Time: median of "
     << o.common.timing.repeat << " frames after one warm-up, the camera turning "
     << o.common.timing.step
     << " degrees of azimuth before each, whole `Render()` + `WaitForCompletion()` (ms); "
     << "slow = a warm-up frame over " << o.common.timing.slowLimit
     << " s, then only that frame. The image compared is drawn at the start view after the "
        "timed frames. Window "
     << o.size << "x" << o.size
     << " as VTK makes it by default (multisampled), and the same single-sampled "
        "(SetMultiSamples(0); contenders marked single-sampled), white background; the targets "
        "take every mapper in its faster window. OpenGL renderer: "
     << o.renderer << ". Load average (1, 5, 15 min) at the start " << o.loadBefore
     << ", at the end " << o.loadAfter
     << ". MTPT with its default settings; VTK's ray caster and Z-sweep at image sample "
        "distance 1 without automatic adjustment. Every contender runs in its own child "
        "process: crashes are reported as such.\n\n"
     << "Transfer functions: smooth = three-colour ramp, opacity rising linearly 0 -> 1 over "
        "the data range; narrow = the same colours, opacity 0 except three peaks of height 40 "
        "and half-width 0.2% of the range at 25%, 50% and 75% of it. Unit distance: 1/50 of "
        "the mesh's bounding-box diagonal. Camera: reset, azimuth 30, elevation 20.\n\n";

  int passA = 0, passB = 0, passBestB = 0, passAFloor = 0, scenes = 0;
  const std::string verdicts = Verdicts(rows, passA, passB, passBestB, passAFloor, scenes);
  md << "## Targets: pre-integrated error and VTK-compatible speed (MTPT CPU backend, 2 "
        "threads)\n\n"
     << "(a) pre-integrated RMSE <= 1/4 of VTK PT's: " << passA << " of " << scenes
     << " scenes. (b) VTK-compatible faster than every VTK mapper with RMSE <= VTK PT's: " << passB
     << " of " << scenes
     << " scenes; with MTPT's fastest VTK-compatible configuration on each scene (CPU at 1 "
        "or 2 threads, or OpenGL): "
     << passBestB << " of " << scenes
     << " scenes. (a) on the error above the 8-bit floor (sqrt(RMSE^2 - floor^2), the floor "
        "being the reference's own rounding to 8 bits, which no mapper read back from an 8-bit "
        "window can beat): "
     << passAFloor << " of " << scenes << " scenes.\n\n"
     << verdicts << "\n";

  md << "## Geometric means over the scenes\n\n"
     << "| contender | scenes | ms | RMSE | PSNR (dB) |\n|---|---:|---:|---:|---:|\n";
  for (const Summary& s : Summarize(rows))
  {
    char line[256];
    if (s.scenes > 0)
    {
      std::snprintf(line, sizeof(line), "| %s | %d | %.1f | %.5f | %.1f |\n", s.contender.c_str(),
        s.scenes, s.ms, s.rmse, -20 * std::log10(s.rmse));
    }
    else
    {
      std::snprintf(line, sizeof(line), "| %s | 0 | | | |\n", s.contender.c_str());
    }
    md << line;
  }
  md << "\n![time against RMSE](accuracy.png)\n\n## Per scene\n\n";
  std::string scene;
  for (const Row& r : rows)
  {
    if (r.scene != scene)
    {
      scene = r.scene;
      md << "\n### " << scene << " (" << r.tets << " tetrahedra)\n\n"
         << "| contender | status | ms | RMSE | PSNR (dB) | worst |\n"
            "|---|---|---:|---:|---:|---:|\n";
    }
    char line[512];
    if (r.contender == "reference")
    {
      std::snprintf(line, sizeof(line),
        "| reference (exact integral; its RMSE: its own 8-bit rounding, the floor) | %s | %.1f | "
        "%.5f | %.1f | %.3f |\n",
        r.status.c_str(), r.ms, r.rmse, r.psnr, r.worst);
    }
    else if (r.Valid())
    {
      std::snprintf(line, sizeof(line), "| %s | %s | %.1f | %.5f | %.1f | %.3f |\n",
        r.contender.c_str(), r.status.c_str(), r.ms, r.rmse, r.psnr, r.worst);
    }
    else
    {
      std::snprintf(
        line, sizeof(line), "| %s | %s | | | | |\n", r.contender.c_str(), r.status.c_str());
    }
    md << line;
  }
  return md.str();
}

/// Time against RMSE, log-log, one point per contender (geometric means), each in its faster
/// window (the project's rule for every comparison; both windows would double the legend,
/// which then hides the fastest points). The tables list both.
void PlotSummary(const std::vector<Row>& rows, const std::string& path)
{
  std::vector<Summary> fastest;
  for (const Summary& s : Summarize(rows))
  {
    if (s.scenes == 0)
    {
      continue;
    }
    const std::string base = EndsWithSingle(s.contender)
      ? s.contender.substr(0, s.contender.size() - Single.size())
      : s.contender;
    auto same = std::find_if(fastest.begin(), fastest.end(),
      [&](const Summary& f)
      {
        return f.contender == base ||
          (EndsWithSingle(f.contender) &&
            f.contender.substr(0, f.contender.size() - Single.size()) == base);
      });
    if (same == fastest.end())
    {
      fastest.push_back(s);
    }
    else if (s.ms < same->ms)
    {
      *same = s;
    }
  }
  std::vector<Series> series;
  for (const Summary& s : fastest)
  {
    series.push_back({ s.contender, { s.ms }, { s.rmse } });
  }
  Chart chart;
  chart.title = "Speed against error (geometric means over the scenes)";
  chart.xTitle = "frame time (ms), log";
  chart.yTitle = "RMSE against the exact integral, log";
  chart.lines = false;
  chart.headroom = 30; // room above the points for the legend
  std::string error;
  if (!WritePlot(path, chart, series, error))
  {
    std::fprintf(stderr, "mtpt_bench_accuracy: %s\n", error.c_str());
  }
}

/// Every contender (of --contenders) in every kind of window of --multisampling, in table
/// order.
std::vector<std::string> ContenderRuns(const Options& o)
{
  std::vector<std::string> runs;
  const std::vector<std::string> wanted = SplitList(o.contenders);
  for (const Contender& c : Contenders())
  {
    const bool chosen = wanted.empty() ||
      std::any_of(wanted.begin(), wanted.end(),
        [&](const std::string& part) { return c.name.find(part) != std::string::npos; });
    for (bool multisampling : o.common.windows)
    {
      if (chosen)
      {
        runs.push_back(InWindow(c, multisampling));
      }
    }
  }
  return runs;
}

void WriteOutputs(const std::vector<Row>& rows, const Options& o)
{
  WriteCsv(o.out + "/accuracy.csv", rows, o);
  std::ofstream(o.out + "/accuracy.md") << Markdown(rows, o);
}

} // namespace

int main(int argc, char** argv)
try
{
  Options o;
  CLI::App app{ "Speed against error: every mapper's image against the exact ray integral, "
                "each contender in its own process." };
  AddCommonOptions(app, o.common);
  o.common.timing.repeat = 3;
  o.common.timing.slowLimit = 10;
  app.add_option("--size", o.size, "window size (square)")->check(CLI::Range(8, 4096));
  app.add_option("--out", o.out, "folder for accuracy.md, accuracy.csv and accuracy.png");
  app.add_option("--from-csv", o.fromCsv, "re-plot a previous run's CSV instead of measuring");
  app.add_option("--meshes", o.meshes,
    "scenes: grid (a generated grid of --grid-tets) and the harness's names (bluntfin, "
    "pulley, comb, fire_ug, kiefer, ...)");
  app.add_option("--grid-tets", o.gridTets, "tetrahedra of the generated grid")
    ->check(CLI::PositiveNumber);
  app.add_flag("--images", o.images, "also write every image as PNG under <out>/images");
  app.add_option("--contenders", o.contenders,
    "only the contenders whose names contain one of these, comma-separated (e.g. "
    "\"pre-integrated CPU 2t,VTK PT\"); default: all");
  CLI11_PARSE(app, argc, argv);
  mkdir(o.out.c_str(), 0755);

  if (!o.fromCsv.empty())
  {
    const std::vector<Row> rows = ReadCsv(o.fromCsv, o);
    if (rows.empty())
    {
      std::fprintf(stderr, "no rows in %s\n", o.fromCsv.c_str());
      return 1;
    }
    WriteOutputs(rows, o);
    PlotSummary(rows, o.out + "/accuracy.png");
    std::printf("%s", Markdown(rows, o).c_str());
    return 0;
  }

  // Meshes first, before any OpenGL context exists (children are forked from here).
  o.loadBefore = LoadAverage();
  std::vector<Scene> meshes;
  for (const std::string& name : SplitList(o.meshes))
  {
    Scene scene;
    std::string error;
    const std::string what = name == "grid" ? "grid:" + std::to_string(o.gridTets) : name;
    if (LoadScene(what, o.common.dataFolder, scene, error))
    {
      scene.name = name;
      meshes.push_back(std::move(scene));
    }
    else
    {
      std::fprintf(stderr, "skipping %s: %s\n", name.c_str(), error.c_str());
    }
  }

  std::vector<Row> rows;
  const std::string scratch = o.out + "/.scratch-" + std::to_string(getpid());
  for (std::size_t m = 0; m < meshes.size(); ++m)
  {
    for (const char* tf : { "smooth", "narrow" })
    {
      for (bool perspective : { false, true })
      {
        AccuracyScene scene;
        scene.mesh = &meshes[m];
        scene.tf = tf;
        scene.perspective = perspective;
        const std::string name = scene.Name();
        Row base;
        base.scene = name;
        base.mesh = meshes[m].name;
        base.tets = static_cast<std::size_t>(meshes[m].grid->GetNumberOfCells());
        base.tf = tf;
        base.view = perspective ? "persp" : "ortho";

        std::vector<double> reference;
        Row ref = base;
        ref.contender = "reference";
        ref.status = RunInChild(scene, "reference", o, scratch, ref.ms, reference);
        std::fprintf(
          stderr, "%s: reference %s %.0f ms\n", name.c_str(), ref.status.c_str(), ref.ms);
        rows.push_back(ref);
        if (!ref.Valid())
        {
          continue;
        }
        // The error floor of an 8-bit window: the reference itself rounded to 8 bits.
        {
          std::vector<double> rounded(reference.size());
          for (std::size_t i = 0; i < reference.size(); ++i)
          {
            rounded[i] = std::round(255 * std::min(1.0, std::max(0.0, reference[i]))) / 255;
          }
          rows.back().rmse = ImageRmse(rounded, reference, rows.back().worst);
          rows.back().psnr = -20 * std::log10(std::max(rows.back().rmse, 1e-12));
        }
        const std::string imageDir = o.out + "/images";
        if (o.images)
        {
          mkdir(imageDir.c_str(), 0755);
          SavePng(reference, o.size, imageDir + "/" + FileName(name + "-reference") + ".png");
        }
        for (const std::string& name : ContenderRuns(o))
        {
          Row r = base;
          r.contender = name;
          std::vector<double> image;
          r.status = RunInChild(scene, name, o, scratch, r.ms, image);
          if (r.Valid())
          {
            r.rmse = ImageRmse(image, reference, r.worst);
            r.psnr = r.rmse > 0 ? -20 * std::log10(r.rmse) : 999;
            if (o.images)
            {
              SavePng(image, o.size, imageDir + "/" + FileName(scene.Name() + "-" + name) + ".png");
            }
          }
          std::fprintf(stderr, "%s: %-52s %-10s %9.1f ms  RMSE %.5f  worst %.3f\n",
            scene.Name().c_str(), name.c_str(), r.status.c_str(), r.ms, r.rmse, r.worst);
          rows.push_back(r);
        }
        // Partial results survive an interrupted run.
        WriteCsv(o.out + "/accuracy.csv", rows, o);
      }
    }
  }
  o.loadAfter = LoadAverage();
  // Only now an OpenGL context in this process (no more forks).
  o.renderer = QueryOpenGL().renderer;
  WriteOutputs(rows, o);
  PlotSummary(rows, o.out + "/accuracy.png");
  std::printf("%s", Markdown(rows, o).c_str());
  return 0;
}
catch (const mtpt::bench::MapperError& error)
{
  return mtpt::bench::ReportMapperError("mtpt_bench_accuracy", error);
}
