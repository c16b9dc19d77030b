// SPDX-License-Identifier: BSD-3-Clause
// The frame plan (mtpt/FramePlan.h): every rule a frame takes from its settings and facts,
// decided in PlanFrame alone; and the pipeline's batch loop (FramePipeline::DrawBatches),
// which hands the backends finished batches.
#include "TestHelpers.h"

#include "mtpt/FramePipeline.h"
#include "mtpt/FramePlan.h"
#include "mtpt/Lighting.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <string>
#include <vector>

namespace
{

using mtpt::BatchTarget;
using mtpt::BlendMode;
using mtpt::FragmentValues;
using mtpt::PlanNote;
using mtpt::Shading;
using mtpt::test::JitteredGrid;
using mtpt::test::LookAt;
using mtpt::test::TetMesh;

mtpt::FrameFacts Facts()
{
  mtpt::FrameFacts facts;
  facts.points = 1000;
  facts.cells = 5000;
  facts.viewport[0] = 800;
  facts.viewport[1] = 600;
  facts.sampledImageLimit = 16384;
  facts.centresOnly = facts.sampledCentresOnly = true;
  facts.projection = mtpt::test::Perspective(30, 800.0 / 600.0, 0.1, 10);
  return facts;
}

/// The notes of `plan` with `key`.
std::vector<PlanNote> NotesWith(const mtpt::FramePlan& plan, const std::string& key)
{
  std::vector<PlanNote> found;
  std::copy_if(plan.notes.begin(), plan.notes.end(), std::back_inserter(found),
    [&](const PlanNote& n) { return n.key == key; });
  return found;
}

TEST(FramePlan, DependentComponentsDrawTheirColoursWithTheVTKCompatibleShading)
{
  mtpt::FrameSettings settings;
  settings.shading = Shading::PreIntegrated;
  mtpt::FrameFacts facts = Facts();
  const mtpt::FramePlan scalars = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(scalars.shading, Shading::PreIntegrated);
  EXPECT_EQ(scalars.values, FragmentValues::Scalars);
  EXPECT_TRUE(scalars.preIntegrationTable);
  EXPECT_TRUE(scalars.perspectiveExact);
  EXPECT_TRUE(scalars.notes.empty());

  facts.vertexColours = true;
  const mtpt::FramePlan colours = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(colours.shading, Shading::VTKCompatible);
  EXPECT_EQ(colours.values, FragmentValues::Colours);
  EXPECT_TRUE(colours.vertexColours);
  EXPECT_FALSE(colours.preIntegrationTable);
  EXPECT_FALSE(colours.perspectiveExact);
  const auto notes = NotesWith(colours, "pre-integrated dependent components");
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_FALSE(notes[0].error);
  EXPECT_EQ(notes[0].about, PlanNote::About::Mapper);
  EXPECT_NE(notes[0].text.find("VTK-compatible"), std::string::npos);

  settings.shading = Shading::VTKCompatible;
  facts.vertexColours = false;
  const mtpt::FramePlan means = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(means.values, FragmentValues::TableMeans);
  EXPECT_FALSE(means.perspectiveExact); // only scalars are interpolated exactly
}

TEST(FramePlan, BlendModesReduceScalarsUnlessTheyCannot)
{
  mtpt::FrameSettings settings;
  for (int mode = 1; mode <= 4; ++mode)
  {
    settings.blendMode = mode;
    const mtpt::FramePlan plan = mtpt::PlanFrame(settings, Facts());
    EXPECT_EQ(static_cast<int>(plan.blendMode), mode);
    EXPECT_FALSE(plan.ordered);
    EXPECT_EQ(plan.values, FragmentValues::Scalars);
    EXPECT_TRUE(plan.intensityTable);
    EXPECT_TRUE(plan.notes.empty());
    EXPECT_STRNE(mtpt::BlendModeName(mode), "Unknown");
  }
  for (const int mode : { -1, 5, 1000 })
  {
    settings.blendMode = mode;
    const mtpt::FramePlan plan = mtpt::PlanFrame(settings, Facts());
    EXPECT_EQ(plan.blendMode, BlendMode::Composite);
    EXPECT_TRUE(plan.ordered);
    const auto notes = NotesWith(plan, "unknown blend mode");
    ASSERT_EQ(notes.size(), 1u) << mode;
    EXPECT_TRUE(notes[0].error);
    EXPECT_NE(notes[0].text.find(std::to_string(mode)), std::string::npos);
    EXPECT_STREQ(mtpt::BlendModeName(mode), "Unknown");
  }
  settings.blendMode = static_cast<int>(BlendMode::MaximumIntensity);
  mtpt::FrameFacts facts = Facts();
  facts.vertexColours = true;
  mtpt::FramePlan plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.blendMode, BlendMode::Composite);
  EXPECT_EQ(plan.values, FragmentValues::Colours);
  EXPECT_EQ(NotesWith(plan, "blend mode with dependent components").size(), 1u);
  facts.vertexColours = false;
  facts.peeling = true;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.blendMode, BlendMode::Composite);
  EXPECT_TRUE(plan.ordered);
  ASSERT_EQ(NotesWith(plan, "blend mode in depth peeling").size(), 1u);
  EXPECT_NE(plan.notes[0].text.find("MaximumIntensity"), std::string::npos);
}

