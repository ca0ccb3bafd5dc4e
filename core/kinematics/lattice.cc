#include "core/kinematics/lattice.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <tuple>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/synchronization/mutex.h"
#include "core/kinematics/lattice_embedded.h"
#include "core/kinematics/lattice_generator.h"
#include "core/status_macros.h"
#include "yaml-cpp/yaml.h"

namespace pathd {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

constexpr std::pair<LatticeRobot, std::string_view> kRobotNames[] = {
    {LatticeRobot::kDifferential, "diff"},
    {LatticeRobot::kAckermann, "ackermann"},
    {LatticeRobot::kOmnidirectional, "omni"},
};

// ---- Writing ----

// Numbers as JSON: no "-0", no exponent surprises for the readers we know
// (%.*g writes 1e-05, which JSON allows).
std::string Number(double v, int digits) {
  if (v == 0.0) return "0.0";
  std::string s = absl::StrFormat("%.*g", digits, v);
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

// ---- Parsing ----

// A YAML node with where it came from, for messages.
class Field {
 public:
  Field(const YAML::Node& node, std::string path, std::string_view source)
      : node_(node), path_(std::move(path)), source_(source) {}

  const YAML::Node& node() const { return node_; }
  const std::string& path() const { return path_; }

  absl::Status Error(std::string_view problem) const {
    const int line = node_.IsDefined() && node_.Mark().line >= 0 ? node_.Mark().line + 1 : 0;
    return absl::InvalidArgumentError(
        line > 0 ? absl::StrFormat("%s:%d: %s: %s", source_, line, path_, problem)
                 : absl::StrFormat("%s: %s: %s", source_, path_, problem));
  }

  // The member `key` of this map; INVALID_ARGUMENT when missing and
  // `required`, naming this node's line.
  absl::StatusOr<Field> Member(const std::string& key, bool required = true) const {
    if (!node_.IsMap()) return Error("expected an object");
    const YAML::Node& map = node_;
    YAML::Node child = map[key];
    if (!child.IsDefined() && required) {
      return Error(absl::StrCat("missing field \"", key, "\""));
    }
    return Field(child, path_.empty() ? key : absl::StrCat(path_, ".", key), source_);
  }
  Field Element(size_t i) const {
    const YAML::Node& list = node_;
    return Field(list[i], absl::StrCat(path_, "[", i, "]"), source_);
  }

  absl::StatusOr<double> Double() const {
    if (!node_.IsScalar()) return Error("expected a number");
    try {
      const double v = node_.as<double>();
      if (!std::isfinite(v)) return Error("expected a finite number");
      return v;
    } catch (const YAML::Exception&) {
      return Error(absl::StrCat("expected a number, got \"", node_.Scalar(), "\""));
    }
  }
  absl::StatusOr<int64_t> Int() const {
    if (!node_.IsScalar()) return Error("expected an integer");
    try {
      return node_.as<int64_t>();
    } catch (const YAML::Exception&) {
      // Nav2 writes num_of_headings as 16.0 in places: whole numbers pass.
      try {
        const double v = node_.as<double>();
        if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15) {
          return static_cast<int64_t>(v);
        }
      } catch (const YAML::Exception&) {
      }
      return Error(absl::StrCat("expected an integer, got \"", node_.Scalar(), "\""));
    }
  }
  absl::StatusOr<bool> Bool() const {
    if (!node_.IsScalar()) return Error("expected true or false");
    try {
      return node_.as<bool>();
    } catch (const YAML::Exception&) {
      return Error(absl::StrCat("expected true or false, got \"", node_.Scalar(), "\""));
    }
  }
  absl::StatusOr<std::string> String() const {
    if (!node_.IsScalar()) return Error("expected a string");
    return node_.Scalar();
  }
  absl::Status ExpectList() const {
    if (!node_.IsSequence()) return Error("expected a list");
    return absl::OkStatus();
  }

 private:
  YAML::Node node_;
  std::string path_;
  std::string_view source_;
};

// Whether `v` is within `tolerance` of a whole number; the number.
bool NearInteger(double v, double tolerance, int32_t* out) {
  const double r = std::round(v);
  if (std::fabs(v - r) > tolerance || std::fabs(r) > 1e6) return false;
  *out = static_cast<int32_t>(r);
  return true;
}

// Inserts linear steps so no two consecutive poses are farther apart than
// the spacing (position and heading).
std::vector<Pose> Densified(const std::vector<Pose>& poses) {
  std::vector<Pose> out{poses.front()};
  for (size_t i = 1; i < poses.size(); ++i) {
    const Pose& a = poses[i - 1];
    const Pose& b = poses[i];
    const double dyaw = NormalizeAngle(b.yaw - a.yaw);
    const int32_t pieces = std::max<int32_t>(
        1, static_cast<int32_t>(std::max(
               std::ceil(std::hypot(b.x - a.x, b.y - a.y) / kLatticePoseSpacing - 1e-9),
               std::ceil(std::fabs(dyaw) / kLatticeYawSpacing - 1e-9))));
    for (int32_t k = 1; k < pieces; ++k) {
      const double f = static_cast<double>(k) / pieces;
      out.push_back(Pose{a.x + f * (b.x - a.x), a.y + f * (b.y - a.y),
                         NormalizeAngle(a.yaw + f * dyaw)});
    }
    out.push_back(b);
  }
  return out;
}

absl::StatusOr<LatticePrimitive> ParsePrimitive(const Field& f, const ControlSet& set) {
  const int32_t n = set.headings();
  const double res = set.resolution_m;
  LatticePrimitive p;
  for (auto [key, out] : {std::pair<const char*, int32_t*>{"start_angle_index", &p.start_heading},
                          {"end_angle_index", &p.end_heading}}) {
    PATHD_ASSIGN_OR_RETURN(const Field index, f.Member(key));
    PATHD_ASSIGN_OR_RETURN(const int64_t v, index.Int());
    if (v < 0 || v >= n) {
      return index.Error(absl::StrFormat("heading index %d is not in 0..%d", v, n - 1));
    }
    *out = static_cast<int32_t>(v);
  }
  PATHD_ASSIGN_OR_RETURN(const Field poses, f.Member("poses"));
  if (absl::Status s = poses.ExpectList(); !s.ok()) return s;
  if (poses.node().size() == 0) return poses.Error("a primitive needs at least one pose");
  std::vector<Pose> read;
  for (size_t i = 0; i < poses.node().size(); ++i) {
    const Field pose = poses.Element(i);
    if (!pose.node().IsSequence() || pose.node().size() != 3) {
      return pose.Error("expected [x, y, yaw]");
    }
    double v[3];
    for (size_t k = 0; k < 3; ++k) {
      PATHD_ASSIGN_OR_RETURN(v[k], pose.Element(k).Double());
    }
    // Headings written rounded near +-pi read as pi, so a file reads back
    // the same whatever side of pi its rounding fell on.
    double yaw = NormalizeAngle(v[2]);
    if (std::fabs(std::fabs(yaw) - std::numbers::pi) < 1e-8) yaw = std::numbers::pi;
    read.push_back(Pose{v[0] / res, v[1] / res, yaw});
  }
  const double start_yaw = NormalizeAngle(set.heading_angles[p.start_heading]);
  const double end_yaw = NormalizeAngle(set.heading_angles[p.end_heading]);
  constexpr double kCellTolerance = 1e-3;
  constexpr double kYawTolerance = 1e-3;
  const bool inserted = std::hypot(read.front().x, read.front().y) > kCellTolerance ||
                        AngleBetween(read.front().yaw, start_yaw) > kYawTolerance;
  // Nav2 leaves out the start of a motion.
  if (inserted) read.insert(read.begin(), Pose{0.0, 0.0, start_yaw});
  const Pose& last = read.back();
  if (!NearInteger(last.x, kCellTolerance, &p.dx) || !NearInteger(last.y, kCellTolerance, &p.dy)) {
    return poses.Element(poses.node().size() - 1)
        .Error(absl::StrFormat(
            "the last pose (%g, %g) m is not on a lattice point (a whole number of %g m cells)",
            last.x * res, last.y * res, res));
  }
  if (AngleBetween(last.yaw, end_yaw) > kYawTolerance) {
    return poses.Element(poses.node().size() - 1)
        .Error(absl::StrFormat("the last pose's yaw %g is not end heading %d (%g rad)", last.yaw,
                               p.end_heading, end_yaw));
  }
  for (size_t i = 1; i < read.size(); ++i) {
    if (std::hypot(read[i].x - read[i - 1].x, read[i].y - read[i - 1].y) > 1.5) {
      return poses.Element(inserted ? i - 1 : i)
          .Error("poses more than 1.5 cells apart: the motion between them is unknown");
    }
  }
  read.front() = Pose{0.0, 0.0, start_yaw};
  read.back() = Pose{static_cast<double>(p.dx), static_cast<double>(p.dy), end_yaw};
  p.poses = Densified(read);
  double travelled = 0.0;
  for (size_t i = 1; i < p.poses.size(); ++i) {
    travelled += std::hypot(p.poses[i].x - p.poses[i - 1].x, p.poses[i].y - p.poses[i - 1].y);
  }
  p.turn_in_place = travelled < 1e-9;
  // Lengths: the file's, else the poses'.
  PATHD_ASSIGN_OR_RETURN(const Field length, f.Member("trajectory_length", false));
  if (length.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(const double v, length.Double());
    if (v < 0.0) return length.Error("must be >= 0");
    p.length = v / res;
  } else {
    p.length = travelled;
  }
  if (p.turn_in_place) p.length = 0.0;
  PATHD_ASSIGN_OR_RETURN(const Field arc, f.Member("arc_length", false));
  if (arc.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(const double v, arc.Double());
    p.arc_length = v / res;
  }
  PATHD_ASSIGN_OR_RETURN(const Field radius, f.Member("trajectory_radius", false));
  if (radius.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(const double v, radius.Double());
    if (v < 0.0) return radius.Error("must be >= 0");
    p.radius = v / res;
  }
  PATHD_ASSIGN_OR_RETURN(const Field left, f.Member("left_turn", false));
  if (left.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(p.left_turn, left.Bool());
  } else {
    p.left_turn = NormalizeAngle(end_yaw - start_yaw) > 0.0;
  }
  PATHD_ASSIGN_OR_RETURN(const Field reverse, f.Member("reverse", false));
  if (reverse.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(p.reverse, reverse.Bool());
  }
  if (p.turn_in_place && p.reverse) return reverse.Error("a turn in place cannot be reversed");
  return p;
}

// ---- The cache ----

struct FileEntry {
  std::filesystem::file_time_type modified;
  std::shared_ptr<const ControlSet> set;
};

// Sets by name or path, and generated ones by parameters. Thread-safe.
class ControlSetCache {
 public:
  absl::StatusOr<std::shared_ptr<const ControlSet>> Shipped(std::string_view name)
      ABSL_LOCKS_EXCLUDED(mu_) {
    {
      absl::MutexLock lock(&mu_);
      auto it = shipped_.find(std::string(name));
      if (it != shipped_.end()) return it->second;
    }
    for (const auto& [shipped, text] : EmbeddedControlSets()) {
      if (shipped != name) continue;
      absl::StatusOr<ControlSet> set =
          ParseControlSet(text, absl::StrFormat("data/lattices/%s.json", name));
      if (!set.ok()) return set.status();
      set->name = std::string(name);
      auto shared = std::make_shared<const ControlSet>(*std::move(set));
      absl::MutexLock lock(&mu_);
      return shipped_.emplace(std::string(name), std::move(shared)).first->second;
    }
    return absl::NotFoundError(absl::StrFormat("no shipped control set \"%s\"", name));
  }

