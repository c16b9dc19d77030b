// SPDX-License-Identifier: BSD-3-Clause
// Allocation failures partway through a frame (mtpt/Faults.h): at each allocation site of the
// pipeline and the compositor, after earlier stages of the same frame have computed and
// cached their results, the failure reaches the caller as std::bad_alloc and the next frame
// is the one a fresh pipeline and compositor draw, bit for bit.
#include "TestHelpers.h"

#include "mtpt/Compositor.h"
#include "mtpt/Faults.h"
#include "mtpt/FramePipeline.h"
#include "mtpt/FramePlan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <new>
#include <string>
#include <vector>

namespace
{

using mtpt::AllocationSite;

/// A jittered grid seen in perspective from close by: the near plane cuts cells, the
/// opacity table culls some, and a moving frame's level of detail leaves some out.
struct FaultScene
{
  static constexpr int Size = 40;
  mtpt::test::TetMesh mesh = mtpt::test::JitteredGrid(8, 21);
  std::vector<float> table;
  std::uint64_t dataVersion = 1;

  FaultScene()
  {
    for (int i = 0; i < 64; ++i)
    {
      const float t = static_cast<float>(i) / 63;
      this->table.insert(this->table.end(), { t, 0.5f, 1 - t, t < 0.3f ? 0.0f : 2 * t });
    }
  }

  mtpt::FrameInput Input(double azimuth, double cellFraction) const
  {
    mtpt::FrameInput input;
    input.points = this->mesh.Points();
    input.cells = this->mesh.Cells();
    input.scalars = { this->mesh.scalars.data(), mtpt::ScalarsView::Association::Points };
    const double r = 3.0;
    input.modelView = mtpt::test::LookAt(
      { r * std::sin(azimuth), 0.7, r * std::cos(azimuth) }, { 0, 0, 0 }, { 0, 1, 0 });
    input.projection = mtpt::test::Perspective(50, 1.0, 2.6, 8);
    input.perspective = true;
    input.imageSize = { Size, Size };
    input.opacity = { this->table.data(), 64, -2.0, 3.0 };
    input.cellFraction = cellFraction;
    input.dataVersion = this->dataVersion;
    input.opacityVersion = 1;
    return input;
  }