TEST(FramePlan, LightingNeedsCompositeBlendingAndPointScalars)
{
  mtpt::FrameSettings settings;
  settings.shade = true;
  mtpt::FrameFacts facts = Facts();
  EXPECT_TRUE(mtpt::PlanFrame(settings, facts).lit);
  settings.shade = false;
  EXPECT_FALSE(mtpt::PlanFrame(settings, facts).lit);
  settings.shade = true;
  settings.blendMode = static_cast<int>(BlendMode::Additive);
  mtpt::FramePlan plan = mtpt::PlanFrame(settings, facts);
  EXPECT_FALSE(plan.lit); // as VTK's GPU ray caster: no note
  EXPECT_TRUE(plan.notes.empty());
  settings.blendMode = 0;
  for (const bool colours : { false, true })
  {
    facts.cellScalars = !colours;
    facts.vertexColours = colours;
    plan = mtpt::PlanFrame(settings, facts);
    EXPECT_FALSE(plan.lit);
    const auto notes = NotesWith(plan, "shading without point scalars");
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_EQ(notes[0].about, PlanNote::About::Property);
    EXPECT_NE(
      notes[0].text.find(colours ? "dependent components" : "cell scalars"), std::string::npos);
  }
}

TEST(FramePlan, TheImageSizeFollowsTheSampleDistanceWithinItsLimits)
{
  mtpt::FrameSettings settings;
  mtpt::FrameFacts facts = Facts();
  mtpt::FramePlan plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.imageSize, (mtpt::ImageSize{ 800, 600 }));
  EXPECT_FALSE(plan.Sampled(facts.viewport));
  settings.imageSampleDistance = 2;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.imageSize, (mtpt::ImageSize{ 400, 300 }));
  EXPECT_EQ(plan.sampledSize, plan.imageSize);
  EXPECT_TRUE(plan.Sampled(facts.viewport));
  // At most 4 samples per pixel side, and the backend's limit.
  settings.imageSampleDistance = 0.1f;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.imageSize, (mtpt::ImageSize{ 3200, 2400 }));
  ASSERT_EQ(plan.notes.size(), 1u);
  EXPECT_NE(plan.notes[0].text.find("8000 x 6000"), std::string::npos);
  facts.sampledImageLimit = 1000;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.imageSize, (mtpt::ImageSize{ 1000, 1000 }));
  // A backend that cannot sample draws at the viewport's size.
  facts.sampledImageLimit = 0;
  settings.imageSampleDistance = 2;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.imageSize, (mtpt::ImageSize{ 800, 600 }));
  // A depth-peeling pass composites at the viewport's size and draws every cell.
  facts.sampledImageLimit = 16384;
  facts.peeling = true;
  settings.cellFraction = 0.3;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.imageSize, (mtpt::ImageSize{ 800, 600 }));
  EXPECT_EQ(plan.sampledSize, (mtpt::ImageSize{ 400, 300 }));
  EXPECT_EQ(plan.cellFraction, 1.0);
  facts.peeling = false;
  EXPECT_EQ(mtpt::PlanFrame(settings, facts).cellFraction, mtpt::CellFractionLevel(0.3, 0.0));
}