  absl::StatusOr<std::shared_ptr<const ControlSet>> File(const std::string& path)
      ABSL_LOCKS_EXCLUDED(mu_) {
    std::error_code error;
    const auto modified = std::filesystem::last_write_time(path, error);
    if (error) {
      return absl::NotFoundError(
          absl::StrCat("control set file ", path, " cannot be read: ", error.message()));
    }
    {
      absl::MutexLock lock(&mu_);
      auto it = files_.find(path);
      if (it != files_.end() && it->second.modified == modified) return it->second.set;
    }
    absl::StatusOr<ControlSet> set = ReadControlSetFile(path);
    if (!set.ok()) return set.status();
    auto shared = std::make_shared<const ControlSet>(*std::move(set));
    absl::MutexLock lock(&mu_);
    files_[path] = FileEntry{modified, shared};
    return shared;
  }

  // Generated outside the lock: two queries racing on a new radius both
  // generate it, which costs time but never correctness.
  absl::StatusOr<std::shared_ptr<const ControlSet>> Generated(
      const LatticeGeneratorOptions& options) ABSL_LOCKS_EXCLUDED(mu_) {
    const auto key = std::make_tuple(static_cast<int>(options.robot), options.reverse,
                                     options.turning_radius_m, options.headings);
    {
      absl::MutexLock lock(&mu_);
      auto it = generated_.find(key);
      if (it != generated_.end()) return it->second;
    }
    absl::StatusOr<ControlSet> set = GenerateControlSet(options);
    if (!set.ok()) return set.status();
    auto shared = std::make_shared<const ControlSet>(*std::move(set));
    absl::MutexLock lock(&mu_);
    return generated_.emplace(key, std::move(shared)).first->second;
  }

