#include "hattr/report/plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "hattr/core/atomic_file.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "svg_plot_internal.hpp"

namespace hattr::report {
namespace {

/// A power as a percentage: whole above 10 %, one decimal below.
std::string percent(double fraction) {
  const double p = 100.0 * fraction;
  return p >= 10.0 ? fmt::format("{:.0f}", p) : fmt::format("{:.1f}", p);
}

/// "43 % (38–48 %)".
std::string powerWithInterval(const analysis::Proportion& p) {
  return fmt::format("{} % ({}–{} %)", percent(p.estimate), percent(p.lower), percent(p.upper));
}

nlohmann::json pointToJson(const PlanPoint& p) {
  return {{"subjects", p.subjects},          {"significant", p.power.successes},
          {"replicates", p.power.trials},    {"power", p.power.estimate},
          {"ci95", {p.power.lower, p.power.upper}}, {"decision", decisionName(p.decision)}};
}

/// What is compared, in words.
std::string comparisonWords(const nlohmann::json& plan) {
  const std::string c = plan.at("comparison").get<std::string>();
  if (c == "mode") return "the effect of the modes (or groups)";
  return c.find('-') != std::string::npos ? c + " (Tukey-adjusted)" : c;
}

/// The outcome, in words.
std::string outcomeWords(const nlohmann::json& plan) {
  const std::string o = plan.at("outcome").get<std::string>();
  if (o == "shape") return "shape (the trajectory's DTW cost)";
  if (o == "force") return "the haptic profile (the force's DTW cost)";
  return o;
}

/// "subjects" or "subjects per group".
std::string subjectsWord(const PlanSearchReport& s) { return s.groups > 1 ? "subjects per group" : "subjects"; }

}  // namespace

void PlanSearchOptions::check() const {
  HATTR_THROW_UNLESS(min_subjects >= 2, "--min-subjects: expected at least 2, got {}", min_subjects);
  HATTR_THROW_UNLESS(max_subjects >= min_subjects, "--max-subjects: expected at least --min-subjects ({}), got {}",
                     min_subjects, max_subjects);
  HATTR_THROW_UNLESS(step >= 1, "--step: expected a whole number of at least 1, got {}", step);
  HATTR_THROW_UNLESS(target > 0.0 && target < 1.0, "--power: expected a target power in (0, 1), got {}", target);
  HATTR_THROW_UNLESS(confidence > 0.0 && confidence < 1.0, "--confidence: expected a level in (0, 1), got {}",
                     confidence);
  HATTR_THROW_UNLESS(batch >= 1 && batch <= 100'000, "--batch: expected 1 to 100000 replicates, got {}", batch);
  HATTR_THROW_UNLESS(max_replicates >= batch && max_replicates <= 10'000'000 && max_replicates % batch == 0,
                     "--max-replicates: expected a whole number of batches of {} (at most 10000000), got {}", batch,
                     max_replicates);
}

const char* decisionName(PlanDecision decision) {
  switch (decision) {
    case PlanDecision::kBelow: return "below";
    case PlanDecision::kAbove: return "above";
    case PlanDecision::kUndecided: return "undecided";
  }
  return "?";
}

bool PlanPoint::reaches(double target) const {
  if (decision == PlanDecision::kUndecided) return power.estimate >= target;
  return decision == PlanDecision::kAbove;
}

const PlanPoint& PlanSearchResult::point(int subjects) const {
  const auto it = std::find_if(points.begin(), points.end(), [&](const PlanPoint& p) { return p.subjects == subjects; });
  if (it == points.end()) throw std::logic_error(fmt::format("plan: no design of {} subjects was decided", subjects));
  return *it;
}

PlanSearch::PlanSearch(const PlanSearchOptions& options) : options_(options) { options_.check(); }

int PlanSearch::gridSize() const noexcept { return (options_.max_subjects - options_.min_subjects) / options_.step + 1; }

void PlanSearch::record(int subjects, int replicate, bool significant) {
  const int offset = subjects - options_.min_subjects;
  HATTR_THROW_UNLESS(offset >= 0 && offset % options_.step == 0 && offset / options_.step < gridSize(),
                     "plan: a design of {} subjects: expected {} to {} in steps of {}", subjects,
                     options_.min_subjects, gridValue(gridSize() - 1), options_.step);
  HATTR_THROW_UNLESS(replicate >= 0 && replicate < options_.max_replicates,
                     "plan: replicate {}: expected 0 to {}", replicate, options_.max_replicates - 1);
  auto& known = outcomes_[subjects];
  if (known.empty()) known.assign(static_cast<std::size_t>(options_.max_replicates), -1);
  signed char& slot = known[static_cast<std::size_t>(replicate)];
  const signed char value = significant ? 1 : 0;
  HATTR_THROW_UNLESS(slot < 0 || slot == value, "plan: replicate {} of {} subjects was {} and is now {}", replicate,
                     subjects, slot == 1 ? "significant" : "not significant",
                     significant ? "significant" : "not significant");
  slot = value;
}

bool PlanSearch::has(int subjects, int replicate) const {
  const auto it = outcomes_.find(subjects);
  return it != outcomes_.end() && replicate >= 0 && replicate < options_.max_replicates &&
         it->second[static_cast<std::size_t>(replicate)] >= 0;
}

PlanSearch::Status PlanSearch::status(int subjects) const {
  const auto it = outcomes_.find(subjects);
  const int looks = options_.looks();
  // Each look's interval at 1 - (1 - confidence) / looks: the decision holds over all looks.
  const double look_confidence = 1.0 - (1.0 - options_.confidence) / looks;
  int successes = 0;
  for (int look = 1; look <= looks; ++look) {
    const int first = (look - 1) * options_.batch;
    const int end = look * options_.batch;
    for (int r = first; r < end; ++r) {
      const signed char v = it == outcomes_.end() ? -1 : it->second[static_cast<std::size_t>(r)];
      if (v < 0) return {std::nullopt, PlanRequest{subjects, first, options_.batch}};
      successes += v;
    }
    const analysis::Proportion at_look = analysis::clopperPearson(successes, end, look_confidence);
    std::optional<PlanDecision> decision;
    if (at_look.upper < options_.target) decision = PlanDecision::kBelow;
    if (at_look.lower > options_.target) decision = PlanDecision::kAbove;
    if (!decision && look == looks) decision = PlanDecision::kUndecided;
    if (decision) return {PlanPoint{subjects, analysis::clopperPearson(successes, end, 0.95), *decision}, std::nullopt};
  }
  return {};  // not reached: the last look decides
}

std::optional<PlanRequest> PlanSearch::walk(std::vector<PlanPoint>* visited, std::optional<int>* answer) const {
  // A design's point once decided (kept in `seen`), else none and the batch it needs.
  std::map<int, PlanPoint> seen;
  std::optional<PlanRequest> pending;
  const auto decided = [&](int index) -> std::optional<PlanPoint> {
    const int subjects = gridValue(index);
    if (const auto it = seen.find(subjects); it != seen.end()) return it->second;
    Status s = status(subjects);
    if (s.request) {
      pending = s.request;
      return std::nullopt;
    }
    seen.emplace(subjects, *s.point);
    return s.point;
  };
  const auto walked = [&]() -> std::optional<PlanRequest> {
    const double target = options_.target;
    const int largest = gridSize() - 1;
    // The largest design: when it falls short, none reaches the target.
    const std::optional<PlanPoint> top = decided(largest);
    if (!top) return pending;
    if (!top->reaches(target)) return std::nullopt;
    // The smallest: when it suffices, it is the answer (and no bisection is needed).
    const std::optional<PlanPoint> bottom = decided(0);
    if (!bottom) return pending;
    // Bisection between a design below (lo) and one that reaches the target (hi).
    int lo = 0, hi = bottom->reaches(target) ? 0 : largest;
    while (hi - lo > 1) {
      const int mid = lo + (hi - lo) / 2;
      const std::optional<PlanPoint> p = decided(mid);
      if (!p) return pending;
      (p->reaches(target) ? hi : lo) = mid;
    }
    *answer = gridValue(hi);
    // The Monte Carlo range: from the answer up to a design decided above the target, and down
    // to one decided below it, walking past at most kMostUndecidedWalked undecided designs on
    // each side (a power curve flat at the target would cost every design's max-replicates):
    // past them the range ends at the decided designs the bisection found, or the grid's end.
    int undecided = 0;
    for (int i = hi; i <= largest && undecided < kMostUndecidedWalked; ++i) {
      const std::optional<PlanPoint> p = decided(i);
      if (!p) return pending;
      if (p->decision == PlanDecision::kAbove) break;
      undecided += p->decision == PlanDecision::kUndecided ? 1 : 0;
    }
    undecided = 0;
    for (int i = hi - 1; i >= 0 && undecided < kMostUndecidedWalked; --i) {
      const std::optional<PlanPoint> p = decided(i);
      if (!p) return pending;
      if (p->decision == PlanDecision::kBelow) break;
      undecided += p->decision == PlanDecision::kUndecided ? 1 : 0;
    }
    return std::nullopt;
  };
  const std::optional<PlanRequest> request = walked();
  for (const auto& [subjects, point] : seen) visited->push_back(point);
  return request;
}

std::optional<PlanRequest> PlanSearch::next() const {
  std::vector<PlanPoint> visited;
  std::optional<int> answer;
  return walk(&visited, &answer);
}

PlanSearchResult PlanSearch::result() const {
  std::vector<PlanPoint> visited;
  PlanSearchResult result;
  if (walk(&visited, &result.answer)) throw std::logic_error("plan: the search has not ended (it needs more replicates)");
  for (const auto& p : visited) result.replicates += p.power.trials;
  if (result.answer) {
    result.range_low = options_.min_subjects;
    result.range_high = gridValue(gridSize() - 1);
    // A design decided on the unexpected side of the answer (Monte Carlo noise) bounds nothing.
    for (const auto& p : visited) {
      if (p.decision == PlanDecision::kBelow && p.subjects < *result.answer) {
        result.range_low = std::max(result.range_low, p.subjects + options_.step);
      }
      if (p.decision == PlanDecision::kAbove && p.subjects >= *result.answer) {
        result.range_high = std::min(result.range_high, p.subjects);
      }
    }
  }
  result.points = std::move(visited);
  return result;
}

nlohmann::json planSearchOptionsToJson(const PlanSearchOptions& o) {
  return {{"min_subjects", o.min_subjects}, {"max_subjects", o.max_subjects}, {"step", o.step},
          {"target", o.target},             {"batch", o.batch},               {"max_replicates", o.max_replicates},
          {"confidence", o.confidence}};
}

double PlanSearchReport::labHours(int subjects) const {
  return static_cast<double>(subjects) * groups * lab_s_per_subject / 3600.0;
}

std::vector<std::pair<std::string, std::optional<std::size_t>>> PlanReport::answers() const {
  std::vector<std::pair<std::string, std::optional<std::size_t>>> out;
  for (std::size_t i = 0; i < searches.size(); ++i) {
    const PlanSearchReport& s = searches[i];
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& a) { return a.first == s.hypothesis; });
    if (it == out.end()) it = out.insert(out.end(), {s.hypothesis, std::nullopt});
    if (!s.result.answer) continue;
    // The cheapest: fewest lab hours, else (no time known) fewest subjects in all.
    const auto cost = [](const PlanSearchReport& r) {
      const double hours = r.labHours(*r.result.answer);
      return std::isfinite(hours) ? hours : static_cast<double>(*r.result.answer * r.groups);
    };
    if (!it->second || cost(s) < cost(searches[*it->second])) it->second = i;
  }
  return out;
}

