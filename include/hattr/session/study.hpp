#pragma once
/// A training study as data: which expert references, which groups of subjects with which
/// strategies in which order, the schedule of sessions and blocks (study_design.hpp), the rests,
/// what the trainee gets in each block, the device and the paper. The paper's protocol (section
/// 5) is one design. Read from a JSON study file (docs/studies.md gives the format and the
/// shipped designs); validation names every problem at once.

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/io/sample_codec.hpp"
#include "hattr/session/study_design.hpp"

namespace hattr::session {

/// How mode orders are assigned to subjects.
enum class OrderKind { kLatinSquare, kFixed, kRandom };

/// What a study does with a trial its servo loop disturbed (a stall that zeroed the force,
/// missed samples, a safety fault or a lost device link): run it again (the disturbed
/// attempt is kept in the database), keep it flagged, or keep it flagged and out of the
/// analysis.
enum class DisturbedPolicy { kRepeat, kFlag, kExclude };
std::string_view disturbedPolicyName(DisturbedPolicy policy);  ///< "repeat", "flag", "exclude"

/// When a study trial ends (docs/studies.md): once the pen has been up for pen_up_s after
/// writing began (the first pen-down), or at the maximum duration.
struct TrialEndRule {
  double pen_up_s = 1.0;  ///< [s]
  double max_s = 0.0;     ///< the longest a trial may last [s]; 0: 3 × the expert's duration
  /// The maximum duration [s] for an expert reference lasting `expert_duration_s`, at most 3600 s.
  [[nodiscard]] double maxDuration_s(double expert_duration_s) const noexcept {
    return std::min(max_s > 0.0 ? max_s : 3.0 * expert_duration_s, 3600.0);
  }
};

/// The study-wide rules, and in a study file of the paper's form its protocol: per mode,
/// training_trials then recall_trials (a design with sessions says its trials per block).
struct Protocol {
  int training_trials = 11;
  int recall_trials = 11;
  /// The recall trials the analysis uses (numbers from 1). Empty: all but the first — hattr's
  /// reading of the paper's "10 of the 11 recall trials" (it does not say which it dropped;
  /// the first recall trial follows the switch from assisted training, docs/replication.md).
  std::vector<int> analyzed_recall_trials;
  DisturbedPolicy disturbed = DisturbedPolicy::kRepeat;
  int max_repeats = 2;        ///< a disturbed trial is run at most this many extra times, then kept flagged
  bool show_scores = false;   ///< show the subject a score after each trial (the paper showed none)
  double rest_s = 10.0;       ///< between trials (a block's default)
  double tail_s = 0.5;        ///< only with fixed_window: each trial lasts the expert's duration plus this
  TrialEndRule trial_end;     ///< when a trial ends (the subject is done)
  /// An old study file (tail_s and no trial_end): every trial lasts the expert's duration plus
  /// tail_s, as before the end rule, so a study begun that way resumes unchanged.
  bool fixed_window = false;
  PhaseView training{true, true};
  PhaseView recall{false, false};
};

/// Who a subject is: a simulated trainee, a scripted hand, or a person.
struct SubjectSpec {
  std::string id;
  std::string participant = "simulated";  ///< "simulated", "script", "person"
  std::uint64_t seed = 0;
  nlohmann::json options;                  ///< participant-specific settings (e.g. a hand script)
  std::string group{kWithinSubjectsGroup}; ///< the group's name (StudyDefinition::groups)
};

/// Who mentors a mentored mode's training trials (the MENTOR-... modes, docs/mentoring.md):
/// a simulated expert who writes the study's expert reference on a second simulated pen,
/// tick for tick with the trainee over an emulated link, or a person at a station running
/// `hattr mentor lead`, reached over UDP.
struct StudyMentor {
  std::string expert = "simulated";        ///< "simulated" or "live"
  std::string connect;                     ///< live: HOST:PORT where `hattr mentor lead` listens
  std::filesystem::path key;               ///< live: the key file both stations share
  double round_trip_s = 0.0;               ///< simulated: the emulated link, half each way [s]
  double jitter_s = 0.0;                   ///< simulated [s]
  double loss = 0.0;                       ///< simulated: the fraction of packets lost, [0, 0.5]
  std::string expert_device = "sim://pen"; ///< simulated: the expert's pen
  bool passivity = true;                   ///< the time-domain passivity controller (bilateral)
  double deadband = 0.0;                   ///< the perceptual deadband's Weber fraction (0: off)
};

struct StudyDefinition {
  std::string name;
  std::string skill;                                        ///< the skill trained (a block's default)
  std::map<std::string, std::filesystem::path> experts;     ///< skill -> expert profile file (or its name)
  /// Skill -> the glyph its expert is named by in place of a profile file: a built-in glyph's
  /// name ("na") or character ("ந"), or a glyph file's whole path (.json, given beside the study
  /// file): the simulated expert writing it, recorded on the study's pen and world when the
  /// study is made (sim::recordNamedExperts), before StudyDatabase::create stores it. Such a
  /// skill's `experts` entry is the same.
  std::map<std::string, std::string> named_experts;
  /// The named experts' recordings, skill -> profile (sim::recordNamedExperts).
  std::map<std::string, HapticProfile> named_expert_profiles;
  std::vector<guidance::TrainingMode> modes;                ///< every strategy the study uses, first use first
  /// strategy_parameters: each strategy's parameters as the study sets them (by name, in the
  /// catalog's units or a choice's name; guidance/strategy_catalog.hpp), applied to every trial's
  /// guidance, so a scheduled strategy's base law has the study's settings too.
  std::map<guidance::TrainingMode, std::vector<guidance::StrategySetting>> strategy_parameters;
  Protocol protocol;
  /// The between-subjects groups (one, kWithinSubjectsGroup, in the paper's form) and the
  /// schedule; study_design.hpp. Always at least one of each once parsed.
  std::vector<Group> groups;
  std::vector<ScheduledSession> schedule;
  /// Read from a study file of the paper's form (modes + protocol): studyToJson writes it back
  /// in that form, so a stored definition stays what it was.
  bool paper_form = true;
  OrderKind order = OrderKind::kLatinSquare;
  std::uint64_t order_seed = 1;                             ///< kRandom
  std::string device = "sim://pen";
  nlohmann::json world = nlohmann::json::object();          ///< a world config object (docs/rendering.md)
  double rate_hz = 1000.0;
  guidance::Indexing indexing = guidance::Indexing::kTime;
  std::vector<SubjectSpec> subjects;
  StudyMentor mentor;                                       ///< used by mentored modes only
  /// storage.resolution: the samples' declared per-channel resolution; empty: lossless
  /// (docs/study-store.md).
  io::ChannelResolution resolution;
  /// Whether any mode is a mentored one (then the study file's mentor block applies).
  [[nodiscard]] bool hasMentoredModes() const noexcept {
    return std::any_of(modes.begin(), modes.end(), [](auto m) { return guidance::isMentored(m); });
  }
};

/// The recall trials the analysis uses: protocol.analyzed_recall_trials, or all but the first.
std::vector<int> analyzedRecallTrials(const Protocol& protocol);

/// Makes `study` the paper's design from its modes, protocol and skill: one group of every
/// subject with the modes, one session of, per mode of the order, a training block then a
/// recall block (blocks of no trials left out). For a definition built in code, after those
/// are set; parseStudy does it for a study file of the paper's form.
void applyPaperForm(StudyDefinition& study);

/// Whether the study is the paper's design: one group, one session, and per strategy of the
/// counterbalanced order a training block then a recall block (the form of a study file
/// with modes + protocol).
[[nodiscard]] bool isPaperDesign(const StudyDefinition& study);

/// Parses and validates a study file's text. Relative expert paths resolve against
/// `base_dir`; with `check_files` (a new study file, not one stored in a database), each must
/// exist and subject ids and skills must be safe file names (isSafeFileName), so a study
/// stored before that rule still opens. Throws InputError listing every problem found, one
/// per line.
StudyDefinition parseStudy(std::string_view json_text, std::string_view source_name,
                           const std::filesystem::path& base_dir, bool check_files = true);
StudyDefinition loadStudy(const std::filesystem::path& file);
/// Refuses a study whose experts its device cannot render (checkRenderable: the continuous
/// force, the workspace), before anything is made: InputError, one line per expert, with the
/// numbers and the remedy. The limits are a sim:// device's declared ones; any other device's
/// are known only once it is opened, so nothing is checked and false is returned.
bool checkExpertsRenderable(const StudyDefinition& study);
/// The definition as JSON (stored in the study database; parseStudy reads it back).
nlohmann::json studyToJson(const StudyDefinition& study);
/// A shipped design (`hattr study example --design NAME`): its name, the question it answers
/// in one line, and its study file.
struct ExampleDesign {
  std::string_view name;
  std::string_view answers;
  std::string_view json;
};
/// The shipped designs, `paper` first.
const std::vector<ExampleDesign>& exampleDesigns();
/// The design called `name`; InputError naming the shipped ones otherwise.
const ExampleDesign& exampleDesign(std::string_view name);
/// The paper's design (`hattr study example`).
std::string exampleStudyJson();

/// The strategy order of each subject, by position in the subject list: within each group, by
/// the subject's position in it, a Williams design (a Latin square balanced for first-order
/// carry-over; two squares for an odd number of strategies), the listed order for everyone,
/// or a seeded shuffle per subject.
std::vector<std::vector<guidance::TrainingMode>> modeOrders(const StudyDefinition& study);

/// One planned trial of one subject.
struct TrialPlan {
  std::string subject;
  int sequence = 0;             ///< position in the subject's whole plan, from 0
  guidance::TrainingMode mode = guidance::TrainingMode::kBasic;  ///< the block's strategy (kBasic: none)
  std::string phase{kPhaseTraining};  ///< the block's phase label
  int index = 0;                ///< trial number within the block, from 1
  PhaseView view;
  std::string skill;            ///< the block's skill
  std::string group{kWithinSubjectsGroup};
  int session = 0;              ///< the schedule's session, from 0
  int day = 0;                  ///< that session's day offset
  int block = 0;                ///< the block within the session, from 0
};

/// Every trial of a subject in order: each session's blocks in turn, each block's trials, the
/// block's strategy taken from `order` where it names a position. In the paper's form: for
/// each mode in `order`, the training trials then the recall trials.
std::vector<TrialPlan> planTrials(const StudyDefinition& study, const SubjectSpec& subject,
                                  const std::vector<guidance::TrainingMode>& order);
/// The block a planned trial belongs to.
const Block& blockOf(const StudyDefinition& study, const TrialPlan& plan);

}  // namespace hattr::session
