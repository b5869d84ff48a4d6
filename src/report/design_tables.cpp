// The design analysis as JSON and as CSV tables: trials.csv, the long table of every completed
// trial, and the tables of curves, phases, retention, transfer, models, curve fits and subject scores.

#include "hattr/report/design_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "hattr/analysis/kinematics.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::report {
namespace {

nlohmann::json kinematicsJson(const std::map<std::string, double>& k) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, v] : k) out[name] = jsonNumber(v);
  return out;
}

nlohmann::json meanJson(const SubjectMean& m) {
  return {{"subjects", m.subjects}, {"mean", jsonNumber(m.mean)}, {"ci95", jsonNumber(m.ci)}};
}

/// A number as a CSV cell (empty when not finite).
std::string cell(double v) { return std::isfinite(v) ? fmt::format("{}", v) : ""; }

/// A mean over subjects as three cells: subjects, mean, the 95 % interval's half-width.
std::vector<std::string> meanCells(const SubjectMean& m) {
  return std::vector<std::string>{fmt::format("{}", m.subjects), cell(m.mean), cell(m.ci)};
}

/// `row` with `more` appended.
std::vector<std::string> joinCells(std::vector<std::string> row, const std::vector<std::string>& more) {
  row.insert(row.end(), more.begin(), more.end());
  return row;
}

/// curves.csv: each point of each learning curve.
void writeCurvesCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table curves{{"condition", "phase", "trial_in_phase", "subjects", "shape_mean", "shape_ci95", "force_subjects",
                    "force_mean", "force_ci95"},
                   {}, ""};
  for (const auto& c : a.curves) {
    curves.rows.push_back(
        joinCells(joinCells({c.condition, c.phase, fmt::format("{}", c.trial_in_phase)}, meanCells(c.shape)), meanCells(c.force)));
  }
  io::writeTable(curves, dir / "curves.csv", true);
}

/// phases.csv: each session and phase of each condition.
void writePhasesCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table cells{{"condition", "session", "phase", "skill", "subjects", "shape_mean", "shape_ci95", "force_subjects",
                   "force_mean", "force_ci95"},
                  {}, ""};
  for (const auto& c : a.cells) {
    cells.rows.push_back(joinCells(
        joinCells({c.condition, fmt::format("{}", c.session), c.phase, c.skill}, meanCells(c.shape)), meanCells(c.force)));
  }
  io::writeTable(cells, dir / "phases.csv", true);
}

/// retention.csv: retention against the block before it, per condition and skill.
void writeRetentionCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table retention{{"condition", "skill", "before", "subjects", "shape_before", "shape_before_ci95", "shape_subjects",
                       "shape_retention", "shape_retention_ci95", "shape_change_subjects", "shape_change",
                       "shape_change_ci95", "force_subjects", "force_change", "force_change_ci95"},
                      {}, ""};
  for (const auto& r : a.retention) {
    retention.rows.push_back(joinCells(joinCells(joinCells(joinCells({r.condition, r.skill, r.before}, meanCells(r.shape_before)),
                                                           meanCells(r.shape_retention)),
                                                 meanCells(r.shape_change)),
                                       meanCells(r.force_change)));
  }
  io::writeTable(retention, dir / "retention.csv", true);
}

/// transfer.csv: transfer of each condition to each skill.
void writeTransferCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table transfer{{"condition", "skill", "subjects", "shape_mean", "shape_ci95", "force_subjects", "force_mean",
                      "force_ci95"},
                     {}, ""};
  for (const auto& t : a.transfer) {
    transfer.rows.push_back(joinCells(joinCells({t.condition, t.skill}, meanCells(t.shape)), meanCells(t.force)));
  }
  io::writeTable(transfer, dir / "transfer.csv", true);
}

/// models.csv: the mixed models: each term's F test, then each coefficient with its 95 % interval.
void writeModelsCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table models{{"phase", "metric", "formula", "kind", "name", "estimate", "std_error", "lower", "upper", "num_df",
                    "den_df", "statistic", "p", "singular", "skipped"},
                   {}, ""};
  for (const PhaseModel& m : a.models) {
    if (!m.skipped.empty()) {
      models.rows.push_back({m.phase, m.metric, "", "", "", "", "", "", "", "", "", "", "", "", io::plainCell(m.skipped)});
      continue;
    }
    const std::string singular = m.fit.singular ? "1" : "0";
    for (const auto& t : m.fit.terms) {
      models.rows.push_back({m.phase, m.metric, m.fit.formula, "term", t.term, "", "", "", "", cell(t.num_df),
                             cell(t.den_df), cell(t.f), cell(t.p), singular, ""});
    }
    for (const auto& c : m.fit.fixed) {
      models.rows.push_back({m.phase, m.metric, m.fit.formula, "coefficient", c.name, cell(c.estimate), cell(c.std_error),
                             cell(c.lower), cell(c.upper), "", cell(c.df), cell(c.t), cell(c.p), singular, ""});
    }
  }
  io::writeTable(models, dir / "models.csv", true);
}

