#pragma once
/// A learner: the person a practice plan is for (a teacher's or therapist's pupil), stored in
/// the study database as that subject's options under "learner":
///
///   {"id": "mia", "participant": "person",
///    "options": {"learner": {"name": "Mia", "age_years": 7, "handedness": "left", "notes": "..."}}}
///
/// The code (the subject id) is what analyses and exports use. The name and the notes identify
/// the person: an export leaves them out unless asked to keep them (pseudonymized by default;
/// docs/studies.md, "Learners"). Age and handedness stay: they describe, they do not name.

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/session/study.hpp"

namespace hattr::session {

struct Learner {
  std::string code;              ///< the subject id: a safe file name ("mia", "L01")
  std::string name;              ///< identifying; "" when not given
  std::optional<int> age_years;  ///< 1 to 120 when given
  std::string handedness;        ///< "right", "left", "both" or "" (not known)
  std::string notes;             ///< identifying; free text
};

/// The learner's details as a subject's options["learner"] (fields not given are left out).
[[nodiscard]] nlohmann::json learnerOptions(const Learner& learner);
/// The learner a subject is: its id and its options["learner"] (all empty but the code when
/// there are none). Throws InputError naming the subject and the field for a malformed one.
[[nodiscard]] Learner learnerOf(const SubjectSpec& subject);
/// Every problem of a new learner, one a line: an empty or unsafe code (isSafeFileName), an age
/// outside 1–120, an unknown handedness. Empty when there is none.
[[nodiscard]] std::vector<std::string> learnerProblems(const Learner& learner);
/// Throws InputError listing learnerProblems, one a line, when there are any.
void checkLearner(const Learner& learner);
/// How people see the learner: "Mia (mia)", or the code alone when no name is given or
/// `identified` is false.
[[nodiscard]] std::string displayName(const Learner& learner, bool identified = true);
/// A skill as people write it, when the letter library names it: "small-a" -> "a", "capital-a"
/// -> "A", "digit-7" -> "7"; any other skill as it is ("na", "loop").
[[nodiscard]] std::string letterName(const std::string& skill);
/// The study with every learner's name and notes removed (an export's default).
void pseudonymize(StudyDefinition& study);

}  // namespace hattr::session
