// The library evaluation's JSON, text, tables, DET figures and files.

#include "hattr/report/library_report.hpp"

#include <cmath>

#include <boost/math/distributions/normal.hpp>
#include <fmt/format.h>

#include "hattr/core/atomic_file.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"
#include "report_document.hpp"

namespace hattr::report {

using detail::Document;
using detail::Series;
using detail::SvgPlot;

namespace {

nlohmann::json ratesJson(const library::ErrorRates& r) {
  return {{"eer_a_posteriori", r.eer}, {"eer_threshold", r.eer_threshold}, {"a_priori_threshold", r.prior_threshold},
          {"far_at_a_priori", r.far}, {"frr_at_a_priori", r.frr}, {"genuine_scores", r.genuine},
          {"impostor_scores", r.impostor}};
}

std::string percent(double v) { return fmt::format("{:.2f}", 100.0 * v); }

}  // namespace

nlohmann::json libraryEvaluationJson(const library::EvaluationResult& r) {
  const auto& o = r.options;
  nlohmann::json sets = nlohmann::json::array();
  for (const auto& s : r.sets) {
    nlohmann::json splits = nlohmann::json::object();
    for (const auto& sp : s.splits) {
      splits[sp.split] = {{"writers", sp.writers},
                          {"skilled", ratesJson(sp.skilled)},
                          {"random", ratesJson(sp.random)},
                          {"identification", {{"probes", sp.probes}, {"rank1", sp.rank1}, {"rank5", sp.rank5}}}};
    }
    sets.push_back({{"features", s.set.name()}, {"splits", splits}});
  }
  nlohmann::json claim = nlohmann::json::array();
  for (const auto& c : r.claim) {
    claim.push_back({{"features", c.set}, {"within_session", c.within_session}, {"across_sessions", c.across_sessions},
                     {"between_writers", c.between_writers},
                     {"writers_nearer_themselves", c.writers_nearer_themselves}});
  }
  return {{"protocol", r.protocol},
          {"options",
           {{"seed", o.seed}, {"runs", o.runs}, {"enrolled", o.enrolled}, {"random_forgers", o.random_forgers},
            {"skill", o.skill}, {"score_rule", library::scoreRuleName(o.rule)}, {"length", o.features.length},
            {"band", o.features.band_fraction}, {"normalization", analysis::normalizationName(o.features.normalization)},
            {"development", o.development}, {"evaluation", o.evaluation}}},
          {"sets", sets},
          {"claim_on_evaluation_writers", claim},
          {"templates_on_evaluation_writers",
           {{"template_distance", r.templates.template_distance}, {"single_distance", r.templates.single_distance},
            {"writers_better", r.templates.writers_better}, {"writers", r.templates.writers}}},
          {"run", {{"seconds", r.seconds}, {"channel_distances", r.distances}, {"threads", o.threads}}}};
}

namespace {

/// The results table: a row per feature set and split.
detail::Table resultsTable(const library::EvaluationResult& r) {
  detail::Table t{{"features", "writers", "skilled EER % (a posteriori)", "skilled FAR % / FRR % (a priori)",
                   "random EER % (a posteriori)", "random FAR % / FRR % (a priori)", "rank-1 %", "rank-5 %"},
                  {}};
  for (const auto& s : r.sets) {
    for (const auto& sp : s.splits) {
      t.rows.push_back({s.set.name(), fmt::format("{} ({})", sp.split, sp.writers), percent(sp.skilled.eer),
                        percent(sp.skilled.far) + " / " + percent(sp.skilled.frr), percent(sp.random.eer),
                        percent(sp.random.far) + " / " + percent(sp.random.frr), percent(sp.rank1), percent(sp.rank5)});
    }
  }
  return t;
}

std::string protocolSentence(const library::EvaluationResult& r) {
  const auto& o = r.options;
  return fmt::format(
      "Protocol {}: for each writer, {} runs, each enrolling {} genuine profiles drawn at random (seed {}) from the "
      "first session and testing the writer's second-session genuine profiles, every skilled forgery of them, and one "
      "genuine profile of each of {} other writers of the same split (random forgeries). Scores are pooled over writers "
      "and runs under one global threshold: the a-posteriori EER is where FAR and FRR meet on the split's own scores; "
      "the a-priori FAR and FRR are at the development writers' EER threshold, fixed before the evaluation writers' "
      "scores are seen. Development writers: {}; evaluation writers: {}. Features: the pen-down samples on writing "
      "time, resampled at {} steps, normalized ({}), per-axis DTW (absolute cost, band {}), score = {} distance to the "
      "references / their mean pairwise distance. Identification: each second-session genuine profile against every "
      "first-session genuine profile of the split's writers, exact search.",
      r.protocol, o.runs, o.enrolled, o.seed, o.random_forgers, fmt::join(o.development, " "),
      fmt::join(o.evaluation, " "), o.features.length, analysis::normalizationName(o.features.normalization),
      o.features.band_fraction, library::scoreRuleName(o.rule));
}

/// The normal deviate of a probability (DET axes), clamped to what the figure shows.
double deviate(double p) {
  constexpr double kLo = 0.0005;
  return boost::math::quantile(boost::math::normal(), std::clamp(p, kLo, 1.0 - kLo));
}

std::string detFigure(const library::SetResult& s, const std::string& split) {
  SvgPlot plot(fmt::format("DET, {} features, {} writers", s.set.name(), split), "false acceptance rate [%]",
               "false rejection rate [%]", 640, 460);
  SvgPlot::Ticks ticks;
  for (const double p : {0.001, 0.005, 0.02, 0.05, 0.1, 0.2, 0.4}) {
    ticks.emplace_back(deviate(p), fmt::format("{:g}", 100.0 * p));
  }
  plot.labelledTicks(ticks, ticks);
  plot.xRange(deviate(0.0005), deviate(0.5));
  plot.yRange(deviate(0.0005), deviate(0.5));
  for (const auto& sp : s.splits) {
    if (sp.split != split) continue;
    const auto curve = [](const std::vector<std::pair<double, double>>& det) {
      std::vector<std::pair<double, double>> out;
      for (const auto& [far, frr] : det) out.emplace_back(deviate(far), deviate(frr));
      return out;
    };
    plot.add(Series{fmt::format("skilled (EER {}%)", percent(sp.skilled.eer)), "#c0392b", curve(sp.det_skilled), 1.8});
    plot.add(Series{fmt::format("random (EER {}%)", percent(sp.random.eer)), "#2471a3", curve(sp.det_random), 1.8});
  }
  return plot.svg();
}

}  // namespace

std::string libraryEvaluationText(const library::EvaluationResult& r) {
  std::string out = fmt::format("{}\n\n", protocolSentence(r));
  out += fmt::format("{:<22} {:<16} {:>10} {:>17} {:>10} {:>17} {:>7} {:>7}\n", "features", "writers", "skilled EER",
                     "a priori FAR/FRR", "random EER", "a priori FAR/FRR", "rank-1", "rank-5");
  for (const auto& s : r.sets) {
    for (const auto& sp : s.splits) {
      out += fmt::format("{:<22} {:<16} {:>9}% {:>16} {:>9}% {:>16} {:>6}% {:>6}%\n", s.set.name(),
                         fmt::format("{} ({})", sp.split, sp.writers), percent(sp.skilled.eer),
                         percent(sp.skilled.far) + "/" + percent(sp.skilled.frr) + "%", percent(sp.random.eer),
                         percent(sp.random.far) + "/" + percent(sp.random.frr) + "%", percent(sp.rank1),
                         percent(sp.rank5));
    }
  }
  out += "\nThe week (evaluation writers; mean distances):\n";
  out += fmt::format("{:<22} {:>14} {:>16} {:>16} {:>22}\n", "features", "within session", "across the week",
                     "between writers", "nearer themselves");
  for (const auto& c : r.claim) {
    out += fmt::format("{:<22} {:>14.4f} {:>16.4f} {:>16.4f} {:>21}%\n", c.set, c.within_session, c.across_sessions,
                       c.between_writers, percent(c.writers_nearer_themselves));
  }
  out += fmt::format("\nTemplates (evaluation writers, shape+force): held-out profiles are {:.4f} from the template of 5 "
                     "recordings, {:.4f} from one recording; the template is nearer for {}% of writers\n",
                     r.templates.template_distance, r.templates.single_distance, percent(r.templates.writers_better));
  out += fmt::format("\n{} channel distances in {:.1f} s on {} threads\n", r.distances, r.seconds, r.options.threads);
  return out;
}

void checkLibraryReportFolder(const std::filesystem::path& out, bool force) {
  if (force) return;
  for (const char* name : {"report.html", "report.md", "results.csv", "scores.csv", "results.json"}) {
    HATTR_THROW_UNLESS(!std::filesystem::exists(out / name), "{}: already exists; expected a new report folder (or --force)",
                       (out / name).string());
  }
}

namespace {

/// results.csv, scores.csv and results.json.
void writeTables(const library::EvaluationResult& r, const std::filesystem::path& out) {
  io::Table results{{"features", "split", "writers", "skilled_eer", "skilled_eer_threshold", "skilled_a_priori_threshold",
                     "skilled_far", "skilled_frr", "random_eer", "random_eer_threshold", "random_a_priori_threshold",
                     "random_far", "random_frr", "rank1", "rank5", "probes"},
                    {},
                    ""};
  const auto num = [](double v) { return fmt::format("{}", v); };
  for (const auto& s : r.sets) {
    for (const auto& sp : s.splits) {
      results.rows.push_back({s.set.name(), sp.split, std::to_string(sp.writers), num(sp.skilled.eer),
                              num(sp.skilled.eer_threshold), num(sp.skilled.prior_threshold), num(sp.skilled.far),
                              num(sp.skilled.frr), num(sp.random.eer), num(sp.random.eer_threshold),
                              num(sp.random.prior_threshold), num(sp.random.far), num(sp.random.frr), num(sp.rank1),
                              num(sp.rank5), std::to_string(sp.probes)});
    }
  }
  io::writeTable(results, out / "results.csv", true);
  io::Table scores{{"split", "features", "claimed", "run", "query", "kind", "score"}, {}, ""};
  scores.rows.reserve(r.scores.size());
  for (const auto& row : r.scores) {
    scores.rows.push_back({row.split, row.set, row.person, std::to_string(row.run), row.query, row.kind, num(row.score)});
  }
  io::writeTable(scores, out / "scores.csv", true);
  writeFileAtomically(out / "results.json", libraryEvaluationJson(r).dump(2) + "\n", Overwrite::kReplace);
}

/// The paper's Figure 3 on a real writer: both sessions' force profiles.
std::string weekFigure(const library::WeekExample& week) {
  SvgPlot plot(fmt::format("Writer {}: force profiles a week apart", week.person), "writing time (0 to 1)",
               "force |f| (normalized)", 640, 360);
  const auto add = [&](const std::vector<std::vector<double>>& curves, const std::string& label, const char* colour) {
    for (std::size_t k = 0; k < curves.size(); ++k) {
      std::vector<std::pair<double, double>> points;
      for (std::size_t i = 0; i < curves[k].size(); ++i) {
        points.emplace_back(static_cast<double>(i) / static_cast<double>(curves[k].size() - 1), curves[k][i]);
      }
      plot.add(Series{k == 0 ? label : "", colour, std::move(points), 1.0});
    }
  };
  add(week.first, "session 1", "#2471a3");
  add(week.second, "session 2 (a week later)", "#c0392b");
  return plot.svg();
}

}  // namespace

void writeLibraryEvaluationReport(const library::EvaluationResult& r, const std::filesystem::path& out) {
  Document doc;
  std::map<std::string, std::string> files;
  doc.heading("Profile library evaluation: " + r.protocol, 1);
  doc.paragraph(protocolSentence(r));
  doc.heading("Verification and identification");
  doc.table(resultsTable(r));
  doc.heading("The week: a writer against themselves and against others");
  detail::Table claim{{"features", "within a session", "across the week", "between writers", "writers nearer themselves %"}, {}};
  for (const auto& c : r.claim) {
    claim.rows.push_back({c.set, detail::g(c.within_session), detail::g(c.across_sessions), detail::g(c.between_writers),
                          percent(c.writers_nearer_themselves)});
  }
  doc.paragraph("Mean feature distances between two genuine profiles of one evaluation writer within a session, "
                "across the two sessions (about a week apart), and between a writer's second session and another "
                "writer's first; the share of writers whose own first session is nearer their second than any other "
                "writer's first session is.");
  doc.table(claim);
  doc.heading("Templates against single recordings");
  doc.paragraph(fmt::format(
      "For each evaluation writer, the DBA template of the {} profiles the first run enrolled, and each of them alone, "
      "against the writer's second-session profiles (held out), shape+force features: mean distance {:.4f} from the "
      "template, {:.4f} from one recording; the template is nearer for {}% of the {} writers.",
      r.options.enrolled, r.templates.template_distance, r.templates.single_distance, percent(r.templates.writers_better),
      r.templates.writers));
  doc.heading("Figure 3 on a real writer");
  doc.figure("figure3_week", weekFigure(r.week),
             fmt::format("The paper's Figure 3 on a real writer: {}'s force profiles (|f| from the tablet's pressure "
                         "and tilt, normalized, on writing time) of the first session and of the second, about a "
                         "week later.",
                         r.week.person),
             files);
  doc.heading("DET curves");
  for (const auto& s : r.sets) {
    for (const std::string split : {"evaluation", "all"}) {
      const std::string name = fmt::format("det_{}_{}", s.set.name(), split);
      std::string file = name;
      std::replace(file.begin(), file.end(), '+', '-');
      doc.figure(file, detFigure(s, split),
                 fmt::format("DET curves of the {} features on the {} writers: skilled and random forgeries, FRR "
                             "against FAR on normal-deviate axes.",
                             s.set.name(), split),
                 files);
    }
  }
  detail::writeReportFiles(out, "Profile library evaluation", doc, files);

  writeTables(r, out);
}

}  // namespace hattr::report
