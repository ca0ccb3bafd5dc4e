// MemoryBudget: admission of sessions and watchers by bytes, per-caller
// shares, and returning freed memory to the system.
#include "server/memory_budget.h"

#include <malloc.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"

namespace pathd::server {
namespace {

std::string_view PartName(MemoryBudget::Part part) {
  return part == MemoryBudget::Part::kSessions ? "navigation sessions"
                                               : "WatchMap streams";
}

int64_t Share(int64_t limit, double share) {
  return std::max<int64_t>(1, static_cast<int64_t>(static_cast<double>(limit) * share));
}

}  // namespace

void PinAllocatorThresholds() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && (std::strstr(tunables, "malloc.mmap_threshold") != nullptr ||
                              std::strstr(tunables, "malloc.trim_threshold") != nullptr)) {
    return;  // the operator's choice
  }
  // Both set: mallopt of either turns off glibc's dynamic adjustment of both.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 4 << 20);
}

// ---- Reservation ----

MemoryBudget::Reservation::Reservation(Reservation&& other) noexcept
    : budget_(std::exchange(other.budget_, nullptr)),
      part_(other.part_),
      caller_(std::move(other.caller_)),
      bytes_(std::exchange(other.bytes_, 0)) {}

MemoryBudget::Reservation& MemoryBudget::Reservation::operator=(
    Reservation&& other) noexcept {
  if (this != &other) {
    Release();
    budget_ = std::exchange(other.budget_, nullptr);
    part_ = other.part_;
    caller_ = std::move(other.caller_);
    bytes_ = std::exchange(other.bytes_, 0);
  }
  return *this;
}

MemoryBudget::Reservation::~Reservation() { Release(); }

void MemoryBudget::Reservation::Release() {
  if (budget_ == nullptr) return;
  budget_->Change(part_, caller_, -bytes_, -1);
  budget_ = nullptr;
  bytes_ = 0;
}

absl::Status MemoryBudget::Reservation::Resize(int64_t bytes) {
  if (budget_ == nullptr) return absl::OkStatus();
  if (bytes > bytes_) {
    const int64_t caches = budget_->cache_bytes();
    absl::MutexLock lock(&budget_->mu_);
    absl::Status fits = budget_->CheckLocked(part_, caller_, bytes - bytes_, 0, caches,
                                             "this stream's new map");
    if (!fits.ok()) {
      budget_->refusals_.fetch_add(1, std::memory_order_relaxed);
      return fits;
    }
    budget_->parts_[static_cast<int>(part_)].bytes += bytes - bytes_;
    budget_->callers_[caller_][static_cast<int>(part_)].bytes += bytes - bytes_;
    bytes_ = bytes;
    return absl::OkStatus();
  }
  Update(bytes);
  return absl::OkStatus();
}

void MemoryBudget::Reservation::Update(int64_t bytes) {
  if (budget_ == nullptr || bytes == bytes_) return;
  budget_->Change(part_, caller_, bytes - bytes_, 0);
  bytes_ = bytes;
}

// ---- MemoryBudget ----

MemoryBudget::MemoryBudget(Options options) : options_(std::move(options)) {
  trimmer_ = std::thread([this] { TrimLoop(); });
}

MemoryBudget::~MemoryBudget() {
  {
    absl::MutexLock lock(&trim_mu_);
    stopping_ = true;
    trim_cv_.Signal();
  }
  trimmer_.join();
}

int64_t MemoryBudget::cache_bytes() const {
  return options_.cache_bytes ? options_.cache_bytes() : 0;
}

