// The shipped designs (`hattr study example --list`, docs/studies.md "Designs").

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study.hpp"

namespace hattr::session {
namespace {

/// The paper's experiment, in the paper's form (hattr's default since the first release).
constexpr std::string_view kPaper = R"({
  "format": "hattr-study/1",
  "name": "Na: three training modes",
  "skill": "na",
  "experts": {"na": "expert.csv"},
  "modes": ["basic", "pcontrol", "alpha"],
  "protocol": {
    "training_trials": 11,
    "recall_trials": 11,
    "rest_s": 10,
    "trial_end": {"pen_up_s": 1.0, "max_s": 0},
    "training": {"show_reference": true, "guidance": true},
    "recall": {"show_reference": false, "guidance": false},
    "analyzed_recall_trials": [2, 3, 4, 5, 6, 7, 8, 9, 10, 11],
    "disturbed_trials": "repeat",
    "max_repeats": 2,
    "show_scores": false
  },
  "order": {"kind": "latin-square"},
  "device": "sim://pen",
  "world": {"relief": {"kind": "grain"}},
  "rate_hz": 1000,
  "indexing": "time",
  "subjects": {"count": 10, "prefix": "S", "participant": "simulated"}
}
)";

/// Three groups, each trained with one strategy over two days, tested the day after.
constexpr std::string_view kGroupsRetention = R"({
  "format": "hattr-study/1",
  "name": "Three groups: training over two days, retention and transfer",
  "skill": "na",
  "experts": {"na": "expert.csv", "loop": "loop.csv"},
  "protocol": {"rest_s": 10, "trial_end": {"pen_up_s": 1.0, "max_s": 0}, "disturbed_trials": "repeat",
               "max_repeats": 2, "show_scores": false},
  "order": {"kind": "fixed"},
  "device": "sim://pen",
  "world": {"relief": {"kind": "grain"}},
  "rate_hz": 1000,
  "indexing": "time",
  "groups": [
    {"name": "free", "strategies": ["basic"], "subjects": {"count": 8, "prefix": "F"}},
    {"name": "path", "strategies": ["pcontrol"], "subjects": {"count": 8, "prefix": "P"}},
    {"name": "force", "strategies": ["alpha"], "subjects": {"count": 8, "prefix": "A"}}
  ],
  "sessions": [
    {"day": 0, "blocks": [
      {"phase": "baseline", "trials": 5, "show_reference": true},
      {"phase": "training", "strategy": "group", "trials": 10}
    ]},
    {"day": 1, "blocks": [
      {"phase": "training", "strategy": "group", "trials": 10},
      {"phase": "post-test", "trials": 5}
    ]},
    {"day": 2, "blocks": [
      {"phase": "retention", "trials": 5},
      {"phase": "transfer", "skill": "loop", "trials": 5, "show_reference": true}
    ]}
  ]
}
)";

/// The paper's modes within subjects, and the whole of it again a week later (figure 3).
constexpr std::string_view kWeekApart = R"({
  "format": "hattr-study/1",
  "name": "Na: three modes, repeated a week later",
  "skill": "na",
  "experts": {"na": "expert.csv"},
  "protocol": {"rest_s": 10, "trial_end": {"pen_up_s": 1.0, "max_s": 0}, "disturbed_trials": "repeat",
               "max_repeats": 2, "show_scores": false},
  "order": {"kind": "latin-square"},
  "device": "sim://pen",
  "world": {"relief": {"kind": "grain"}},
  "rate_hz": 1000,
  "indexing": "time",
  "groups": [
    {"name": "all", "strategies": ["basic", "pcontrol", "alpha"], "subjects": {"count": 6, "prefix": "S"}}
  ],
  "sessions": [
    {"day": 0, "blocks": [
      {"phase": "training", "strategy": {"order": 1}, "trials": 11},
      {"phase": "recall", "strategy": {"order": 1}, "guidance": false, "trials": 11},
      {"phase": "training", "strategy": {"order": 2}, "trials": 11},
      {"phase": "recall", "strategy": {"order": 2}, "guidance": false, "trials": 11},
      {"phase": "training", "strategy": {"order": 3}, "trials": 11},
      {"phase": "recall", "strategy": {"order": 3}, "guidance": false, "trials": 11}
    ]},
    {"day": 7, "blocks": [
      {"phase": "training", "strategy": {"order": 1}, "trials": 11},
      {"phase": "recall", "strategy": {"order": 1}, "guidance": false, "trials": 11},
      {"phase": "training", "strategy": {"order": 2}, "trials": 11},
      {"phase": "recall", "strategy": {"order": 2}, "guidance": false, "trials": 11},
      {"phase": "training", "strategy": {"order": 3}, "trials": 11},
      {"phase": "recall", "strategy": {"order": 3}, "guidance": false, "trials": 11}
    ]}
  ]
}
)";

