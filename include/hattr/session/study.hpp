#pragma once
/// A training study (the paper's section 5) as data: which expert references, which modes
/// in which order for which subjects, how many training and recall trials, the rests, what
/// the trainee sees in each phase, the device and the paper. Read from a JSON study file
/// (docs/studies.md gives the format and an example); validation names every problem at
/// once.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/guidance/training_guidance.hpp"

namespace hattr::session {

/// The two phases of each mode's block.
enum class Phase { kTraining, kRecall };
std::string_view phaseName(Phase phase);  ///< "training", "recall"

/// What the trainee gets in a phase.
struct PhaseView {
  bool show_reference = true;  ///< the expert's trajectory is drawn
  bool guidance = true;        ///< the mode's assistance force acts (false: BASIC)
};

/// How mode orders are assigned to subjects.
enum class OrderKind { kLatinSquare, kFixed, kRandom };

struct Protocol {
  int training_trials = 11;
  int recall_trials = 11;
  double rest_s = 10.0;       ///< between trials
  double tail_s = 0.5;        ///< each trial lasts the expert's duration plus this
  PhaseView training{true, true};
  PhaseView recall{false, false};
};

/// Who a subject is: a simulated trainee, a scripted hand, or a person.
struct SubjectSpec {
  std::string id;
  std::string participant = "simulated";  ///< "simulated", "script", "person"
  std::uint64_t seed = 0;
  nlohmann::json options;                  ///< participant-specific settings (e.g. a hand script)
};

struct StudyDefinition {
  std::string name;
  std::string skill;                                        ///< the character / skill trained
  std::map<std::string, std::filesystem::path> experts;     ///< skill -> expert profile file
  std::vector<guidance::TrainingMode> modes;                ///< compared modes
  Protocol protocol;
  OrderKind order = OrderKind::kLatinSquare;
  std::uint64_t order_seed = 1;                             ///< kRandom
  std::string device = "sim://pen";
  nlohmann::json world = nlohmann::json::object();          ///< a world config object (docs/rendering.md)
  double rate_hz = 1000.0;
  guidance::Indexing indexing = guidance::Indexing::kTime;
  std::vector<SubjectSpec> subjects;
};

/// Parses and validates a study file's text. Relative expert paths resolve against
/// `base_dir`; with `check_files`, each must exist. Throws InputError listing every problem
/// found, one per line.
StudyDefinition parseStudy(std::string_view json_text, std::string_view source_name,
                           const std::filesystem::path& base_dir, bool check_files = true);
StudyDefinition loadStudy(const std::filesystem::path& file);
/// The definition as JSON (stored in the study database; parseStudy reads it back).
nlohmann::json studyToJson(const StudyDefinition& study);
/// An example study file (`hattr study example`).
std::string exampleStudyJson();

/// The mode order of each subject, by position in the subject list: a Williams design
/// (a Latin square balanced for first-order carry-over; two squares for an odd number of
/// modes), the listed order for everyone, or a seeded shuffle per subject.
std::vector<std::vector<guidance::TrainingMode>> modeOrders(const StudyDefinition& study);

/// One planned trial of one subject.
struct TrialPlan {
  std::string subject;
  int sequence = 0;             ///< position in the subject's whole session, from 0
  guidance::TrainingMode mode = guidance::TrainingMode::kBasic;
  Phase phase = Phase::kTraining;
  int index = 0;                ///< trial number within the mode's phase, from 1
  PhaseView view;
};

/// Every trial of a subject in order: for each mode in `order`, the training trials then
/// the recall trials.
std::vector<TrialPlan> planTrials(const StudyDefinition& study, const std::string& subject,
                                  const std::vector<guidance::TrainingMode>& order);

}  // namespace hattr::session
