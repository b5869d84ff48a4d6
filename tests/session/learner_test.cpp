// A learner's details in the study database (issue 39): stored as the subject's options, read
// back, checked, and left out of an export unless asked for.

#include "hattr/session/learner.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/session/study_export.hpp"
#include "session/study_fixture.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::session {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

Learner mia() {
  return {.code = "mia", .name = "Mia Example", .age_years = 7, .handedness = "left", .notes = "grips hard"};
}

TEST(Learner, DetailsGoIntoTheSubjectsOptionsAndComeBack) {
  HATTR_STARTS_NO_THREAD();
  const SubjectSpec subject{.id = "mia", .participant = "person", .options = {{"learner", learnerOptions(mia())}}};
  const Learner back = learnerOf(subject);
  EXPECT_EQ(back.code, "mia");
  EXPECT_EQ(back.name, "Mia Example");
  EXPECT_EQ(back.age_years, 7);
  EXPECT_EQ(back.handedness, "left");
  EXPECT_EQ(back.notes, "grips hard");
  // Nothing given: only the code; fields not given are left out of the options.
  EXPECT_EQ(learnerOptions({.code = "L01"}), nlohmann::json::object());
  const Learner bare = learnerOf({.id = "L01"});
  EXPECT_EQ(bare.code, "L01");
  EXPECT_FALSE(bare.age_years.has_value());
}

TEST(Learner, AMalformedStoredLearnerIsNamedWithItsField) {
  HATTR_STARTS_NO_THREAD();
  const SubjectSpec age{.id = "mia", .options = {{"learner", {{"age_years", "seven"}}}}};
  EXPECT_THAT([&] { (void)learnerOf(age); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("subject mia: options.learner.age_years: expected a whole")));
  const SubjectSpec name{.id = "mia", .options = {{"learner", {{"name", 3}}}}};
  EXPECT_THAT([&] { (void)learnerOf(name); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("options.learner.name: expected text, got 3")));
}

TEST(Learner, ANewLearnersProblemsAreAllListed) {
  HATTR_STARTS_NO_THREAD();
  EXPECT_NO_THROW(checkLearner(mia()));
  EXPECT_NO_THROW(checkLearner({.code = "L-01_b"}));
  try {
    checkLearner({.code = "../x", .age_years = 0, .handedness = "up"});
    FAIL() << "a bad learner was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_THAT(message, HasSubstr("learner: 3 problems"));
    EXPECT_THAT(message, HasSubstr("code \"../x\": expected 1 to 64 letters"));
    EXPECT_THAT(message, HasSubstr("age: expected 1 to 120 years, got 0"));
    EXPECT_THAT(message, HasSubstr("handedness: expected right, left or both (or nothing), got \"up\""));
  }
}

TEST(Learner, TheLetterLibrarysSkillsReadAsTheLetters) {
  HATTR_STARTS_NO_THREAD();
  EXPECT_EQ(letterName("small-a"), "a");
  EXPECT_EQ(letterName("capital-q"), "Q");
  EXPECT_EQ(letterName("digit-7"), "7");
  EXPECT_EQ(letterName("na"), "na");
  EXPECT_EQ(letterName("small-ab"), "small-ab");  // not one letter: as it is
}

// The export leaves names and notes out unless asked; the database keeps them.
TEST(Learner, AnExportIsPseudonymizedUnlessIdentified) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  writeExpert(dir / "expert.csv");
  test::writeText(dir / "study.json", R"({"name": "one learner", "skill": "dash", "experts": {"dash": "expert.csv"},
      "modes": ["pcontrol"], "protocol": {"training_trials": 1, "recall_trials": 1},
      "subjects": [{"id": "mia", "participant": "person",
                    "options": {"learner": {"name": "Mia Example", "age_years": 7, "handedness": "left",
                                            "notes": "grips hard"}}}]})");
  const StudyDatabase db = StudyDatabase::create(dir / "s.sqlite", loadStudy(dir / "study.json"));
  (void)exportStudy(db, dir / "plain");
  const std::string plain = test::readText(dir / "plain" / "study.json");
  EXPECT_THAT(plain, Not(HasSubstr("Mia Example")));
  EXPECT_THAT(plain, Not(HasSubstr("grips hard")));
  EXPECT_THAT(plain, HasSubstr("\"age_years\": 7"));
  EXPECT_THAT(plain, HasSubstr("\"handedness\": \"left\""));
  (void)exportStudy(db, dir / "named", {.identified = true});
  const std::string named = test::readText(dir / "named" / "study.json");
  EXPECT_THAT(named, HasSubstr("Mia Example"));
  EXPECT_THAT(named, HasSubstr("grips hard"));
  EXPECT_EQ(learnerOf(db.subjects().front().spec).name, "Mia Example");  // the database keeps them
}

}  // namespace
}  // namespace hattr::session