std::string planSearchSentence(const PlanSearchReport& search, double target) {
  const PlanSearchResult& r = search.result;
  if (!r.answer) {
    // The best design seen: the highest estimate (the largest, unless power is not monotone).
    const auto best = std::max_element(r.points.begin(), r.points.end(), [](const PlanPoint& a, const PlanPoint& b) {
      return a.power.estimate < b.power.estimate;
    });
    return fmt::format("no design within {} {} reaches {} % power: best {} at {}{}", search.max_subjects,
                       subjectsWord(search), percent(target), powerWithInterval(best->power), best->subjects,
                       best->decision == PlanDecision::kUndecided ? " (undecided: its interval holds the target)" : "");
  }
  const PlanPoint& p = r.point(*r.answer);
  std::string text = fmt::format("{} {}: power {} from {} studies (Monte Carlo range {}–{})", *r.answer,
                                 subjectsWord(search), powerWithInterval(p.power), p.power.trials, r.range_low,
                                 r.range_high);
  if (std::isfinite(search.lab_s_per_subject)) {
    text += fmt::format("; {:.1f} lab hours ({:.2f} h per subject{})", search.labHours(*r.answer),
                        search.lab_s_per_subject / 3600.0,
                        search.groups > 1 ? fmt::format(", {} groups", search.groups) : std::string());
  }
  return text;
}