 private:
  absl::Mutex mu_;
  std::map<std::string, std::shared_ptr<const ControlSet>> shipped_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, FileEntry> files_ ABSL_GUARDED_BY(mu_);
  std::map<std::tuple<int, bool, double, int32_t>, std::shared_ptr<const ControlSet>> generated_
      ABSL_GUARDED_BY(mu_);
};

ControlSetCache& Cache() {
  static ControlSetCache* cache = new ControlSetCache();
  return *cache;
}

// What a query's default choice needs to know of a shipped set, read from
// its metadata alone (parsing a whole set takes a quarter of a second).
struct ShippedSummary {
  std::string_view name;
  LatticeRobot robot = LatticeRobot::kAckermann;
  bool reverse = false;
  int64_t headings = 0;
  double radius_cells = 0.0;
};

ShippedSummary Summarize(std::string_view name, std::string_view text) {
  ShippedSummary s;
  s.name = name;
  // The metadata object: from its key to the first closing brace (it holds
  // no nested object).
  const size_t key = text.find("\"lattice_metadata\"");
  const size_t open = key == std::string_view::npos ? key : text.find('{', key);
  const size_t close = open == std::string_view::npos ? open : text.find('}', open);
  if (close == std::string_view::npos) return s;
  try {
    const YAML::Node meta = YAML::Load(std::string(text.substr(open, close - open + 1)));
    absl::StatusOr<LatticeRobot> robot = ParseLatticeRobot(meta["motion_model"].as<std::string>());
    if (!robot.ok()) return s;
    s.robot = *robot;
    s.headings = meta["num_of_headings"].as<int64_t>();
    s.radius_cells = meta["turning_radius"].as<double>() / meta["grid_resolution"].as<double>();
  } catch (const YAML::Exception&) {
    return ShippedSummary{name};
  }
  s.reverse = text.find("\"reverse\": true") != std::string_view::npos;
  return s;
}

const std::vector<ShippedSummary>& ShippedSummaries() {
  static const auto* const kSummaries = [] {
    auto* out = new std::vector<ShippedSummary>();
    for (const auto& [name, text] : EmbeddedControlSets()) out->push_back(Summarize(name, text));
    return out;
  }();
  return *kSummaries;
}

}  // namespace

