#include "hattr/sim/strategy_comparison.hpp"

#include <algorithm>
#include <limits>
#include <map>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"
#include "hattr/sim/participant.hpp"
#include "hattr/sim/scratch_folder.hpp"

namespace hattr::sim {
namespace {

using nlohmann::json;

void checkOptions(const StrategyComparisonOptions& o) {
  HATTR_THROW_UNLESS(o.subjects >= 2 && o.subjects <= 100, "subjects: expected 2 to 100 per strategy, got {}", o.subjects);
  HATTR_THROW_UNLESS(o.max_trials >= 0 && o.max_trials <= 1000, "trials: expected 0 (as designed) to 1000, got {}",
                     o.max_trials);
  HATTR_THROW_UNLESS(o.aa_seeds >= 0 && o.aa_seeds <= 1000, "aa-seeds: expected 0 to 1000, got {}", o.aa_seeds);
  HATTR_THROW_UNLESS(o.threads >= 0 && o.threads <= 256, "threads: expected 0 (the hardware's) to 256, got {}",
                     o.threads);
  HATTR_THROW_UNLESS(o.seed <= 1'000'000'000'000ULL, "seed: expected 0 to 1e12, got {}", o.seed);
  std::set<guidance::TrainingMode> seen;
  for (const auto m : o.strategies) {
    HATTR_THROW_UNLESS(!guidance::isMentored(m), "strategies: {} needs a live mentor: expected strategies that are "
                       "not mentored", guidance::strategyName(m));
    HATTR_THROW_UNLESS(seen.insert(m).second, "strategies: {} is given twice", guidance::strategyName(m));
  }
  HATTR_THROW_UNLESS(o.strategies.empty() || o.strategies.size() >= 2, "strategies: expected at least 2 to compare, "
                     "got {}", o.strategies.size());
  const std::set<LearningHypothesis> distinct(o.hypotheses.begin(), o.hypotheses.end());
  HATTR_THROW_UNLESS(distinct.size() == o.hypotheses.size(), "hypotheses: a hypothesis is given twice");
}

/// The design as a study file's JSON, each shipped design's experts named by their glyph.
json designJson(const StrategyComparisonOptions& o, std::filesystem::path& base_dir) {
  if (!o.study.empty()) {
    base_dir = std::filesystem::absolute(o.study).parent_path();
    return parseJsonObject(readTextFile(o.study), o.study.string());
  }
  json design = json::parse(session::exampleDesign(o.design).json);
  for (auto& [skill, expert] : design["experts"].items()) expert = skill;  // "na", "loop": built-in glyphs
  return design;
}

/// The design with one group per strategy of simulated subjects under `hypothesis` (seeded from
/// `seed`), each block at most `max_trials` trials, and with `guidance` false every force off.
json comparisonStudy(json design, const StrategyComparisonOptions& o, const std::vector<guidance::TrainingMode>& strategies,
                     LearningHypothesis hypothesis, std::uint64_t seed, bool guidance) {
  return readingJson(o.study.empty() ? o.design : o.study.string(), [&] {
  json groups = json::array();
  int position = 0;
  for (const auto mode : strategies) {
    json subjects = json::array();
    const std::string name = guidance::strategyName(mode);
    for (int i = 1; i <= o.subjects; ++i) {
      subjects.push_back({{"id", fmt::format("{}{:02}", name, i)}, {"participant", "simulated"},
                          {"seed", seed * 1000 + static_cast<std::uint64_t>(++position)},
                          {"options", {{"hypothesis", hypothesisName(hypothesis)}}}});
    }
    groups.push_back({{"name", name}, {"strategies", {name}}, {"subjects", subjects}});
  }
  design["groups"] = groups;
  design["order"] = {{"kind", "fixed"}};
  // Each well-formed block (parseStudy reports the others by name).
  for (auto& session : design["sessions"]) {
    if (!session.is_object() || !session.contains("blocks") || !session["blocks"].is_array()) continue;
    for (auto& block : session["blocks"]) {
      if (!block.is_object()) continue;
      const auto trials = block.find("trials");
      if (o.max_trials > 0 && trials != block.end() && trials->is_number() && *trials > o.max_trials) {
        *trials = o.max_trials;
      }
      if (!guidance) block["guidance"] = false;
    }
  }
  return design;
  });
}

/// Whether any block of the design takes the group's strategy.
bool usesGroupStrategy(const session::StudyDefinition& study) {
  for (const auto& session : study.schedule) {
    for (const auto& block : session.blocks) {
      if (block.strategy.kind == session::StrategyRef::Kind::kOrderPosition) return true;
    }
  }
  return false;
}

/// Runs one study in `folder` and analyzes it (the folder removed after).
report::DesignAnalysis runAndAnalyze(session::StudyDefinition study, const std::filesystem::path& folder, int threads) {
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  const std::filesystem::path file = folder / "study.sqlite";
  report::DesignAnalysis analysis;
  {
    (void)session::StudyDatabase::create(file, study);
    session::StudyDatabase db = session::StudyDatabase::open(file, session::OpenMode::kRunner);
    session::StudyRunner runner(db, [](const session::SubjectRecord& s, const HapticProfile& expert) {
      return makeSimulatedParticipant(s, expert);
    });
    session::RunOptions run;
    run.subjects_at_once = threads;
    (void)runner.run(run);
    analysis = report::analyzeDesign(db, {.threads = static_cast<unsigned>(threads)});
  }
  std::filesystem::remove_all(folder);
  return analysis;
}

/// Each (phase, skill) of the analysis in order, its scores.
std::vector<std::pair<std::pair<std::string, std::string>, std::vector<const report::DesignTrialScore*>>> byPhase(
    const report::DesignAnalysis& analysis) {
  std::vector<std::pair<std::pair<std::string, std::string>, std::vector<const report::DesignTrialScore*>>> out;
  for (const auto& s : analysis.scores) {
    const std::pair<std::string, std::string> key{s.phase, s.skill};
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& entry) { return entry.first == key; });
    if (it == out.end()) it = out.insert(out.end(), {key, {}});
    it->second.push_back(&s);
  }
  return out;
}

