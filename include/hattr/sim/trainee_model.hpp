#pragma once
/// The simulated trainee's parameters: one versioned file (data/sim/trainee_model.json) that
/// states for every parameter its value, unit, allowed range, literature source (or
/// "assumption: " and a reason) and how it varies between simulated subjects. The loader
/// converts to SI once (millimetres to metres) and checks everything. docs/simulation.md.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace hattr::sim {

/// What a simulated trainee is assumed to learn, and from what (docs/simulation.md,
/// "Learning hypotheses"). Each has its own model file in data/sim.
enum class LearningHypothesis {
  kPositionPlan,       ///< a movement plan; felt guidance read as a position error
  kForcePlan,          ///< a feedforward force plan; the path follows through a loose grip
  kGuidanceDependent,  ///< a position plan whose own error learning drops under guidance
};

/// "position-plan", "force-plan", "guidance-dependent".
std::string_view hypothesisName(LearningHypothesis hypothesis);
/// The hypothesis of a name; throws InputError naming `where`, the names, and what was given.
LearningHypothesis parseHypothesis(std::string_view name, std::string_view where);
/// Every hypothesis, in the order above.
const std::vector<LearningHypothesis>& allHypotheses();

/// How a parameter varies between simulated subjects.
struct SubjectDistribution {
  enum class Kind {
    kFixed,                ///< every subject has the value
    kNormal,               ///< mean = value, sd = spread (SI)
    kLogNormal,            ///< median = value, sigma of ln = spread
    kLogNormalComplement,  ///< 1 − x lognormal: median 1 − value, sigma of ln = spread
  };
  Kind kind = Kind::kFixed;
  double spread = 0.0;
};

/// One parameter as the file states it, converted to SI.
struct ModelParameter {
  std::string key;                 ///< the file's key ("deviation_rms_mm")
  double value = 0.0;              ///< population value (SI)
  double min = 0.0;                ///< allowed range (SI), also for every subject's draw
  double max = 0.0;
  std::string source;              ///< "Author year, title ..." or "assumption: reason"
  SubjectDistribution per_subject;
};

/// Every parameter of the trainee model (file version 1). The hypothesis's own parameters
/// are stated only in its file; for the others they keep the neutral values below.
struct TraineeModel {
  std::string source_name;                  ///< the file it came from, for messages
  int version = 1;
  LearningHypothesis hypothesis = LearningHypothesis::kPositionPlan;
  ModelParameter basis_count;               ///< number of basis functions [1]
  ModelParameter basis_width_ratio;         ///< Gaussian width / centre spacing [1]
  ModelParameter projection_ridge;          ///< relative ridge of the error projection [1]
  ModelParameter fast_retention;            ///< A_f [1]
  ModelParameter fast_rate;                 ///< B_f [1]
  ModelParameter slow_retention;            ///< A_s [1]
  ModelParameter slow_rate;                 ///< B_s [1]
  ModelParameter weber_fraction;            ///< relative SD of perceived force [1]
  ModelParameter felt_force_stiffness_N_per_m;  ///< felt force → plan error [N/m]
  ModelParameter position_noise_coefficient;    ///< signal-dependent position noise [1]
  ModelParameter force_noise_coefficient;       ///< signal-dependent force noise [1]
  ModelParameter deviation_rms_m;               ///< initial plan deviation, RMS [m] (file: mm)
  ModelParameter force_scale;                   ///< personal force scale [1]
  ModelParameter force_offset_N;                ///< personal force offset [N]
  ModelParameter pace_cv;                       ///< trial-to-trial variability of the pace [1]
  // force-plan only
  ModelParameter grip_ratio{.key = "grip_ratio", .value = 1.0, .min = 1.0, .max = 1.0};  ///< hand impedance share [1]
  ModelParameter plan_friction{.key = "plan_friction", .value = 0.0, .min = 0.0, .max = 0.0};  ///< μ the plan expects [1]
  // guidance-dependent only
  ModelParameter guidance_dependence{.key = "guidance_dependence", .value = 0.0, .min = 0.0, .max = 0.0};  ///< [1]
  ModelParameter guidance_felt_N{.key = "guidance_felt_N", .value = 1.0, .min = 1.0, .max = 1.0};  ///< [N]
};