std::string_view LatticeRobotName(LatticeRobot robot) {
  for (const auto& [r, name] : kRobotNames) {
    if (r == robot) return name;
  }
  return "unknown";
}

absl::StatusOr<LatticeRobot> ParseLatticeRobot(std::string_view name) {
  std::vector<std::string> names;
  for (const auto& [r, n] : kRobotNames) {
    if (n == name) return r;
    names.emplace_back(n);
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "unknown lattice robot \"%s\"; expected one of %s", name, absl::StrJoin(names, ", ")));
}

double ControlSet::tightest_radius_cells() const {
  double r = std::numeric_limits<double>::infinity();
  for (const LatticePrimitive& p : primitives) {
    if (p.radius > 0.0) r = std::min(r, p.radius);
  }
  return r;
}

bool ControlSet::has_reverse() const {
  return std::any_of(primitives.begin(), primitives.end(),
                     [](const LatticePrimitive& p) { return p.reverse; });
}

bool ControlSet::has_turn_in_place() const {
  return std::any_of(primitives.begin(), primitives.end(),
                     [](const LatticePrimitive& p) { return p.turn_in_place; });
}

int32_t ControlSet::HeadingOf(double yaw, double tolerance) const {
  const int32_t h = NearestHeading(yaw);
  return AngleBetween(yaw, heading_angles[h]) <= tolerance ? h : -1;
}

