#include "hattr/session/learner.hpp"

#include <cctype>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"

namespace hattr::session {
namespace {

using nlohmann::json;

bool knownHandedness(const std::string& h) { return h.empty() || h == "right" || h == "left" || h == "both"; }

/// A string field of options["learner"] ("" when absent).
std::string textField(const json& learner, const char* key, const std::string& subject) {
  if (!learner.contains(key)) return {};
  HATTR_THROW_UNLESS(learner[key].is_string(), "subject {}: options.learner.{}: expected text, got {}", subject, key,
                     jsonExcerpt(learner[key]));
  return learner[key].get<std::string>();
}

}  // namespace

json learnerOptions(const Learner& learner) {
  json out = json::object();
  if (!learner.name.empty()) out["name"] = learner.name;
  if (learner.age_years) out["age_years"] = *learner.age_years;
  if (!learner.handedness.empty()) out["handedness"] = learner.handedness;
  if (!learner.notes.empty()) out["notes"] = learner.notes;
  return out;
}

Learner learnerOf(const SubjectSpec& subject) {
  Learner out{.code = subject.id};
  if (!subject.options.is_object() || !subject.options.contains("learner")) return out;
  const json& l = subject.options["learner"];
  HATTR_THROW_UNLESS(l.is_object(), "subject {}: options.learner: expected an object, got {}", subject.id,
                     jsonExcerpt(l));
  out.name = textField(l, "name", subject.id);
  out.handedness = textField(l, "handedness", subject.id);
  out.notes = textField(l, "notes", subject.id);
  if (l.contains("age_years")) {
    HATTR_THROW_UNLESS(l["age_years"].is_number_integer(), "subject {}: options.learner.age_years: expected a whole "
                       "number of years, got {}", subject.id, jsonExcerpt(l["age_years"]));
    out.age_years = l["age_years"].get<int>();
  }
  return out;
}

std::vector<std::string> learnerProblems(const Learner& learner) {
  std::vector<std::string> problems;
  if (!isSafeFileName(learner.code)) {
    problems.push_back(fmt::format("code \"{}\": expected {} (it names the learner in files and exports)",
                                   textExcerpt(learner.code), kSafeFileNameRule));
  }
  if (learner.age_years && (*learner.age_years < 1 || *learner.age_years > 120)) {
    problems.push_back(fmt::format("age: expected 1 to 120 years, got {}", *learner.age_years));
  }
  if (!knownHandedness(learner.handedness)) {
    problems.push_back(fmt::format("handedness: expected right, left or both (or nothing), got \"{}\"",
                                   textExcerpt(learner.handedness)));
  }
  return problems;
}

void checkLearner(const Learner& learner) {
  const auto problems = learnerProblems(learner);
  if (problems.empty()) return;
  std::string message = fmt::format("learner: {} problem{}:", problems.size(), problems.size() == 1 ? "" : "s");
  for (const auto& p : problems) message += "\n  - " + p;
  throw InputError(message);
}

std::string displayName(const Learner& learner, bool identified) {
  return identified && !learner.name.empty() ? learner.name + " (" + learner.code + ")" : learner.code;
}

std::string letterName(const std::string& skill) {
  const auto single = [&](std::string_view prefix) {
    return skill.size() == prefix.size() + 1 && skill.starts_with(prefix);
  };
  if (single("small-")) return skill.substr(6);
  if (single("capital-")) return {static_cast<char>(std::toupper(static_cast<unsigned char>(skill.back())))};
  if (single("digit-")) return skill.substr(6);
  return skill;
}

void pseudonymize(StudyDefinition& study) {
  for (SubjectSpec& s : study.subjects) {
    if (!s.options.is_object() || !s.options.contains("learner") || !s.options["learner"].is_object()) continue;
    s.options["learner"].erase("name");
    s.options["learner"].erase("notes");
  }
}

}  // namespace hattr::session