/// Parses a trainee model file's text; `source_name` names it in messages. Throws InputError
/// (naming the file and key, the expected range or form, and the value found) for: invalid
/// JSON, a wrong format or version, a missing or unknown parameter or field, a unit other than
/// the parameter's, a range outside what the model can use, a value outside its range, an empty
/// source, a distribution of an unknown kind or with a negative spread, a structural parameter
/// (basis_count, basis_width_ratio, projection_ridge) that is not fixed, a non-integer
/// basis_count, or fast and slow values that break A_f <= A_s or B_f >= B_s (the fast process
/// forgets faster and learns faster: Smith et al. 2006), an unknown "hypothesis" (default
/// "position-plan"), a parameter of another hypothesis, or a missing one of its own.
/// Not for the servo thread.
TraineeModel parseTraineeModel(std::string_view json_text, std::string_view source_name);

/// Loads and parses a trainee model file; throws InputError if it cannot be read.
TraineeModel loadTraineeModel(const std::filesystem::path& file);

/// The model file of a hypothesis in the data folder: data/sim/trainee_model.json for
/// position-plan, data/sim/hypotheses/<name>.json for the others.
std::filesystem::path hypothesisModelFile(LearningHypothesis hypothesis);
/// Loads it; throws InputError if it cannot be read or parsed.
TraineeModel loadHypothesisModel(LearningHypothesis hypothesis);

/// One simulated subject's own values (SI). The plan's structure (basis) is the model's.
struct SubjectTraits {
  double fast_retention = 0.0;                ///< A_f
  double fast_rate = 0.0;                     ///< B_f
  double slow_retention = 0.0;                ///< A_s
  double slow_rate = 0.0;                     ///< B_s
  double weber_fraction = 0.0;                ///< relative SD of each perceived force
  double felt_force_stiffness_N_per_m = 0.0;  ///< a felt in-plane force f means a plan error f / K [N/m]
  double position_noise_coefficient = 0.0;    ///< position noise SD / distance covered per basis window
  double force_noise_coefficient = 0.0;       ///< force noise SD / planned axial force per basis window
  double deviation_rms_m = 0.0;               ///< RMS of the initial plan's offset from the template [m]
  double force_scale = 1.0;                   ///< axial force plan = scale × template + offset
  double force_offset_N = 0.0;                ///< [N]
  /// Trial-to-trial variability of the pace: each trial plays the plan uniformly slower or
  /// faster by a factor exp(pace_cv × N(0, 1)) (SD of its log; about its coefficient of variation).
  double pace_cv = 0.0;
  /// force-plan: the hand's in-plane impedance, as a share of the simulated hand's (1:
  /// position-plan's stiff tracking), whenever it holds the pen; the rest is the plan's push.
  double grip_ratio = 1.0;
  /// force-plan: the dynamic friction coefficient the force plan expects of the paper.
  double plan_friction = 0.0;
  /// guidance-dependent: the share of its own (visual) error learning a trainee loses in a
  /// trial in which it felt guidance.
  double guidance_dependence = 0.0;
  /// guidance-dependent: the RMS guidance force over a trial above which it was felt [N].
  double guidance_felt_N = 1.0;
  friend bool operator==(const SubjectTraits&, const SubjectTraits&) = default;
};

/// The population's values (every parameter at its 'value').
SubjectTraits populationTraits(const TraineeModel& model);

/// One subject's values drawn from the model's per-subject distributions with `seed` (the
/// same seed gives the same subject); each draw is repeated until it lies in the parameter's
/// range and the fast and slow processes keep A_f <= A_s and B_f >= B_s. Not for the servo thread.
SubjectTraits drawSubject(const TraineeModel& model, std::uint64_t seed);

/// Checks traits (what a SimulatedTrainee needs: retention and rates in [0, 1], A_f <= A_s,
/// B_f >= B_s, non-negative noise, deviation and force scale, a positive stiffness); throws
/// InputError naming the field and the value.
void validateTraits(const SubjectTraits& traits);

}  // namespace hattr::sim
