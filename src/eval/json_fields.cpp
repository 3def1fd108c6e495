// JSON spellings shared by the experiments' outputs (src/eval/json_fields.hpp).
#include "json_fields.hpp"

namespace seif {

nlohmann::json toJson(const NoiseModel& n) {
  return {{"sigma_v", n.sigma_v},
          {"sigma_w", n.sigma_w},
          {"sigma_range", n.sigma_range},
          {"sigma_bearing", n.sigma_bearing}};
}

nlohmann::json toJson(const SeifOptions& o) {
  FilterSpec spec;
  spec.name = "seif";
  spec.seif = o;
  nlohmann::json j = nlohmann::json::object();
  for (const FilterOption& option : filterOptions()) {
    if (option.scope != FilterOption::Scope::Seif || option.kind == FilterOption::Kind::Profile) continue;
    const std::string value = option.get(spec);
    switch (option.kind) {
      case FilterOption::Kind::Choice: j[std::string(option.key)] = value; break;
      case FilterOption::Kind::Integer: j[std::string(option.key)] = std::stoll(value); break;
      case FilterOption::Kind::Seed: j[std::string(option.key)] = std::stoull(value); break;
      case FilterOption::Kind::Length:
      case FilterOption::Kind::Fraction:
      case FilterOption::Kind::Real: j[std::string(option.key)] = std::stod(value); break;
      case FilterOption::Kind::Profile: break;
    }
  }
  return j;
}

nlohmann::json toJson(const AssociationOptions& o) {
  nlohmann::json j = nlohmann::json::object();
  for (const AssociationOption& option : associationOptions()) {
    const std::string value = option.get(o), key(option.attribute);
    switch (option.kind) {
      case AssociationOption::Kind::Choice: j[key] = value; break;
      case AssociationOption::Kind::Integer: j[key] = std::stoll(value); break;
      case AssociationOption::Kind::Probability:
      case AssociationOption::Kind::Length:
      case AssociationOption::Kind::Real: j[key] = std::stod(value); break;
      case AssociationOption::Kind::Flag: j[key] = value == "true"; break;
    }
  }
  return j;
}

nlohmann::json toJson(const FilterStats& s) {
  return {{"landmarks", s.landmarks},
          {"links", s.links},
          {"robot_links", s.robot_links},
          {"max_landmark_links", s.max_landmark_links},
          {"blocks_touched", s.blocks_touched},
          {"information_scale", s.information_scale}};
}

}  // namespace seif
