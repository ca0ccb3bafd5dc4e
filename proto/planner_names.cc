// Planner names from the pathd.v1.Planner descriptor.
#include "proto/planner_names.h"

#include <cctype>

#include "google/protobuf/descriptor.h"

namespace pathd {

const std::vector<WirePlanner>& WirePlanners() {
  static const std::vector<WirePlanner>* const kPlanners = [] {
    auto* planners = new std::vector<WirePlanner>();
    const google::protobuf::EnumDescriptor* descriptor = v1::Planner_descriptor();
    constexpr std::string_view kPrefix = "PLANNER_";
    for (int i = 0; i < descriptor->value_count(); ++i) {
      const google::protobuf::EnumValueDescriptor* value = descriptor->value(i);
      if (value->number() == v1::PLANNER_UNSPECIFIED) continue;
      std::string name = value->name().substr(kPrefix.size());
      for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      planners->push_back({static_cast<v1::Planner>(value->number()), std::move(name)});
    }
    return planners;
  }();
  return *kPlanners;
}

std::optional<std::string_view> WirePlannerName(int planner) {
  for (const WirePlanner& p : WirePlanners()) {
    if (p.wire == planner) return std::string_view(p.name);
  }
  return std::nullopt;
}

std::optional<v1::Planner> WirePlannerFromName(std::string_view name) {
  for (const WirePlanner& p : WirePlanners()) {
    if (p.name == name) return p.wire;
  }
  return std::nullopt;
}

}  // namespace pathd