absl::StatusOr<MemoryBudget::Reservation> MemoryBudget::Reserve(
    Part part, const std::string& caller, int64_t bytes, std::string_view what) {
  const int64_t caches = cache_bytes();
  absl::MutexLock lock(&mu_);
  if (absl::Status fits = CheckLocked(part, caller, bytes, 1, caches, what); !fits.ok()) {
    refusals_.fetch_add(1, std::memory_order_relaxed);
    return fits;
  }
  Usage& total = parts_[static_cast<int>(part)];
  total.bytes += bytes;
  ++total.holders;
  Usage& mine = callers_[caller][static_cast<int>(part)];
  mine.bytes += bytes;
  ++mine.holders;
  return Reservation(this, part, caller, bytes);
}

absl::Status MemoryBudget::CheckLocked(Part part, const std::string& caller,
                                       int64_t extra_bytes, int64_t extra_holders,
                                       int64_t caches, std::string_view what) const {
  const Usage& in_part = parts_[static_cast<int>(part)];
  Usage mine;
  if (auto it = callers_.find(caller); it != callers_.end()) {
    mine = it->second[static_cast<int>(part)];
  }
  const double share = options_.caller_share;
  const auto refuse = [&](std::string_view flag, const std::string& why) {
    return absl::ResourceExhaustedError(absl::StrCat(
        std::string(what), " needs about ", extra_bytes, " bytes of memory but ",
        why, " (", std::string(flag), "); close streams or retry later"));
  };
  if (part == Part::kWatchers && extra_holders > 0) {
    if (in_part.holders + extra_holders > options_.max_watchers) {
      return refuse("--max_watchers",
                    absl::StrFormat("%d WatchMap streams are open, the limit",
                                    in_part.holders));
    }
    const int64_t own = Share(options_.max_watchers, share);
    if (mine.holders + extra_holders > own) {
      return refuse("--caller_memory_share",
                    absl::StrFormat("this caller (%s) already has %d WatchMap streams "
                                    "open, its share of --max_watchers",
                                    caller, mine.holders));
    }
  }
  if (part == Part::kSessions && options_.session_bytes > 0) {
    if (in_part.bytes + extra_bytes > options_.session_bytes) {
      return refuse("--session_memory_bytes",
                    absl::StrFormat("%s hold %d of the %d bytes allowed",
                                    PartName(part), in_part.bytes,
                                    options_.session_bytes));
    }
    const int64_t own = Share(options_.session_bytes, share);
    if (mine.bytes + extra_bytes > own) {
      return refuse("--caller_memory_share",
                    absl::StrFormat("this caller (%s) holds %d bytes of %s, its "
                                    "share is %d bytes of --session_memory_bytes",
                                    caller, mine.bytes, PartName(part), own));
    }
  }
  if (options_.total_bytes > 0) {
    const int64_t used = parts_[0].bytes + parts_[1].bytes + caches;
    if (used + extra_bytes > options_.total_bytes) {
      return refuse("--memory_budget_bytes",
                    absl::StrFormat("caches, sessions and WatchMap streams hold %d "
                                    "of the %d bytes budgeted (caches %d)",
                                    used, options_.total_bytes, caches));
    }
    if (part == Part::kWatchers) {
      const int64_t own = Share(options_.total_bytes, share);
      if (mine.bytes + extra_bytes > own) {
        return refuse("--caller_memory_share",
                      absl::StrFormat("this caller (%s) holds %d bytes of %s, its "
                                      "share is %d bytes of --memory_budget_bytes",
                                      caller, mine.bytes, PartName(part), own));
      }
    }
  }
  return absl::OkStatus();
}

void MemoryBudget::Change(Part part, const std::string& caller, int64_t delta_bytes,
                          int64_t delta_holders) {
  bool trim = false;
  {
    absl::MutexLock lock(&mu_);
    Usage& total = parts_[static_cast<int>(part)];
    total.bytes += delta_bytes;
    total.holders += delta_holders;
    auto it = callers_.find(caller);
    if (it != callers_.end()) {
      Usage& mine = it->second[static_cast<int>(part)];
      mine.bytes += delta_bytes;
      mine.holders += delta_holders;
      const bool empty = std::all_of(it->second.begin(), it->second.end(),
                                     [](const Usage& u) { return u.holders <= 0; });
      if (empty) callers_.erase(it);
    }
    if (delta_bytes < 0) {
      freed_since_trim_ -= delta_bytes;
      if (freed_since_trim_ >= kTrimAfterFreedBytes) {
        freed_since_trim_ = 0;
        trim = true;
      }
    }
  }
  if (trim) {
    absl::MutexLock lock(&trim_mu_);
    trim_pending_ = true;
    trim_cv_.Signal();
  }
}