int32_t ControlSet::NearestHeading(double yaw) const {
  int32_t best = 0;
  for (int32_t h = 1; h < headings(); ++h) {
    if (AngleBetween(yaw, heading_angles[h]) < AngleBetween(yaw, heading_angles[best])) best = h;
  }
  return best;
}

void ControlSet::Index() {
  std::stable_sort(primitives.begin(), primitives.end(),
                   [](const LatticePrimitive& a, const LatticePrimitive& b) {
                     return a.start_heading < b.start_heading;
                   });
  first_of_heading.assign(headings() + 1, primitives.size());
  for (size_t i = primitives.size(); i-- > 0;) {
    first_of_heading[primitives[i].start_heading] = i;
  }
  for (int32_t h = headings() - 1; h >= 0; --h) {
    first_of_heading[h] = std::min(first_of_heading[h], first_of_heading[h + 1]);
  }
}

std::string WriteControlSet(const ControlSet& set) {
  const double res = set.resolution_m;
  std::string out = "{\n  \"version\": 1.0,\n";
  absl::StrAppend(&out, "  \"generator\": \"pathd lattice_gen\",\n");
  absl::StrAppend(&out, "  \"lattice_metadata\": {\n");
  absl::StrAppend(&out, "    \"motion_model\": \"", std::string(LatticeRobotName(set.robot)),
                  "\",\n");
  absl::StrAppend(&out, "    \"turning_radius\": ", Number(set.turning_radius_m, 12), ",\n");
  absl::StrAppend(&out, "    \"grid_resolution\": ", Number(set.resolution_m, 12), ",\n");
  absl::StrAppend(&out, "    \"stopping_threshold\": ", set.stopping_threshold, ",\n");
  absl::StrAppend(&out, "    \"length_tolerance\": ", Number(set.length_tolerance, 12), ",\n");
  absl::StrAppend(&out, "    \"num_of_headings\": ", set.headings(), ",\n");
  std::vector<std::string> angles;
  for (double a : set.heading_angles) angles.push_back(Number(a, 17));
  absl::StrAppend(&out, "    \"heading_angles\": [", absl::StrJoin(angles, ", "), "],\n");
  absl::StrAppend(&out, "    \"number_of_trajectories\": ", set.primitives.size(), "\n  },\n");
  absl::StrAppend(&out, "  \"primitives\": [");
  for (size_t i = 0; i < set.primitives.size(); ++i) {
    const LatticePrimitive& p = set.primitives[i];
    absl::StrAppend(&out, i == 0 ? "\n" : ",\n", "    {\n");
    absl::StrAppend(&out, "      \"trajectory_id\": ", i, ",\n");
    absl::StrAppend(&out, "      \"start_angle_index\": ", p.start_heading, ",\n");
    absl::StrAppend(&out, "      \"end_angle_index\": ", p.end_heading, ",\n");
    absl::StrAppend(&out, "      \"left_turn\": ", p.left_turn ? "true" : "false", ",\n");
    absl::StrAppend(&out, "      \"reverse\": ", p.reverse ? "true" : "false", ",\n");
    absl::StrAppend(&out, "      \"trajectory_radius\": ", Number(p.radius * res, 12), ",\n");
    absl::StrAppend(&out, "      \"trajectory_length\": ", Number(p.length * res, 12), ",\n");
    absl::StrAppend(&out, "      \"arc_length\": ", Number(p.arc_length * res, 12), ",\n");
    absl::StrAppend(&out, "      \"straight_length\": ",
                    Number(std::max(0.0, p.length - p.arc_length) * res, 12), ",\n");
    absl::StrAppend(&out, "      \"poses\": [");
    for (size_t k = 0; k < p.poses.size(); ++k) {
      const Pose& q = p.poses[k];
      absl::StrAppend(&out, k == 0 ? "\n" : ",\n", "        [", Number(q.x * res, 10), ", ",
                      Number(q.y * res, 10), ", ", Number(q.yaw, 10), "]");
    }
    absl::StrAppend(&out, "\n      ]\n    }");
  }
  absl::StrAppend(&out, "\n  ]\n}\n");
  return out;
}

