// The report of a study that is not the paper's design: the design, learning curves per phase,
// the session and phase table, retention and transfer.

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/report/design_analysis.hpp"
#include "report_document.hpp"

namespace hattr::report {
namespace {

using detail::Document;
using detail::g;
using detail::Series;
using detail::SvgPlot;
using detail::Table;

/// One colour per condition, in the study's order.
std::string conditionColour(const std::vector<std::string>& conditions, const std::string& condition) {
  static const char* kColours[] = {"#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
  const auto at = static_cast<std::size_t>(std::find(conditions.begin(), conditions.end(), condition) - conditions.begin());
  return at < std::size(kColours) ? kColours[at] : "#7f7f7f";
}

std::string withCi(const SubjectMean& m) {
  return std::isfinite(m.ci) ? fmt::format("{} ± {}", g(m.mean), g(m.ci)) : g(m.mean);
}

std::string strategyText(const session::StudyDefinition& study, const session::StrategyRef& ref) {
  const bool one_each = std::all_of(study.groups.begin(), study.groups.end(),
                                    [](const session::Group& g) { return g.strategies.size() == 1; });
  switch (ref.kind) {
    case session::StrategyRef::Kind::kNone: return "none";
    case session::StrategyRef::Kind::kNamed: return std::string(guidance::modeName(ref.mode));
    case session::StrategyRef::Kind::kOrderPosition:
      return one_each ? "the group's" : fmt::format("the subject's {} in order", ref.position);
  }
  return "";
}

void writeDesignSection(const session::StudyDatabase& db, const DesignAnalysis& a, Document& doc) {
  const session::StudyDefinition& study = db.study();
  doc.heading("Design");
  Table groups{{"group", "strategies (counterbalanced)", "subjects"}, {}};
  for (const auto& group : study.groups) {
    std::vector<std::string> names, ids;
    for (const auto m : group.strategies) names.emplace_back(guidance::modeName(m));
    for (const auto& s : study.subjects) {
      if (s.group == group.name) ids.push_back(s.id);
    }
    groups.rows.push_back({group.name, fmt::format("{}", fmt::join(names, ", ")), fmt::format("{}", fmt::join(ids, " "))});
  }
  doc.table(groups);
  Table sessions{{"session", "day", "block", "phase", "skill", "strategy", "trials", "reference", "guidance"}, {}};
  for (std::size_t s = 0; s < study.schedule.size(); ++s) {
    for (std::size_t b = 0; b < study.schedule[s].blocks.size(); ++b) {
      const session::Block& block = study.schedule[s].blocks[b];
      sessions.rows.push_back({fmt::format("{}", s + 1), fmt::format("{}", study.schedule[s].day), fmt::format("{}", b + 1),
                               block.phase, block.skill, strategyText(study, block.strategy), fmt::format("{}", block.trials),
                               block.view.show_reference ? "shown" : "hidden", block.view.guidance ? "on" : "off"});
    }
  }
  doc.table(sessions);
  doc.paragraph(fmt::format(
      "Compared: the {}s ({}). Costs: the paper's DTW of the shape (x + y) and of the force profile (fx + fy + fz) "
      "against the expert of each trial's skill; each subject's mean first, then the mean over subjects with its 95 % "
      "confidence interval. {} of {} planned trials are completed and analyzed. Analysis: {}.",
      a.condition_kind, fmt::join(a.conditions, ", "), a.scores.size(), a.trials_planned, a.reason));
}

void writeCurves(const DesignAnalysis& a, Document& doc, std::map<std::string, std::string>& files) {
  doc.heading("Learning curves");
  for (const std::string& phase : a.phases) {
    for (const bool shape : {true, false}) {
      SvgPlot plot(fmt::format("{}: mean {} cost per trial", phase, shape ? "shape" : "force"),
                   "trial of the phase (its sessions in turn)", shape ? "DTW cost of x + y" : "DTW cost of fx + fy + fz");
      plot.integerX();
      bool any = false;
      for (const std::string& condition : a.conditions) {
        Series series{condition, conditionColour(a.conditions, condition), {}, 1.5, false, true, {}};
        for (const CurvePoint& p : a.curves) {
          if (p.phase != phase || p.condition != condition) continue;
          const SubjectMean& m = shape ? p.shape : p.force;
          series.points.emplace_back(p.trial_in_phase, m.mean);
          series.errors.push_back(m.ci);
        }
        if (series.points.empty()) continue;
        any = true;
        plot.add(series);
      }
      if (!any) continue;
      doc.figure(fmt::format("curve_{}_{}", phase, shape ? "shape" : "force"), plot.svg(),
                 fmt::format("{} trials: mean {} cost over the subjects of each {}, with 95 % confidence intervals.",
                             phase, shape ? "shape" : "force", a.condition_kind),
                 files);
    }
  }
}

void writeTables(const DesignAnalysis& a, Document& doc) {
  doc.heading("Sessions and phases");
  Table cells{{"session", "phase", "skill", a.condition_kind, "subjects", "shape", "force"}, {}};
  for (const PhaseCell& c : a.cells) {
    cells.rows.push_back({fmt::format("{}", c.session), c.phase, c.skill, c.condition, fmt::format("{}", c.shape.subjects),
                          withCi(c.shape), withCi(c.force)});
  }
  doc.table(cells);
  doc.heading("Retention");
  if (a.retention.empty()) {
    doc.paragraph("No retention trial is completed.");
  } else {
    Table t{{a.condition_kind, "skill", "compared with", "subjects", "shape before", "shape at retention", "shape change",
             "force change"},
            {}};
    for (const RetentionRow& r : a.retention) {
      t.rows.push_back({r.condition, r.skill, r.before, fmt::format("{}", r.shape_change.subjects), withCi(r.shape_before),
                        withCi(r.shape_retention), withCi(r.shape_change), withCi(r.force_change)});
    }
    doc.paragraph("Each subject's mean cost at retention minus their mean in the last block named (a positive change: "
                  "the cost rose, part of what was learned was lost).");
    doc.table(t);
  }
  doc.heading("Transfer");
  if (a.transfer.empty()) {
    doc.paragraph("No transfer trial is completed.");
  } else {
    Table t{{a.condition_kind, "skill", "subjects", "shape", "force"}, {}};
    for (const TransferRow& r : a.transfer) {
      t.rows.push_back({r.condition, r.skill, fmt::format("{}", r.shape.subjects), withCi(r.shape), withCi(r.force)});
    }
    doc.table(t);
  }
}

void writeModels(const DesignAnalysis& a, Document& doc) {
  if (a.subjects < 2) return;
  doc.heading("Mixed models");
  doc.paragraph(fmt::format(
      "Each phase's {}s compared by a linear mixed model of its trials, fitted by REML as R's lme4 fits it, with "
      "Satterthwaite's degrees of freedom as lmerTest computes them (docs/analysis.md): subjects are random, and so is "
      "each subject's own {} effect where subjects tried several with several trials each. The F test says whether the "
      "{}s differ; each difference is from the first {} with its 95 % confidence interval.",
      a.condition_kind, a.condition_kind, a.condition_kind, a.condition_kind));
  Table t{{"phase", "cost", "model", "test", "differences (95 % CI)"}, {}};
  for (const PhaseModel& m : a.models) {
    if (!m.skipped.empty()) {
      t.rows.push_back({m.phase, m.metric, "", m.skipped, ""});
      continue;
    }
    std::string test;
    for (const auto& term : m.fit.terms) {
      test += fmt::format("{}{}: F({:g}, {:.1f}) = {}, p = {}", test.empty() ? "" : "; ", term.term, term.num_df,
                          term.den_df, g(term.f), g(term.p));
    }
    std::vector<std::string> differences;
    for (const auto& c : m.fit.fixed) {
      if (c.name == "(Intercept)") continue;
      differences.push_back(fmt::format("{} − {}: {} ({} to {})", c.name.substr(a.condition_kind.size()), m.reference,
                                        g(c.estimate), g(c.lower), g(c.upper)));
    }
    t.rows.push_back({m.phase, m.metric, m.fit.formula + (m.fit.singular ? " (singular)" : ""), test,
                      fmt::format("{}", fmt::join(differences, "; "))});
  }
  doc.table(t);
}

void writeFits(const DesignAnalysis& a, Document& doc) {
  Table t{{a.condition_kind, "phase", "cost", "law", "asymptote (95 % CI)", "to learn (95 % CI)", "rate per trial (95 % CI)", "note"}, {}};
  for (const CurveFitRow& f : a.fits) {
    if (!f.subject.empty()) continue;
    for (const analysis::CurveFit* fit : {&f.exponential, &f.power}) {
      const auto p = [](const analysis::CurveParameter& x) { return fmt::format("{} ({} to {})", g(x.estimate), g(x.lower), g(x.upper)); };
      t.rows.push_back({f.condition, f.phase, f.metric, analysis::curveLawName(fit->law), p(fit->asymptote),
                        p(fit->amplitude), p(fit->rate), fit->note});
    }
  }
  if (t.rows.empty()) return;
  doc.heading("Learning curve fits");
  doc.paragraph("The mean cost at each trial of a phase fitted by the exponential law a + b·exp(−c(n − 1)) and the power "
                "law a + b·n^(−c) (least squares, as R's nls): a is where practice leads, b what there was to learn, c the "
                "rate. Each subject's own fits are in curve_fits.csv.");
  doc.table(t);
}

void writeLearner(const DesignAnalysis& a, Document& doc) {
  if (a.learner.empty()) return;
  doc.heading("The learner's progress");
  doc.paragraph("One learner: no between-subject statistics (there is no one to compare with). Shape costs, lower "
                "closer to the expert.");
  Table t{{a.condition_kind, "phase", "skill", "trials", "first", "best (trial)", "latest", "mean"}, {}};
  for (const LearnerRow& r : a.learner) {
    t.rows.push_back({r.condition, r.phase, r.skill, fmt::format("{}", r.trials), g(r.first),
                      fmt::format("{} ({})", g(r.best), r.best_trial), g(r.latest), g(r.mean)});
  }
  doc.table(t);
}

}  // namespace

std::filesystem::path writeDesignReport(const session::StudyDatabase& db, const DesignAnalysis& a,
                                        const std::filesystem::path& out) {
  std::map<std::string, std::string> files;
  Document doc;
  doc.heading(fmt::format("Study report: {}", db.study().name), 1);
  doc.heading("Summary");
  doc.list(designSummary(a));
  writeDesignSection(db, a, doc);
  doc.heading("Conclusions");
  const auto lines = designConclusions(a);
  if (lines.empty()) doc.paragraph("No retention or transfer trial is completed yet: see the curves and tables.");
  else doc.list(lines);
  writeLearner(a, doc);
  writeCurves(a, doc, files);
  writeModels(a, doc);
  writeFits(a, doc);
  writeTables(a, doc);
  detail::writeReportFiles(out, db.study().name, doc, files);
  return out / "report.html";
}

}  // namespace hattr::report