  mtpt::CompositeSettings Settings(const mtpt::FrameInput& input) const
  {
    mtpt::CompositeSettings s;
    s.width = s.height = Size;
    s.transferFunction = { this->table.data(), 64, -2.0, 3.0 };
    s.unitDistance = 0.4;
    s.interpolation = mtpt::PerspectiveInterpolation::FromProjection(input.projection);
    s.clipping = mtpt::DepthClipping::FromProjection(input.projection);
    return s;
  }
};

/// Fans in batches of 150 cells: a frame takes several, so a fault can come between two.
mtpt::FramePlan Plan()
{
  mtpt::FramePlan plan;
  plan.target = mtpt::BatchTarget::Fans;
  plan.batchSize = 150;
  return plan;
}

/**
 * One frame as the CPU backend draws it: the level of detail's analysis, the stages, the
 * batches composited as they come. `afterFirstBatch` runs once the first batch is
 * composited (to inject a fault there). Returns the premultiplied RGBA image.
 */
std::vector<float> Frame(mtpt::FramePipeline& pipeline, mtpt::Compositor& compositor,
  const FaultScene& scene, const mtpt::FrameInput& input, AllocationSite afterFirstBatch)
{
  const mtpt::CompositeSettings settings = scene.Settings(input);
  pipeline.PrepareLevelOfDetail(input, 2);
  EXPECT_TRUE(pipeline.Prepare(input, 2));
  compositor.Begin(settings);
  int batches = 0;
  const mtpt::BatchesDrawn drawn = pipeline.DrawBatches(Plan(),
    [&](const mtpt::Batch& batch)
    {
      compositor.Composite(batch.fans, batch.count, 2);
      if (++batches == 1)
      {
        mtpt::InjectAllocationFault(afterFirstBatch);
      }
      return true;
    });
  EXPECT_FALSE(drawn.failed || drawn.stopped);
  std::vector<float> image(4 * FaultScene::Size * FaultScene::Size);
  compositor.Resolve({ 0, 0, settings.width, settings.height }, nullptr, image.data(), 2);
  return image;
}

bool SameImage(const std::vector<float>& a, const std::vector<float>& b)
{
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

struct FaultCase
{
  AllocationSite site;
  bool moving;   ///< a moving frame: the level of detail draws half the cells
  bool newData;  ///< the faulty frame has new data (every stage computes again)
  bool midFrame; ///< injected after the first batch, not before the frame
};

class PipelineFaults : public ::testing::TestWithParam<FaultCase>
{
protected:
  void TearDown() override { mtpt::InjectAllocationFault(AllocationSite::None); }
};

TEST_P(PipelineFaults, ReachTheCallerAndTheNextFrameIsAFreshPipelines)
{
  const FaultCase c = GetParam();
  const double fraction = c.moving ? 0.5 : 1.0;
  FaultScene scene;
  mtpt::FramePipeline pipeline;
  pipeline.SetReuse(true);
  mtpt::Compositor compositor;

  // A whole frame first: every stage holds a result.
  const mtpt::FrameInput whole = scene.Input(0.2, fraction);
  Frame(pipeline, compositor, scene, whole, AllocationSite::None);
  ASSERT_GT(pipeline.Stats().nearClipped, 0u) << "the near plane must cut cells";
  ASSERT_GT(pipeline.Stats().opacityCulled, 0u);

  // The view turns (and the data may change): the fault comes at its site partway through.
  if (c.newData)
  {
    ++scene.dataVersion;
  }
  const mtpt::FrameInput input = scene.Input(0.5, fraction);
  if (!c.midFrame)
  {
    mtpt::InjectAllocationFault(c.site);
  }
  EXPECT_THROW(
    Frame(pipeline, compositor, scene, input, c.midFrame ? c.site : AllocationSite::None),
    std::bad_alloc)
    << mtpt::AllocationSiteName(c.site);
  mtpt::InjectAllocationFault(AllocationSite::None);

  // The failed frame again, then the whole frame's, whose results the stages held before the
  // failure (nothing half written may serve as either): each as a fresh pipeline and
  // compositor draw it.
  for (const mtpt::FrameInput& again : { input, whole })
  {
    const std::vector<float> image =
      Frame(pipeline, compositor, scene, again, AllocationSite::None);
    mtpt::FramePipeline freshPipeline;
    mtpt::Compositor freshCompositor;
    const std::vector<float> fresh =
      Frame(freshPipeline, freshCompositor, scene, again, AllocationSite::None);
    EXPECT_EQ(pipeline.Keys(), freshPipeline.Keys()) << mtpt::AllocationSiteName(c.site);
    EXPECT_TRUE(SameImage(image, fresh)) << mtpt::AllocationSiteName(c.site);
  }
}

std::string CaseName(const ::testing::TestParamInfo<FaultCase>& info)
{
  std::string name = mtpt::AllocationSiteName(info.param.site);
  for (char& ch : name)
  {
    ch = ch == '-' ? '_' : ch;
  }
  return name + (info.param.moving ? "_moving" : "") + (info.param.newData ? "_newData" : "") +
    (info.param.midFrame ? "_midFrame" : "");
}

INSTANTIATE_TEST_SUITE_P(EverySite, PipelineFaults,
  ::testing::Values(FaultCase{ AllocationSite::Transform, false, false, false },
    FaultCase{ AllocationSite::Culling, false, true, false },
    FaultCase{ AllocationSite::LevelOfDetail, true, true, false },
    FaultCase{ AllocationSite::DepthKeys, false, false, false },
    FaultCase{ AllocationSite::DepthKeys, true, true, false },
    FaultCase{ AllocationSite::NearPlane, false, false, false },
    FaultCase{ AllocationSite::Order, false, false, false },
    FaultCase{ AllocationSite::Order, true, true, false },
    FaultCase{ AllocationSite::Decomposition, false, false, true },
    FaultCase{ AllocationSite::Tiles, false, false, true }),
  CaseName);

} // namespace