nlohmann::json planReportToJson(const PlanReport& report) {
  const double target = report.plan.at("search").at("target").get<double>();
  nlohmann::json searches = nlohmann::json::array();
  for (const auto& s : report.searches) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : s.result.points) points.push_back(pointToJson(p));
    nlohmann::json answer = nullptr;
    if (s.result.answer) {
      const PlanPoint& p = s.result.point(*s.result.answer);
      answer = {{"subjects", p.subjects},
                {"power", p.power.estimate},
                {"ci95", {p.power.lower, p.power.upper}},
                {"mc_range", {s.result.range_low, s.result.range_high}},
                {"lab_hours", jsonNumber(s.labHours(p.subjects))}};
    }
    searches.push_back({{"label", s.label},
                        {"hypothesis", s.hypothesis},
                        {"design", s.design},
                        {"groups", s.groups},
                        {"lab_hours_per_subject", jsonNumber(s.lab_s_per_subject / 3600.0)},
                        {"max_subjects", s.max_subjects},
                        {"points", points},
                        {"replicates", s.result.replicates},
                        {"answer", answer},
                        {"sentence", planSearchSentence(s, target)}});
  }
  nlohmann::json answers = nlohmann::json::array();
  for (const auto& [hypothesis, index] : report.answers()) {
    answers.push_back({{"hypothesis", hypothesis}, {"search", index ? nlohmann::json(*index) : nlohmann::json(nullptr)}});
  }
  return {{"plan", report.plan}, {"searches", searches}, {"skipped", report.skipped}, {"answers", answers}};
}

