#include "hattr/sim/in_silico.hpp"

#include <gtest/gtest.h>

#include "hattr/session/study_database.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

/// A short in-silico study (3 subjects, 1 training and 2 recall trials per mode) run with
/// `threads` subjects at once: its database's trials and its analysis.
struct SmallStudy {
  std::vector<HapticProfile> trials;
  std::vector<std::string> outcomes;
  std::vector<double> trajectory_costs;
  std::vector<double> force_costs;
};

SmallStudy runSmallStudy(const std::filesystem::path& dir, int threads) {
  const InSilicoResult r = runInSilicoStudy(
      {.out_dir = dir, .glyph = test::kStudyGlyph, .subjects = 3, .seed = 7, .training_trials = 1, .recall_trials = 2, .write_report = false,
       .threads = threads});
  SmallStudy s;
  const auto db = session::StudyDatabase::open(r.database, session::OpenMode::kReadOnly);
  for (const session::TrialRecord& t : db.trials()) {
    EXPECT_EQ(t.status, session::TrialStatus::kCompleted) << t.id;
    s.trials.push_back(db.trialProfile(t.id));
    s.outcomes.push_back(t.plan.subject + " " + t.outcome);
  }
  for (const auto& c : r.analysis.costs) {
    s.trajectory_costs.push_back(c.score.shape());
    s.force_costs.push_back(c.score.force());
  }
  return s;
}

// Simulated subjects run at once, each on its own thread with its own paper and device, give
// the same trials to the bit as one at a time: each subject's trials depend on it alone.
TEST(InSilicoStudy, SubjectsRunAtOnceGiveTheSameTrialsToTheBitAsOneAtATime) {
  test::TempDir dir;
  const SmallStudy one = runSmallStudy(dir / "one", 1);
  const SmallStudy three = runSmallStudy(dir / "three", 3);
  ASSERT_EQ(one.trials.size(), 3u * 3u * 3u);
  ASSERT_EQ(three.trials.size(), one.trials.size());
  for (std::size_t i = 0; i < one.trials.size(); ++i) {
    EXPECT_EQ(three.trials[i], one.trials[i]) << "trial " << i;
    EXPECT_EQ(three.outcomes[i], one.outcomes[i]) << "trial " << i;
  }
  EXPECT_EQ(three.trajectory_costs, one.trajectory_costs);
  EXPECT_EQ(three.force_costs, one.force_costs);
  EXPECT_FALSE(one.trajectory_costs.empty());
}

}  // namespace
}  // namespace hattr::sim