/// Each subject's mean cost over `scores` minus its mean over `baseline`, with its group (the
/// subjects with both): what it learned, free of who it was to begin with.
analysis::OneWayData changeFromBaseline(const std::vector<const report::DesignTrialScore*>& scores,
                                        const std::vector<const report::DesignTrialScore*>& baseline, bool shape) {
  const auto means = [shape](const std::vector<const report::DesignTrialScore*>& of) {
    std::map<std::string, std::pair<std::string, std::vector<double>>> by_subject;
    for (const auto* s : of) {
      by_subject[s->subject].first = s->group;
      by_subject[s->subject].second.push_back(shape ? s->shape() : s->force());
    }
    std::map<std::string, std::pair<std::string, double>> out;
    for (const auto& [subject, entry] : by_subject) {
      out[subject] = {entry.first, report::meanOverSubjects(entry.second).mean};
    }
    return out;
  };
  const auto after = means(scores), before = means(baseline);
  analysis::OneWayData data;
  for (const auto& [subject, entry] : after) {
    const auto b = before.find(subject);
    if (b == before.end()) continue;
    data.group.push_back(entry.first);
    data.y.push_back(entry.second - b->second.second);
  }
  return data;
}

/// The phases compared: each (phase, skill), then each one after a baseline of its skill as its
/// change from that baseline ("post-test − baseline"). Each with its one-way data (shape, force).
struct ComparedPhase {
  std::string phase;
  std::string skill;
  analysis::OneWayData shape, force;
};
std::vector<ComparedPhase> comparedPhases(const report::DesignAnalysis& analysis) {
  const auto phases = byPhase(analysis);
  std::vector<ComparedPhase> out;
  for (const auto& [key, scores] : phases) {
    out.push_back({key.first, key.second, report::groupSubjectMeans(scores, true), report::groupSubjectMeans(scores, false)});
  }
  for (const auto& [key, scores] : phases) {
    const auto baseline = std::find_if(phases.begin(), phases.end(), [&](const auto& entry) {
      return entry.first.first == session::kPhaseBaseline && entry.first.second == key.second;
    });
    if (key.first == session::kPhaseBaseline || baseline == phases.end()) continue;
    out.push_back({fmt::format("{} − baseline", key.first), key.second, changeFromBaseline(scores, baseline->second, true),
                   changeFromBaseline(scores, baseline->second, false)});
  }
  return out;
}