/// curve_fits.csv: both laws of practice fitted to each condition's (and subject's) curve.
void writeCurveFitsCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table fits{{"condition", "phase", "subject", "metric", "law", "asymptote", "asymptote_lower", "asymptote_upper",
                  "amplitude", "amplitude_lower", "amplitude_upper", "rate", "rate_lower", "rate_upper", "rss", "points", "note"},
                 {}, ""};
  for (const CurveFitRow& f : a.fits) {
    for (const analysis::CurveFit* fit : {&f.exponential, &f.power}) {
      fits.rows.push_back({f.condition, f.phase, f.subject, f.metric, analysis::curveLawName(fit->law),
                           cell(fit->asymptote.estimate), cell(fit->asymptote.lower), cell(fit->asymptote.upper),
                           cell(fit->amplitude.estimate), cell(fit->amplitude.lower), cell(fit->amplitude.upper),
                           cell(fit->rate.estimate), cell(fit->rate.lower), cell(fit->rate.upper), cell(fit->rss),
                           fmt::format("{}", fit->points), io::plainCell(fit->note)});
    }
  }
  io::writeTable(fits, dir / "curve_fits.csv", true);
}

/// subject_scores.csv: each subject's post-test, retention and transfer scores.
void writeSubjectScoresCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  io::Table subject_scores{{"subject", "condition", "skill", "score", "shape", "force"}, {}, ""};
  for (const SubjectScore& x : a.subject_scores) {
    subject_scores.rows.push_back({x.subject, x.condition, x.skill, x.score, cell(x.shape), cell(x.force)});
  }
  io::writeTable(subject_scores, dir / "subject_scores.csv", true);
}

}  // namespace

nlohmann::json designAnalysisToJson(const DesignAnalysis& a) {
  nlohmann::json scores = nlohmann::json::array(), curves = nlohmann::json::array(), cells = nlohmann::json::array(),
                 retention = nlohmann::json::array(), transfer = nlohmann::json::array();
  const auto trialJson = [](const DesignTrialScore& s) {
    nlohmann::json j{{"trial_id", s.trial_id}, {"subject", s.subject}, {"condition", s.condition}, {"group", s.group},
                     {"strategy", s.strategy}, {"session", s.session}, {"day", s.day}, {"block", s.block},
                     {"phase", s.phase}, {"skill", s.skill}, {"trial", s.trial}, {"trial_in_phase", s.trial_in_phase},
                     {"shape", s.shape()}, {"force", s.force()}, {"z", s.score.z}, {"disturbed", s.disturbed},
                     {"kinematics", kinematicsJson(s.kinematics)}};
    if (!s.left_out.empty()) j["left_out"] = s.left_out;
    return j;
  };
  nlohmann::json left_out = nlohmann::json::array();
  for (const auto& s : a.scores) scores.push_back(trialJson(s));
  for (const auto& s : a.left_out) left_out.push_back(trialJson(s));
  for (const auto& c : a.curves) {
    curves.push_back({{"condition", c.condition}, {"phase", c.phase}, {"trial_in_phase", c.trial_in_phase},
                      {"shape", meanJson(c.shape)}, {"force", meanJson(c.force)}});
  }
  for (const auto& c : a.cells) {
    cells.push_back({{"condition", c.condition}, {"session", c.session}, {"phase", c.phase}, {"skill", c.skill},
                     {"shape", meanJson(c.shape)}, {"force", meanJson(c.force)}});
  }
  for (const auto& r : a.retention) {
    retention.push_back({{"condition", r.condition}, {"skill", r.skill}, {"before", r.before},
                         {"shape", {{"before", meanJson(r.shape_before)}, {"retention", meanJson(r.shape_retention)},
                                    {"change", meanJson(r.shape_change)}}},
                         {"force", {{"before", meanJson(r.force_before)}, {"retention", meanJson(r.force_retention)},
                                    {"change", meanJson(r.force_change)}}}});
  }
  for (const auto& t : a.transfer) {
    transfer.push_back({{"condition", t.condition}, {"skill", t.skill}, {"shape", meanJson(t.shape)},
                        {"force", meanJson(t.force)}});
  }
  nlohmann::json models = nlohmann::json::array(), fits = nlohmann::json::array(), learner = nlohmann::json::array();
  for (const PhaseModel& m : a.models) {
    models.push_back({{"phase", m.phase}, {"metric", m.metric}, {"reference", m.reference},
                      {"fit", m.skipped.empty() ? analysis::toJson(m.fit) : nlohmann::json(nullptr)}, {"skipped", m.skipped}});
  }
  for (const CurveFitRow& f : a.fits) {
    fits.push_back({{"condition", f.condition}, {"phase", f.phase}, {"subject", f.subject}, {"metric", f.metric},
                    {"exponential", analysis::toJson(f.exponential)}, {"power", analysis::toJson(f.power)}});
  }
  for (const LearnerRow& r : a.learner) {
    learner.push_back({{"condition", r.condition}, {"phase", r.phase}, {"skill", r.skill}, {"trials", r.trials},
                       {"first", jsonNumber(r.first)}, {"best", jsonNumber(r.best)}, {"best_trial", r.best_trial},
                       {"latest", jsonNumber(r.latest)}, {"mean", jsonNumber(r.mean)}});
  }
  nlohmann::json subject_scores = nlohmann::json::array();
  for (const SubjectScore& x : a.subject_scores) {
    subject_scores.push_back({{"subject", x.subject}, {"condition", x.condition}, {"skill", x.skill}, {"score", x.score},
                              {"shape", jsonNumber(x.shape)}, {"force", jsonNumber(x.force)}});
  }
  const char* design = a.subjects == 1 ? "one-learner" : a.paper_design ? "paper-incomplete" : "groups-and-sessions";
  return {{"design", design}, {"analysis", a.reason}, {"subjects", a.subjects},
          {"subject_scores", subject_scores},
          {"summary", designSummary(a)}, {"models", models}, {"curve_fits", fits}, {"learner", learner},
          {"condition_kind", a.condition_kind}, {"conditions", a.conditions},
          {"phases", a.phases}, {"trials_planned", a.trials_planned}, {"trials_pending", a.trials_pending},
          {"trials_excluded", a.trials_excluded}, {"trials_flagged", a.trials_flagged},
          {"disturbed_policy", a.disturbed_policy}, {"trial_scores", scores}, {"trials_left_out", left_out}, {"curves", curves}, {"phase_cells", cells},
          {"retention", retention}, {"transfer", transfer}, {"conclusions", designConclusions(a)}};
}

void writeDesignCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  writeTrialsCsv(a, dir / "trials.csv");
  writeCurvesCsv(a, dir);
  writePhasesCsv(a, dir);
  writeRetentionCsv(a, dir);
  writeTransferCsv(a, dir);
  writeModelsCsv(a, dir);
  writeCurveFitsCsv(a, dir);
  writeSubjectScoresCsv(a, dir);
}

void writeTrialsCsv(const session::StudyDatabase& db, const StudyAnalysis& balanced, AnalysisOptions options,
                    const std::filesystem::path& file) {
  std::map<std::int64_t, analysis::TrialScore> scored;
  for (const auto& c : balanced.costs) scored[c.trial_id] = c.score;
  options.scored = &scored;
  options.kinematics_of_scored = true;
  writeTrialsCsv(analyzeDesign(db, options), file);
}

void writeTrialsCsv(const DesignAnalysis& a, const std::filesystem::path& file) {
  std::vector<std::string> header{"trial_id", "subject", "condition", "group", "strategy", "session", "day", "block",
                                  "phase", "skill", "trial", "trial_in_phase", "x", "y", "z", "fx", "fy", "fz", "shape",
                                  "force"};
  for (const char* name : analysis::kinematicsNames()) header.emplace_back(name);
  for (const char* name : {"disturbed", "analyzed", "left_out"}) header.emplace_back(name);
  // Analyzed and left-out trials together, in the study's order.
  std::vector<const DesignTrialScore*> trials;
  for (const auto* list : {&a.scores, &a.left_out}) {
    for (const auto& s : *list) trials.push_back(&s);
  }
  std::sort(trials.begin(), trials.end(), [](const auto* x, const auto* y) { return x->trial_id < y->trial_id; });
  io::Table table{header, {}, ""};
  for (const DesignTrialScore* p : trials) {
    const DesignTrialScore& s = *p;
    const analysis::TrialScore& c = s.score;
    std::vector<std::string> row{fmt::format("{}", s.trial_id), s.subject, s.condition, s.group, s.strategy,
                                 fmt::format("{}", s.session), fmt::format("{}", s.day), fmt::format("{}", s.block), s.phase,
                                 s.skill, fmt::format("{}", s.trial), fmt::format("{}", s.trial_in_phase), cell(c.x), cell(c.y),
                                 cell(c.z), cell(c.fx), cell(c.fy), cell(c.fz), cell(s.shape()), cell(s.force())};
    for (const char* name : analysis::kinematicsNames()) {
      const auto it = s.kinematics.find(name);
      row.push_back(it == s.kinematics.end() ? "" : cell(it->second));
    }
    row.push_back(io::plainCell(s.disturbed));
    row.emplace_back(s.left_out.empty() ? "1" : "0");
    row.push_back(io::plainCell(s.left_out));
    table.rows.push_back(std::move(row));
  }
  std::filesystem::create_directories(file.parent_path());
  io::writeTable(table, file, true);
}

}  // namespace hattr::report
