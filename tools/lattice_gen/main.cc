// lattice_gen: writes a minimal control set for the state_lattice planner
// (core/kinematics/lattice_generator.h) as a control-set file, the JSON of
// ROS 2 Nav2's lattice primitive generator (docs/planners.md, "Control
// sets"). The sets in data/lattices/ were made with it:
//
//   lattice_gen --robot ackermann --resolution 0.05 --turning_radius 0.5
//       --output data/lattices/ackermann_5cm_r50cm.json
//
// --summary prints the primitives per start heading to stderr; --check FILE
// reads a control-set file (pathd's or Nav2's) and prints its summary or
// the error naming the line and field.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/kinematics/lattice.h"
#include "core/kinematics/lattice_generator.h"

ABSL_FLAG(std::string, robot, "ackermann", "diff, ackermann or omni");
ABSL_FLAG(bool, reverse, false, "ackermann: add every move driven backwards");
ABSL_FLAG(double, resolution, 0.05, "grid resolution, metres per cell");
ABSL_FLAG(double, turning_radius, 0.5, "minimum turning radius, metres");
ABSL_FLAG(int32_t, headings, 16, "heading count, a multiple of 8 (8..64)");
ABSL_FLAG(double, length_tolerance, 0.1,
          "drop a candidate that a chain of kept primitives reaches within "
          "(1 + this) x its length");
ABSL_FLAG(int32_t, stopping_threshold, 5,
          "rings of end points without a new primitive before stopping");
ABSL_FLAG(std::string, output, "", "file to write (default: standard output)");
ABSL_FLAG(bool, summary, false, "print the primitives per start heading to stderr");
ABSL_FLAG(std::string, check, "",
          "read this control-set file instead of generating one; print its summary");

namespace {

void PrintSummary(const pathd::ControlSet& set) {
  for (int32_t h = 0; h < set.headings(); ++h) {
    std::cerr << absl::StrFormat("heading %2d (%6.2f deg):", h,
                                 set.heading_angles[h] * 180.0 / 3.14159265358979323846);
    for (size_t i = set.first_of_heading[h]; i < set.first_of_heading[h + 1]; ++i) {
      const pathd::LatticePrimitive& p = set.primitives[i];
      std::cerr << absl::StrFormat(" %s(%d,%d)->%d", p.reverse ? "-" : (p.turn_in_place ? "@" : ""),
                                   p.dx, p.dy, p.end_heading);
    }
    std::cerr << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "Generates a minimal control set for the state_lattice planner.\n"
      "  lattice_gen --robot ackermann --reverse --resolution 0.05 "
      "--turning_radius 0.5 --output set.json");
  absl::ParseCommandLine(argc, argv);
  if (const std::string file = absl::GetFlag(FLAGS_check); !file.empty()) {
    absl::StatusOr<pathd::ControlSet> set = pathd::ReadControlSetFile(file);
    if (!set.ok()) {
      std::cerr << "lattice_gen: " << set.status().message() << "\n";
      return 1;
    }
    std::cerr << absl::StrFormat("%s: %s, %d primitives, %d headings, turning radius %g cells%s\n",
                                 file, pathd::LatticeRobotName(set->robot), set->primitives.size(),
                                 set->headings(), set->turning_radius_cells(),
                                 set->has_reverse() ? ", with reverse moves" : "");
    if (absl::GetFlag(FLAGS_summary)) PrintSummary(*set);
    return 0;
  }
  absl::StatusOr<pathd::LatticeRobot> robot = pathd::ParseLatticeRobot(absl::GetFlag(FLAGS_robot));
  if (!robot.ok()) {
    std::cerr << "lattice_gen: --robot: " << robot.status().message() << "\n";
    return 2;
  }
  pathd::LatticeGeneratorOptions options;
  options.robot = *robot;
  options.reverse = absl::GetFlag(FLAGS_reverse);
  options.resolution_m = absl::GetFlag(FLAGS_resolution);
  options.turning_radius_m = absl::GetFlag(FLAGS_turning_radius);
  options.headings = absl::GetFlag(FLAGS_headings);
  options.length_tolerance = absl::GetFlag(FLAGS_length_tolerance);
  options.stopping_threshold = absl::GetFlag(FLAGS_stopping_threshold);
  const absl::Time started = absl::Now();
  absl::StatusOr<pathd::ControlSet> set = pathd::GenerateControlSet(options);
  if (!set.ok()) {
    std::cerr << "lattice_gen: " << set.status().message() << "\n";
    return 2;
  }
  const double seconds = absl::ToDoubleSeconds(absl::Now() - started);
  const std::string text = pathd::WriteControlSet(*set);
  const std::string output = absl::GetFlag(FLAGS_output);
  if (output.empty()) {
    std::cout << text;
  } else {
    std::ofstream out(output, std::ios::binary);
    out << text;
    if (!out.good()) {
      std::cerr << "lattice_gen: cannot write " << output << "\n";
      return 1;
    }
  }
  std::cerr << absl::StrFormat("%s: %d primitives, %d headings, turning radius %g cells, %.2f s\n",
                               set->name, set->primitives.size(), set->headings(),
                               set->turning_radius_cells(), seconds);
  if (absl::GetFlag(FLAGS_summary)) PrintSummary(*set);
  return 0;
}
