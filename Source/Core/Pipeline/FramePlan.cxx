// SPDX-License-Identifier: BSD-3-Clause
#include "mtpt/FramePlan.h"

#include "mtpt/ImageSampling.h"
#include "mtpt/LevelOfDetail.h"

#include <algorithm>
#include <sstream>

namespace mtpt
{

namespace
{

void Note(FramePlan& plan, PlanNote::About about, bool error, std::string key, std::string text)
{
  plan.notes.push_back({ about, error, std::move(key), std::move(text) });
}

/// Shading and blending: the data's colours (dependent components) come through unchanged,
/// so they admit neither pre-integration nor a reduction of scalars; a depth-peeling pass
/// composites.
void PlanBlending(const FrameSettings& s, const FrameFacts& f, FramePlan& plan)
{
  plan.vertexColours = f.vertexColours;
  plan.shading = s.shading;
  if (f.vertexColours && s.shading == Shading::PreIntegrated)
  {
    plan.shading = Shading::VTKCompatible;
    Note(plan, PlanNote::About::Mapper, false, "pre-integrated dependent components",
      "pre-integrated shading integrates one scalar through the transfer functions; with "
      "dependent components (IndependentComponents off) the data give the colours, which are "
      "drawn with VTK-compatible shading");
  }
  const int mode = s.blendMode;
  const std::string name = BlendModeName(mode);
  plan.blendMode = BlendMode::Composite;
  if (mode < static_cast<int>(BlendMode::Composite) || mode > static_cast<int>(BlendMode::Additive))
  {
    std::ostringstream text;
    text << "blend mode " << mode << " is none of 0 (composite) to 4 (additive); drawing with "
         << "composite blending";
    Note(plan, PlanNote::About::Mapper, true, "unknown blend mode", text.str());
  }
  else if (mode != static_cast<int>(BlendMode::Composite) && f.vertexColours)
  {
    Note(plan, PlanNote::About::Mapper, false, "blend mode with dependent components",
      name +
        " blending reduces one scalar; with dependent components (IndependentComponents "
        "off) the data give the colours, which are drawn with composite blending");
  }
  else if (mode != static_cast<int>(BlendMode::Composite) && f.peeling)
  {
    Note(plan, PlanNote::About::Mapper, false, "blend mode in depth peeling",
      name +
        " blending is not defined between translucent surfaces; inside depth peeling the "
        "volume is drawn with composite blending");
  }
  else
  {
    plan.blendMode = static_cast<BlendMode>(mode);
  }
  plan.averageRange[0] = s.averageRange[0];
  plan.averageRange[1] = s.averageRange[1];
  plan.ordered = !ReducesInAnyOrder(plan.blendMode);
}

/// Lighting (Lighting.h) shades composite blending only, as VTK's GPU ray caster does, and
/// needs the gradient of one point scalar.
void PlanLighting(const FrameSettings& s, const FrameFacts& f, FramePlan& plan)
{
  plan.lit = false;
  if (!s.shade || plan.blendMode != BlendMode::Composite)
  {
    return;
  }
  if (f.vertexColours || f.cellScalars)
  {
    Note(plan, PlanNote::About::Property, false, "shading without point scalars",
      std::string("shading (ShadeOn) lights the gradient of one point scalar; ") +
        (f.vertexColours ? "with dependent components (IndependentComponents off)"
                         : "cell scalars have none, and") +
        " the volume is drawn unlit");
    return;
  }
  plan.lit = true;
}

/// What the records carry and the tables read follow from the shading and blending.
void PlanFragments(const FrameSettings& s, const FrameFacts& f, FramePlan& plan)
{
  const bool reduce = ReducesInAnyOrder(plan.blendMode);
  plan.values = plan.vertexColours
    ? FragmentValues::Colours
    : (plan.shading == Shading::PreIntegrated || reduce ? FragmentValues::Scalars
                                                        : FragmentValues::TableMeans);
  plan.preIntegrationTable = plan.shading == Shading::PreIntegrated;
  plan.intensityTable = reduce;
  plan.unitDistance = s.unitDistance;
  plan.interpolation = PerspectiveInterpolation::FromProjection(f.projection);
  plan.perspectiveExact = plan.values == FragmentValues::Scalars && plan.interpolation.perspective;
  plan.clipping = DepthClipping::FromProjection(f.projection);
  plan.clipPlanes = f.clipPlanes;
}

/// The composited image's size: the viewport's at distance 1; else the sampled size, at
/// most MaximumSamplesPerPixel samples per pixel side and the backend's limit (drawn at the
/// viewport's size where it has none). A depth-peeling pass composites at the viewport's
/// size.
void PlanImage(const FrameSettings& s, const FrameFacts& f, FramePlan& plan)
{
  const int* viewport = f.viewport;
  const int sampled[2] = { SampledImageSize(viewport[0], s.imageSampleDistance),
    SampledImageSize(viewport[1], s.imageSampleDistance) };
  plan.sampledSize = { viewport[0], viewport[1] };
  const int limit =
    sampled[0] == viewport[0] && sampled[1] == viewport[1] ? 0 : f.sampledImageLimit;
  if (limit > 0)
  {
    const int most[2] = { std::min(limit, MaximumSamplesPerPixel * viewport[0]),
      std::min(limit, MaximumSamplesPerPixel * viewport[1]) };
    plan.sampledSize = { std::min(sampled[0], most[0]), std::min(sampled[1], most[1]) };
    if (sampled[0] > most[0] || sampled[1] > most[1])
    {
      std::ostringstream text;
      text << "ImageSampleDistance " << s.imageSampleDistance << " asks for an image of "
           << sampled[0] << " x " << sampled[1] << " pixels; drawing " << plan.sampledSize.width
           << " x " << plan.sampledSize.height << " (at most " << MaximumSamplesPerPixel
           << " samples per pixel side and " << limit << " pixels per side here)";
      Note(plan, PlanNote::About::Mapper, false, text.str(), text.str());
    }
  }
  plan.imageSize = f.peeling ? ImageSize{ viewport[0], viewport[1] } : plan.sampledSize;
  plan.cellFraction = f.peeling ? 1.0 : CellFractionLevel(s.cellFraction, 0.0);
  // Culling never changes the image (Culling.h, DepthKeys.h): cells covering no pixel
  // centre are culled only where every fragment is sampled at one.
  plan.cullOpacity = plan.cullFrustum = s.cullInvisibleCells;
  plan.cullPixels =
    s.cullInvisibleCells && (plan.Sampled(viewport) ? f.sampledCentresOnly : f.centresOnly);
}

/// The batches, and the memory they and the stages take at most.
void PlanBatches(const FrameSettings& s, const FrameFacts& f, FramePlan& plan)
{
  plan.target = f.target;
  plan.batchSize = s.batchSize;
  // The CPU compositor blends front to back: batches in that order continue each tile's
  // blending and let what turned opaque hide the cells behind it. OpenGL blends back to
  // front; the reductions fold in any order.
  plan.frontToBack = f.target == BatchTarget::Fans && plan.ordered;
  plan.threads = s.threads;
  MemoryNeed& need = plan.memory;
  need.points = f.points;
  need.cells = f.cells;
  need.batch = s.batchSize > 0 ? s.batchSize : f.cells;
  need.slots = f.target == BatchTarget::Slots;
  need.fans = !need.slots;
  need.levelOfDetail = plan.cellFraction < 1 || s.autoAdjustCellFraction;
  need.threads = s.threads;
  need.pieces = f.nearPieces;
}

} // namespace

CompositeSettings CompositeSettingsFor(const FramePlan& plan, const TransferFunctionTable& table,
  const PreIntegrationTable& preIntegration, const IntensityTable& intensity, double unitDistance)
{
  CompositeSettings settings;
  settings.width = plan.imageSize.width;
  settings.height = plan.imageSize.height;
  settings.transferFunction = table;
  settings.unitDistance = unitDistance;
  settings.clipping = plan.clipping;
  settings.clipPlanes = plan.clipPlanes;
  settings.vertexColours = plan.vertexColours;
  if (plan.preIntegrationTable)
  {
    settings.UsePreIntegration(preIntegration, plan.interpolation);
  }
  settings.blendMode = plan.blendMode;
  if (ReducesInAnyOrder(plan.blendMode))
  {
    // Reductions interpolate the scalars as pre-integrated shading does.
    settings.interpolation = plan.interpolation;
    settings.intensity = plan.intensityTable ? &intensity : nullptr;
    settings.averageRange[0] = plan.averageRange[0];
    settings.averageRange[1] = plan.averageRange[1];
  }
  return settings;
}

const char* BlendModeName(int mode)
{
  switch (mode)
  {
    case static_cast<int>(BlendMode::Composite):
      return "Composite";
    case static_cast<int>(BlendMode::MaximumIntensity):
      return "MaximumIntensity";
    case static_cast<int>(BlendMode::MinimumIntensity):
      return "MinimumIntensity";
    case static_cast<int>(BlendMode::AverageIntensity):
      return "AverageIntensity";
    case static_cast<int>(BlendMode::Additive):
      return "Additive";
    default:
      return "Unknown";
  }
}

FramePlan PlanFrame(const FrameSettings& settings, const FrameFacts& facts)
{
  FramePlan plan;
  PlanBlending(settings, facts, plan);
  PlanLighting(settings, facts, plan);
  PlanFragments(settings, facts, plan);
  PlanImage(settings, facts, plan);
  PlanBatches(settings, facts, plan);
  return plan;
}

} // namespace mtpt