absl::StatusOr<ControlSet> ParseControlSet(std::string_view text, std::string_view source) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::ParserException& e) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s:%d: not JSON: %s", source, e.mark.line + 1, e.msg));
  }
  const Field top(root, "", source);
  if (!root.IsMap()) return top.Error("expected a JSON object");
  ControlSet set;
  set.name = std::string(source);
  PATHD_ASSIGN_OR_RETURN(const Field meta, top.Member("lattice_metadata"));
  PATHD_ASSIGN_OR_RETURN(const Field model, meta.Member("motion_model"));
  PATHD_ASSIGN_OR_RETURN(const std::string model_name, model.String());
  absl::StatusOr<LatticeRobot> robot = ParseLatticeRobot(model_name);
  if (!robot.ok()) return model.Error(std::string(robot.status().message()));
  set.robot = *robot;
  PATHD_ASSIGN_OR_RETURN(const Field resolution, meta.Member("grid_resolution"));
  PATHD_ASSIGN_OR_RETURN(set.resolution_m, resolution.Double());
  if (set.resolution_m <= 0.0) return resolution.Error("must be > 0");
  PATHD_ASSIGN_OR_RETURN(const Field radius, meta.Member("turning_radius"));
  PATHD_ASSIGN_OR_RETURN(set.turning_radius_m, radius.Double());
  if (set.turning_radius_m <= 0.0) return radius.Error("must be > 0");
  PATHD_ASSIGN_OR_RETURN(const Field threshold, meta.Member("stopping_threshold", false));
  if (threshold.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(const int64_t v, threshold.Int());
    set.stopping_threshold = static_cast<int32_t>(std::clamp<int64_t>(v, 0, 1000));
  }
  PATHD_ASSIGN_OR_RETURN(const Field tolerance, meta.Member("length_tolerance", false));
  if (tolerance.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(set.length_tolerance, tolerance.Double());
  }
  PATHD_ASSIGN_OR_RETURN(const Field count, meta.Member("num_of_headings"));
  PATHD_ASSIGN_OR_RETURN(const int64_t headings, count.Int());
  if (headings < 1 || headings > 3600) return count.Error("must be in 1..3600");
  PATHD_ASSIGN_OR_RETURN(const Field angles, meta.Member("heading_angles"));
  if (absl::Status s = angles.ExpectList(); !s.ok()) return s;
  if (static_cast<int64_t>(angles.node().size()) != headings) {
    return angles.Error(absl::StrFormat("has %d angles, num_of_headings says %d",
                                        angles.node().size(), headings));
  }
  for (size_t i = 0; i < angles.node().size(); ++i) {
    PATHD_ASSIGN_OR_RETURN(const double a, angles.Element(i).Double());
    if (a < -1e-9 || a >= kTwoPi + 1e-9 || (i > 0 && a <= set.heading_angles.back())) {
      return angles.Element(i).Error("heading angles must increase within [0, 2pi)");
    }
    set.heading_angles.push_back(a);
  }
  PATHD_ASSIGN_OR_RETURN(const Field primitives, top.Member("primitives"));
  if (absl::Status s = primitives.ExpectList(); !s.ok()) return s;
  for (size_t i = 0; i < primitives.node().size(); ++i) {
    PATHD_ASSIGN_OR_RETURN(LatticePrimitive p, ParsePrimitive(primitives.Element(i), set));
    set.primitives.push_back(std::move(p));
  }
  PATHD_ASSIGN_OR_RETURN(const Field declared, meta.Member("number_of_trajectories", false));
  if (declared.node().IsDefined()) {
    PATHD_ASSIGN_OR_RETURN(const int64_t v, declared.Int());
    if (v != static_cast<int64_t>(set.primitives.size())) {
      return declared.Error(absl::StrFormat("says %d, the file has %d primitives", v,
                                            set.primitives.size()));
    }
  }
  if (set.primitives.empty()) return primitives.Error("a control set needs primitives");
  set.Index();
  return set;
}

