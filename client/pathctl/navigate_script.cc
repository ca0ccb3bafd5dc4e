// Parser of navigate scripts.
#include "client/pathctl/navigate_script.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "client/pathctl/text.h"

namespace pathd::pathctl {
namespace {

// Longest `wait` / `expect-push`: a typo such as an extra zero should not
// hang a run for hours.
constexpr int64_t kMaxWaitMs = 3'600'000;

class LineParser {
 public:
  LineParser(std::string where, std::vector<absl::string_view> words)
      : where_(std::move(where)), words_(std::move(words)) {}

  absl::Status Error(absl::string_view problem) const {
    return absl::InvalidArgumentError(absl::StrCat(where_, ": ", problem));
  }

  // The words after the command must be exactly `names`.
  absl::Status ExpectArgs(size_t first, std::initializer_list<const char*> names,
                          absl::string_view command) const {
    if (words_.size() - first == names.size()) return absl::OkStatus();
    return Error(absl::StrCat(command, " takes ", absl::StrJoin(names, " "),
                              ", got '", absl::StrJoin(words_, " "), "'"));
  }

  absl::StatusOr<int32_t> Int(size_t i, absl::string_view name) const {
    int32_t value = 0;
    if (!absl::SimpleAtoi(words_[i], &value)) {
      return Error(absl::StrCat(name, ": '", words_[i], "' is not an integer"));
    }
    return value;
  }

  absl::StatusOr<double> Double(size_t i, absl::string_view name) const {
    double value = 0;
    if (!absl::SimpleAtod(words_[i], &value) || !std::isfinite(value)) {
      return Error(absl::StrCat(name, ": '", words_[i], "' is not a finite number"));
    }
    return value;
  }

  absl::StatusOr<absl::Duration> Millis(size_t i) const {
    int64_t ms = 0;
    if (!absl::SimpleAtoi(words_[i], &ms) || ms < 0 || ms > kMaxWaitMs) {
      return Error(absl::StrCat("MS: '", words_[i],
                                "' is not a number of milliseconds in 0..",
                                kMaxWaitMs));
    }
    return absl::Milliseconds(ms);
  }

  absl::StatusOr<uint32_t> Cost(size_t i) const {
    absl::StatusOr<uint32_t> cost = ParseCost(words_[i]);
    if (!cost.ok()) return Error(cost.status().message());
    return cost;
  }

  // block / free / cost / rect starting at words_[first].
  absl::StatusOr<v1::CellChange> Change(size_t first) const {
    const absl::string_view command = words_[first];
    v1::CellChange change;
    if (command == "rect") {
      if (absl::Status s = ExpectArgs(first + 1, {"X0", "Y0", "X1", "Y1", "COST"},
                                      "rect");
          !s.ok()) {
        return s;
      }
      int32_t c[4];
      static constexpr const char* kNames[] = {"X0", "Y0", "X1", "Y1"};
      for (int k = 0; k < 4; ++k) {
        absl::StatusOr<int32_t> v = Int(first + 1 + k, kNames[k]);
        if (!v.ok()) return v.status();
        c[k] = *v;
      }
      absl::StatusOr<uint32_t> cost = Cost(first + 5);
      if (!cost.ok()) return cost.status();
      // Any two opposite corners name the same rectangle, as for maps rect.
      v1::CellRect* rect = change.mutable_rect();
      rect->set_x_min(std::min(c[0], c[2]));
      rect->set_y_min(std::min(c[1], c[3]));
      rect->set_x_max(std::max(c[0], c[2]));
      rect->set_y_max(std::max(c[1], c[3]));
      change.set_cost(*cost);
      return change;
    }
    absl::StatusOr<uint32_t> cost;
    if (command == "cost") {
      if (absl::Status s = ExpectArgs(first + 1, {"X", "Y", "COST"}, "cost");
          !s.ok()) {
        return s;
      }
      cost = Cost(first + 3);
      if (!cost.ok()) return cost.status();
    } else {
      if (absl::Status s = ExpectArgs(first + 1, {"X", "Y"}, command); !s.ok()) {
        return s;
      }
      cost = command == "block" ? 254u : 0u;
    }
    absl::StatusOr<int32_t> x = Int(first + 1, "X");
    if (!x.ok()) return x.status();
    absl::StatusOr<int32_t> y = Int(first + 2, "Y");
    if (!y.ok()) return y.status();
    change.mutable_cell()->set_x(*x);
    change.mutable_cell()->set_y(*y);
    change.set_cost(*cost);
    return change;
  }