/// One learner practising a letter three times a week for two weeks.
constexpr std::string_view kLearner = R"({
  "format": "hattr-study/1",
  "name": "Practice: one learner, two weeks",
  "skill": "na",
  "experts": {"na": "expert.csv"},
  "protocol": {"rest_s": 5, "trial_end": {"pen_up_s": 1.0, "max_s": 0}, "disturbed_trials": "repeat",
               "max_repeats": 2, "show_scores": true},
  "order": {"kind": "fixed"},
  "device": "sim://pen",
  "world": {"relief": {"kind": "grain"}},
  "rate_hz": 1000,
  "indexing": "time",
  "groups": [
    {"name": "learner", "strategies": ["alpha"], "subjects": [{"id": "L01", "participant": "person"}]}
  ],
  "sessions": [
    {"day": 0, "blocks": [{"phase": "baseline", "trials": 3, "show_reference": true},
                          {"phase": "training", "strategy": "group", "trials": 8},
                          {"phase": "post-test", "trials": 3}]},
    {"day": 2, "blocks": [{"phase": "training", "strategy": "group", "trials": 8}, {"phase": "post-test", "trials": 3}]},
    {"day": 4, "blocks": [{"phase": "training", "strategy": "group", "trials": 8}, {"phase": "post-test", "trials": 3}]},
    {"day": 7, "blocks": [{"phase": "training", "strategy": "group", "trials": 8}, {"phase": "post-test", "trials": 3}]},
    {"day": 9, "blocks": [{"phase": "training", "strategy": "group", "trials": 8}, {"phase": "post-test", "trials": 3}]},
    {"day": 11, "blocks": [{"phase": "training", "strategy": "group", "trials": 8}, {"phase": "post-test", "trials": 3}]},
    {"day": 14, "blocks": [{"phase": "retention", "trials": 3}]}
  ]
}
)";

/// Guidance fading over sessions: the guided path at full strength throughout, faded to nothing
/// over three days of training, or adapted to each trainee's errors; then a post-test and retention.
constexpr std::string_view kFading = R"({
  "format": "hattr-study/1",
  "name": "Guided path: constant, fading over sessions, or as needed",
  "skill": "na",
  "experts": {"na": "expert.csv"},
  "protocol": {"rest_s": 10, "trial_end": {"pen_up_s": 1.0, "max_s": 0}, "disturbed_trials": "repeat",
               "max_repeats": 2, "show_scores": false},
  "order": {"kind": "fixed"},
  "device": "sim://pen",
  "world": {"relief": {"kind": "grain"}},
  "rate_hz": 1000,
  "indexing": "time",
  "strategy_parameters": {
    "fading": {"base": "pcontrol", "by": "trials", "start_gain": 1, "end_gain": 0, "trials": 30},
    "assist-as-needed": {"base": "pcontrol", "start_gain": 1}
  },
  "groups": [
    {"name": "constant", "strategies": ["pcontrol"], "subjects": {"count": 8, "prefix": "C"}},
    {"name": "fading", "strategies": ["fading"], "subjects": {"count": 8, "prefix": "F"}},
    {"name": "as-needed", "strategies": ["assist-as-needed"], "subjects": {"count": 8, "prefix": "N"}}
  ],
  "sessions": [
    {"day": 0, "blocks": [
      {"phase": "baseline", "trials": 5, "show_reference": true},
      {"phase": "training", "strategy": "group", "trials": 10}
    ]},
    {"day": 1, "blocks": [{"phase": "training", "strategy": "group", "trials": 10}]},
    {"day": 2, "blocks": [
      {"phase": "training", "strategy": "group", "trials": 10},
      {"phase": "post-test", "trials": 5}
    ]},
    {"day": 3, "blocks": [{"phase": "retention", "trials": 5}]}
  ]
}
)";

}  // namespace

const std::vector<ExampleDesign>& exampleDesigns() {
  static const std::vector<ExampleDesign> designs{
      {"paper", "the paper's: which mode helps most, every subject in every mode in one sitting", kPaper},
      {"groups-retention",
       "which strategy's learning lasts a day and transfers to a new character: three groups, two training days",
       kGroupsRetention},
      {"week-apart", "does each mode's effect hold a week later: the paper's modes, repeated on day 7", kWeekApart},
      {"learner", "how one learner progresses: practice three times a week for two weeks, then retention", kLearner},
      {"fading",
       "does guidance that fades over sessions, or adapts to errors, leave more learning than constant guidance",
       kFading},
  };
  return designs;
}

const ExampleDesign& exampleDesign(std::string_view name) {
  std::string names;
  for (const ExampleDesign& d : exampleDesigns()) {
    if (d.name == name) return d;
    names += names.empty() ? std::string(d.name) : ", " + std::string(d.name);
  }
  throw InputError(fmt::format("--design {}: no such design: expected one of {}", name, names));
}

std::string exampleStudyJson() { return std::string(kPaper); }

}  // namespace hattr::session