std::string planReportText(const PlanReport& report) {
  const nlohmann::json& plan = report.plan;
  const double target = plan.at("search").at("target").get<double>();
  std::string out = fmt::format("Plan: {} on {} ({}), target power {} % at α = {}; each design's decision at {} % "
                                "confidence over its looks.\n",
                                comparisonWords(plan), outcomeWords(plan),
                                plan.at("analysis").get<std::string>(), percent(target), plan.at("alpha").get<double>(),
                                percent(plan.at("search").at("confidence").get<double>()));
  for (const auto& s : report.searches) {
    out += fmt::format("\n{}\n  {:>8}  {:>7}  {:<15}  {:>10}  {}\n", s.label, "subjects", "power", "95 % CI",
                       "replicates", "decision");
    for (const auto& p : s.result.points) {
      out += fmt::format("  {:>8}  {:>6} %  [{:>5}, {:>5}] %  {:>10}  {}\n", p.subjects, percent(p.power.estimate),
                         percent(p.power.lower), percent(p.power.upper), p.power.trials, decisionName(p.decision));
    }
    out += "  " + planSearchSentence(s, target) + "\n";
  }
  for (const auto& why : report.skipped) out += "\nskipped: " + why + "\n";
  const auto answers = report.answers();
  if (report.searches.size() > 1) {
    out += "\n";
    for (const auto& [hypothesis, index] : answers) {
      const std::string who = hypothesis.empty() ? "answer" : hypothesis;
      out += index ? fmt::format("{}: {}\n", who, report.searches[*index].label)
                   : fmt::format("{}: no design reaches the target within the limits\n", who);
    }
  }
  return out;
}

