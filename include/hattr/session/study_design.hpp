#pragma once
/// A study's experimental design (docs/studies.md "Designs"): between-subjects groups, each with
/// its strategies in a counterbalanced order, and a schedule of sessions on day offsets, each a
/// sequence of blocks (a phase, a skill, a strategy, trials, what the trainee gets). The paper's
/// protocol (every subject in every mode, training then recall, one sitting) is one design:
/// a study file in the paper's form (modes + protocol) is read as one group and one session.

#include <string>
#include <string_view>
#include <vector>

#include "hattr/guidance/training_guidance.hpp"

namespace hattr::session {

/// What the trainee gets in a block's trials.
struct PhaseView {
  bool show_reference = true;  ///< the expert's trajectory is drawn
  bool guidance = true;        ///< the strategy's assistance force acts (false: none)
};

/// The phases hattr names (any other label is allowed and reported as it is).
inline constexpr std::string_view kPhaseTraining = "training";
inline constexpr std::string_view kPhaseRecall = "recall";
inline constexpr std::string_view kPhaseBaseline = "baseline";
inline constexpr std::string_view kPhasePostTest = "post-test";
inline constexpr std::string_view kPhaseRetention = "retention";
inline constexpr std::string_view kPhaseTransfer = "transfer";

/// Which strategy a block's trials use: none, a named one, or the one at a position of the
/// subject's counterbalanced order (its group's strategies; "group" in a study file is position 1).
struct StrategyRef {
  enum class Kind { kNone, kNamed, kOrderPosition };
  Kind kind = Kind::kNone;
  guidance::TrainingMode mode = guidance::TrainingMode::kBasic;  ///< kNamed
  int position = 1;                                               ///< kOrderPosition, from 1
};

/// One block of a session: `trials` trials of one phase, skill and strategy.
struct Block {
  std::string phase{kPhaseTraining};
  std::string skill;   ///< a key of the study's experts
  StrategyRef strategy;
  int trials = 1;
  PhaseView view;
  double rest_s = 10.0;  ///< before each trial but the session's first [s]
};

/// One session of the schedule: its day offset from the subject's first session, and its blocks.
struct ScheduledSession {
  int day = 0;
  std::vector<Block> blocks;
};

/// A between-subjects group: its strategies, counterbalanced across its subjects by the
/// study's order (one strategy: every subject of the group gets it).
struct Group {
  std::string name;
  std::vector<guidance::TrainingMode> strategies;
};

/// The group name of a study file in the paper's form (one group, every subject in every mode).
inline constexpr std::string_view kWithinSubjectsGroup = "all";

}  // namespace hattr::session