absl::StatusOr<ControlSet> ReadControlSetFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat("control set file ", path, " cannot be read"));
  std::stringstream text;
  text << in.rdbuf();
  return ParseControlSet(text.str(), path);
}

std::vector<std::string> ShippedControlSetNames() {
  std::vector<std::string> names;
  for (const auto& [name, text] : EmbeddedControlSets()) names.emplace_back(name);
  std::sort(names.begin(), names.end());
  return names;
}

absl::StatusOr<std::shared_ptr<const ControlSet>> LoadControlSet(std::string_view name_or_path) {
  for (const auto& [name, text] : EmbeddedControlSets()) {
    if (name == name_or_path) return Cache().Shipped(name);
  }
  const bool path_like = name_or_path.find('/') != std::string_view::npos ||
                         (name_or_path.size() > 5 &&
                          name_or_path.substr(name_or_path.size() - 5) == ".json");
  if (!path_like) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "lattice \"%s\" is neither a shipped control set (%s) nor a file path", name_or_path,
        absl::StrJoin(ShippedControlSetNames(), ", ")));
  }
  absl::StatusOr<std::shared_ptr<const ControlSet>> set = Cache().File(std::string(name_or_path));
  // A file the query names and cannot be read is the query's fault.
  if (!set.ok() && absl::IsNotFound(set.status())) {
    return absl::InvalidArgumentError(std::string(set.status().message()));
  }
  return set;
}

absl::StatusOr<std::shared_ptr<const ControlSet>> ControlSetForQuery(const KinematicQuery& query) {
  if (!query.lattice.empty()) return LoadControlSet(query.lattice);
  LatticeGeneratorOptions options;
  options.headings = 16;
  switch (query.motion) {
    case MotionModel::kDubins:
      options.robot = LatticeRobot::kAckermann;
      break;
    case MotionModel::kReedsShepp:
      options.robot = LatticeRobot::kAckermann;
      options.reverse = true;
      break;
    case MotionModel::kDifferential:
      options.robot = LatticeRobot::kDifferential;
      break;
    case MotionModel::kOmnidirectional:
      options.robot = LatticeRobot::kOmnidirectional;
      break;
  }
  double radius = query.min_turning_radius_cells;
  if (options.robot != LatticeRobot::kAckermann && radius == 0.0) radius = kDefaultArcRadiusCells;
  if (!std::isfinite(radius) || radius <= 0.0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "min_turning_radius %g cells must be a positive number for a %s robot", radius,
        MotionModelName(query.motion)));
  }
  const bool reverse = options.robot != LatticeRobot::kAckermann || options.reverse;
  for (const ShippedSummary& s : ShippedSummaries()) {
    // A set with reverse moves serves a robot without: the planner leaves
    // them out.
    if (s.robot == options.robot && (s.reverse || !reverse) && s.headings == 16 &&
        std::fabs(s.radius_cells - radius) <= 1e-9 * radius) {
      return Cache().Shipped(s.name);
    }
  }
  options.resolution_m = 1.0;
  options.turning_radius_m = radius;
  return Cache().Generated(options);
}

}  // namespace pathd
