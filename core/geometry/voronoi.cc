#include "core/geometry/voronoi.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/geometry/structure.h"
#include "core/map/cost_model.h"

namespace pathd {
namespace {

// Sign of p + q * sqrt(2) for integers far below 2^31: exact, because
// p^2 = 2 q^2 only for p = q = 0.
int SignPlusRoot2(int64_t p, int64_t q) {
  if (p >= 0 && q >= 0) return (p | q) != 0 ? 1 : 0;
  if (p <= 0 && q <= 0) return -1;
  const int64_t pp = p * p;
  const int64_t qq = 2 * q * q;
  return p > 0 ? (pp > qq ? 1 : -1) : (qq > pp ? 1 : -1);
}

constexpr int kDx8[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy8[8] = {0, 0, 1, -1, 1, -1, 1, -1};

}  // namespace

OctileLength OctileLength::Between(int64_t dx, int64_t dy) {
  dx = std::abs(dx);
  dy = std::abs(dy);
  return {std::max(dx, dy) - std::min(dx, dy), std::min(dx, dy)};
}

double OctileLength::value() const {
  return static_cast<double>(straight) + static_cast<double>(diagonal) * kSqrt2;
}

int Compare(const OctileLength& a, const OctileLength& b) {
  return SignPlusRoot2(a.straight - b.straight, a.diagonal - b.diagonal);
}

VoronoiField::VoronoiField(int32_t width, int32_t height, bool unknown_is_free)
    : width_(width),
      height_(height),
      stride_(width + 2),
      unknown_is_free_(unknown_is_free),
      site_(static_cast<size_t>(stride_) * (height + 2), kCleared),
      flags_(site_.size(), kBlockedBit) {}

VoronoiField::VoronoiField(const Grid& grid, bool unknown_is_free)
    : VoronoiField(grid.width(), grid.height(), unknown_is_free) {
  Fill(grid, nullptr);
}

std::shared_ptr<const VoronoiField> VoronoiField::Build(const Grid& grid,
                                                        bool unknown_is_free,
                                                        DerivedStop& stop) {
  std::shared_ptr<VoronoiField> field(
      new VoronoiField(grid.width(), grid.height(), unknown_is_free));
  if (!field->Fill(grid, &stop)) {
    stop.Note(absl::StrFormat(
        "building the Voronoi field of this map version (%d x %d cells)",
        grid.width(), grid.height()));
    return nullptr;
  }
  return field;
}

bool VoronoiField::Fill(const Grid& grid, DerivedStop* stop) {
  // Row by row, a poll per kPollCells cells.
  const int32_t poll_rows = std::max(1, kPollCells / stride_);
  auto stopped = [&](int32_t y) {
    return stop != nullptr && y % poll_rows == 0 && stop->Stopped();
  };
  for (int32_t y = 0; y < height_; ++y) {
    if (stopped(y)) return false;
    for (int32_t x = 0; x < width_; ++x) {
      if (Traversable(grid.cost(x, y), unknown_is_free_)) {
        flags_[Index(Cell{x, y})] = 0;
      }
    }
  }
  // Obstacles are their own nearest obstacle; only those beside free space
  // can be anyone else's (a nearest obstacle's neighbour on the way to it is
  // free), so only they start the wave.
  for (int32_t y = -1; y <= height_; ++y) {
    if (stopped(y + 1)) return false;
    for (int32_t x = -1; x <= width_; ++x) {
      const int32_t i = Index(Cell{x, y});
      if (!BlockedAt(i)) continue;
      site_[i] = i;
      for (int k = 0; k < 8; ++k) {
        const int32_t nx = x + kDx8[k];
        const int32_t ny = y + kDy8[k];
        if (InPadded(nx, ny) && !BlockedAt(Index(Cell{nx, ny}))) {
          Push(i);
          break;
        }
      }
    }
  }
  if (!Lower(nullptr, stop)) return false;
  for (int32_t y = 0; y < height_; ++y) {
    if (stopped(y)) return false;
    for (int32_t x = 0; x < width_; ++x) SetDiagramBit(Index(Cell{x, y}));
  }
  return true;
}

OctileLength VoronoiField::Between(int32_t a, int32_t b) const {
  return OctileLength::Between(a % stride_ - b % stride_,
                               a / stride_ - b / stride_);
}

OctileLength VoronoiField::Distance(Cell c) const {
  const int32_t i = Index(c);
  return Between(i, site_[i]);
}

void VoronoiField::Push(int32_t cell) {
  const auto bucket = static_cast<size_t>(Between(cell, site_[cell]).value());
  if (bucket >= buckets_.size()) buckets_.resize(bucket + 1);
  buckets_[bucket].push_back(Entry{site_[cell], cell});
  first_bucket_ = std::min(first_bucket_, bucket);
}

bool VoronoiField::Lower(std::vector<int32_t>* touched, DerivedStop* stop) {
  // Label-correcting: the order (nearest first) only saves work; a cell
  // offered a better site is queued again, so the waves end at the unique
  // fixed point whatever was queued.
  for (int64_t pops = 0;; ++pops) {
    if (stop != nullptr && pops % kPollCells == 0 && stop->Stopped()) return false;
    while (first_bucket_ < buckets_.size() && buckets_[first_bucket_].empty()) {
      ++first_bucket_;
    }
    if (first_bucket_ == buckets_.size()) break;
    const Entry e = buckets_[first_bucket_].back();
    buckets_[first_bucket_].pop_back();
    if (site_[e.cell] != e.site) continue;  // superseded
    const int32_t x = e.cell % stride_;
    const int32_t y = e.cell / stride_;
    for (int k = 0; k < 8; ++k) {
      const int32_t nx = x + kDx8[k];
      const int32_t ny = y + kDy8[k];
      if (nx < 0 || ny < 0 || nx >= stride_ || ny >= height_ + 2) continue;
      const int32_t n = ny * stride_ + nx;
      if (BlockedAt(n)) continue;
      if (site_[n] != kCleared) {
        const int c = Compare(Between(n, e.site), Between(n, site_[n]));
        if (c > 0 || (c == 0 && e.site >= site_[n])) continue;
      }
      site_[n] = e.site;
      Push(n);
      if (touched != nullptr) touched->push_back(n);
    }
  }
  return true;
}

void VoronoiField::SetDiagramBit(int32_t index) {
  flags_[index] &= static_cast<uint8_t>(~kDiagramBit);
  if (BlockedAt(index)) return;
  const int32_t s = site_[index];
  for (const int32_t n :
       {index + 1, index - 1, index + stride_, index - stride_}) {
    if (BlockedAt(n)) continue;
    const int32_t t = site_[n];
    // The same obstacle: one cell or two touching ones.
    if (std::abs(s % stride_ - t % stride_) <= 1 &&
        std::abs(s / stride_ - t / stride_) <= 1) {
      continue;
    }
    // d(c, t) - d(c, s) <= d(n, s) - d(n, t), rearranged to sums.
    if (Compare(Between(index, t) + Between(n, t),
                Between(n, s) + Between(index, s)) <= 0) {
      flags_[index] |= kDiagramBit;
      return;
    }
  }
}

void VoronoiField::Update(const Grid& grid, absl::Span<const Cell> changed) {
  std::vector<int32_t> freed;
  std::vector<int32_t> blocked;
  for (const Cell& c : changed) {
    const int32_t i = Index(c);
    const bool now_blocked = !Traversable(grid.cost(c), unknown_is_free_);
    if (now_blocked == BlockedAt(i)) continue;
    (now_blocked ? blocked : freed).push_back(i);
  }
  if (freed.empty() && blocked.empty()) return;
  // Raise: a vanished obstacle's cells, found through neighbours because
  // every cell it was nearest to is next to another such cell one step
  // closer to it. Cells about to be blocked still pass the wave on.
  std::vector<int32_t> touched;
  for (const int32_t i : freed) {
    flags_[i] &= static_cast<uint8_t>(~kBlockedBit);
    site_[i] = kCleared;
  }
  std::vector<int32_t> cleared = freed;
  for (size_t head = 0; head < cleared.size(); ++head) {
    const int32_t c = cleared[head];
    for (int k = 0; k < 8; ++k) {
      const int32_t n = c + kDx8[k] + kDy8[k] * stride_;
      if (BlockedAt(n) || site_[n] == kCleared || BlockedAt(site_[n])) continue;
      site_[n] = kCleared;
      cleared.push_back(n);
    }
  }
  for (const int32_t i : blocked) {
    flags_[i] |= kBlockedBit;
    site_[i] = i;
    Push(i);
  }
  // Lower: the obstacles that appeared, and the intact cells around the
  // cleared ones, spread their sites into them.
  for (const int32_t c : cleared) {
    for (int k = 0; k < 8; ++k) {
      const int32_t n = c + kDx8[k] + kDy8[k] * stride_;
      if (site_[n] != kCleared) Push(n);
    }
  }
  Lower(&touched);
  touched.insert(touched.end(), cleared.begin(), cleared.end());
  touched.insert(touched.end(), blocked.begin(), blocked.end());
  // A diagram bit depends on the cell's and its 4-neighbours' sites.
  for (const int32_t i : touched) {
    for (const int32_t n : {i, i + 1, i - 1, i + stride_, i - stride_}) {
      const Cell c = CellOf(n);
      if (c.x >= 0 && c.y >= 0 && c.x < width_ && c.y < height_)
        SetDiagramBit(n);
    }
  }
}

int64_t VoronoiField::DiagramCells() const {
  int64_t count = 0;
  for (const uint8_t f : flags_) count += (f & kDiagramBit) != 0 ? 1 : 0;
  return count;
}

GeometricStructure DescribeVoronoi(const Grid& grid, bool unknown_is_free) {
  GeometricStructure s;
  s.kind = "voronoi";
  if (!VoronoiField::Fits(grid)) return s;
  const absl::Time started = absl::Now();
  const VoronoiField field(grid, unknown_is_free);
  s.build_time = absl::Now() - started;
  s.counts = {{"diagram cells", field.DiagramCells()}};
  s.bytes = field.bytes();
  for (int32_t y = 0; y < grid.height(); ++y) {
    for (int32_t x = 0; x < grid.width(); ++x) {
      if (field.OnDiagram(Cell{x, y}))
        s.points.push_back(CellPoint{x + 0.5, y + 0.5});
    }
  }
  return s;
}

}  // namespace pathd