/// The one-way ANOVA's p between the strategies (NaN when it cannot be computed: one strategy's
/// subjects only, no residual).
double pBetween(const analysis::OneWayData& data) {
  try {
    return analysis::oneWayAnova(data).row("group").p;
  } catch (const InputError&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

/// Each strategy's subjects' mean with its interval, in `strategies`' order.
std::vector<report::SubjectMean> strategyMeans(const analysis::OneWayData& data,
                                               const std::vector<guidance::TrainingMode>& strategies) {
  std::vector<report::SubjectMean> means;
  for (const auto mode : strategies) {
    std::vector<double> values;
    for (std::size_t i = 0; i < data.y.size(); ++i) {
      if (data.group[i] == guidance::strategyName(mode)) values.push_back(data.y[i]);
    }
    means.push_back(report::meanOverSubjects(values));
  }
  return means;
}

}  // namespace

StrategyComparison compareStrategies(const StrategyComparisonOptions& options) {
  StrategyComparisonOptions o = options;
  checkOptions(o);
  if (o.strategies.empty()) {
    for (const auto& s : guidance::strategyCatalog()) {
      if (!s.mentored) o.strategies.push_back(s.mode);
    }
  }
  if (o.hypotheses.empty()) o.hypotheses = allHypotheses();
  if (o.threads == 0) o.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  // The design, checked once: a design of sessions whose blocks take the group's strategy.
  std::filesystem::path base_dir = std::filesystem::current_path();
  const json design = designJson(o, base_dir);
  const std::string where = o.study.empty() ? fmt::format("design {}", o.design) : o.study.string();
  HATTR_THROW_UNLESS(design.contains("sessions") && design["sessions"].is_array(), "{}: expected a design of groups and sessions "
                     "(the paper's form compares modes within subjects: `hattr sim compare-hypotheses`)", where);
  session::StudyDefinition probe = session::parseStudy(
      comparisonStudy(design, o, o.strategies, o.hypotheses.front(), o.seed, true).dump(), where, base_dir);
  HATTR_THROW_UNLESS(usesGroupStrategy(probe), "{}: no block takes the group's strategy (\"strategy\": \"group\"): "
                     "the strategies would not differ", where);
  HATTR_THROW_UNLESS(probe.device.rfind("sim://", 0) == 0, "{}: device \"{}\": expected a sim:// device (the "
                     "studies are simulated)", where, probe.device);
  recordNamedExperts(probe);

  StrategyComparison result{o.strategies, o.study.empty() ? o.design : o.study.string(), o.subjects, o.aa_seeds, o.seed, {}};
  const ScratchFolder scratch_folder(o.scratch, "strategies");
  const std::filesystem::path& scratch = scratch_folder.path();
  const int total = static_cast<int>(o.hypotheses.size()) * (1 + o.aa_seeds);
  int done = 0;
  for (const LearningHypothesis h : o.hypotheses) {
    const auto study = [&](std::uint64_t seed, bool guidance) {
      session::StudyDefinition s =
          session::parseStudy(comparisonStudy(design, o, o.strategies, h, seed, guidance).dump(), where, base_dir);
      s.named_expert_profiles = probe.named_expert_profiles;  // recorded once
      return s;
    };
    const std::string name(hypothesisName(h));
    HypothesisStrategies outcome{h, {}};
    const report::DesignAnalysis guided = runAndAnalyze(study(o.seed, true), scratch / name, o.threads);
    if (o.progress) o.progress(++done, total, fmt::format("{}: the strategies", name));
    for (const ComparedPhase& p : comparedPhases(guided)) {
      outcome.phases.push_back({p.phase, p.skill, strategyMeans(p.shape, o.strategies),
                                strategyMeans(p.force, o.strategies), pBetween(p.shape), pBetween(p.force), 0, 0});
    }
    // A/A: every force off, other subjects; a phase found different counts.
    for (int k = 1; k <= o.aa_seeds; ++k) {
      const report::DesignAnalysis aa =
          runAndAnalyze(study(o.seed + static_cast<std::uint64_t>(k), false), scratch / fmt::format("{}-aa", name),
                        o.threads);
      if (o.progress) o.progress(++done, total, fmt::format("{}: A/A study {} of {}", name, k, o.aa_seeds));
      for (const ComparedPhase& p : comparedPhases(aa)) {
        for (auto& phase : outcome.phases) {
          if (phase.phase != p.phase || phase.skill != p.skill) continue;
          phase.aa_significant_shape += pBetween(p.shape) < 0.05 ? 1 : 0;
          phase.aa_significant_force += pBetween(p.force) < 0.05 ? 1 : 0;
        }
      }
    }
    result.hypotheses.push_back(std::move(outcome));
  }
  return result;
}

json strategyComparisonToJson(const StrategyComparison& c) {
  const auto mean = [](const report::SubjectMean& m) {
    return json{{"subjects", m.subjects}, {"mean", m.mean}, {"ci", m.ci}};
  };
  json strategies = json::array();
  for (const auto m : c.strategies) strategies.push_back(guidance::strategyName(m));
  json hypotheses = json::array();
  for (const auto& h : c.hypotheses) {
    json phases = json::array();
    for (const auto& p : h.phases) {
      json rows = json::array();
      for (std::size_t i = 0; i < c.strategies.size(); ++i) {
        rows.push_back({{"strategy", guidance::strategyName(c.strategies[i])}, {"shape", mean(p.shape[i])},
                        {"force", mean(p.force[i])}});
      }
      phases.push_back({{"phase", p.phase}, {"skill", p.skill}, {"p_shape", p.p_shape}, {"p_force", p.p_force},
                        {"aa", {{"significant_shape", p.aa_significant_shape},
                                {"significant_force", p.aa_significant_force}}},
                        {"strategies", rows}});
    }
    hypotheses.push_back({{"hypothesis", hypothesisName(h.hypothesis)}, {"phases", phases}});
  }
  return {{"design", c.design}, {"subjects", c.subjects}, {"seed", c.seed}, {"aa_seeds", c.aa_seeds}, {"alpha", 0.05},
          {"strategies", strategies}, {"hypotheses", hypotheses}};
}

}  // namespace hattr::sim