TEST(FramePlan, PixelCullingOnlyWhereEveryFragmentIsAPixelCentre)
{
  mtpt::FrameSettings settings;
  mtpt::FrameFacts facts = Facts();
  facts.centresOnly = false;
  facts.sampledCentresOnly = true;
  EXPECT_FALSE(mtpt::PlanFrame(settings, facts).cullPixels);
  settings.imageSampleDistance = 2;
  EXPECT_TRUE(mtpt::PlanFrame(settings, facts).cullPixels);
  settings.cullInvisibleCells = false;
  const mtpt::FramePlan plan = mtpt::PlanFrame(settings, facts);
  EXPECT_FALSE(plan.cullPixels || plan.cullFrustum || plan.cullOpacity);

  // ApplyPlan sets exactly what the plan decides of a frame's input.
  mtpt::FrameInput input;
  const float table[8] = { 0, 0, 0, 1, 1, 1, 1, 1 };
  input.opacity = { table, 2, 0.0, 1.0 };
  input.opacityVersion = 7;
  mtpt::ApplyPlan(plan, input);
  EXPECT_EQ(input.opacity.table, nullptr);
  EXPECT_FALSE(input.cullFrustum);
  EXPECT_TRUE(input.imageSize.Empty());
  settings.cullInvisibleCells = true;
  settings.blendMode = static_cast<int>(BlendMode::MinimumIntensity);
  settings.shade = true;
  const mtpt::FramePlan culled = mtpt::PlanFrame(settings, facts);
  input.opacity = { table, 2, 0.0, 1.0 };
  mtpt::ApplyPlan(culled, input);
  EXPECT_EQ(input.opacity.table, table);
  EXPECT_EQ(input.imageSize, (mtpt::ImageSize{ 400, 300 }));
  EXPECT_FALSE(input.ordered);
  EXPECT_FALSE(input.lit);
}

TEST(FramePlan, TheMemoryNeedFollowsTheBatchesAndTheLevelOfDetail)
{
  mtpt::FrameSettings settings;
  mtpt::FrameFacts facts = Facts();
  settings.threads = 3;
  mtpt::FramePlan plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.memory.points, 1000u);
  EXPECT_EQ(plan.memory.cells, 5000u);
  EXPECT_EQ(plan.memory.batch, 5000u); // batch size 0: the whole order
  EXPECT_TRUE(plan.memory.fans && !plan.memory.slots);
  EXPECT_FALSE(plan.memory.levelOfDetail);
  EXPECT_EQ(plan.memory.threads, 3);
  settings.batchSize = 64;
  settings.autoAdjustCellFraction = true;
  facts.target = BatchTarget::Slots;
  plan = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(plan.memory.batch, 64u);
  EXPECT_EQ(plan.batchSize, 64u);
  EXPECT_TRUE(plan.memory.slots && !plan.memory.fans);
  EXPECT_TRUE(plan.memory.levelOfDetail);
  settings.autoAdjustCellFraction = false;
  settings.cellFraction = 0.5;
  EXPECT_TRUE(mtpt::PlanFrame(settings, facts).memory.levelOfDetail);

  // The policy: a limit, or the memory available (asked only then) beside what is held.
  int asked = 0;
  const auto available = [&asked]
  {
    ++asked;
    return std::size_t{ 1 } << 30;
  };
  const std::size_t bytes = mtpt::FramePipeline::BytesNeeded(plan.memory);
  mtpt::MemoryVerdict verdict = mtpt::CheckMemory(plan.memory, bytes, 0, available);
  EXPECT_TRUE(verdict.fits);
  EXPECT_EQ(verdict.bytes, bytes);
  verdict = mtpt::CheckMemory(plan.memory, bytes - 1, 0, available);
  EXPECT_FALSE(verdict.fits);
  EXPECT_EQ(verdict.limit, bytes - 1);
  EXPECT_EQ(asked, 0);
  verdict = mtpt::CheckMemory(plan.memory, 0, 5, available);
  EXPECT_EQ(asked, 1);
  EXPECT_EQ(verdict.limit, (std::size_t{ 1 } << 30) + 5);
}

