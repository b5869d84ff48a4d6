#pragma once
/// Reading a study file (study.cpp, study_design.cpp): every problem is collected before they
/// are reported together, each naming its key.

#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/session/study.hpp"

namespace hattr::session::detail {

/// Collects every problem of a study file before reporting them together.
class Problems {
 public:
  explicit Problems(std::string_view source) : source_(source) {}
  void add(std::string text) { lines_.push_back(std::move(text)); }
  [[nodiscard]] std::size_t count() const noexcept { return lines_.size(); }
  void throwIfAny() const {
    if (lines_.empty()) return;
    std::string message = fmt::format("{}: {} problem{} in the study definition:", source_, lines_.size(),
                                      lines_.size() == 1 ? "" : "s");
    for (const auto& l : lines_) message += "\n  - " + l;
    throw InputError(message);
  }

 private:
  std::string source_;
  std::vector<std::string> lines_;
};

/// Reads a number key within a range, noting a problem instead of throwing.
template <typename T>
void readNumber(const nlohmann::json& object, const char* key, T& value, double lo, double hi, const std::string& where,
                Problems& problems) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  const bool integral = std::is_integral_v<T>;
  if (!it->is_number() || (integral && !it->is_number_integer()) || it->get<double>() < lo || it->get<double>() > hi) {
    problems.add(fmt::format("{}{}: expected {} in [{}, {}], got {}", where, key, integral ? "an integer" : "a number",
                             lo, hi, jsonExcerpt(*it)));
    return;
  }
  value = it->get<T>();
}

/// Reads a boolean key, noting a problem instead of throwing.
inline void readBool(const nlohmann::json& object, const char* key, bool& value, const std::string& where,
                     Problems& problems) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  if (it->is_boolean()) value = it->get<bool>();
  else problems.add(fmt::format("{}{}: expected true or false, got {}", where, key, jsonExcerpt(*it)));
}

/// Subjects as a study file lists them: a list of {"id", "participant", "seed", "options"}, or
/// {"count": N, "prefix": P, "participant", "options"} (ids P01...; P by default "S" in the paper's
/// form, the group's name in a group; seeds first_seed + 1...). `where` prefixes the key in
/// messages ("subjects", "groups[1].subjects").
std::vector<SubjectSpec> readSubjects(const nlohmann::json& subjects, const std::string& where,
                                      const std::string& group, std::uint64_t first_seed, Problems& problems,
                                      const std::string& default_prefix = "S");

/// The design keys of a study file (groups, sessions) into `study`, or the paper's form
/// (modes, protocol, subjects) turned into its one group and one session; then every check
/// of the design as a whole. `study.protocol` and `study.skill` are read already.
void readDesign(const nlohmann::json& root, StudyDefinition& study, Problems& problems);

/// The design keys as studyToJson writes them for a study not of the paper's form.
void writeDesign(const StudyDefinition& study, nlohmann::json& root);

}  // namespace hattr::session::detail
