// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file OpaquePixels.h
 * @brief The pixels of an image being composited front to back that hide whatever lies
 * behind them: the CPU compositor marks them (Compositor.h) and the decomposition of the
 * cells behind them reads them (Decompose.h, DecomposeInput::hidden), so that a cell every
 * one of whose pixels is already opaque is neither decomposed nor drawn
 * (Documentation/algorithm.md, "Batches front to back").
 *
 * Conventions: pixel (x, y) of the image, row 0 at the bottom, as the compositor's
 * (Compositor.h). A pixel is opaque once its coverage alpha reached OpaqueAlpha: a fragment
 * behind it could add at most 1 - OpaqueAlpha of full intensity, and every path of the
 * compositor skips such fragments, so skipping their cells changes no pixel. Alpha only grows
 * while fragments are composited front to back, so a pixel once opaque stays so.
 */
#ifndef mtpt_OpaquePixels_h
#define mtpt_OpaquePixels_h

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mtpt
{

/**
 * The coverage alpha at which a pixel hides what lies behind it: 2^-11 below 1, an eighth
 * of an 8-bit step of what could still reach it.
 */
constexpr float OpaqueAlpha = 1.0f - 1.0f / 2048;

/**
 * A bit per pixel of an image: set where the pixel is opaque (OpaqueAlpha). Each row is
 * stored as 64-bit words, pixel x in bit x % 64 of word x / 64, so that one word is one row
 * of one of the compositor's tiles (TileSize, Records.h).
 * Thread safety: Hides and the getters may run on any number of threads together; the
 * writers need the caller's exclusion (threads writing different words may run together).
 */
class OpaquePixels
{
public:
  static constexpr int BitsPerWord = 64;

  /// An image of width x height pixels, none opaque; the version changes.
  void Reset(int width, int height);

  int Width() const { return this->ImageWidth; }
  int Height() const { return this->ImageHeight; }
  /// Words per row: ceil(width / 64).
  int WordsPerRow() const { return this->RowWords; }
  /// The words of row y (WordsPerRow() of them), for the compositor to mark.
  std::uint64_t* Row(int y)
  {
    return this->Bits.data() + static_cast<std::size_t>(y) * this->RowWords;
  }
  const std::uint64_t* Row(int y) const
  {
    return this->Bits.data() + static_cast<std::size_t>(y) * this->RowWords;
  }

  /// Whether no pixel is opaque, as the marker said with Marked (Reset: none).
  bool Empty() const { return !this->AnyOpaque; }
  /**
   * After the compositor changed the bits: whether any pixel is now opaque. The version
   * changes, so that what was computed from the earlier bits is stale.
   */
  void Marked(bool anyOpaque);

  /**
   * Changes whenever the bits may have changed (Reset, Marked); never 0. Results computed
   * from the bits (a decomposed batch) key on it.
   */
  std::uint64_t Version() const { return this->Stamp; }

  /**
   * Whether every pixel of the box [x0, x1] x [y0, y1] is opaque. The box is clamped to the
   * image first; an empty box (or one wholly outside the image) hides nothing: false.
   */
  bool Hides(int x0, int x1, int y0, int y1) const;

  /// Bytes held (capacity).
  std::size_t MemoryBytes() const { return this->Bits.capacity() * sizeof(std::uint64_t); }
  /// Frees the bits (an empty image).
  void Release();

private:
  int ImageWidth = 0, ImageHeight = 0, RowWords = 0;
  std::vector<std::uint64_t> Bits;
  bool AnyOpaque = false;
  std::uint64_t Stamp = 1;
};

inline bool OpaquePixels::Hides(int x0, int x1, int y0, int y1) const
{
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, this->ImageWidth - 1);
  y1 = std::min(y1, this->ImageHeight - 1);
  if (!this->AnyOpaque || x0 > x1 || y0 > y1)
  {
    return false;
  }
  const int first = x0 / BitsPerWord, last = x1 / BitsPerWord;
  // The bits of the box in its first and last word (one word: both masks apply).
  const std::uint64_t all = ~std::uint64_t{ 0 };
  const std::uint64_t head = all << (x0 % BitsPerWord);
  const std::uint64_t tail = all >> (BitsPerWord - 1 - x1 % BitsPerWord);
  for (int y = y0; y <= y1; ++y)
  {
    const std::uint64_t* row = this->Row(y);
    for (int w = first; w <= last; ++w)
    {
      const std::uint64_t want = (w == first ? head : all) & (w == last ? tail : all);
      if ((row[w] & want) != want)
      {
        return false;
      }
    }
  }
  return true;
}

} // namespace mtpt

#endif