void writePlanPage(const PlanReport& report, const std::filesystem::path& file) {
  using detail::escape;
  const double target = report.plan.at("search").at("target").get<double>();
  std::string body;
  for (const auto& s : report.searches) {
    // The power curve over the designs decided, its interval dashed, the target a grey line.
    detail::SvgPlot plot(s.label, subjectsWord(s), "power (fraction of studies)");
    detail::Series power{"power", "#1f77b4", {}, 2.0, false, true, {}};
    detail::Series lower{"95 % interval", "#1f77b4", {}, 1.0, true, false, {}};
    detail::Series upper{"", "#1f77b4", {}, 1.0, true, false, {}};
    for (const auto& p : s.result.points) {
      power.points.emplace_back(p.subjects, p.power.estimate);
      lower.points.emplace_back(p.subjects, p.power.lower);
      upper.points.emplace_back(p.subjects, p.power.upper);
    }
    const double x0 = s.result.points.empty() ? 0.0 : s.result.points.front().subjects;
    const double x1 = s.result.points.empty() ? 1.0 : s.result.points.back().subjects;
    detail::Series goal{fmt::format("target {} %", percent(target)), "#888888", {{x0, target}, {x1, target}}, 1.0, true,
                        false, {}};
    plot.integerX();
    plot.yRange(0.0, 1.0);
    plot.add(std::move(power));
    plot.add(std::move(lower));
    plot.add(std::move(upper));
    plot.add(std::move(goal));
    std::string rows;
    for (const auto& p : s.result.points) {
      rows += fmt::format("<tr><td>{}</td><td>{} %</td><td>{}–{} %</td><td>{}</td><td>{}</td></tr>", p.subjects,
                          percent(p.power.estimate), percent(p.power.lower), percent(p.power.upper), p.power.trials,
                          decisionName(p.decision));
    }
    body += fmt::format("<h2>{}</h2>\n<figure>{}<figcaption>{}</figcaption></figure>\n<table><tr><th>{}</th><th>power</th>"
                        "<th>95 % CI</th><th>replicates</th><th>decision</th></tr>{}</table>\n",
                        escape(s.label), plot.svg(), escape(planSearchSentence(s, target)), subjectsWord(s), rows);
  }
  std::string skipped;
  for (const auto& why : report.skipped) skipped += "<li>" + escape(why) + "</li>";
  if (!skipped.empty()) skipped = "<p>Left out by the limits:</p><ul>" + skipped + "</ul>\n";
  const nlohmann::json& plan = report.plan;
  const std::string html = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hattr study plan</title>\n"
      "<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}figure{{margin:1em 0}}"
      "table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:.2em .5em;text-align:right}}</style></head>"
      "<body>\n<h1>Study plan</h1>\n<p>The smallest design whose analysis ({}) finds {} on {} with {} % power at "
      "α = {}, by simulation. Each design's power is the fraction of its simulated studies with p &lt; α, with its "
      "exact 95 % interval; each design got replicates in batches until its interval at {} % confidence over "
      "its looks excluded the target.</p>\n{}{}</body></html>\n",
      escape(plan.at("analysis").get<std::string>()), escape(comparisonWords(plan)), escape(outcomeWords(plan)),
      percent(target), plan.at("alpha").get<double>(),
      percent(plan.at("search").at("confidence").get<double>()), body, skipped);
  hattr::writeFileAtomically(file, html, hattr::Overwrite::kReplace);
}

}  // namespace hattr::report
