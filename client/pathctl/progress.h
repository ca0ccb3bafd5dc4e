// A one-line progress bar that pathctl draws on stderr during long work
// (batch plans, bench, sending a large map). It redraws in place with "\r",
// at most every kRedrawInterval, and only once the work has run for
// kShowAfter, so quick commands never flash a bar. The clock is injected so
// tests can check the rendering without sleeping.
#ifndef PATHD_CLIENT_PATHCTL_PROGRESS_H_
#define PATHD_CLIENT_PATHCTL_PROGRESS_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <ostream>
#include <string>

#include "absl/strings/string_view.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"

namespace pathd::pathctl {

// Whether pathctl draws progress bars: only for a person watching, i.e.
// stdout and stderr are both terminals (a redirected stdout means a script
// or a file is the reader) and --no_progress was not given.
bool ProgressBarsWanted(bool stdout_is_terminal, bool stderr_is_terminal,
                        bool no_progress);

// Not thread-safe: one thread updates it.
class ProgressBar {
 public:
  // How `done` and `total` read: a count of items, bytes (KiB/MiB/GiB), or
  // seconds.
  enum class Unit { kCount, kBytes, kSeconds };
  using Clock = std::function<absl::Time()>;

  // No bar is drawn within this long of construction.
  static constexpr absl::Duration kShowAfter = absl::Milliseconds(500);
  // Redraws are at least this far apart.
  static constexpr absl::Duration kRedrawInterval = absl::Milliseconds(100);
  // Characters between the brackets.
  static constexpr int kBarWidth = 24;

  // Draws on `err` only if `enabled`. `total` <= 0: unknown, so no bar and no
  // percentage, only the figures. `start`: when the work began (default:
  // now), from which kShowAfter and the rate count.
  ProgressBar(std::ostream& err, std::string label, double total, Unit unit,
              bool enabled, Clock clock = &absl::Now,
              std::optional<absl::Time> start = std::nullopt);
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  // Finishes the line if one is showing.
  ~ProgressBar();

  // Records that `done` of total is done, `detail` being extra text shown
  // after the figures, and redraws when the rate limit allows, or at once
  // when Clear erased a shown bar (so it stays under the caller's lines).
  void Update(double done, absl::string_view detail = "");

  // Erases the bar so the caller can print a line of its own on the same
  // terminal; the next Update that the rate limit allows draws it again.
  void Clear();

  // Draws the last state once more (if a bar was ever shown) and ends the
  // line, so what follows starts on a fresh one. Later calls do nothing.
  void Finish();

  // The line Update draws, without "\r" and the erase-to-end sequence:
  // "LABEL [=====>      ]  42%  420/1000  84.0/s  DETAIL".
  std::string Render(absl::Time now) const;

 private:
  void Draw(absl::Time now);

  std::ostream& err_;
  const std::string label_;
  const double total_;
  const Unit unit_;
  const bool enabled_;
  const Clock clock_;
  const absl::Time start_;
  double done_ = 0;
  std::string detail_;
  absl::Time last_draw_ = absl::InfinitePast();
  bool shown_ = false;    // a bar was drawn at least once
  bool visible_ = false;  // it is on the screen now
  bool finished_ = false;
};

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_PROGRESS_H_