  absl::StatusOr<ScriptStep> Parse() const {
    ScriptStep step;
    step.where = where_;
    step.text = absl::StrJoin(words_, " ");
    const absl::string_view command = words_[0];
    if (command == "move") {
      if (absl::Status s = ExpectArgs(1, {"X", "Y"}, "move"); !s.ok()) return s;
      absl::StatusOr<int32_t> x = Int(1, "X");
      if (!x.ok()) return x.status();
      absl::StatusOr<int32_t> y = Int(2, "Y");
      if (!y.ok()) return y.status();
      step.kind = ScriptStep::Kind::kMove;
      step.cell.set_x(*x);
      step.cell.set_y(*y);
      return step;
    }
    if (command == "pose") {
      if (absl::Status s = ExpectArgs(1, {"X", "Y", "YAW"}, "pose"); !s.ok()) return s;
      absl::StatusOr<double> x = Double(1, "X");
      if (!x.ok()) return x.status();
      absl::StatusOr<double> y = Double(2, "Y");
      if (!y.ok()) return y.status();
      absl::StatusOr<double> yaw = Double(3, "YAW");
      if (!yaw.ok()) return yaw.status();
      step.kind = ScriptStep::Kind::kPose;
      step.pose.set_x(*x);
      step.pose.set_y(*y);
      step.pose.set_yaw(*yaw);
      return step;
    }
    if (command == "follow") {
      if (absl::Status s = ExpectArgs(1, {"N"}, "follow"); !s.ok()) return s;
      absl::StatusOr<int32_t> n = Int(1, "N");
      if (!n.ok()) return n.status();
      if (*n < 1) return Error(absl::StrCat("N: follow needs N >= 1, not ", *n));
      step.kind = ScriptStep::Kind::kFollow;
      step.steps = *n;
      return step;
    }
    if (command == "wait") {
      if (absl::Status s = ExpectArgs(1, {"MS"}, "wait"); !s.ok()) return s;
      absl::StatusOr<absl::Duration> d = Millis(1);
      if (!d.ok()) return d.status();
      step.kind = ScriptStep::Kind::kWait;
      step.duration = *d;
      return step;
    }
    if (command == "expect-push") {
      if (words_.size() > 2) {
        return Error(absl::StrCat("expect-push takes at most MS, got '",
                                  step.text, "'"));
      }
      step.kind = ScriptStep::Kind::kExpectPush;
      step.duration = kDefaultExpectPushWait;
      if (words_.size() == 2) {
        absl::StatusOr<absl::Duration> d = Millis(1);
        if (!d.ok()) return d.status();
        step.duration = *d;
      }
      return step;
    }
    const bool session_only = command == "private";
    const size_t first = session_only ? 1 : 0;
    if (words_.size() > first &&
        (words_[first] == "block" || words_[first] == "free" ||
         words_[first] == "cost" || words_[first] == "rect")) {
      absl::StatusOr<v1::CellChange> change = Change(first);
      if (!change.ok()) return change.status();
      step.kind = ScriptStep::Kind::kObserve;
      *step.observation.add_changes() = *std::move(change);
      step.observation.set_session_only(session_only);
      return step;
    }
    if (session_only) {
      return Error("private must be followed by block, free, cost or rect");
    }
    return Error(absl::StrCat("unknown command '", command,
                              "'; expected move, pose, follow, block, free, cost, "
                              "rect, private, wait or expect-push"));
  }

 private:
  std::string where_;
  std::vector<absl::string_view> words_;
};

}  // namespace

absl::StatusOr<std::vector<ScriptStep>> ParseNavigateScript(
    absl::string_view text, absl::string_view source_name) {
  std::vector<ScriptStep> steps;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    if (size_t hash = line.find('#'); hash != absl::string_view::npos) {
      line = line.substr(0, hash);
    }
    std::vector<absl::string_view> words =
        absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty());
    if (words.empty()) continue;
    LineParser parser(absl::StrCat(source_name, ":", line_number),
                      std::move(words));
    absl::StatusOr<ScriptStep> step = parser.Parse();
    if (!step.ok()) return step.status();
    steps.push_back(*std::move(step));
  }
  return steps;
}

}  // namespace pathd::pathctl
