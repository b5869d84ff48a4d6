#pragma once
/// The analysis of a study that is not the paper's design (docs/analysis.md "Designs"): every
/// completed trial scored against the expert of its skill (analysis::TrialScorer, the paper's
/// DTW costs of shape and force), then per condition (the group, or the strategy when one
/// group compares strategies within subjects):
/// - learning curves: per phase, the mean cost at each trial of the phase (its sessions in
///   turn) with a 95 % confidence interval over the subjects;
/// - a table per session and phase: each subject's mean, then their mean with its interval;
/// - retention: each subject's retention mean minus the mean of the last post-test before it
///   (of the same skill; else the last training block), paired over the subjects;
/// - transfer: the mean cost on each transfer block's skill.
/// It analyzes what is completed so far (a study over weeks is reported while it runs) and
/// says what is not. Disturbed trials follow the study's policy: "exclude" leaves them out.
/// Offline code.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/learning_curve.hpp"
#include "hattr/analysis/lmm.hpp"
#include "hattr/report/study_analysis.hpp"

namespace hattr::report {

/// One completed trial's costs and its place in the design.
struct DesignTrialScore {
  std::int64_t trial_id = 0;
  std::string subject;
  std::string condition;  ///< the group, or the strategy (DesignAnalysis::condition_kind)
  std::string group;
  std::string strategy;   ///< the block's strategy ("none" where its force is off and it names none)
  int session = 1;        ///< from 1
  int day = 0;
  int block = 1;          ///< within the session, from 1
  std::string phase;
  std::string skill;
  int trial = 1;          ///< within the block, from 1
  int trial_in_phase = 1; ///< within the phase over the sessions, from 1 (the curves' x)
  bool guided = false;    ///< the block's guidance was on
  analysis::TrialScore score;
  std::string disturbed;
  std::string left_out;   ///< why the analysis leaves it out ("": analyzed); it is in trials.csv still
  /// The trial's kinematics by name (analysis::kinematicsNames(); NaN where not a number),
  /// as stored with the trial, else measured from its samples; empty when not read.
  std::map<std::string, double> kinematics;
  [[nodiscard]] double shape() const { return score.shape(); }
  [[nodiscard]] double force() const { return score.force(); }
};

/// A mean over subjects with the half-width of its 95 % confidence interval (Student's t; NaN
/// below two subjects).
struct SubjectMean {
  int subjects = 0;
  double mean = 0.0;
  double ci = 0.0;
};

/// One session and phase of one condition: each subject's mean cost, then their mean.
struct PhaseCell {
  std::string condition;
  int session = 1;
  std::string phase;
  std::string skill;
  SubjectMean shape;
  SubjectMean force;
};

/// Retention of one condition: retention − before, per subject, then their mean (positive:
/// the cost rose, what was learned was partly lost).
struct RetentionRow {
  std::string condition;
  std::string skill;
  std::string before;  ///< "post-test" or "training": what retention is compared with
  SubjectMean shape_before, shape_retention, shape_change;
  SubjectMean force_before, force_retention, force_change;
};

/// One subject's mean shape and force cost in a phase the design's tests define: "post-test"
/// (or "training", the block retention is compared with), "retention", "retention-change"
/// (retention minus that block) and "transfer".
struct SubjectScore {
  std::string subject;
  std::string condition;
  std::string skill;
  std::string score;  ///< which of the above
  double shape = 0.0;
  double force = 0.0;
};

/// Transfer of one condition to one skill.
struct TransferRow {
  std::string condition;
  std::string skill;
  SubjectMean shape;
  SubjectMean force;
};

/// One point of a learning curve: a condition's mean cost at one trial of a phase.
struct CurvePoint {
  std::string condition;
  std::string phase;
  int trial_in_phase = 1;
  SubjectMean shape;
  SubjectMean force;
};

/// A phase's conditions compared by a linear mixed model of its trials (subjects random).
struct PhaseModel {
  std::string phase;
  std::string metric;     ///< "shape" or "force"
  std::string reference;  ///< the condition the others are compared with
  analysis::LmmFit fit;   ///< fit.formula says the model; empty formula when skipped
  std::string skipped;    ///< why no model was fitted ("" when one was)
};

/// A condition's (or one subject's) mean cost over a phase's trials, fitted by both laws of practice.
struct CurveFitRow {
  std::string condition;
  std::string phase;
  std::string subject;  ///< "" for the mean over the condition's subjects
  std::string metric;   ///< "shape" or "force"
  analysis::CurveFit exponential;
  analysis::CurveFit power;
};

/// One learner's scores in one phase of one condition: first, best, latest.
struct LearnerRow {
  std::string condition;
  std::string phase;
  std::string skill;
  int trials = 0;
  double first = 0.0;   ///< shape cost of the phase's first trial
  double best = 0.0;    ///< the lowest shape cost
  int best_trial = 0;   ///< at this trial of the phase
  double latest = 0.0;  ///< the last trial's shape cost
  double mean = 0.0;
};

struct DesignAnalysis {
  AnalysisOptions options;
  std::string condition_kind;           ///< "group" or "strategy"
  std::vector<std::string> conditions;  ///< in the study's order
  std::vector<std::string> phases;      ///< in the order they first come
  std::vector<DesignTrialScore> scores; ///< the analyzed trials, in the study's order
  /// Completed trials scored but left out of every table and model (DesignTrialScore::left_out):
  /// disturbed ones under "exclude"; of a paper's design, the recall trials the paper's
  /// analysis does not take (paperRecallTrials). trials.csv lists them with analyzed = 0.
  std::vector<DesignTrialScore> left_out;
  std::vector<CurvePoint> curves;
  std::vector<PhaseCell> cells;
  std::vector<RetentionRow> retention;
  std::vector<TransferRow> transfer;
  int trials_planned = 0;
  int trials_pending = 0;               ///< not completed yet (left out)
  int trials_excluded = 0;              ///< disturbed, left out by the "exclude" policy
  int trials_flagged = 0;               ///< disturbed, analyzed and flagged
  std::string disturbed_policy;
  int subjects = 0;                     ///< with analyzed trials
  bool paper_design = false;            ///< the paper's design (incomplete, or one learner's)
  std::string reason;                   ///< why this analysis (chooseAnalysis), for the report
  std::vector<PhaseModel> models;       ///< per phase and metric, with two subjects or more
  std::vector<CurveFitRow> fits;        ///< per condition and phase (and per subject) of 4 trials or more
  std::vector<LearnerRow> learner;      ///< one learner only
  std::vector<SubjectScore> subject_scores;  ///< each subject's post-test, retention and transfer
};

/// The mean of one value per subject with its interval (SubjectMean; none: NaN, 0 subjects).
SubjectMean meanOverSubjects(const std::vector<double>& values);

/// Each subject's mean cost (shape, or force) over `scores`, with the subject's group: the data
/// of a one-way ANOVA between the groups (factor "group"), subjects in id order.
analysis::OneWayData groupSubjectMeans(const std::vector<const DesignTrialScore*>& scores, bool shape);
/// The same from one value per trial: trial k's subject, group and value (summed in order).
analysis::OneWayData groupSubjectMeans(const std::vector<std::string>& subject, const std::vector<std::string>& group,
                                       const std::vector<double>& value);

/// One phase's conditions compared by the design report's linear mixed model: `response` ~
/// `condition_name` + (1 | subject), with + (1 | subject:`condition_name`) where subjects did
/// several conditions several times each (the model R's aov(y ~ c + Error(subject/c))
/// approximates); trial k's subject, condition and value; `reference` the baseline condition,
/// `source` the trials in words for messages. Throws InputError as analysis::fitLmm does.
analysis::LmmFit fitConditionModel(const std::vector<std::string>& subject, const std::vector<std::string>& condition,
                                   const std::vector<double>& value, const std::string& condition_name,
                                   const std::string& response, const std::string& reference,
                                   const std::string& source);

/// Scores and tabulates a study's completed trials. Throws InputError when none is completed.
DesignAnalysis analyzeDesign(const session::StudyDatabase& db, const AnalysisOptions& options = {});

/// The analysis as JSON (`hattr study analyze --json` for a design).
nlohmann::json designAnalysisToJson(const DesignAnalysis& analysis);

/// What writeDesignCsv writes.
inline const std::vector<std::string> kDesignCsvFiles{"trials.csv", "curves.csv", "phases.csv", "retention.csv",
                                                      "transfer.csv", "models.csv", "curve_fits.csv",
                                                      "subject_scores.csv"};

/// The long table of every completed trial, the one an R or pandas user starts from: its
/// place in the design, every score, every kinematic measure, disturbed, and whether the
/// analysis takes it (analyzed, left_out), in the study's order (trials.csv).
void writeTrialsCsv(const DesignAnalysis& analysis, const std::filesystem::path& file);
/// The same for a paper's study analyzed by the balanced ANOVA: its recall trials as `balanced`
/// scored them, the others (training) scored now with `options`.
void writeTrialsCsv(const session::StudyDatabase& db, const StudyAnalysis& balanced, AnalysisOptions options,
                    const std::filesystem::path& file);
/// Writes the tables as CSV into `out_dir` (created; earlier ones replaced).
void writeDesignCsv(const DesignAnalysis& analysis, const std::filesystem::path& out_dir);

/// One line per finding, stating only what the numbers show (the report's conclusions).
std::vector<std::string> designConclusions(const DesignAnalysis& analysis);

/// The report's opening in plain words, for a teacher as much as a researcher: what was
/// compared, what was found with its size and interval, and what the numbers do not show.
std::vector<std::string> designSummary(const DesignAnalysis& analysis);

/// Writes OUT/report.html, OUT/report.md and OUT/figures/*.svg for a design: the design
/// (groups, sessions, blocks), learning curves per phase, the session and phase table,
/// retention and transfer. Returns the path of report.html.
std::filesystem::path writeDesignReport(const session::StudyDatabase& db, const DesignAnalysis& analysis,
                                        const std::filesystem::path& out_dir);

}  // namespace hattr::report
