// The printable page of a learner's progress (learner_progress.hpp): one self-contained HTML
// file, the learning curve inline SVG, laid out for A4 or Letter paper when printed.
#include <cmath>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/report/learner_progress.hpp"
#include "svg_plot_internal.hpp"

namespace hattr::report {
namespace {

using detail::escape;

/// A phase as a teacher reads it.
std::string plainPhase(const ProgressTrial& t) {
  if (t.phase == session::kPhaseBaseline) return "before practice";
  if (t.phase == session::kPhaseTraining) return t.guided ? "guided" : "practice";
  if (t.phase == session::kPhasePostTest) return "alone, after practice";
  if (t.phase == session::kPhaseRetention) return "alone, days later";
  if (t.phase == session::kPhaseTransfer) return "new letter";
  return t.phase;
}

std::string number(double v, const char* format = "{:.1f}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : "–";
}

/// The curve: every trial's shape cost in the order written, guided trials apart, the compared
/// ones joined letter by letter, the best and the latest marked.
std::string curveSvg(const LearnerProgress& p) {
  static const char* kLetterColours[] = {"#1f4e79", "#2e7d32", "#6a1b9a", "#8d6e63", "#00838f"};
  const std::string compared = p.compares_alone ? "written alone" : "guided";
  detail::SvgPlot plot("Shape of each letter written (lower is closer to the model)", "trial", "shape cost");
  plot.integerX();
  detail::Series guided{.label = "guided", .colour = "#8fb3d9", .width = 0.0, .markers = true};
  detail::Series best{.label = "best (" + compared + ")", .colour = "#d4a017", .width = 0.0, .markers = true};
  detail::Series latest{.label = "latest (" + compared + ")", .colour = "#c0392b", .width = 0.0, .markers = true};
  std::map<std::string, detail::Series> by_letter;
  for (const auto& t : p.trials) {
    if (!std::isfinite(t.shape)) continue;
    const std::pair<double, double> point{t.number, t.shape};
    if (t.guided && p.compares_alone) {
      guided.points.push_back(point);
    } else {
      auto [it, fresh] = by_letter.try_emplace(t.skill);
      if (fresh) {
        it->second = {.label = (p.letters.size() > 1 ? t.skill + " " : "") + compared,
                      .colour = kLetterColours[(by_letter.size() - 1) % std::size(kLetterColours)],
                      .width = 1.0,
                      .markers = true};
      }
      it->second.points.push_back(point);
    }
    if (t.best) best.points.push_back(point);
    if (t.latest) latest.points.push_back(point);
  }
  if (!guided.points.empty()) plot.add(guided);
  for (auto& [letter, series] : by_letter) plot.add(series);
  for (auto* s : {&best, &latest}) {
    if (!s->points.empty()) plot.add(*s);
  }
  return plot.svg();
}

std::string learnerHeader(const LearnerProgress& p, const ProgressPageOptions& o) {
  const session::Learner& l = p.learner;
  const std::string who = o.identified && !l.name.empty() ? session::displayName(l) : "learner " + l.code;
  std::string facts;
  if (l.age_years) facts += fmt::format("age {}", *l.age_years);
  if (!l.handedness.empty()) facts += (facts.empty() ? "" : " · ") + l.handedness + "-handed";
  std::string out = fmt::format("<h1>Progress of {}</h1>\n<p class=\"plan\">{} · {} · letters {}{}</p>\n", escape(who),
                                escape(p.study), escape(p.strategy), escape(fmt::format("{}", fmt::join(p.letters, ", "))),
                                o.printed.empty() ? "" : " · printed " + escape(o.printed));
  if (!facts.empty()) out += "<p>" + escape(facts) + "</p>\n";
  if (o.identified && !l.notes.empty()) out += "<p class=\"notes\">Notes: " + escape(l.notes) + "</p>\n";
  return out + "<p><strong>Next:</strong> " + escape(p.next) + "</p>\n";
}

std::string sessionsTable(const LearnerProgress& p) {
  std::string out =
      fmt::format("<table><tr><th>session</th><th>date</th><th>trials</th><th>shape {}</th><th>change from the "
                  "start</th><th>seconds a letter</th><th>pen lifts</th><th>speed changes</th></tr>\n",
                  p.compares_alone ? "written alone" : "guided");
  for (const auto& s : p.sessions) {
    const std::string change = s.is_start                ? std::string("the start")
                               : std::isfinite(s.change) ? fmt::format("{:+.0f} %{}", s.change * 100.0, s.best_so_far ? " ★" : "")
                                                         : std::string("–");
    out += fmt::format("<tr><td>{}</td><td>{}</td><td>{} of {}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
                       "<td>{}</td></tr>\n",
                       s.session, escape(s.date.empty() ? "–" : s.date), s.completed, s.planned, number(s.alone_shape),
                       change, number(s.writing_time_s), number(s.pen_lifts), number(s.velocity_peaks));
  }
  return out + "</table>\n";
}

/// Every trial; `compact`: the columns a narrow panel has room for.
std::string trialsTable(const LearnerProgress& p, bool compact) {
  // The narrow table's short headers do not wrap (a narrow view broke "session" letter by letter).
  std::string out = compact ? "<table width=\"100%\"><tr style=\"white-space:nowrap\"><th>#</th><th>session</th>"
                              "<th>letter</th><th>how</th><th>shape</th><th></th></tr>\n"
                            : "<table><tr><th>#</th><th>session</th><th>date</th><th>letter</th><th>how</th><th>shape</th>"
                              "<th>pressure</th><th>seconds</th><th>pen lifts</th><th>speed changes</th><th></th></tr>\n";
  for (const auto& t : p.trials) {
    std::vector<std::string> marks;
    if (t.best) marks.emplace_back("★ best");
    if (t.latest) marks.emplace_back("● latest");
    if (t.disturbed) marks.emplace_back("disturbed: not compared");
    const std::string mark = fmt::format("{}", fmt::join(marks, ", "));
    const std::string row = t.guided ? "<tr class=\"guided\">" : "<tr>";
    if (compact) {
      out += fmt::format("{}<td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", row, t.number,
                         t.session, escape(t.skill), escape(plainPhase(t)), number(t.shape), mark);
      continue;
    }
    out += fmt::format("{}<td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
                       "<td>{}</td><td>{}</td><td>{}</td></tr>\n",
                       row, t.number, t.session, escape(t.date), escape(t.skill), escape(plainPhase(t)), number(t.shape),
                       number(t.force), number(t.writing_time_s), number(t.pen_lifts, "{:.0f}"),
                       number(t.velocity_peaks, "{:.0f}"), mark);
  }
  return out + "</table>\n";
}

constexpr std::string_view kStyle =
    "body{font-family:sans-serif;max-width:900px;margin:1.5em auto;color:#222}"
    "table{border-collapse:collapse;margin:0.5em 0;font-size:0.9em}td,th{border:1px solid #bbb;padding:2px 6px;"
    "text-align:right}td{white-space:nowrap}th{background:#eee}tr.guided td{color:#555}.plan{color:#444}.about{color:#555;font-size:0.85em}"
    "@media print{body{margin:0;max-width:none}h2{page-break-after:avoid}table,figure{page-break-inside:avoid}}";

}  // namespace

std::string progressPageHtml(const LearnerProgress& p, const ProgressPageOptions& o) {
  std::string body = o.whole_page ? learnerHeader(p, o) : "";
  body += "<h2>Sessions</h2>\n<ul class=\"sentences\">";
  for (const auto& s : p.sessions) body += "<li>" + escape(s.sentence) + "</li>";
  body += "</ul>\n";
  if (o.whole_page && !p.trials.empty()) body += "<figure>" + curveSvg(p) + "</figure>\n";
  if (o.whole_page) body += sessionsTable(p);  // the sentences say it where there is little room
  body += "<h2>Every trial</h2>\n" +
          (p.trials.empty() ? std::string("<p>No trial written yet.</p>\n") : trialsTable(p, !o.whole_page));
  if (o.whole_page) body += fmt::format(
      "<p class=\"about\">Shape and pressure are hattr's scores of each letter against the model letter (the paper's "
      "dynamic time warping of the pen's path and of its force, after scaling to the model's size and time): lower is "
      "closer. “Written alone”: without guidance, the way the learner writes. ★ the best, ● the latest letter {}. "
      "Training strategy: {} ({}). Study file: {}.</p>\n",
      p.compares_alone ? "written alone" : "(every trial of this plan is guided)", escape(p.strategy),
      escape(p.strategy_name), escape(p.file.filename().string()));
  return fmt::format("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Progress of {}</title>\n"
                     "<style>{}</style></head><body>\n{}</body></html>\n",
                     escape(o.identified && !p.learner.name.empty() ? p.learner.name : p.learner.code), kStyle, body);
}

}  // namespace hattr::report
