// Implementation of pathctl's progress bar.
#include "client/pathctl/progress.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace pathd::pathctl {
namespace {

// The largest binary unit that keeps `bytes` at 1 or more, for a pair of
// figures shown in one unit.
struct ByteUnit {
  double scale;
  const char* name;
};
ByteUnit ByteUnitFor(double bytes) {
  static constexpr ByteUnit kUnits[] = {
      {1024.0 * 1024 * 1024, "GiB"}, {1024.0 * 1024, "MiB"}, {1024.0, "KiB"}};
  for (const ByteUnit& unit : kUnits) {
    if (bytes >= unit.scale) return unit;
  }
  return {1.0, "B"};
}

std::string FormatBytes(double bytes, const ByteUnit& unit) {
  return unit.scale == 1.0 ? absl::StrFormat("%.0f", bytes)
                           : absl::StrFormat("%.1f", bytes / unit.scale);
}

}  // namespace

bool ProgressBarsWanted(bool stdout_is_terminal, bool stderr_is_terminal,
                        bool no_progress) {
  return stdout_is_terminal && stderr_is_terminal && !no_progress;
}

ProgressBar::ProgressBar(std::ostream& err, std::string label, double total,
                         Unit unit, bool enabled, Clock clock,
                         std::optional<absl::Time> start)
    : err_(err),
      label_(std::move(label)),
      total_(total),
      unit_(unit),
      enabled_(enabled),
      clock_(std::move(clock)),
      start_(start.has_value() ? *start : clock_()) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Update(double done, absl::string_view detail) {
  done_ = done;
  detail_ = std::string(detail);
  if (!enabled_ || finished_) return;
  const absl::Time now = clock_();
  const bool erased = shown_ && !visible_;
  if (!erased &&
      (now - start_ < kShowAfter || now - last_draw_ < kRedrawInterval)) {
    return;
  }
  Draw(now);
}

void ProgressBar::Clear() {
  if (!visible_) return;
  err_ << "\r\x1b[K" << std::flush;
  visible_ = false;
}

void ProgressBar::Finish() {
  if (finished_) return;
  finished_ = true;
  if (!shown_) return;
  Draw(clock_());
  err_ << "\n" << std::flush;
  visible_ = false;
}

void ProgressBar::Draw(absl::Time now) {
  // "\x1b[K" erases what a longer earlier line left to the right.
  err_ << "\r" << Render(now) << "\x1b[K" << std::flush;
  last_draw_ = now;
  shown_ = true;
  visible_ = true;
}

std::string ProgressBar::Render(absl::Time now) const {
  std::string line = label_;
  if (total_ > 0) {
    const double fraction = std::clamp(done_ / total_, 0.0, 1.0);
    const int filled = static_cast<int>(std::floor(fraction * kBarWidth));
    absl::StrAppend(&line, " [", std::string(filled, '#'),
                    std::string(kBarWidth - filled, '.'), "] ",
                    absl::StrFormat("%3d%%", static_cast<int>(fraction * 100)));
  }
  const double seconds = absl::ToDoubleSeconds(now - start_);
  switch (unit_) {
    case Unit::kCount:
      absl::StrAppend(&line, "  ", absl::StrFormat("%.0f", done_));
      if (total_ > 0) absl::StrAppend(&line, absl::StrFormat("/%.0f", total_));
      if (seconds > 0) {
        absl::StrAppend(&line, absl::StrFormat("  %.1f/s", done_ / seconds));
      }
      break;
    case Unit::kBytes: {
      const ByteUnit unit = ByteUnitFor(std::max(done_, total_));
      absl::StrAppend(&line, "  ", FormatBytes(done_, unit));
      if (total_ > 0) absl::StrAppend(&line, "/", FormatBytes(total_, unit));
      absl::StrAppend(&line, " ", unit.name);
      if (seconds > 0) {
        const double rate = done_ / seconds;
        const ByteUnit rate_unit = ByteUnitFor(rate);
        absl::StrAppend(&line, "  ", FormatBytes(rate, rate_unit), " ",
                        rate_unit.name, "/s");
      }
      break;
    }
    case Unit::kSeconds:
      absl::StrAppend(&line, absl::StrFormat("  %.1f", done_));
      if (total_ > 0) absl::StrAppend(&line, absl::StrFormat("/%.1f", total_));
      absl::StrAppend(&line, " s");
      break;
  }
  if (!detail_.empty()) absl::StrAppend(&line, "  ", detail_);
  return line;
}

}  // namespace pathd::pathctl
