// Exact Euclidean distance transform of a grid: the squared distance from
// every cell centre to the centre of the nearest "source" cell, in O(cells).
// Used for obstacle inflation (core/map/inflation.h) and the potential field's
// obstacle distance.
//
// Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled Functions",
// Theory of Computing 8 (2012): a 1-D pass down each column, then the lower
// envelope of parabolas along each row. All arithmetic is on integers
// (squared distances between cell centres are integers, and the envelope's
// breakpoints are compared as exact fractions), so the result is exact.
// Bounded transforms (only distances up to a small radius matter) replace the
// row pass with a vectorised window minimum, and the thresholded transform
// (inside the radius or not, for inflation) with painted disc chords.
#ifndef PATHD_CORE_MAP_EUCLIDEAN_DISTANCE_H_
#define PATHD_CORE_MAP_EUCLIDEAN_DISTANCE_H_

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/map/grid.h"

namespace pathd {

// Which cells the distances are measured to.
struct DistanceSources {
  // by_cost[c]: every cell of cost c is a source.
  std::array<bool, 256> by_cost{};
  // The ring of cells just outside the grid (x = -1 or width, y = -1 or
  // height) are sources too, so distances also measure clearance from the
  // map edge.
  bool border = false;
};

// Sources are the cells of exactly the given cost.
DistanceSources SourcesOfCost(uint8_t cost);

// The largest integer n with n <= radius^2 in exact arithmetic, so that an
// integer squared distance d2 is within the radius (inclusive) exactly when
// d2 <= n: the bound to give the transforms below for "within radius".
// Radii beyond any grid's diagonal are clamped to 2^40. Precondition:
// radius finite and >= 0.
int64_t SquaredRadiusBound(double radius);

// Reusable working memory for the transform; the buffers grow to the largest
// grid seen and are then reused, so repeated transforms do not allocate. Not
// thread-safe: one per thread.
class EuclideanDistanceField {
 public:
  // Marks "no source within the requested bound" (or no source at all).
  static constexpr int64_t kFar = std::numeric_limits<int64_t>::max();

  // Squared distances, cells^2, row-major, one per cell of `grid`; entries
  // greater than max_squared are kFar. A bound makes the transform cheaper:
  // sources further away than it are never considered. The returned vector
  // is owned by this object and valid until the next call.
  const std::vector<int64_t>& Compute(const Grid& grid,
                                      const DistanceSources& sources,
                                      int64_t max_squared = kFar);

  // As Compute, without storing the result: calls sink(y, row) for y = 0 ..
  // height-1 in order, where row points at the width squared distances of
  // row y, valid only during the call.
  template <typename RowSink>
  void ForEachRow(const Grid& grid, const DistanceSources& sources,
                  int64_t max_squared, RowSink&& sink) {
    ForEachRowIn(grid, sources, max_squared, 0, grid.height() - 1, sink);
  }
  // As ForEachRow for rows first_row .. last_row only (the distances still
  // count every source of the grid): a window's rows cost only their own
  // row pass.
  template <typename RowSink>
  void ForEachRowIn(const Grid& grid, const DistanceSources& sources,
                    int64_t max_squared, int32_t first_row, int32_t last_row,
                    RowSink&& sink) {
    const int64_t bound = Prepare(grid, sources, max_squared);
    for (int32_t y = first_row; y <= last_row; ++y) {
      DistanceRow(y, grid.width(), sources.border, bound);
      sink(y, static_cast<const int64_t*>(row_.data()));
    }
  }

  // The transform thresholded: calls sink(y, within) for y = 0 .. height-1
  // in order, where within[x] is 1 when cell (x, y) is within squared
  // distance max_squared of a source and 0 otherwise, valid only during the
  // call. Several times cheaper than the distances: each column paints the
  // chord its nearest source's disc cuts from the row, instead of the row
  // pass building an envelope of parabolas.
  template <typename RowSink>
  void ForEachRowWithin(const Grid& grid, const DistanceSources& sources,
                        int64_t max_squared, RowSink&& sink) {
    ForEachRowWithinIn(grid, sources, max_squared, 0, grid.height() - 1, sink);
  }
  // As ForEachRowWithin for rows first_row .. last_row only.
  template <typename RowSink>
  void ForEachRowWithinIn(const Grid& grid, const DistanceSources& sources,
                          int64_t max_squared, int32_t first_row, int32_t last_row,
                          RowSink&& sink) {
    PrepareChords(Prepare(grid, sources, max_squared));
    for (int32_t y = first_row; y <= last_row; ++y) {
      ChordRow(y, grid.width(), sources.border);
      sink(y, static_cast<const uint8_t*>(within_.data()));
    }
  }

 private:
  // Runs the column pass into column_, chooses the row pass (window_) and
  // returns the effective bound.
  int64_t Prepare(const Grid& grid, const DistanceSources& sources,
                  int64_t max_squared);
  // Fills row_ with the squared distances of row y from column_, by
  // WindowRow for small bounds and LowerEnvelopeRow otherwise.
  void DistanceRow(int32_t y, int32_t width, bool border, int64_t bound);
  void LowerEnvelopeRow(int32_t y, int32_t width, bool border, int64_t bound);
  void WindowRow(int32_t y, int32_t width, bool border, int64_t bound);
  // Fills half_width_ for ChordRow.
  void PrepareChords(int64_t bound);
  // Fills within_ for row y from column_ and half_width_.
  void ChordRow(int32_t y, int32_t width, bool border);

  // Vertical distance, in cells, from each cell to the nearest source in its
  // column (kNoneInColumn when there is none).
  std::vector<int32_t> column_;
  // The envelope: parabola apexes, their heights, and the left end of each
  // parabola's interval as the fraction start_num_ / start_den_.
  std::vector<int32_t> apex_;
  std::vector<int64_t> apex_height_;
  std::vector<int64_t> start_num_;
  std::vector<int64_t> start_den_;
  std::vector<int64_t> row_;
  std::vector<int64_t> result_;
  // WindowRow's radius, floor(sqrt(bound)), or -1 when the bound is too
  // large for it; its padded row of squared column distances and minima.
  int32_t window_ = -1;
  std::vector<int32_t> padded_;
  std::vector<int32_t> window_min_;
  // half_width_[g]: the largest h with g^2 + h^2 <= bound, or -1, for column
  // distances g up to chord_limit_; larger g share the last entry (-1).
  std::vector<int32_t> half_width_;
  int32_t chord_limit_ = 0;
  std::vector<uint8_t> within_;
};

// Squared Euclidean distance, cells^2, from each cell centre to the centre of
// the nearest source, row-major; +infinity everywhere when there is no source.
// Exact (squared distances are integers, represented exactly in a double).
// Allocates its working memory; use EuclideanDistanceField to reuse it.
std::vector<double> SquaredDistanceToNearest(const Grid& grid,
                                             const DistanceSources& sources);

}  // namespace pathd

#endif  // PATHD_CORE_MAP_EUCLIDEAN_DISTANCE_H_
