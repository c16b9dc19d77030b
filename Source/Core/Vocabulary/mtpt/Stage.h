// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Stage.h
 * @brief What every stage of a frame keeps besides its result: the key it was computed from
 * and a version that changes whenever the result does (Documentation/architecture.md,
 * "The stages of a frame").
 *
 * A stage's key is a small struct with operator== holding every input its result depends
 * on, inputs from earlier stages included as their versions; it is defined beside the stage
 * (TransformKey beside TransformStage), and FramePipeline builds each one in one function.
 * The stage recomputes exactly when this frame's key differs from the one it holds (or it
 * holds none), so adding an input to a stage is one field in its key. Versions let a later
 * stage, a backend or a cache depend on a result without comparing it: equal versions mean
 * an equal result.
 */
#ifndef mtpt_Stage_h
#define mtpt_Stage_h

#include <cstddef>
#include <cstdint>

namespace mtpt
{

template <typename Key>
class StageRecord
{
public:
  /// Whether the result was computed from `key` (and not forgotten since).
  bool Holds(const Key& key) const { return this->Current && this->Computed == key; }

  /**
   * Stores that the result was computed from `key`. `changed` false keeps the version: the
   * new result equals the previous one (a stage that can tell, such as culling after a
   * colour-only change of the transfer function, saves the later stages their work).
   */
  void Store(const Key& key, bool changed = true)
  {
    this->Computed = key;
    this->Current = true;
    if (changed || this->Number == 0)
    {
      ++this->Number;
    }
  }

  /// The result may no longer be used (freed, or left incomplete): the next frame
  /// recomputes it, and a later result gets a new version.
  void Forget()
  {
    if (this->Current)
    {
      ++this->Number;
    }
    this->Current = false;
  }

  bool Valid() const { return this->Current; }
  /// The key the result was computed from (meaningful only while Valid()).
  const Key& Inputs() const { return this->Computed; }
  /// Changes whenever the result changes; 0 before the first.
  std::uint64_t Version() const { return this->Number; }

private:
  Key Computed{};
  bool Current = false;
  std::uint64_t Number = 0;
};

/**
 * What every stage of a frame offers the pipeline that runs it (FramePipeline), which keeps
 * them in one list: forget the result (the next frame recomputes it and gives it a new
 * version), free every buffer, and count the bytes the buffers hold (capacity, not size).
 */
class StageBase
{
public:
  virtual ~StageBase() = default;
  virtual void Forget() = 0;
  virtual void Release() = 0;
  virtual std::size_t MemoryBytes() const = 0;
};

/**
 * A stage whose result is computed from a Key (a struct with operator==, defined beside the
 * stage): the one place that holds its record and gives its version and forgetting. A
 * stage that keeps more than one result overrides Forget to forget them all.
 */
template <typename KeyType>
class StageOf : public StageBase
{
public:
  using Key = KeyType;
  /// Changes whenever the result changes; 0 before the first.
  std::uint64_t Version() const { return this->Record.Version(); }
  /// Whether the result was computed from `key`: the next Update with it computes nothing.
  bool Holds(const Key& key) const { return this->Record.Holds(key); }
  void Forget() override { this->Record.Forget(); }

protected:
  StageRecord<Key> Record;
};

/// The stages of a frame after which FramePipeline reports progress (a StageCallback,
/// FramePipeline.h); Cull includes the level of detail's subset.
enum class Stage
{
  Transform,
  Cull,
  DepthKeys,
  Order,
};

} // namespace mtpt

#endif