TEST(FramePlan, SameSettingsAndFactsGiveTheSamePlan)
{
  mtpt::FrameSettings settings;
  settings.shading = Shading::PreIntegrated;
  settings.imageSampleDistance = 1.5f;
  settings.shade = true;
  mtpt::FrameFacts facts = Facts();
  facts.clipPlanes.count = 1;
  facts.clipPlanes.plane[0][2] = 1;
  const mtpt::FramePlan a = mtpt::PlanFrame(settings, facts);
  const mtpt::FramePlan b = mtpt::PlanFrame(settings, facts);
  EXPECT_EQ(a.imageSize, b.imageSize);
  EXPECT_TRUE(a.clipPlanes == facts.clipPlanes && b.clipPlanes == a.clipPlanes);
  EXPECT_EQ(a.interpolation.inverseWScale, b.interpolation.inverseWScale);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.lit, b.lit);

  // The compositor's settings carry the tables the plan reads, and only those.
  const std::vector<float> table(4 * 4, 0.5f);
  mtpt::PreIntegrationTable integrals;
  mtpt::IntensityTable intensity;
  const mtpt::TransferFunctionTable tf{ table.data(), 4, 0.0, 1.0 };
  mtpt::CompositeSettings s = mtpt::CompositeSettingsFor(a, tf, integrals, intensity, 2.0);
  EXPECT_EQ(s.shading, Shading::PreIntegrated);
  EXPECT_EQ(s.preIntegration, &integrals);
  EXPECT_EQ(s.intensity, nullptr);
  EXPECT_EQ(s.unitDistance, 2.0);
  EXPECT_EQ(s.width, a.imageSize.width);
  settings.shading = Shading::VTKCompatible;
  settings.blendMode = static_cast<int>(BlendMode::AverageIntensity);
  s = mtpt::CompositeSettingsFor(mtpt::PlanFrame(settings, facts), tf, integrals, intensity, 1);
  EXPECT_EQ(s.shading, Shading::VTKCompatible);
  EXPECT_EQ(s.preIntegration, nullptr);
  EXPECT_EQ(s.intensity, &intensity);
  EXPECT_EQ(s.blendMode, BlendMode::AverageIntensity);
}

/// A frame of a jittered grid from an oblique view, planned for `target`.
struct PlannedFrame
{
  TetMesh mesh = JitteredGrid(7, 3);
  std::vector<float> normals;
  mtpt::FrameInput input;
  mtpt::FramePlan plan;