void MemoryBudget::TrimLoop() {
  // Bytes the allocator held free after the last trim: a trim returns free
  // pages but leaves them counted as free, so only growth since then says
  // something new was freed.
  size_t free_after_trim = mallinfo2().fordblks;
  absl::MutexLock lock(&trim_mu_);
  for (;;) {
    // Woken at once by a large released reservation; otherwise every
    // kTrimPoll, to catch what is freed late and unreserved (gRPC frees a
    // closed stream's buffers after the stream's reactor and its
    // reservation are gone, later still on a loaded machine).
    // A CondVar and a predicate checked here, not Await with a Condition:
    // Abseil may evaluate a Condition inside its wait, where the test-only
    // TSan shim (tests/tsan/absl_mutex_tsan.cc) cannot show the lock held.
    const absl::Time deadline = absl::Now() + kTrimPoll;
    while (!trim_pending_ && !stopping_) {
      if (trim_cv_.WaitWithDeadline(&trim_mu_, deadline)) break;  // timed out
    }
    if (stopping_) return;
    const bool pending = trim_pending_;
    trim_pending_ = false;
    trim_mu_.Unlock();
    const size_t free_now = mallinfo2().fordblks;
    if (pending ||
        free_now > free_after_trim + static_cast<size_t>(kTrimAfterFreedBytes)) {
      // glibc keeps freed heap memory (and raises its mmap threshold after
      // large frees, so later big blocks come from the heap too): without
      // this RSS stays at its peak after sessions and streams close. Outside
      // the lock: it walks every arena.
      malloc_trim(0);
      trims_.fetch_add(1, std::memory_order_relaxed);
      free_after_trim = mallinfo2().fordblks;
    } else if (free_now < free_after_trim) {
      free_after_trim = free_now;  // reused since: measure growth from here
    }
    trim_mu_.Lock();
  }
}

std::string MemoryBudget::CallerOf(const grpc::ServerContextBase& context) const {
  if (options_.callers_by_token) {
    const auto& metadata = context.client_metadata();
    if (auto it = metadata.find("authorization"); it != metadata.end()) {
      // A hash, so no token is ever kept or shown.
      const size_t hash =
          std::hash<std::string_view>()(std::string_view(it->second.data(), it->second.size()));
      return absl::StrFormat("token:%016x", hash);
    }
  }
  // "ipv4:127.0.0.1:5555", "ipv6:[::1]:5555": the address without the port.
  std::string peer = context.peer();
  // A call the HTTP gateway forwards over the in-process channel: the HTTP
  // client's address (only in-process callers can name one).
  if (absl::StartsWith(peer, "inproc")) {
    const auto& metadata = context.client_metadata();
    if (auto it = metadata.find("x-pathd-http-peer"); it != metadata.end()) {
      return absl::StrCat("http:", std::string(it->second.data(), it->second.size()));
    }
  }
  if (const size_t colon = peer.rfind(':');
      colon != std::string::npos && peer.find(':') != colon) {
    peer.resize(colon);
  }
  return absl::StrCat("peer:", peer);
}

int64_t MemoryBudget::reserved(Part part) const {
  absl::MutexLock lock(&mu_);
  return parts_[static_cast<int>(part)].bytes;
}

int64_t MemoryBudget::holders(Part part) const {
  absl::MutexLock lock(&mu_);
  return parts_[static_cast<int>(part)].holders;
}

}  // namespace pathd::server