  PlannedFrame(BatchTarget target, std::size_t batch, bool lit)
  {
    input.points = mesh.Points();
    input.cells = mesh.Cells();
    input.scalars = { mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    input.modelView = LookAt({ 0.7, 1.1, 2.6 }, { 0.1, 0, 0 }, { 0, 1, 0 });
    input.projection = mtpt::test::Perspective(40, 1.0, 0.5, 10);
    input.perspective = true;
    mtpt::FrameSettings settings;
    settings.batchSize = batch;
    settings.threads = 2;
    settings.shade = lit;
    mtpt::FrameFacts facts;
    facts.points = input.points.count;
    facts.cells = input.cells.cellCount;
    facts.target = target;
    facts.viewport[0] = facts.viewport[1] = 64;
    facts.centresOnly = facts.sampledCentresOnly = true;
    facts.projection = input.projection;
    plan = mtpt::PlanFrame(settings, facts);
    mtpt::ApplyPlan(plan, input);
    normals.assign(3 * input.cells.cellCount, 0.0f);
    for (std::size_t c = 0; c < input.cells.cellCount; ++c)
    {
      normals[3 * c + c % 3] = 1.0f;
    }
    input.normals = normals.data();
    input.normalsVersion = 1;
  }
};

TEST(FramePlan, TheCompositorsCompositeBatchesGoFrontToBack)
{
  mtpt::FrameSettings settings;
  mtpt::FrameFacts facts = Facts();
  EXPECT_TRUE(mtpt::PlanFrame(settings, facts).frontToBack);
  settings.shading = Shading::PreIntegrated;
  EXPECT_TRUE(mtpt::PlanFrame(settings, facts).frontToBack);
  // OpenGL blends back to front; the reductions fold in any order.
  facts.target = BatchTarget::Slots;
  EXPECT_FALSE(mtpt::PlanFrame(settings, facts).frontToBack);
  facts.target = BatchTarget::Fans;
  settings.shading = Shading::VTKCompatible;
  for (const BlendMode mode : { BlendMode::MaximumIntensity, BlendMode::MinimumIntensity,
         BlendMode::AverageIntensity, BlendMode::Additive })
  {
    settings.blendMode = static_cast<int>(mode);
    EXPECT_FALSE(mtpt::PlanFrame(settings, facts).frontToBack);
  }
}

TEST(FramePipelineBatches, DrawBatchesGivesTheWindowsOfTheOrderInOrder)
{
  for (const BatchTarget target : { BatchTarget::Fans, BatchTarget::Slots })
  {
    for (const std::size_t batch : { std::size_t{ 0 }, std::size_t{ 1 }, std::size_t{ 97 } })
    {
      PlannedFrame frame(target, batch, false);
      // The compositor's fans front to back, OpenGL's slots back to front.
      EXPECT_EQ(frame.plan.frontToBack, target == BatchTarget::Fans);
      mtpt::FramePipeline pipeline, whole;
      ASSERT_TRUE(pipeline.Prepare(frame.input, 2));
      ASSERT_TRUE(whole.Prepare(frame.input, 2));
      const std::size_t total = pipeline.SortedCount();
      ASSERT_GT(total, 100u);
      const std::size_t size = batch > 0 ? batch : total;
      const std::size_t windows = (total + size - 1) / size;
      std::size_t given = 0;
      const mtpt::BatchesDrawn drawn = pipeline.DrawBatches(frame.plan,
        [&](const mtpt::Batch& b)
        {
          const std::size_t w = frame.plan.frontToBack ? windows - 1 - given : given;
          EXPECT_EQ(b.first, w * size);
          EXPECT_EQ(b.lights, nullptr);
          EXPECT_EQ(b.count, std::min(size, total - b.first));
          // The same window decomposed on its own gives the same records.
          if (target == BatchTarget::Fans)
          {
            whole.DecomposeFans(b.first, b.count, 1);
            EXPECT_EQ(std::memcmp(b.fans, whole.Fans().data(), b.count * sizeof(mtpt::Fan)), 0);
            EXPECT_EQ(std::memcmp(b.classes, whole.FanClasses(), b.count), 0);
          }
          else
          {
            whole.DecomposeBatch(b.first, b.count, 1);
            EXPECT_EQ(std::memcmp(b.vertices, whole.Vertices().data(),
                        b.count * mtpt::VerticesPerTetrahedron * sizeof(mtpt::TetVertex)),
              0);
          }
          ++given;
          return true;
        });
      EXPECT_EQ(given, windows);
      EXPECT_FALSE(drawn.stopped || drawn.failed);
      EXPECT_EQ(static_cast<std::size_t>(drawn.batches), windows);
    }
  }
}

TEST(FramePipelineBatches, CellsBehindThePixelsEarlierBatchesMadeOpaqueAreNotDecomposed)
{
  PlannedFrame frame(BatchTarget::Fans, 97, false);
  ASSERT_TRUE(frame.plan.frontToBack);
  mtpt::FramePipeline pipeline, whole;
  ASSERT_TRUE(pipeline.Prepare(frame.input, 2));
  ASSERT_TRUE(whole.Prepare(frame.input, 2));
  const std::size_t total = pipeline.SortedCount();
  ASSERT_GT(total, 4 * 97u);
  // The left half of the image opaque once two batches are drawn.
  mtpt::OpaquePixels opaque;
  opaque.Reset(frame.plan.imageSize.width, frame.plan.imageSize.height);
  const int half = opaque.Width() / 2;
  int given = 0;
  std::size_t hidden = 0, drawnFans = 0;
  pipeline.DrawBatches(
    frame.plan,
    [&](const mtpt::Batch& b)
    {
      whole.DecomposeFans(b.first, b.count, 1);
      for (std::size_t k = 0; k < b.count; ++k)
      {
        const mtpt::ProjectionClass kind = b.classes[k];
        if (given < 2)
        {
          // Nothing opaque yet: every fan as the window decomposed alone.
          EXPECT_EQ(kind, whole.FanClasses()[k]);
        }
        // The last pixel centre its box reaches, in window x (the fan as drawn alone).
        const mtpt::Fan& f = whole.Fans()[k];
        float maxX = f.centre.x;
        for (int c = 0; c < f.count; ++c)
        {
          maxX = std::max(maxX, f.boundary[c].x);
        }
        const float reach = (maxX + 1.0f) * 0.5f * static_cast<float>(opaque.Width()) - 0.5f;
        if (kind == mtpt::ProjectionClass::Hidden)
        {
          // Hidden only where its box lies in the opaque half.
          ++hidden;
          EXPECT_TRUE(mtpt::Drawn(whole.FanClasses()[k]));
          EXPECT_LT(reach, half + 0.01f);
          continue;
        }
        // Every other fan written, as the window decomposed alone; once the half is opaque,
        // those drawn reach past it.
        EXPECT_EQ(kind, whole.FanClasses()[k]);
        if (mtpt::Drawn(kind))
        {
          ++drawnFans;
          EXPECT_EQ(std::memcmp(b.fans + k, whole.Fans().data() + k, sizeof(mtpt::Fan)), 0);
          if (given >= 2)
          {
            EXPECT_GT(reach, half - 0.02f);
          }
        }
      }
      if (++given == 2)
      {
        for (int y = 0; y < opaque.Height(); ++y)
        {
          opaque.Row(y)[0] = (std::uint64_t{ 1 } << half) - 1;
        }
        opaque.Marked(true);
      }
      return true;
    },
    &opaque);
  EXPECT_GT(hidden, 0u);
  EXPECT_GT(drawnFans, 0u);
  EXPECT_EQ(pipeline.Stats().hidden, hidden);
}

TEST(FramePipelineBatches, TheCallbackStopsAndAFailedBatchEndsTheLoop)
{
  PlannedFrame frame(BatchTarget::Fans, 50, false);
  mtpt::FramePipeline pipeline;
  ASSERT_TRUE(pipeline.Prepare(frame.input, 2));
  std::vector<double> fractions;
  pipeline.SetBatchCallback(
    [&](double fraction)
    {
      fractions.push_back(fraction);
      return fractions.size() < 2;
    });
  int draws = 0;
  mtpt::BatchesDrawn drawn = pipeline.DrawBatches(frame.plan,
    [&](const mtpt::Batch&)
    {
      ++draws;
      return true;
    });
  EXPECT_TRUE(drawn.stopped);
  EXPECT_FALSE(drawn.failed);
  EXPECT_EQ(draws, 2);
  ASSERT_EQ(fractions.size(), 2u);
  EXPECT_DOUBLE_EQ(fractions[0], 50.0 / pipeline.SortedCount());
  pipeline.SetBatchCallback({});
  draws = 0;
  drawn = pipeline.DrawBatches(frame.plan, [&](const mtpt::Batch&) { return ++draws < 3; });
  EXPECT_TRUE(drawn.failed);
  EXPECT_FALSE(drawn.stopped);
  EXPECT_EQ(draws, 3);
  EXPECT_EQ(drawn.batches, 3);
}

TEST(FramePipelineBatches, LitBatchesCarryTheirCellsLightingKeptWhileNothingChanges)
{
  for (const BatchTarget target : { BatchTarget::Fans, BatchTarget::Slots })
  {
    PlannedFrame frame(target, 0, true);
    ASSERT_TRUE(frame.plan.lit && frame.input.lit);
    mtpt::FramePipeline pipeline;
    pipeline.SetReuse(true);
    ASSERT_TRUE(pipeline.Prepare(frame.input, 2));
    std::vector<mtpt::LightFactors> expected;
    pipeline.LightWindow(0, pipeline.SortedCount(), frame.input.lighting, frame.normals.data(),
      frame.input.modelView, expected, 1);
    std::uint64_t version = 0;
    const auto check = [&](const mtpt::Batch& b)
    {
      EXPECT_NE(b.lights, nullptr);
      EXPECT_EQ(b.count, expected.size());
      EXPECT_EQ(std::memcmp(b.lights, expected.data(), b.count * sizeof(mtpt::LightFactors)), 0);
      version = b.lightsVersion;
      return true;
    };
    pipeline.DrawBatches(frame.plan, check);
    const std::uint64_t first = version;
    EXPECT_NE(first, 0u);
    // A frame that changes nothing keeps the lighting; new normals light again.
    ASSERT_TRUE(pipeline.Prepare(frame.input, 2));
    pipeline.DrawBatches(frame.plan, check);
    EXPECT_EQ(version, first);
    frame.input.normalsVersion = 2;
    ASSERT_TRUE(pipeline.Prepare(frame.input, 2));
    pipeline.DrawBatches(frame.plan, check);
    EXPECT_NE(version, first);
  }
}

} // namespace
